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
candidate reaching the target scores its own time. Under a constant continuation rate this is
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
    return max(1.0 / target_db**2 - 1.0 / max(combined_db, 1e-12) ** 2, 0.0)


def information_rate(before_db: float, after_db: float, duration_s: float) -> float:
    """The growth of the combined spread's inverse square per second [1/(dB^2 s)]."""
    return (1.0 / max(after_db, 1e-12) ** 2 - 1.0 / max(before_db, 1e-12) ** 2) / max(duration_s, 1e-9)


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
        deficit = information_deficit(combined(after.spreads()), target_db)
        best = 0.0
        if deficit > 0.0:
            moved = {**state, **ranked.candidate.ends}
            for nxt, _ in score_from(after, moved):
                b = combined(np.array(list(nxt.spread_before_db.values())))
                a = combined(np.array(list(nxt.spread_after_db.values())))
                best = max(best, information_rate(b, a, float(nxt.duration_s)))
        estimates.append(time_to_target_s(float(ranked.duration_s), deficit, best))
    order = sorted(range(len(head)), key=lambda k: (estimates[k], k))
    return [(head[k], estimates[k]) for k in order] + [(item, None) for item in scored[len(head):]]


__all__ = ["information_deficit", "information_rate", "lookahead_order", "time_to_target_s"]
