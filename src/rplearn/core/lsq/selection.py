"""Automatic choice of a pattern's order and smoothing from per-unit sufficient statistics.

The learned coefficients are shrunk by a smoothness penalty ``lambda * sum_j w_j c_j^2`` with
``w_j`` the basis's :meth:`~rplearn.core.basis_base.Basis.roughness` (``(l (l+1))^p`` for a
spherical harmonic of degree ``l``, ``p`` = :data:`DEFAULT_PENALTY_POWER`; plain ridge for BG and
P). ``lambda`` is given *relative* to the mean diagonal of the learning data's ``X^T X``, so one
value means the same shrinkage for a short and a long flight: the absolute weight added to
``X^T X`` is ``smoothing * mean(diag(X^T X)) * w_j``. The penalty and the ridge shrink toward
a target whose constant per node is the learning data's own level, not zero
(:mod:`rplearn.core.lsq.level`), so that no validation error depends on the level of the RSSI values.

Order and smoothing are chosen by **grouped cross-validation over flight units**: each unit in
turn is held out, the pattern learned from the others, and its squared error on the held-out
unit computed from that unit's statistics alone (``y^T y - 2 c^T X^T y + c^T X^T X c``); random
samples are never held out, because neighbouring packets of one flight leak into each other.
With a single unit the choice is by **generalised cross-validation** (Golub, Heath and Wahba
1979) on the whole data; ``rplearn fit`` avoids that case by cutting a single flight into
contiguous stretches of time that play the units' part. Either way the validation error is that
of the flown region: a test that looks where no unit looked (another altitude) is an
extrapolation, which the coverage warnings of predict and evaluate flag. Everything comes from the :class:`NormalEquations` accumulated once per
unit at the largest order: for spherical harmonics a lower order's statistics are a sub-block
(degrees nest), so nothing is refitted from raw samples.

The search, a coordinate descent over the validation error (every point is kept as the curve):

1. the smoothing grid :data:`SMOOTHING_GRID` at a middle candidate order (every other value,
   then the neighbours of the best): the relative smoothing means nearly the same at every
   order, and a middle order costs a fraction of the largest;
2. the candidate orders at that smoothing (every other order from the largest down, then the
   neighbours of the best);
3. at the best order, the smoothing walks along the grid while it improves; then step 2 runs
   again at the new smoothing, and step 3 repeats while the order moves;
4. from where that stops, steps to the best of the eight neighbours in (order, smoothing)
   while one validates better (:func:`_diagonal_steps`: order and smoothing trade off, and
   steps along one coordinate miss the valley along the diagonal);
5. of the points evaluated, those within noise of the best (:func:`rplearn.core.lsq.ties.within_noise`: from three
   held-out units, at most :data:`rplearn.core.lsq.ties.WITHIN_NOISE_SE` standard errors of the paired per-unit
   difference and :data:`rplearn.core.lsq.ties.WITHIN_NOISE_FRACTION` of the mean square above it), the least
   smoothed (then the largest order) is chosen: the joint gain validates the sum of two
   patterns, not their split, which the penalty decides; more smoothing than the held-out
   units can justify pulls the split toward the prior (on the ``paper`` preset, seed 1: a
   pattern error per node of 1.48 dB at smoothing 3.2e-5 against 1.33 dB at 1e-5, for a
   validation error no unit can tell apart; ``benchmarks/split.py``). The points the units
   cannot tell from the best are kept with their variance inflations (:attr:`Selection.ties`,
   :mod:`rplearn.core.lsq.ties`): the own-pattern spread averages their posteriors.

The validation error of an order and smoothing is computed once (a Cholesky solve per held-out
unit) and kept in the curve. The cost is dominated by the few solves at the largest orders:
about 6 of them per held-out unit, against 12-14 for a full grid at the largest order. The
points of one smoothing share one factorisation per held-out unit, at the largest of their
orders (:mod:`rplearn.core.lsq.selection_lead`: with the columns reordered, a smaller order's
system is a leading block of the larger's; the folds' penalty unit, ``mean(diag(X^T X))``, is
read at the largest order, which for SH is every order's to rounding): on the ``paper`` preset
the scan of 9 orders at one smoothing costs about one factorisation at SH-15.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn.core.basis_base import Basis
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import DEFAULT_PENALTY_POWER, nested_columns, penalty_scale, penalty_vector, sub_statistics
from rplearn.core.lsq.selection_evaluator import MAX_SMOOTHING, SMOOTHING_GRID, FoldEvaluator
from rplearn.core.lsq.selection_result import CurvePoint, Selection
from rplearn.core.lsq.ties import tied_keys, tied_points
from rplearn.core.lsq.ties import tightest_split as _tightest_split
from rplearn.errors import IdentifiabilityError, InputError


def at_smoothing_cap(smoothing: float) -> bool:
    """Whether a chosen relative smoothing is the largest the search tries (:data:`MAX_SMOOTHING`):
    the validation error still fell toward more smoothing there, so the data do not identify the
    patterns' shape, and a posterior read at it has the spread the cap gives it (about none), not
    one the data give (``rplearn live``'s first refits of a few seconds of flight).

    Parameters
    ----------
    smoothing : float
        A selection's relative smoothing (:attr:`Selection.smoothing`).

    Returns
    -------
    bool
    """
    return 10.0 * float(smoothing) > MAX_SMOOTHING


def _prefetch(ev: Any, points: Sequence[tuple[int, float]]) -> None:
    """:meth:`FoldEvaluator.prefetch` of the points the search is about to compare (any evaluator
    with ``rmse`` alone is asked one point at a time)."""
    if hasattr(ev, "prefetch"):
        ev.prefetch(points)


def _best_smoothing(ev: FoldEvaluator, order: int, grid: Sequence[float]) -> float:
    """Best smoothing of ``grid`` at one order: every other value, then the neighbours of the best."""
    values = sorted(float(g) for g in grid)
    coarse = values[::2] if values[-1] in values[::2] else [*values[::2], values[-1]]
    _prefetch(ev, [(order, s) for s in coarse])
    best = min(coarse, key=lambda s: ev.rmse(order, s))
    while best == values[-1] and best * 10.0 <= MAX_SMOOTHING:  # the best is at the edge: go on
        values.append(best * 10.0)
        best = min((best, values[-1]), key=lambda s: ev.rmse(order, s))
    i = values.index(best)
    _prefetch(ev, [(order, s) for s in values[max(0, i - 1): i + 2]])
    return min(values[max(0, i - 1): i + 2], key=lambda s: ev.rmse(order, s))


def _best_order(ev: FoldEvaluator, orders: Sequence[int], smoothing: float) -> int:
    """Best order at one smoothing: every other order from the largest down (the curve is flat
    with small wiggles at high orders: no early stop), then the neighbours of the best."""
    _prefetch(ev, [(o, smoothing) for o in list(orders)[::-1][::2]])
    best = min(list(orders)[::-1][::2], key=lambda o: ev.rmse(o, smoothing))
    _prefetch(ev, [(o, smoothing) for o in orders if abs(o - best) <= 1])
    return min([o for o in orders if abs(o - best) <= 1], key=lambda o: ev.rmse(o, smoothing))


def _walk_smoothing(ev: FoldEvaluator, order: int, start: float, values: list[float]) -> tuple[float, list[float]]:
    """From ``start``, step along the sorted smoothing ``values`` at one order while the
    validation error falls (past the largest, by decades up to :data:`MAX_SMOOTHING`)."""
    values = list(values)
    best = start
    for direction in (1, -1):
        while True:
            i = values.index(best) + direction
            if i == len(values) and values[-1] * 10.0 <= MAX_SMOOTHING:
                values.append(values[-1] * 10.0)
            if not 0 <= i < len(values) or ev.rmse(order, values[i]) >= ev.rmse(order, best):
                break
            best = values[i]
    return best, values


def _diagonal_steps(ev: FoldEvaluator, orders: Sequence[int], order: int, smoothing: float,
                    values: Sequence[float]) -> list[tuple[int, float]]:
    """From where the coordinate descent stopped, move to the best of the eight neighbours
    (the next order and the next smoothing of the grid, either way, alone or together) while
    one validates better; the points moved to, in order. Order and smoothing trade off (a
    smaller order needs less smoothing for the same fit), so the validation error has valleys
    along the diagonal that steps along one coordinate at a time do not enter (``ground``
    preset, seed 0: SH-4 at 1e-5 validates better than the SH-5 at 3.2e-5 where the descent
    stopped, and its worst per-node pattern error is 1.53 against 1.59 dB)."""
    grid = sorted({float(v) for v in values} | {float(smoothing)})
    path: list[tuple[int, float]] = []
    while True:
        i, j = orders.index(order), grid.index(smoothing)
        steps = [(orders[i + di], grid[j + dj]) for di in (-1, 0, 1) for dj in (-1, 0, 1)
                 if (di or dj) and 0 <= i + di < len(orders) and 0 <= j + dj < len(grid)]
        _prefetch(ev, steps)
        best = min(steps, key=lambda p: ev.rmse(*p), default=(order, smoothing))
        if not ev.rmse(*best) < ev.rmse(order, smoothing):
            return path
        order, smoothing = best
        path.append(best)


def select_order_and_smoothing(
    units: Mapping[str, NormalEquations],
    make_basis: Callable[[int], Basis],
    orders: Sequence[int],
    ridge: float = 1.0,
    power: float = DEFAULT_PENALTY_POWER,
    grid: Sequence[float] = SMOOTHING_GRID,
    target: np.ndarray | None = None,
    prior_level: str = "data",
) -> Selection:
    """Choose order and smoothing by grouped cross-validation (or GCV for one unit).

    Parameters
    ----------
    units : mapping of unit label to NormalEquations
        Statistics of every learning unit, all accumulated with the basis of ``max(orders)``.
    make_basis : callable
        ``make_basis(order)`` -> the basis of that order (nested in the largest for SH).
    orders : sequence of int
        Candidate orders; for BG and P a single one.
    ridge : float
        The solver's ridge, kept in every solve.
    power : float
        Exponent of the SH roughness weights.
    grid : sequence of float
        Relative smoothing values tried.
    target : ndarray, optional
        Prior coefficients at the largest order (one per pattern column, ``fit --prior``): the
        ridge and the penalty shrink toward their shape (each node's sphere mean dropped)
        instead of toward zero. With or without it, each fold's constant per node is its
        learning units' own level (:func:`rplearn.core.lsq.level.shrink_target`), so a constant
        added to every sample changes no validation error.
    prior_level : {"data", "prior"}
        ``"prior"``: shrink toward ``target`` itself, its absolute level included (calibrated
        power and a trusted reference; see :func:`rplearn.core.lsq.solver.solve`).

    Raises
    ------
    IdentifiabilityError
        When no unit holds samples, or every candidate fails.
    """
    return select_beside(units, make_basis, orders, ridge, power, grid, SearchPrior(target, prior_level))[1]


@dataclass(frozen=True, eq=False)
class SearchPrior:
    """What the penalty of :func:`select_beside` shrinks toward.

    Attributes
    ----------
    target : ndarray or None
        Prior coefficients at the largest order (one per pattern column), as ``target`` of
        :func:`select_order_and_smoothing`; None: toward zero (each fold's own level).
    prior_level : {"data", "prior"}
        As ``prior_level`` of :func:`select_order_and_smoothing`.
    """

    target: np.ndarray | None = None
    prior_level: str = "data"


def select_beside(
    units: Mapping[str, NormalEquations],
    make_basis: Callable[[int], Basis],
    orders: Sequence[int],
    ridge: float = 1.0,
    power: float = DEFAULT_PENALTY_POWER,
    grid: Sequence[float] = SMOOTHING_GRID,
    prior: SearchPrior = SearchPrior(),
    beside: Callable[[int, float, list[tuple[int, float]]], Sequence[Callable[[], Any]]] | None = None,
) -> tuple[list[Any], Selection]:
    """:func:`select_order_and_smoothing`, with work of the caller's that needs only the choice
    run on the statistics' workers together with the variance inflations of the chosen and tied
    points (the last step of the selection).

    Parameters
    ----------
    units, make_basis, orders, ridge, power, grid
        As :func:`select_order_and_smoothing`.
    prior : SearchPrior
        Its ``target`` and ``prior_level`` (:func:`select_order_and_smoothing`).
    beside : callable, optional
        ``beside(order, smoothing, tied)`` with the chosen point and the ``(order, smoothing)``
        of the tied points (:func:`rplearn.core.lsq.ties.tied_keys`, the chosen first) -> jobs
        (callables without arguments; one BLAS thread each, any thread).

    Returns
    -------
    results : list
        The jobs' results, in their order (empty without ``beside``).
    selection : Selection
        As :func:`select_order_and_smoothing`.
    """
    units = {str(k): v for k, v in units.items() if v.n_samples > 0}
    if not units:
        raise IdentifiabilityError("no learning samples to choose an order from")
    orders = sorted({int(o) for o in orders})
    if not orders:
        raise InputError("orders: no candidate order", param="orders")
    ev = FoldEvaluator(units, make_basis, ridge, power, prior.target, prior.prior_level)
    best_s = _best_smoothing(ev, orders[(len(orders) - 1) // 2], grid)
    best_o = _best_order(ev, orders, best_s)
    values = sorted({float(g) for g in grid} | {best_s})
    for _ in range(len(orders) + len(values)):  # coordinate descent; each pass moves or stops
        best_s, values = _walk_smoothing(ev, best_o, best_s, values)
        moved = _best_order(ev, orders, best_s)
        if moved == best_o:
            break
        best_o = moved
    searched = len(ev.curve)
    path = _diagonal_steps(ev, orders, best_o, best_s, values)
    # the neighbours it probed without moving are checks of the best's neighbourhood, not more
    # candidates for the tie rule below: only the points it moved to join the descent's (the
    # spread's ties take every point evaluated: none of them is a prior the units can exclude)
    candidates = ev.curve[:searched] + [p for p in ev.curve[searched:] if (p.order, p.smoothing) in path]
    finite = [p for p in candidates if np.isfinite(p.rmse_db)]
    if not finite:
        raise IdentifiabilityError("no candidate order and smoothing could be fitted")
    best = min(finite, key=lambda p: (p.rmse_db, p.order, -p.smoothing))
    choice = _tightest_split(ev, best, finite)
    evaluated = [p for p in ev.curve if np.isfinite(p.rmse_db)]
    keys = tied_keys(ev, best, evaluated)
    extra = beside(int(choice.order), float(choice.smoothing), keys) if beside is not None else []
    beside_results = ev.prefetch_spreads([(choice.order, choice.smoothing), *keys], extra)  # all at once
    kappa, level_var = ev.spread(choice.order, choice.smoothing)
    return beside_results, Selection("grouped-cv" if ev.cv else "gcv", choice.order, choice.smoothing, choice.rmse_db,
                                     ev.curve, sorted(units) if ev.cv else [], float(power), kappa,
                                     float(np.sqrt(level_var)),
                                     ev.excess_db2.get((int(choice.order), float(choice.smoothing)), 0.0),
                                     tied_points(ev, best, evaluated))


def variance_inflation(
    units: Mapping[str, NormalEquations],
    make_basis: Callable[[int], Basis],
    order: int,
    smoothing: float,
    ridge: float = 1.0,
    power: float = DEFAULT_PENALTY_POWER,
    target: np.ndarray | None = None,
    prior_level: str = "data",
) -> float:
    """How much the posterior covariance understates the error *within* held-out flight units.

    For each unit ``u`` held out, the fit ``c`` of the others predicts its samples with errors
    ``e``; their mean ``m_u`` over the unit (from :meth:`NormalEquations.column_sums`) is the unit's own level
    against the others', which no pattern can know and which is estimated apart (below). About
    that mean, the squared error's expectation under the Bayesian reading of the penalised
    solve is ``(n_u - 1) sigma^2 + sigma^2 (tr(A^-1 X_u^T X_u) - a_u^T A^-1 a_u / n_u)``: new
    noise plus the posterior variance of the fit at the held-out directions less its part
    along the unit's mean (``A`` the penalised normal matrix, ``a_u = X_u^T 1``, ``sigma^2``
    the fold's learning residual variance about each learning unit's own mean, over the
    samples less the fit's effective number of parameters ``tr(A^-1 X^T X)`` and the units'
    means, so that a correct model gives 1). The factor returned is the observed excess over
    the noise divided by that predicted variance, summed over the folds, and at least 1. It is
    above 1 when neighbouring packets share their errors (fading and shadowing correlated in
    time: fewer independent samples than packets) and when the pattern misfits within units
    (another altitude, another stretch of the sphere); multiplying the posterior covariance by
    it makes the predictive spread honest. Everything comes from the per-unit statistics; 1 for
    a single unit.

    The between-unit level variance (:attr:`Selection.flight_level_std_db`, squared) is the
    mean over the folds of ``m_u^2`` less its expected noise and posterior variance
    (``kappa sigma^2 (1 + a_u^T A^-1 a_u / n_u) / n_u``), divided by ``1 + sum_v w_v^2``: the
    fit's level is the learning units' levels weighed by their shares ``w_v`` of the samples,
    so ``m_u`` varies by the held-out unit's level and by that average. It is 0 when the
    units' means vary no more than noise and fit explain.
    """
    units = {str(k): v for k, v in units.items() if v.n_samples > 0}
    if not units:
        raise IdentifiabilityError("no learning samples to validate on")
    return FoldEvaluator(units, make_basis, ridge, power, target, prior_level).inflation(int(order), float(smoothing))


def validation_rmse(
    units: Mapping[str, NormalEquations],
    make_basis: Callable[[int], Basis],
    orders: Sequence[int],
    smoothing: float,
    ridge: float = 1.0,
    power: float = DEFAULT_PENALTY_POWER,
) -> list[float]:
    """Validation RMSE [dB] of every order at one smoothing (the curve a sweep plots), by
    grouped cross-validation (GCV with one unit), from statistics at ``max(orders)``."""
    units = {str(k): v for k, v in units.items() if v.n_samples > 0}
    if not units:
        raise IdentifiabilityError("no learning samples to validate on")
    ev = FoldEvaluator(units, make_basis, ridge, power)
    return [ev.rmse(int(o), float(smoothing)) for o in orders]


__all__ = [
    "validation_rmse",
    "variance_inflation",
    "DEFAULT_PENALTY_POWER",
    "MAX_SMOOTHING",
    "SMOOTHING_GRID",
    "CurvePoint",
    "SearchPrior",
    "Selection",
    "nested_columns",
    "penalty_scale",
    "penalty_vector",
    "select_beside",
    "select_order_and_smoothing",
    "sub_statistics",
]
