"""Which validated points of the order-and-smoothing search the held-out units cannot tell apart.

Two uses (:mod:`rplearn.core.lsq.selection`):

- **the choice** (:func:`tightest_split`): of the points within noise of the best validation
  error, the least smoothed (then the largest order), so that the split between the nodes'
  patterns is not pulled toward the prior for a gain the units cannot tell;
- **the spread** (:func:`tied_points`): every point the units cannot tell from the best, whose
  posteriors the own-pattern spread averages (:func:`rplearn.models.own_posterior.tied_own_posterior`).

Why the spread is averaged and the choice is not. The per-node spread where the flight looked is
mostly the posterior's components the joint gain cannot see (the split between the nodes), and
their variance is the prior's: it scales as the variance inflation over the smoothing, which the
held-out joint errors pin only loosely. A point estimate of the smoothing carries that looseness
into the spread (``ground`` preset, seed 1: SH-5 at smoothing 3.2e-5 validates 4.524 dB against
4.532 dB for SH-4 at 1e-5, and the own-pattern spread is 1.20 dB against 1.89 dB, while the
pattern errors are alike). The fit must be one pattern; its stated uncertainty should not hang
on which of several equally good priors won by 0.2%.

With fewer than :data:`MIN_NOISE_UNITS` held-out units no standard error of the paired
difference can be estimated: the choice keeps the best point (no evidence to move), while the
spread takes every point within the cap :data:`WITHIN_NOISE_FRACTION` of the best mean square
(no evidence to exclude them). A weakness, stated: the set is of the points the search
evaluated, each weighed alike.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rplearn.core.lsq.selection_result import CurvePoint

#: Points within this many standard errors (of the held-out units' paired difference in squared
#: error) of the best validation error count as equally good: the least smoothed of them is chosen.
WITHIN_NOISE_SE = 2.0
#: ... and by at most this fraction of the best validation mean square (a cap on what a noisy
#: standard error from a few units may excuse: 1% is 0.5% of the RMSE, 0.02 dB at 4.4 dB).
WITHIN_NOISE_FRACTION = 0.01
#: Held-out units needed to estimate that standard error (with fewer the best point is chosen).
MIN_NOISE_UNITS = 3


def within_noise(ev: Any, best: CurvePoint, point: CurvePoint) -> bool:
    """Whether ``point``'s validation mean square exceeds ``best``'s by at most
    :data:`WITHIN_NOISE_SE` standard errors of their paired difference (the held-out units'
    differences taken as independent draws) and by at most :data:`WITHIN_NOISE_FRACTION` of it.
    Needs :data:`MIN_NOISE_UNITS` held-out units: from two, the standard error is no estimate.
    ``ev``: the selection's evaluator (``cv``, ``folds``, ``n``, ``fold_sse`` per point)."""
    if not ev.cv or len(ev.folds) < MIN_NOISE_UNITS:
        return bool(point == best)
    b = ev.fold_sse[(best.order, best.smoothing)]
    d = (ev.fold_sse[(point.order, point.smoothing)] - b) / ev.n
    se = float(np.sqrt(d.size * np.var(d, ddof=1)))
    return float(d.sum()) <= min(WITHIN_NOISE_SE * se, WITHIN_NOISE_FRACTION * float(b.sum()) / ev.n)


def tightest_split(ev: Any, best: CurvePoint, points: Sequence[CurvePoint]) -> CurvePoint:
    """Among the points within noise of the best validation error, the one that shrinks the
    patterns least (the least smoothing, then the largest order): smoothing chosen for the joint
    prediction alone leaves the split between the nodes' patterns (what the joint gain does not
    see) to the penalty, so a smoothing the held-out units cannot tell from the best is no
    reason to pull the patterns further toward the prior."""
    close = [p for p in points if within_noise(ev, best, p)]
    return min(close, key=lambda p: (p.smoothing, -p.order)) if close else best


def tied_points(ev: Any, best: CurvePoint, points: Sequence[CurvePoint]) -> list[tuple[int, float, float]]:
    """The points the held-out units cannot tell from the best (module docstring), each with its
    variance inflation: ``(order, smoothing, inflation)``, the best first. With at least
    :data:`MIN_NOISE_UNITS` units, those :func:`within_noise`; with two, those within
    :data:`WITHIN_NOISE_FRACTION` of the best mean square; none without held-out units."""
    keys = tied_keys(ev, best, points)
    if keys and hasattr(ev, "prefetch_spreads"):
        ev.prefetch_spreads(keys)  # every point's folds at once
    return [(o, s, float(ev.inflation(o, s))) for o, s in keys]


def tied_keys(ev: Any, best: CurvePoint, points: Sequence[CurvePoint]) -> list[tuple[int, float]]:
    """The ``(order, smoothing)`` of :func:`tied_points`, the best first.

    Parameters
    ----------
    ev : selection evaluator
        The search's (its folds, whether it cross-validates, its per-fold errors).
    best : CurvePoint
        The chosen point.
    points : sequence of CurvePoint
        The candidates (the validation curve).

    Returns
    -------
    list of (int, float)
        The best first, then the others within noise of it in increasing (order, smoothing);
        empty without held-out units.
    """
    if not ev.cv:
        return []
    if len(ev.folds) >= MIN_NOISE_UNITS:
        close = [p for p in points if within_noise(ev, best, p)]
    else:
        close = [p for p in points if p.rmse_db**2 <= (1.0 + WITHIN_NOISE_FRACTION) * best.rmse_db**2]
    first = (int(best.order), float(best.smoothing))
    return sorted({(int(p.order), float(p.smoothing)) for p in close} | {first}, key=lambda k: (k != first, k))


__all__ = ["MIN_NOISE_UNITS", "WITHIN_NOISE_FRACTION", "WITHIN_NOISE_SE", "tied_keys", "tied_points", "tightest_split",
           "within_noise"]
