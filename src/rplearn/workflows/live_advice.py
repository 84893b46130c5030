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

**An earlier flight's hyper-parameters** (``rplearn live --from-model EARLIER.json``,
:class:`EarlierFit`: the model of an earlier flight of the same drones, e.g. before a payload
change, the recalibration case). A young session's own estimates are poor: measured on the
simulator (``benchmarks/manoeuvres.py --ranker live``), the smoothing chosen from 2-20 s of
flight jumps between 0 and the search's cap, and the drift is estimated from a few 5-s blocks.
While the session is young the ranking therefore reads its posterior with the earlier fit's
noise times the square root of its variance inflation, its smoothing as an absolute penalty
weight and its drift per block (:func:`rplearn.workflows.calibration_plan.options_from_model`,
what ``trajectory --optimize --from-model`` plans with), over the session's own statistics.
*Young* means: the session has learned fewer samples than the earlier fit learned from
(``training.n_samples``). Each of the three is estimated from the fit's samples (the smoothing
and the inflation by cross-validation over them, the noise from their residuals, the drift from
their time blocks at the radio's packet rate), so, with fewer samples, the session's estimate of
it is the noisier of the two; from as many on, the session's are at least as precise and they
are this flight's (the earlier one's are of another flight), so they take over. The rule states
no threshold of its own: the earlier fit's sample count is the yardstick. Before that the
earlier fit's values stand whether or not the session's fit is at the search's largest
smoothing. The session's fitted model is unchanged: only the advice's hyper-parameters are.
They are of the earlier fit's antennas in its band: a session learning a node that fit did not,
or at another band (:meth:`EarlierFit.mismatch`), is refused by :func:`earlier_fit` when its nodes
or carrier are known before it starts, and otherwise ranks with its own from the first refit that
shows it (:meth:`ManoeuvreAdvisor.mismatch`; the session's summary says why).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.analysis.manoeuvre_prior import NOMINAL_PRIOR_STD_DB
from rplearn.analysis.manoeuvres import ManoeuvreOptions, prior_penalty_weight, rank_manoeuvres
from rplearn.core.lsq.selection import at_smoothing_cap
from rplearn.core.plausible import describe_band, same_band
from rplearn.errors import InputError, RplearnError
from rplearn.models.base import relative_levels
from rplearn.models.load import load_model
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec
from rplearn.plan.manoeuvres import CandidateOptions
from rplearn.workflows.calibration_plan import options_from_model

#: Seconds of wall time between two rankings of a live session.
DEFAULT_ADVICE_EVERY_S = 15.0


@check_types
@dataclass(frozen=True)
class EarlierFit:
    """An earlier flight's hyper-parameters for a young session's ranking (module docstring).

    Attributes
    ----------
    path : str
        The model file they were read from.
    noise_std_db : float
        The earlier fit's noise times the square root of its variance inflation [dB].
    penalty_weight, power : float
        Its smoothness penalty as an absolute weight (units of ``X^T X``) and its power.
    drift_std_db : float
        Its drifting error per :data:`~rplearn.core.lsq.block_sums.DEFAULT_BLOCK_S` block [dB].
    n_samples : int
        The samples it learned from: the session's own estimates take over from as many.
    nodes : tuple of str
        The nodes it learned (empty: not checked): a session learning a node outside them ranks
        with its own (:meth:`mismatch`).
    frequency_hz : float or None
        The carrier it learned at (None: not stated, not checked): a session of another band
        ranks with its own.
    """

    path: str
    noise_std_db: float
    penalty_weight: float
    power: float
    drift_std_db: float
    n_samples: int
    nodes: tuple[str, ...] = ()
    frequency_hz: float | None = None

    def mismatch(self, nodes: Sequence[str] = (), frequency_hz: float | None = None) -> str | None:
        """Why these hyper-parameters are not of a session learning ``nodes`` at ``frequency_hz``
        (one line naming the file and its field), or None: a node the earlier fit did not learn
        (another drone's antenna), or another band (antenna patterns change with frequency)."""
        missing = [n for n in nodes if self.nodes and n not in self.nodes]
        if missing:
            return (f"{self.path} learned the nodes {', '.join(self.nodes)} (its model's nodes), the session learns "
                    f"{', '.join(nodes)}: {', '.join(missing)} not among them (its noise, smoothing and drift are of "
                    "other antennas)")
        if frequency_hz is not None and self.frequency_hz is not None and not same_band(frequency_hz, self.frequency_hz):
            return (f"{self.path} learned at {describe_band(self.frequency_hz, self.frequency_hz)} "
                    f"(training.frequency_hz), the session's rows are at {describe_band(frequency_hz, frequency_hz)}: "
                    "antenna patterns change with frequency")
        return None

    def young(self, statistics: Any) -> bool:
        """Whether a session with these statistics has learned fewer samples than the earlier fit."""
        return int(statistics.n_samples) < self.n_samples

    def options(self, options: ManoeuvreOptions) -> ManoeuvreOptions:
        """``options`` with these hyper-parameters (the inflated posterior: no misfit term)."""
        return replace(options, noise_std_db=self.noise_std_db, penalty_weight=self.penalty_weight, power=self.power,
                       correlated_std_db=self.drift_std_db, misfit_std_db=0.0, prior_variance_factor=1.0)

    def text(self) -> str:
        """What the ranking takes, and until when."""
        return (f"manoeuvres ranked with {self.path}'s noise {self.noise_std_db:.2f} dB, smoothness penalty weight "
                f"{self.penalty_weight:.3g} and drift {self.drift_std_db:.2f} dB per 5-s block until the session has "
                f"learned {self.n_samples} samples (as many as that fit), then with the session's own")


@check_types
def earlier_fit(model: str, spec: ModelSpec | None = None, nodes: Sequence[str] | None = None,
                frequency_hz: float | None = None) -> EarlierFit:
    """The hyper-parameters of an earlier flight's model file for a session learning ``spec``
    (default ``sh``), read as ``trajectory --optimize --from-model`` reads them
    (:func:`rplearn.workflows.calibration_plan.options_from_model`).

    Parameters
    ----------
    model : str
        The model file.
    spec : ModelSpec, optional
        The session's model.
    nodes : sequence of str, optional
        The session's nodes when known before it starts (``--nodes``).
    frequency_hz : float, optional
        The session's carrier when known before it starts (a MAVLink stream's ``--frequency``).

    Raises
    ------
    InputError
        ``param="from_model"``, one line: the file is missing or not an automatic pattern fit
        (``rplearn fit --order auto``; a reference-pattern model learned from no flight), of
        another kind than ``spec``, fitted with priors, learned from relative RSSI, of nodes or a
        band other than ``nodes`` and ``frequency_hz`` (:meth:`EarlierFit.mismatch`), or lacks a
        field the ranking needs or holds a nonsensical one (naming it).
    """
    spec = spec or ModelSpec.parse("sh")
    try:
        loaded = load_model(model)
    except (OSError, RplearnError):
        loaded = None  # options_from_model says why, in one line
    if isinstance(loaded, PatternSet) and loaded.training.reference is not None:
        raise InputError(f"from_model: {model} is a reference-pattern model (training.reference: rplearn reference), learned "
                         "from no flight: it has no noise, smoothing or drift; give an earlier flight's model of rplearn "
                         "fit DATASET --order auto", param="from_model")
    if isinstance(loaded, PatternSet) and relative_levels(loaded):
        raise InputError(f"from_model: {model} learned from relative RSSI (training.rssi_scale relative, sync --rssi-scale "
                         "relative): its noise and drift are on that radio's own scale, the session learns dBm; give a model "
                         "of calibrated RSSI", param="from_model")
    if isinstance(loaded, PatternSet) and loaded.training.selection is not None:
        t, refit = loaded.training, "fit the earlier flight with rplearn fit DATASET --order auto -o MODEL.json"
        if loaded.basis.kind != spec.kind:
            raise InputError(f"from_model: {model} is a {loaded.basis.label} fit; the session learns {spec.kind}: give a "
                             f"{spec.kind} model's file, or --model {loaded.basis.kind}", param="from_model")
        if t.prior:
            raise InputError(f"from_model: {model} was fitted with priors (--prior): its penalty is a ridge toward them, not a "
                             f"smoothness prior; {refit} without --prior", param="from_model")
        for name in ("noise_std_db", "variance_inflation", "planning_penalty_weight", "drift_std_db", "n_samples"):
            if getattr(t, name) is None:
                raise InputError(f"from_model: {model} has no training.{name} (written by rplearn fit --order auto of a "
                                 f"dataset in memory); {refit}", param="from_model")
        if int(t.n_samples or 0) <= 0:  # never written so: a damaged file, whose values would never be used
            raise InputError(f"from_model: {model}: training.n_samples: expected a positive count of samples, got "
                             f"{t.n_samples}", param="from_model")
    opts = options_from_model(model, ManoeuvreOptions(), spec, overridable=False)
    assert isinstance(loaded, PatternSet) and loaded.training.n_samples is not None  # else options_from_model refused
    frequency = loaded.frequency_hz
    earlier = EarlierFit(model, float(opts.noise_std_db), float(opts.penalty_weight or 0.0), float(opts.power),
                         float(opts.correlated_std_db or 0.0), int(loaded.training.n_samples), tuple(loaded.nodes),
                         None if frequency is None else float(frequency))
    why = earlier.mismatch(tuple(nodes or ()), frequency_hz)
    if why is not None:
        raise InputError(f"from_model: {why}; give a model of the session's drones and band", param="from_model")
    return earlier


def ranking_options(options: ManoeuvreOptions, statistics: Any, fitted: Any, earlier: EarlierFit | None = None) -> ManoeuvreOptions:
    """The ranking's options for one refit: with ``earlier`` while the session is young, its
    noise, smoothing and drift; else the fitted model's noise, and, when the fit took the
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
    earlier : EarlierFit, optional
        An earlier flight's hyper-parameters (:func:`earlier_fit`).

    Returns
    -------
    ManoeuvreOptions
    """
    if earlier is not None and earlier.young(statistics):
        return earlier.options(options)
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
    earlier : EarlierFit, optional
        An earlier flight's hyper-parameters, ranked with while the session is young.
    """

    def __init__(self, options: ManoeuvreOptions | None = None, every_s: float = DEFAULT_ADVICE_EVERY_S,
                 earlier: EarlierFit | None = None) -> None:
        if not (math.isfinite(every_s) and every_s >= 0):
            raise InputError(f"every_s: expected a non-negative number of seconds, got {every_s!r}", param="every_s")
        self.options = options or ManoeuvreOptions()
        self.every_s = float(every_s)
        self.earlier = earlier
        #: Whether the latest ranking (before any: the next) reads ``earlier``'s hyper-parameters.
        self.young = earlier is not None
        self._last: tuple[float, list[tuple[str, float, float]]] | None = None

    def capped_note(self) -> str:
        """What the view adds while the fit is at the search's largest smoothing: the prior the
        manoeuvres are ranked under meanwhile ('' when it is the caller's penalty)."""
        if self.earlier is not None and self.young:
            return f"; manoeuvres are ranked with {self.earlier.path}'s noise, smoothing and drift meanwhile"
        if self.options.penalty_weight is None:
            return f"; manoeuvres are ranked under a {NOMINAL_PRIOR_STD_DB:g}-dB smoothness prior meanwhile"
        return ""

    def mismatch(self, fitted: Any) -> str | None:
        """Why ``earlier`` is not of the session whose refit is ``fitted`` (its nodes, its band;
        :meth:`EarlierFit.mismatch`): the ranking then reads the session's own hyper-parameters
        (and the session says so); None when it is, or when there is no ``earlier``."""
        if self.earlier is None:
            return None
        frequency = getattr(fitted.model, "frequency_hz", None)
        return self.earlier.mismatch(tuple(fitted.model.nodes), None if frequency is None else float(frequency))

    def __call__(self, statistics: Any, fitted: Any, latest: pd.DataFrame) -> list[tuple[str, float, float]]:
        now = time.monotonic()
        if self._last is not None and now - self._last[0] < self.every_s:
            return self._last[1]
        earlier = self.earlier if self.earlier is not None and self.mismatch(fitted) is None else None
        self.young = earlier is not None and earlier.young(statistics)
        options = ranking_options(self.options, statistics, fitted, earlier)
        ranked = rank_manoeuvres(statistics, fitted.spec, list(fitted.model.nodes), latest, options,
                                 getattr(statistics, "blocks", None))
        rows = [(r.name, float(r.duration_s), float(max(r.spread_after_db.values()))) for r in ranked]
        self._last = (now, rows)
        return rows


@check_types
def live_advisor(fixed_nodes: tuple[str, ...] = (), every_s: float = DEFAULT_ADVICE_EVERY_S,
                 floor_db: float | None = None, from_model: str | None = None,
                 spec: ModelSpec | None = None, nodes: Sequence[str] | None = None,
                 frequency_hz: float | None = None) -> ManoeuvreAdvisor:
    """The advisor ``rplearn live`` uses: the default candidates with ``fixed_nodes`` held still,
    no reward below ``floor_db`` (the session's ``--until-spread``); with ``from_model`` (an
    earlier flight's model file, ``--from-model``) its hyper-parameters while the session is
    young (:func:`earlier_fit`; ``spec``: the session's model; ``nodes``, ``frequency_hz``: the
    session's when known before it starts, checked against the file's)."""
    candidates = CandidateOptions(fixed_nodes=tuple(fixed_nodes))
    earlier = None if from_model is None else earlier_fit(from_model, spec, nodes, frequency_hz)
    return ManoeuvreAdvisor(ManoeuvreOptions(candidates=candidates, floor_db=floor_db), every_s, earlier)


__all__ = ["DEFAULT_ADVICE_EVERY_S", "EarlierFit", "ManoeuvreAdvisor", "earlier_fit", "live_advisor", "ranking_options"]
