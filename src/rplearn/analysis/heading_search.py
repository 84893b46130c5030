"""The search of :func:`rplearn.analysis.headings.best_swarm_headings` over a yaw grid: exhaustive
for up to three drones, else coordinate ascent whose every step scores all yaws of one drone
at once on the precomputed gain tables (``problem.yaw_scores``: array operations and a batch of
maximum spanning trees, no model call)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

#: Most yaw combinations :func:`best_swarm_headings` tries exhaustively (about 30 MB of work).
EXHAUSTIVE_MAX_COMBINATIONS = 400_000

Score = tuple[float, float]


def search(problem: Any, free: Sequence[str], max_sweeps: int, restarts: int) -> tuple[dict[str, int], Score, int]:
    """Best choice of grid yaws for the free drones: exhaustive when small, else coordinate ascent.

    Returns the choice, its score and the number of sweeps of the ascent (0 when exhaustive).
    """
    n_grid = problem.n_grid
    if len(problem.drones) <= 3 and n_grid ** len(free) <= EXHAUSTIVE_MAX_COMBINATIONS:
        choice, best = exhaustive_three(problem, free)
        return choice, best, 0
    # coordinate ascent from the current yaws, then from seeded random yaws
    start_index = problem.start_index
    rng = np.random.default_rng(0)
    starts = [dict(start_index)] + [
        {d: (int(rng.integers(n_grid)) if d in free else start_index[d]) for d in problem.drones} for _ in range(restarts)
    ]
    best, choice, sweeps = (-np.inf, -np.inf), dict(start_index), 0
    for first in starts:
        found, s_found, n_sweeps = coordinate_ascent(first, free, n_grid, problem, max_sweeps)
        sweeps += n_sweeps
        if s_found > best:
            best, choice = s_found, found
    return choice, best, sweeps


def coordinate_ascent(
    choice: dict[str, int], free: Sequence[str], n_grid: int, problem: Any, max_sweeps: int
) -> tuple[dict[str, int], Score, int]:
    """Each free drone in turn takes its best grid yaw (all of them scored at once; the first
    of equal best ones, and only when strictly better), until a sweep changes nothing."""
    best = problem.score(choice)
    sweeps = 0
    for sweeps in range(1, max_sweeps + 1):  # noqa: B007 (the count is reported after the loop)
        changed = False
        for d in free:
            bottleneck, mean = problem.yaw_scores(choice, d)
            key = np.lexsort((-mean, -np.nan_to_num(bottleneck, nan=-np.inf)))[0]  # best, first among equals
            s = (float(bottleneck[key]), float(mean[key]))
            if s > best:
                best, choice, changed = s, {**choice, d: int(key)}, True
        if not changed:
            break
    return choice, best, sweeps


def exhaustive_three(problem: Any, free: Sequence[str]) -> tuple[dict[str, int], Score]:
    """Best grid yaws of two or three drones by trying every combination (vectorised).

    The bottleneck of two drones is their one pair; of three, the second strongest pair (a
    triangle's spanning tree is its two strongest edges). Exact ties of the bottleneck go to
    the best mean.
    """
    drones, start_index = problem.drones, problem.start_index
    axes = [np.arange(problem.n_grid) if d in free else np.array([start_index[d]]) for d in drones]
    idx = dict(zip(drones, np.meshgrid(*axes, indexing="ij")))
    w = np.stack([problem.base_dbm[(a, b)] + problem.tables[(a, b)][idx[a]] + problem.tables[(b, a)][idx[b]] for a, b in problem.pairs])
    bottleneck = w[0] if len(problem.pairs) == 1 else np.sort(w, axis=0)[-2]
    mean = w.mean(axis=0)
    top = bottleneck.max()
    candidates = bottleneck >= top  # exact ties, then the best mean among them
    flat = int(np.argmax(np.where(candidates, mean, -np.inf)))
    pos = np.unravel_index(flat, bottleneck.shape)
    return {d: int(idx[d][pos]) for d in drones}, (float(top), float(mean[pos]))


__all__ = ["EXHAUSTIVE_MAX_COMBINATIONS", "coordinate_ascent", "exhaustive_three", "search"]
