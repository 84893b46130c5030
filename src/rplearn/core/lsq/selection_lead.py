"""The folds of the order selection with every order's problem a leading block of the largest's.

Split from :mod:`rplearn.core.lsq.selection_evaluator`. The joint problem's columns are node
blocks (each node's coefficients, degree by degree), so a smaller SH order's problem is a
scattered sub-block of the largest order's. Reordered by :func:`~rplearn.core.lsq.selection_folds.lead_columns`
(the shared columns, then each coefficient's column of every node in turn) it is a *leading*
block, and so is its penalised system: the ridge and the roughness weights of a smaller order
are the leading ones of the largest's, and the penalty's unit, the mean diagonal of ``X^T X``
over the pattern columns, is read at the largest order for every order (it is the same at every
SH order: the squares of the degree-``l`` harmonics sum to ``(2 l + 1) / (4 pi)`` in every
direction, Unsöld's theorem, so each order's mean is ``samples / (4 pi)`` per node end, to
rounding). The Cholesky factor of a leading block is the leading block of the factor, so the
folds of every order at one smoothing are solved from one factorisation per fold, at the
largest order asked at that smoothing (:class:`LeadFolds`), and the factors are kept per
smoothing for the orders asked later.

Which order a point's factor was read from is recorded (``source``): solving the point again
(its variance inflation, :func:`~rplearn.core.lsq.selection_folds.fold_spread_terms`) factorises
that order again, to the same bits.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from rplearn.core.lsq.runtime import DEFAULT_RUNTIME
from rplearn.core.lsq.selection_folds import Fold, lead_columns, lead_size, permuted
from rplearn.core.lsq.solver_cholesky import factor_solve, spd_factor

#: Bytes of the folds' factors :class:`LeadFolds` keeps per smoothing (the paper's SH-15 folds:
#: 4.9 MB a smoothing); the oldest smoothing's are dropped past it.
LEAD_FACTOR_BYTES = 64 * 2**20

#: One point of one fold: its solution, the factor of its system (a view of the leading block of
#: the factor it was read from; None when the system is not positive definite), the held-out
#: unit's squared error and the order whose factor it was read from.
LeadPoint = tuple[np.ndarray, Any, float, int]


class LeadFolds:
    """Per fold, the learning and held-out statistics at the largest order in the lead layout
    (module docstring), and the solves of any order from them.

    Parameters
    ----------
    folds : sequence of Fold
        The folds at the largest order, natural layout (node blocks, then shared columns): each
        learning block is ``gram`` less the held-out block (:func:`~rplearn.core.lsq.selection_folds.unit_folds`).
    gram : numpy.ndarray
        ``X^T X`` of all units, natural layout.
    sums : sequence of (numpy.ndarray, float)
        Per unit: its column sums ``X_u^T 1`` at the largest order and ``sum y``.
    pins : sequence
        Per fold: None, or the weights and values pinning the shared columns.
    layout : (int, int, int)
        Coefficients per node at the largest order, nodes, shared columns.
    penalty : (float, numpy.ndarray, sequence of float)
        The ridge (on the pattern columns), the roughness weights of every column at the largest
        order (natural layout; 0 at the shared columns) and per fold the penalty's unit.
    orders : (callable, callable)
        ``n_coef(order)``: an order's coefficients per node; ``targets(order)``: per fold, the
        target of that order's fit in the lead layout (its leading columns).
    """

    def __init__(self, folds: Sequence[Fold], gram: np.ndarray, sums: Sequence[tuple[np.ndarray, float]], pins: Sequence[Any],
                 layout: tuple[int, int, int], penalty: tuple[float, np.ndarray, Sequence[float]],
                 orders: tuple[Callable[[int], int], Callable[[int], list[np.ndarray]]]) -> None:
        n_coef, self.n_nodes, self.n_shared = layout
        self.perm = lead_columns(n_coef, self.n_nodes, self.n_shared)
        perm = self.perm
        # a fold's learning block is all units' less its held-out unit's: the units' blocks and
        # their sum reordered (copies, on the workers), then subtracted (the same bits)
        # (new memory, slow on first touch: the subtractions on the workers too)
        total, *held = DEFAULT_RUNTIME.in_order(lambda g: permuted(g, layout), [gram, *(f.held_gram for f in folds)],
                                                ahead=len(folds) + 1)
        learning = list(DEFAULT_RUNTIME.in_order(lambda h: total - h, held, ahead=len(held)))
        self.folds = [Fold(g, f.rhs[perm], h, f.held_rhs[perm], f.held_yty, f.held_n)
                      for f, g, h in zip(folds, learning, held)]
        self.sums = [(a[perm], sum_y) for a, sum_y in sums]
        self.pins = list(pins)
        ridge, weights, scales = penalty
        self.ridge, self.weights, self.scales = float(ridge), np.asarray(weights, np.float64)[perm], list(scales)
        self._n_coef, self._targets = orders
        self._orders: dict[int, tuple[int, list[np.ndarray]]] = {}
        #: per smoothing, the order factorised and each fold's factor (None: not positive definite)
        self.factors: dict[float, tuple[int, list[Any]]] = {}

    def order(self, order: int) -> tuple[int, list[np.ndarray]]:
        """An order's leading columns and per fold its fit's target (computed once: call it in
        one thread before the jobs that read it)."""
        got = self._orders.get(int(order))
        if got is None:
            got = (lead_size(self._n_coef(int(order)), self.n_nodes, self.n_shared), self._targets(int(order)))
            self._orders[int(order)] = got
        return got

    def fold(self, fold: int, order: int) -> Fold:
        """A fold's statistics at an order: views of the leading blocks."""
        m = self.order(order)[0]
        f = self.folds[fold]
        return Fold(f.gram[:m, :m], f.rhs[:m], f.held_gram[:m, :m], f.held_rhs[:m], f.held_yty, f.held_n)

    def column_sums(self, order: int) -> list[tuple[np.ndarray, float]]:
        """Per unit, its column sums at an order (views) and ``sum y``."""
        m = self.order(order)[0]
        return [(a[:m], sum_y) for a, sum_y in self.sums]

    def system(self, fold: int, m: int, weight: float) -> np.ndarray:
        """The penalised normal matrix of a fold's leading ``m`` columns (a new C-ordered array):
        the ridge on the pattern columns, the smoothness penalty (``weight``: the smoothing times
        the penalty's unit) and the weights of pinned shared columns."""
        a = np.array(self.folds[fold].gram[:m, :m])
        diagonal = a.reshape(-1)[:: m + 1]  # a view of the diagonal
        ns = self.n_shared
        diagonal[ns:] += self.ridge
        diagonal += weight * self.weights[:m]
        pin = self.pins[fold]
        if pin is not None:
            diagonal[:ns] += pin[0]
        return a

    def pulled(self, fold: int, m: int, weight: float, target: np.ndarray) -> np.ndarray:
        """``X^T y`` plus the pull of the ridge and the penalty toward the target and of pinned
        shared columns toward their values (leading ``m`` columns)."""
        out = self.folds[fold].rhs[:m].copy()
        ns = self.n_shared
        out[ns:] += (self.ridge + weight * self.weights[ns:m]) * target[ns:]
        pin = self.pins[fold]
        if pin is not None:
            out[:ns] += pin[0] * pin[1]
        return out

    def factor(self, fold: int, order: int, smoothing: float) -> Any:
        """The upper Cholesky factor of a fold's system at an order (None: not positive definite)."""
        m = self.order(order)[0]
        return spd_factor(self.system(fold, m, smoothing * self.scales[fold]), overwrite=True)

    def solve(self, fold: int, order: int, smoothing: float, top: tuple[int, Any]) -> tuple[np.ndarray, Any, int]:
        """A fold's penalised solution at ``order``, from ``top``: the order factorised (at least
        ``order``) and its factor. When that factor is None (not positive definite) the order's
        own system is factorised; when that fails too, least squares.

        Returns
        -------
        c : numpy.ndarray
        upper : numpy.ndarray or None
            The factor of the order's system: a view of the leading block of ``top``'s.
        source : int
            The order whose factor was read.
        """
        m, targets = self.order(order)
        weight = smoothing * self.scales[fold]
        rhs = self.pulled(fold, m, weight, targets[fold])
        source, upper = top
        if upper is None and source != int(order):
            source, upper = int(order), self.factor(fold, order, smoothing)
        if upper is None:
            import scipy.linalg

            return scipy.linalg.lstsq(self.system(fold, m, weight), rhs)[0], None, source
        view = upper[:m, :m]
        return factor_solve(view, rhs), view, source

    def group(self, fold: int, smoothing: float, orders: Sequence[int], source: int, upper: Any) -> tuple[Any, list[LeadPoint]]:
        """One fold's points at one smoothing (any thread): the factor at ``source`` (``upper``, or
        factorised here when None), and each order's :data:`LeadPoint` read from it."""
        if upper is None:
            upper = self.factor(fold, source, smoothing)
        out: list[LeadPoint] = []
        for order in orders:
            c, view, read = self.solve(fold, order, smoothing, (source, upper))
            f = self.folds[fold]
            m = c.size
            sse = max(f.held_yty - 2.0 * c @ f.held_rhs[:m] + c @ f.held_gram[:m, :m] @ c, 0.0)
            out.append((c, view, sse, read))
        return upper, out

    def resolve(self, fold: int, order: int, smoothing: float, source: int) -> tuple[np.ndarray, Any]:
        """A point solved again as it was first (from the factor of ``source``; the kept factor
        at that smoothing when it is that order's): the same bits."""
        kept = self.factors.get(float(smoothing))
        upper = kept[1][fold] if kept is not None and kept[0] == source else self.factor(fold, source, smoothing)
        c, view, _ = self.solve(fold, order, smoothing, (source, upper))
        return c, view

    def keep(self, smoothing: float, order: int, uppers: list[Any]) -> None:
        """Keep the folds' factors of ``order`` at ``smoothing`` (every one positive definite) for
        the smaller orders asked later, within :data:`LEAD_FACTOR_BYTES` (the oldest dropped)."""
        if any(u is None for u in uppers):
            return
        self.factors.pop(float(smoothing), None)
        self.factors[float(smoothing)] = (int(order), uppers)
        while self.factors and sum(u.nbytes for _, us in self.factors.values() for u in us) > LEAD_FACTOR_BYTES:
            self.factors.pop(next(iter(self.factors)))


__all__ = ["LEAD_FACTOR_BYTES", "LeadFolds", "LeadPoint"]
