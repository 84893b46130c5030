"""The next-best manoeuvres of a live session: :func:`rplearn.analysis.manoeuvres.rank_manoeuvres`
on the session's statistics, as the hook of :class:`rplearn.workflows.live.LiveOptions`.

The statistics the session keeps are at its accumulation order (the largest candidate order of
``--order auto``), so the ranking reads the posterior of the chosen fit's smoothness prior
continued to that order, as the per-node spreads of the live view are read
(:mod:`rplearn.models.own_posterior`), with the chosen fit's noise. A ranking scores every
candidate with a rank-k update (seconds for a hundred candidates), so it is redone at most every
``every_s`` seconds of wall time and the last one is shown in between; rows are best first (the
largest reduction of the nodes' spread per second of flight). The session's sums per time block
(the statistics' ``blocks``) carry an error drifting over seconds into the ranking's posterior,
its size estimated from them (:mod:`rplearn.core.lsq.block_sums`).

A fit at the search's largest smoothing (:func:`rplearn.core.lsq.selection.at_smoothing_cap`: a
session's first refits, a few seconds of flight) claims a pattern known to a few hundredths of a
dB: under it every candidate scores alike (measured on the ``ground`` preset after 2 s: all 39
candidates' predicted spread 0.0002 dB), so its ranking's order is arbitrary. There the ranking
reads the smoothness prior ``rplearn trajectory --optimize`` plans with before any flight
(:data:`rplearn.analysis.manoeuvre_prior.NOMINAL_PRIOR_STD_DB` over each node's sphere,
:func:`rplearn.analysis.manoeuvres.prior_penalty_weight`) with the samples so far and the fit's
noise: the manoeuvres that teach the most of what neither the prior nor the flight so far says.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.analysis.manoeuvre_prior import NOMINAL_PRIOR_STD_DB
from rplearn.analysis.manoeuvres import ManoeuvreOptions, prior_penalty_weight, rank_manoeuvres
from rplearn.core.lsq.selection import at_smoothing_cap
from rplearn.errors import InputError
from rplearn.plan.manoeuvres import CandidateOptions

#: Seconds of wall time between two rankings of a live session.
DEFAULT_ADVICE_EVERY_S = 15.0


def ranking_options(options: ManoeuvreOptions, statistics: Any, fitted: Any) -> ManoeuvreOptions:
    """The ranking's options for one refit: the fitted model's noise, and, when the fit took the
    search's largest smoothing and ``options`` give no penalty weight, the nominal smoothness
    prior's (module docstring).

    Parameters
    ----------
    options : ManoeuvreOptions
        The advisor's options.
    statistics : NormalEquations
        The session's statistics (their basis is the prior's).
    fitted : FittedModel
        The refit's model.

    Returns
    -------
    ManoeuvreOptions
    """
    training = fitted.model.training
    noise = training.noise_std_db if training.noise_std_db is not None else training.rmse_db
    if noise is not None and noise > 0:
        # the noise the fit's covariance is read with: times its variance inflation (the held-out
        # error beyond the noise), as the session's spreads and its --until-spread read it
        inflation = training.variance_inflation if training.variance_inflation is not None else 1.0
        options = replace(options, noise_std_db=float(noise) * float(np.sqrt(max(float(inflation), 1.0))))
    smoothing = fitted.spec.smoothing
    if options.penalty_weight is None and smoothing is not None and at_smoothing_cap(smoothing):
        weight = prior_penalty_weight(statistics.basis, NOMINAL_PRIOR_STD_DB, options.noise_std_db,
                                      float(fitted.spec.ridge_weight), options.power)
        options = replace(options, penalty_weight=weight)
    return options


@check_types
class ManoeuvreAdvisor:
    """Callable hook ``(statistics, fitted, latest poses) -> [(name, duration [s], spread after [dB])]``.

    Parameters
    ----------
    options : ManoeuvreOptions, optional
        The candidates and their scoring; its noise is replaced by the fitted model's, and the
        nodes in ``fixed_nodes`` cannot move (a ground station).
    every_s : float
        Seconds of wall time between rankings (the last one is returned in between).
    """

    def __init__(self, options: ManoeuvreOptions | None = None, every_s: float = DEFAULT_ADVICE_EVERY_S) -> None:
        if not (math.isfinite(every_s) and every_s >= 0):
            raise InputError(f"every_s: expected a non-negative number of seconds, got {every_s!r}", param="every_s")
        self.options = options or ManoeuvreOptions()
        self.every_s = float(every_s)
        self._last: tuple[float, list[tuple[str, float, float]]] | None = None

    def __call__(self, statistics: Any, fitted: Any, latest: pd.DataFrame) -> list[tuple[str, float, float]]:
        now = time.monotonic()
        if self._last is not None and now - self._last[0] < self.every_s:
            return self._last[1]
        options = ranking_options(self.options, statistics, fitted)
        ranked = rank_manoeuvres(statistics, fitted.spec, list(fitted.model.nodes), latest, options,
                                 getattr(statistics, "blocks", None))
        rows = [(r.name, float(r.duration_s), float(max(r.spread_after_db.values()))) for r in ranked]
        self._last = (now, rows)
        return rows


@check_types
def live_advisor(fixed_nodes: tuple[str, ...] = (), every_s: float = DEFAULT_ADVICE_EVERY_S,
                 floor_db: float | None = None) -> ManoeuvreAdvisor:
    """The advisor ``rplearn live`` uses: the default candidates with ``fixed_nodes`` held still,
    no reward below ``floor_db`` (the session's ``--until-spread``)."""
    candidates = CandidateOptions(fixed_nodes=tuple(fixed_nodes))
    return ManoeuvreAdvisor(ManoeuvreOptions(candidates=candidates, floor_db=floor_db), every_s)


__all__ = ["DEFAULT_ADVICE_EVERY_S", "ManoeuvreAdvisor", "live_advisor", "ranking_options"]
