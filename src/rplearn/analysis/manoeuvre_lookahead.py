"""Ranking by the estimated time to the target spread: a two-step look-ahead of the greedy ranking.

The ranking of :func:`rplearn.analysis.manoeuvres.rank_manoeuvres` orders the candidates by
their information per second (``ManoeuvreOptions.rate``), which is the right order while the
rate the flight goes on at afterwards does not depend on the manoeuvre chosen now. It does: a
short manoeuvre that takes the directions cheapest to learn leaves a slower rate to the next
one, and near the target the flight stops as soon as the spread is reached, so what counts is
the time to get there, not the rate. With :attr:`~rplearn.analysis.manoeuvres.ManoeuvreOptions.lookahead`
``= k`` the ``k`` best candidates by rate are therefore ranked again by an estimate of the flight
time to the target spread ``T`` (the stop criterion, ``ManoeuvreOptions.floor_db``):

``t_c + D_c / r_c``, with ``t_c`` the candidate's time (its lead included), ``D_c = 1/T^2 - 1/a_c^2``
the *information deficit* it leaves (``a_c`` the combined spread after it, each node's spread
floored at ``T``, so ``D_c = 0`` once every node is at the target), and ``r_c`` the best
information rate ``(1/a'^2 - 1/a_c^2) / t'`` among the candidates flyable from where it ends, on
the posterior it leaves (one more ranking per candidate looked at: ``k`` more rankings). A
candidate reaching the target scores the time at which it reaches it, for the flight stops
there (the stop criterion): its lead plus the fraction ``max_k d_k / g_k`` of its own time, with
``d_k`` the information node ``k`` still misses and ``g_k`` the information the whole manoeuvre
gives it (``1/s_k'^2 - 1/s_k^2``, unfloored), as if each node learned at a steady rate along it. Under a constant continuation rate this is
the rate ranking again (minimising ``t_c + (D - g_c)/r`` is maximising ``g_c - r t_c``, whose best
is the best ``g_c / t_c``); it differs where the manoeuvre chosen changes what the next one can
teach, and at the end of the flight.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from rplearn.analysis.manoeuvre_posterior import ManoeuvrePosterior

#: A scored candidate: (its RankedManoeuvre, (its feature rows, their link ends)).
Scored = tuple[Any, tuple[np.ndarray, Any]]


def information_deficit(combined_db: float, target_db: float) -> float:
    """``1/T^2 - 1/a^2`` [1/dB^2]: the information still missing to bring the combined spread
    ``a`` (each node's floored at the target) down to the target ``T``; 0 at or below it."""
    if combined_db <= target_db * (1.0 + 1e-9):  # the floored combination at the target, to rounding
        return 0.0
    return 1.0 / target_db**2 - 1.0 / combined_db**2


def information_rate(before_db: float, after_db: float, duration_s: float) -> float:
    """The growth of the combined spread's inverse square per second [1/(dB^2 s)]."""
    return (1.0 / max(after_db, 1e-12) ** 2 - 1.0 / max(before_db, 1e-12) ** 2) / max(duration_s, 1e-9)


def reach_fraction(before_db: np.ndarray, after_db: np.ndarray, target_db: float) -> float:
    """The fraction of a manoeuvre at which every node's spread reaches the target, at a steady
    information rate along it: ``max_k d_k / g_k`` over the nodes above the target (module
    docstring); 0 if none is, ``inf`` if the manoeuvre leaves one above it."""
    before, after = np.asarray(before_db, np.float64), np.asarray(after_db, np.float64)
    need = before > target_db
    if not np.any(need):
        return 0.0
    if np.any(after[need] > target_db * (1.0 + 1e-12)):
        return float("inf")
    d = 1.0 / target_db**2 - 1.0 / before[need] ** 2
    g = 1.0 / np.maximum(after[need], 1e-12) ** 2 - 1.0 / before[need] ** 2
    return float(np.clip(np.max(d / np.maximum(g, 1e-300)), 0.0, 1.0))


def time_to_target_s(duration_s: float, deficit_after: float, best_rate_after: float) -> float:
    """``t_c + D_c / r_c`` (module docstring) [s]; ``inf`` when a deficit is left and no
    candidate after it teaches anything."""
    if deficit_after <= 0.0:
        return float(duration_s)
    if not best_rate_after > 0.0:
        return float("inf")
    return float(duration_s) + deficit_after / best_rate_after


def lookahead_order(post: ManoeuvrePosterior, scored: Sequence[Scored], width: int, target_db: float, weight: float,
                    combined: Callable[[np.ndarray], float],
                    score_from: Callable[[ManoeuvrePosterior, dict[str, Any]], list[Scored]],
                    state: dict[str, Any]) -> list[tuple[Scored, float | None]]:
    """``scored`` (best rate first) with its first ``width`` reordered by their estimated time to
    the target (module docstring), each with that estimate (None for the rest, left in rate order).

    Parameters
    ----------
    post : ManoeuvrePosterior
        The posterior now (left unchanged: each candidate looked at updates a copy).
    scored : sequence of (RankedManoeuvre, (rows, ends))
        The candidates scored on ``post``, best rate first.
    width : int
        How many of the best to look ahead from.
    target_db : float
        The target spread ``T`` [dB].
    weight : float
        Packets per feature row (:meth:`ManoeuvrePosterior.update`).
    combined : callable
        The nodes' spreads [dB] -> the combined spread, each floored at the target.
    score_from : callable
        ``(posterior, poses) -> scored candidates`` flyable from ``poses`` on that posterior.
    state : dict
        The nodes' current poses, ``{node: ((x, y, z), yaw_deg)}``.
    """
    head = list(scored[:max(int(width), 0)])
    estimates = []
    for item in head:
        ranked, (rows, ends) = item
        after = copy.copy(post)  # update() rebinds its arrays: the copy's are its own afterwards
        after.update(rows, weight, ends)
        left = after.spreads()
        deficit = information_deficit(combined(left), target_db)
        best = 0.0
        if deficit > 0.0:
            moved = {**state, **ranked.candidate.ends}
            for nxt, _ in score_from(after, moved):
                b = combined(np.array(list(nxt.spread_before_db.values())))
                a = combined(np.array(list(nxt.spread_after_db.values())))
                best = max(best, information_rate(b, a, float(nxt.duration_s)))
        took = float(ranked.duration_s)
        if deficit <= 0.0:  # it reaches the target: the flight stops where it does
            lead = float(ranked.candidate.lead_s)
            frac = reach_fraction(post.spreads(), left, target_db)
            took = lead + (took - lead) * min(frac, 1.0)
        estimates.append(time_to_target_s(took, deficit, best))
    order = sorted(range(len(head)), key=lambda k: (estimates[k], k))
    return [(head[k], estimates[k]) for k in order] + [(item, None) for item in scored[len(head):]]


__all__ = ["information_deficit", "information_rate", "lookahead_order", "reach_fraction", "time_to_target_s"]
