"""The folds of the order selection: their statistics, sub-blocks, and each one's share of the
variance inflation and level spread.

Split from :mod:`rplearn.core.lsq.selection`. A fold is the learning units' statistics (all but
one) and the held-out unit's (:func:`unit_folds`); :func:`sub_block` takes a smaller order's
block. :func:`fold_spread_terms` (:func:`~rplearn.core.lsq.selection.variance_inflation` states
the model): for one fold, from its penalised solution ``c`` and the Cholesky factor of its
system, the observed excess of the held-out unit's squared error over the noise, the part of it
the posterior predicts, and the unit's squared mean residual with its expectation. The folds are
independent, so the selection computes them on the statistics' workers at once
(:meth:`rplearn.core.lsq.runtime.StatisticsRuntime.in_order`); the sums over the folds are taken
in fold order afterwards, as one loop did.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.runtime import DEFAULT_RUNTIME
from rplearn.core.lsq.solver_cholesky import factor_inverse_upper, symmetric_inner


@dataclass
class Fold:
    """Learning statistics (all units but one) and the held-out unit's."""

    gram: np.ndarray
    rhs: np.ndarray
    held_gram: np.ndarray
    held_rhs: np.ndarray
    held_yty: float
    held_n: int


def unit_folds(units: Mapping[str, NormalEquations]) -> tuple[list[Fold], np.ndarray, np.ndarray, float, int]:
    """One fold per unit held out, and the sums over every unit.

    Parameters
    ----------
    units : mapping of unit label to NormalEquations
        Every unit's statistics, of one basis and node count.

    Returns
    -------
    folds : list of Fold
        Per unit, in ``units``' order: the statistics of the others and its own.
    gram, rhs : numpy.ndarray
        ``X^T X`` and ``X^T y`` of all units.
    yty : float
        ``y^T y`` of all units.
    n : int
        Their samples.
    """
    every = list(units.values())
    gram = np.array(every[0].gram, np.float64)  # summed in place, in the units' order
    for u in every[1:]:
        gram += u.gram
    rhs = cast(np.ndarray, sum(u.rhs for u in every))
    yty = float(sum(u.yty for u in every))
    n = int(sum(u.n_samples for u in every))
    # the learning blocks (new memory, slow on first touch: on the workers)
    learning = list(DEFAULT_RUNTIME.in_order(lambda held: gram - held, [u.gram for u in every], ahead=len(every)))
    folds = [Fold(g, rhs - u.rhs, u.gram, u.rhs, u.yty, u.n_samples) for g, u in zip(learning, every)]
    return folds, gram, rhs, yty, n


