"""The optimal-design bound on the flight time to a target spread, from statistics and poses.

:func:`design_bound` reads the posterior the ranking reads (:func:`rplearn.analysis.manoeuvres.rank_manoeuvres`)
and the candidates it offers from the latest poses, and solves the continuous optimal design
over them (:mod:`rplearn.analysis.manoeuvre_design`): the least total flight time, split over
those candidates in any proportions, ignoring the way between them and their order, after which
every node's spread is at most the target. With ``drift=False`` (the white-noise posterior) it
is a lower bound on the time of any plan made of those candidates from those poses.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from rplearn.analysis.manoeuvre_design import Design, scored_design
from rplearn.analysis.manoeuvres import ManoeuvreOptions, check_statistics_nodes, latest_poses, packet_weight, scored_candidates, start_posterior
from rplearn.core.lsq.block_sums import BlockSums
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.threads import one_blas_thread
from rplearn.models.spec import ModelSpec


@dataclass(frozen=True)
class DesignBound:
    """An optimal design over the candidates from one pose.

    Attributes
    ----------
    design : Design
        Seconds per candidate, their total [s], the spreads it leaves [dB], the Frank-Wolfe gap.
    names : tuple of str
        The candidates, in the order of ``design.times_s``.
    spreads_now_db : dict of str to float
        Each node's spread before any of them [dB].
    """

    design: Design
    names: tuple[str, ...]
    spreads_now_db: dict[str, float]

    def support(self, min_s: float = 0.5) -> list[tuple[str, float]]:
        """The candidates the design flies for at least ``min_s`` seconds, longest first."""
        t = self.design.times_s
        order = [int(i) for i in np.argsort(-t) if t[i] >= min_s]
        return [(self.names[i], float(t[i])) for i in order]


def design_bound(normal: NormalEquations, spec: ModelSpec, nodes: Sequence[str], poses: pd.DataFrame | Mapping[str, Any],
                 target_spread_db: float, options: ManoeuvreOptions | None = None, blocks: BlockSums | None = None,
                 drift: bool = False) -> DesignBound:
    """The optimal design over the candidates from ``poses`` (module docstring; arguments as
    :func:`~rplearn.analysis.manoeuvres.rank_manoeuvres`, without the misfit's direction cells;
    ``drift``: with the drifting error, an estimate rather than a bound)."""
    opts = replace(options or ManoeuvreOptions(), lookahead=0, design="rate")
    names = [str(n) for n in nodes]
    check_statistics_nodes(normal, names)
    state = latest_poses(poses, names)
    with one_blas_thread():
        post = start_posterior(normal, spec, names, opts, blocks)
        scored = scored_candidates(post, state, names, normal.basis, opts)
        _, design = scored_design(post, scored, packet_weight(opts), float(target_spread_db), drift)
    return DesignBound(design, tuple(r.name for r, _ in scored), dict(zip(names, post.spreads().tolist())))


__all__ = ["DesignBound", "design_bound"]
