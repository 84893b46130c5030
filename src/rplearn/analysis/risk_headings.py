"""Risk-aware headings: yaws ranked by a link's (a swarm's) availability instead of its gain.

Given a sensitivity ``s`` [dBm], the heading searches of :mod:`rplearn.analysis.headings`
either maximise the availability ``P(RSSI >= s)`` (:mod:`rplearn.analysis.availability`), or,
with a required availability ``P``, the received power among the headings whose availability
is at least ``P`` (the most available heading when none is). A heading's spread is its two
ends' pattern spreads (the gain tables' standard errors), the environment term's, a new
flight's level and one packet's noise: an extrapolated heading with a high but uncertain gain
loses to a flown one predicted a little lower.

For a swarm the availability of a choice of yaws is that of the weakest link of the most
available spanning tree (its pairs weighed by their availability, both directions' weaker):
the connectivity probability's bottleneck, cheap enough to score every yaw of a drone at once.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn.analysis.heading_search import coordinate_ascent
from rplearn.analysis.swarm import maximum_spanning_edges
from rplearn.core.availability import link_availability
from rplearn.core.geometry import distance_m
from rplearn.core.link import free_space_path_loss_db
from rplearn.errors import InputError
from rplearn.models.base import model_frequency_hz
from rplearn.models.patterns import PatternSet

#: Heading combinations of one link scored at once (tx yaws x rx yaws).
MAX_YAW_PAIRS = 4_000_000

Score = tuple[float, float]


def objective(availability: np.ndarray, rssi_dbm: np.ndarray, min_availability: float | None) -> np.ndarray:
    """What the searches maximise: the availability, or with ``min_availability`` the RSSI of
    the headings that reach it, every other heading ranked below by its availability."""
    if min_availability is None:
        return availability
    return np.where(availability >= min_availability, rssi_dbm, availability - 1e6)


def best_link_yaws(
    rssi_dbm: tuple[np.ndarray, np.ndarray], std_db: tuple[np.ndarray, np.ndarray], candidates: tuple[np.ndarray, np.ndarray],
    base: tuple[float, float], sensitivity_dbm: float, min_availability: float | None,
) -> tuple[int, int, float]:
    """Best ``(tx index, rx index, availability)`` of one link over every candidate pair.

    ``rssi_dbm`` are the two ends' gain tables [dB], ``std_db`` their standard errors,
    ``candidates`` the indices each end may take, ``base`` the received power without the
    gains [dBm] and the spread every heading shares [dB].
    """
    i, j = candidates
    if i.size * j.size > MAX_YAW_PAIRS:
        raise InputError(f"step_deg: {i.size} x {j.size} yaw pairs are too many to score at once; use a coarser "
                         "yaw step", param="step_deg")
    mean = base[0] + rssi_dbm[0][i][:, None] + rssi_dbm[1][j][None, :]
    std = np.sqrt(std_db[0][i][:, None] ** 2 + std_db[1][j][None, :] ** 2 + base[1] ** 2)
    p = link_availability(mean, std, sensitivity_dbm)
    score = objective(p, mean, min_availability)
    order = np.lexsort((-mean.ravel(), -score.ravel()))[0]  # best score, then the stronger mean
    a, b = np.unravel_index(order, score.shape)
    return int(i[a]), int(j[b]), float(p[a, b])


@dataclass(frozen=True)
class RiskProblem:
    """A hovering swarm's heading problem scored by availability (``problem``: the
    :class:`~rplearn.analysis.headings` gain problem; ``std``: the gain tables' standard
    errors; ``shared_std_db``: the spread every link shares [dB])."""

    problem: object
    std: Mapping[tuple[str, str], np.ndarray]
    shared_std_db: float
    sensitivity_dbm: float
    min_availability: float | None

    @property
    def drones(self) -> list[str]:
        return self.problem.drones  # type: ignore[attr-defined]

    @property
    def n_grid(self) -> int:
        return self.problem.n_grid  # type: ignore[attr-defined]

    @property
    def start_index(self) -> dict[str, int]:
        return self.problem.start_index  # type: ignore[attr-defined]

    def pair_std(self, index: Mapping[str, np.ndarray | int]) -> np.ndarray:
        """Spread of every pair [dB] (columns) for the yaw indices ``index`` (rows)."""
        pairs = self.problem.pairs  # type: ignore[attr-defined]
        cols = [np.sqrt(self.std[(a, b)][index[a]] ** 2 + self.std[(b, a)][index[b]] ** 2 + self.shared_std_db**2)
                for a, b in pairs]
        return np.stack(np.broadcast_arrays(*cols), axis=-1)

    def availability(self, w: np.ndarray, std: np.ndarray) -> np.ndarray:
        """Every pair's availability from its RSSI [dBm] and spread [dB]."""
        return np.asarray(link_availability(w, std, self.sensitivity_dbm))

    def scores(self, w: np.ndarray, std: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Objective, bottleneck availability and bottleneck RSSI of many choices: ``w`` and
        ``std`` (choices, pairs)."""
        p = self.availability(w, std)
        n = len(self.drones)
        iu, ju = self.problem.iu, self.problem.ju  # type: ignore[attr-defined]
        full = np.full((w.shape[0], n, n), -np.inf)
        full[:, iu, ju] = p
        full[:, ju, iu] = p
        p_bottleneck = maximum_spanning_edges(full)[0].min(axis=1)
        full[:, iu, ju] = w
        full[:, ju, iu] = w
        rssi_bottleneck = maximum_spanning_edges(full)[0].min(axis=1)
        return objective(p_bottleneck, rssi_bottleneck, self.min_availability), p_bottleneck, rssi_bottleneck

    def score(self, choice: Mapping[str, int]) -> Score:
        w = self.problem.pair_rssi(choice)[None, :]  # type: ignore[attr-defined]
        s, _, _ = self.scores(w, self.pair_std(choice)[None, :])
        return float(s[0]), float(w.mean())

    def yaw_scores(self, choice: Mapping[str, int], drone: str) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`score` of ``choice`` with ``drone`` at every grid yaw."""
        k = np.arange(self.n_grid)
        index = {d: (k if d == drone else choice[d]) for d in self.drones}
        pairs, t, base = self.problem.pairs, self.problem.tables, self.problem.base_dbm  # type: ignore[attr-defined]
        w = np.stack(np.broadcast_arrays(*[base[(a, b)] + t[(a, b)][index[a]] + t[(b, a)][index[b]] for a, b in pairs]),
                     axis=-1)
        s, _, _ = self.scores(w, self.pair_std(index))
        return s, w.mean(axis=1)

    def bottleneck_availability(self, choice: Mapping[str, int]) -> float:
        w = self.problem.pair_rssi(choice)[None, :]  # type: ignore[attr-defined]
        return float(self.scores(w, self.pair_std(choice)[None, :])[1][0])


def search_risk(problem: RiskProblem, free: list[str], max_sweeps: int, restarts: int) -> tuple[dict[str, int], Score]:
    """Coordinate ascent of :class:`RiskProblem` from the current yaws and seeded random ones
    (the same search as the gain's, :func:`rplearn.analysis.heading_search.coordinate_ascent`)."""
    rng = np.random.default_rng(0)
    start = dict(problem.start_index)
    starts = [start] + [{d: (int(rng.integers(problem.n_grid)) if d in free else start[d]) for d in problem.drones}
                        for _ in range(restarts)]
    best, choice = problem.score(start), start
    for first in starts:
        found, s_found, _ = coordinate_ascent(first, free, problem.n_grid, problem, max_sweeps)
        if s_found > best:
            best, choice = s_found, found
    return choice, best




def shared_std_db(model: object, environment_std_db: float) -> float:
    """Spread every heading of a link shares [dB]: the environment term's, a new flight's level
    and one packet's noise about it (:func:`rplearn.analysis.availability.residual_std_db`)."""
    from rplearn.analysis.availability import residual_std_db

    level = float(getattr(model, "new_flight_level_std_db", 0.0))
    noise = residual_std_db(model)  # type: ignore[arg-type]
    return float(np.sqrt(environment_std_db**2 + level**2 + (noise**2 if np.isfinite(noise) else 0.0)))



def risk_link_choice(
    model: PatternSet, nodes: tuple[str, str], positions: Mapping[str, Sequence[float]], tables: tuple[Any, Any, float], n: int,
    turn: str, options: Any,
) -> tuple[int, int, dict[str, float | None]]:
    """:func:`best_yaw`'s choice by availability: the yaw indices and the result's fields."""
    (g_tx, g_rx), (s_tx, s_rx), env_std = tables
    frequency_hz = model_frequency_hz(model, options.frequency_hz)
    d = float(distance_m(np.asarray(positions["tx"], np.float64), np.asarray(positions["rx"], np.float64)))
    env = float(model.link_environment_db(nodes[0], nodes[1], positions["tx"], positions["rx"], frequency_hz)[0])
    base = (float(options.tx_power_dbm) - float(free_space_path_loss_db(d, frequency_hz)) + env,
            shared_std_db(model, env_std))
    sensitivity = float(options.sensitivity_dbm)
    given = (np.array([n]), np.array([n + 1]))
    free = (np.arange(n) if turn in ("tx", "both") else given[0], np.arange(n) if turn in ("rx", "both") else given[1])
    i_tx, i_rx, p = best_link_yaws((g_tx, g_rx), (s_tx, s_rx), free, base, sensitivity, options.min_availability)
    p0 = best_link_yaws((g_tx, g_rx), (s_tx, s_rx), given, base, sensitivity, None)[2]
    return i_tx, i_rx, {"availability": p, "baseline_availability": p0, "sensitivity_dbm": sensitivity,
                        "min_availability": options.min_availability}



def risk_swarm_choice(
    model: PatternSet, problem: Any, stds: Mapping[tuple[str, str], np.ndarray] | None, free: list[str], options: Any,
) -> tuple[dict[str, int], dict[str, float | None], int]:
    """:func:`~rplearn.analysis.headings.best_swarm_headings`'s choice by availability: the
    yaw indices, the result's fields and the search's restarts (never less available, by this
    measure, than the current yaws: the search starts there and moves only to better)."""
    zeros = {pair: np.zeros(problem.yaw_deg.size) for pair in problem.tables}
    risk = RiskProblem(problem, stds or zeros, shared_std_db(model, 0.0), float(options.sensitivity_dbm),
                       options.min_availability)
    choice, _ = search_risk(risk, free, options.max_sweeps, options.restarts)
    return choice, {"availability": risk.bottleneck_availability(choice),
                    "start_availability": risk.bottleneck_availability(problem.start_index),
                    "sensitivity_dbm": risk.sensitivity_dbm, "min_availability": options.min_availability}, 0


__all__ = ["MAX_YAW_PAIRS", "RiskProblem", "best_link_yaws", "objective", "risk_link_choice", "risk_swarm_choice", "search_risk", "shared_std_db"]