def sub_block(matrix: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``matrix[idx][:, idx]``: the matrix itself (no copy) when ``idx`` is every column in order;
    copied range by range when ``idx`` is a few increasing runs of consecutive columns (a nested
    order: the first columns of each node's block, then the shared ones), which gathers no
    intermediate as wide as the matrix.

    Parameters
    ----------
    matrix : (n, n) numpy.ndarray
    idx : 1-D integer numpy.ndarray
        The rows and columns to keep, in the order wanted.

    Returns
    -------
    (len(idx), len(idx)) numpy.ndarray
        ``matrix`` itself when ``idx`` is ``0..n-1``, else a new array.
    """
    if idx.size == matrix.shape[0] and np.array_equal(idx, np.arange(idx.size)):
        return matrix
    cuts = np.flatnonzero(np.diff(idx) != 1) + 1
    if cuts.size > _MAX_BLOCK_RUNS or np.any(np.diff(idx) <= 0):
        return matrix.take(idx, axis=0).take(idx, axis=1)
    runs = [(int(r[0]), int(r[-1]) + 1) for r in np.split(idx, cuts)]
    out = np.empty((idx.size, idx.size))
    row = 0
    for a, b in runs:
        col = 0
        for c, d in runs:
            out[row : row + b - a, col : col + d - c] = matrix[a:b, c:d]
            col += d - c
        row += b - a
    return out


#: Runs of consecutive columns up to which :func:`sub_block` copies range by range.
_MAX_BLOCK_RUNS = 8


def lead_columns(n_coef: int, n_nodes: int, n_shared: int) -> np.ndarray:
    """The columns of a joint problem (``n_nodes`` blocks of ``n_coef`` coefficients, then
    ``n_shared`` shared columns) reordered so that every nested smaller order's problem is a
    leading block: the shared columns first, then each coefficient's column of every node in
    turn (SH orders nest: an order's coefficients are the first ``order**2`` of each block).

    The Cholesky factor of a leading block of a matrix is the leading block of the matrix's
    factor, so one factorisation at the largest order asked serves every smaller order at the
    same penalty (:class:`~rplearn.core.lsq.selection_evaluator.FoldEvaluator`).

    Parameters
    ----------
    n_coef : int
        Coefficients per node at the largest order.
    n_nodes : int
    n_shared : int

    Returns
    -------
    1-D integer numpy.ndarray
        ``perm``: position ``i`` of the reordered problem is column ``perm[i]`` of the natural one.
    """
    pat = n_coef * n_nodes
    pattern = (np.arange(n_nodes)[None, :] * n_coef + np.arange(n_coef)[:, None]).ravel()
    return np.concatenate([pat + np.arange(n_shared), pattern]).astype(np.intp)


def lead_size(n_coef: int, n_nodes: int, n_shared: int) -> int:
    """Columns of the leading block of :func:`lead_columns` that is the problem of a basis of
    ``n_coef`` coefficients per node."""
    return n_shared + n_nodes * n_coef


def permuted(matrix: np.ndarray, layout: tuple[int, int, int]) -> np.ndarray:
    """``matrix[perm][:, perm]`` for ``perm = lead_columns(*layout)``, C-contiguous (a new array),
    copied block by block through reshaped views (five times faster than fancy indexing).

    Parameters
    ----------
    matrix : (n, n) numpy.ndarray
        In the natural layout: ``n_nodes`` blocks of ``n_coef`` columns, then ``n_shared``.
    layout : (int, int, int)
        ``n_coef``, ``n_nodes``, ``n_shared``.

    Returns
    -------
    (n, n) numpy.ndarray
    """
    p, nodes, ns = layout
    pat = p * nodes
    out = np.empty_like(matrix, order="C")
    out[:ns, :ns] = matrix[pat:, pat:]
    out[:ns, ns:] = matrix[pat:, :pat].reshape(ns, nodes, p).transpose(0, 2, 1).reshape(ns, pat)
    out[ns:, :ns] = matrix[:pat, pat:].reshape(nodes, p, ns).transpose(1, 0, 2).reshape(pat, ns)
    out[ns:, ns:] = matrix[:pat, :pat].reshape(nodes, p, nodes, p).transpose(1, 0, 3, 2).reshape(pat, pat)
    return out


def fold_spread_terms(c: np.ndarray, upper: np.ndarray, fold: Fold, index: int, sums: list[tuple[np.ndarray, float]],
                      counts: np.ndarray, total: tuple[int, float]) -> tuple[float, float, tuple[float, float, float]]:
    """One fold's terms of the variance inflation and the between-unit level variance.

    Parameters
    ----------
    c : 1-D numpy.ndarray
        The fold's penalised solution.
    upper : numpy.ndarray
        The Cholesky factor of its system (:func:`rplearn.core.lsq.solver_cholesky.spd_factor`).
    fold : Fold
        Its statistics and its held-out unit's, at the order (shared columns appended).
    index : int
        The held-out unit's position among the units.
    sums : list of (numpy.ndarray, float)
        Per unit: its column sums ``X_u^T 1`` at the order and ``sum y``.
    counts : 1-D numpy.ndarray
        Per unit: its samples.
    total : (int, float)
        The samples and ``y^T y`` of all units.

    Returns
    -------
    excess : float
        The held-out unit's squared error about its own mean level, less the noise expected in it.
    predicted : float
        That excess as the fold's posterior predicts it (``sigma^2 tr(A^-1 H)`` less the part
        along the unit's mean).
    level : (float, float, float)
        The held-out unit's squared mean residual, its expectation from noise and the posterior,
        and the weight of the fit's level (``1 + sum w^2`` over the learning units).
    """
    n, yty = total
    k = index
    g, held_g = fold.gram, fold.held_gram
    # the upper triangle of A^-1 from the solve's factor (a third of the work of an LU inverse);
    # the traces and the quadratic form below are read off it, the whole inverse never formed
    inverse = factor_inverse_upper(upper)
    learn = [j for j in range(len(sums)) if j != k]
    learn_n = n - fold.held_n
    # the learning residual about each learning unit's own mean: noise, not the units' levels
    unit_means = np.array([(sums[j][1] - c @ sums[j][0]) / counts[j] for j in learn])
    learn_sse = (yty - fold.held_yty) - 2.0 * c @ fold.rhs + c @ g @ c - float(counts[learn] @ unit_means**2)
    # less the fit's effective parameters tr(A^-1 G) and the other units' means
    dof = learn_n - symmetric_inner(inverse, g) - (len(learn) - 1)
    noise_var = max(learn_sse, 0.0) / max(dof, 1.0)
    held_sse = max(fold.held_yty - 2.0 * c @ fold.held_rhs + c @ held_g @ c, 0.0)
    a, sum_y = sums[k]
    mean = (sum_y - c @ a) / fold.held_n
    # n^2 times the posterior variance of the unit's mean, over sigma^2
    quad = 2.0 * float(a @ (inverse @ a)) - float(np.diagonal(inverse) @ a**2)
    excess = held_sse - fold.held_n * mean**2 - (fold.held_n - 1) * noise_var
    # sum over the held-out samples of x^T (sigma^2 A^-1) x = sigma^2 tr(A^-1 X_u^T X_u),
    # less the part along the unit's mean (removed above)
    predicted = noise_var * (symmetric_inner(inverse, held_g) - quad / fold.held_n)  # tr(A^-1 H)
    weights = counts[learn] / learn_n  # the fit's level: the learning units' levels, weighed by samples
    return float(excess), float(predicted), (float(mean**2), float(noise_var * (1.0 + quad / fold.held_n) / fold.held_n),
                                             1.0 + float(weights @ weights))


def on_one_blas_thread(job: Callable[[], Any]) -> Any:
    """``job()`` with one BLAS thread, wherever it runs: on the statistics' workers (inside their
    own one-thread limit: the limit is re-entrant) or in the calling thread when the workers are
    busy, which would otherwise solve with the caller's BLAS threads and round differently.

    Parameters
    ----------
    job : callable
        A fold's work (no arguments).

    Returns
    -------
    object
        What ``job`` returns.
    """
    from rplearn.core.threads import one_blas_thread

    with one_blas_thread():
        return job()


__all__ = ["Fold", "fold_spread_terms", "lead_columns", "lead_size", "on_one_blas_thread", "permuted", "sub_block",
           "unit_folds"]
