"""The level a regularised pattern fit shrinks toward: the data's own, never a fixed value.

Every pattern column of the joint solve is regularised (the ridge of
:func:`rplearn.core.lsq.solver.solve`, the smoothness penalty of :mod:`rplearn.core.lsq.selection`; the
large-swarm factorisations rely on it). Shrunk toward zero, the constant part of each pattern
(its level) would be pulled toward 0 dBi, and with uncalibrated power (``rssi_scale``
``relative``) adding a constant to every RSSI value would change the fit. So the coefficients
are shrunk toward a *target* (:func:`shrink_target`) whose shape is the prior's (zero without
a prior; a prior's per-node sphere mean removed: a prior fixes the shape of a pattern, not its
absolute level) and whose constant per node is the least-squares fit, from the statistics
alone, of one constant per node (plus the shared columns: path-loss exponent, link offsets) to
what the shape leaves of the data, under the same gauge constraints as the solve.

Why this makes a fit level-free. Let ``d`` be constants per node with ``c_t + c_r = 1`` on
every link (``1/2`` each always works) and ``Q d`` their coefficients (the constant function in
every node's block, :func:`constant_coefficients`), so that ``X Q d = 1``. Adding ``C`` to every
``y`` moves the constants' fit by exactly ``C d`` (for some such ``d`` within the gauge), hence
the target by ``C Q d``; the penalised normal equations ``(G + R) c = X^T y + R t`` are then
solved by ``c + C Q d``, whose predictions are those of ``c`` plus ``C`` and whose residuals,
spreads and validation errors are those of ``c``. Exact for spherical harmonics and Legendre
polynomials, whose constant function is one coefficient; a Gaussian-kernel grid (BG) represents
a constant only approximately (its least-squares coefficients on a Fibonacci grid), so there the
shift holds to that approximation.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn.core.basis_base import Basis

FloatArray = NDArray[np.float64]

#: Weight, relative to its own diagonal, of a small ridge on the shared columns in the level's
#: fit: keeps a shared column the constants explain (an exponent over a constant distance) from
#: taking part of a level shift; changes nothing otherwise.
_SHARED_FLOOR = 1e-9


def constant_coefficients(basis: Basis) -> FloatArray:
    """Coefficients of the constant function 1 in ``basis``: exact for SH (``sqrt(4 pi)`` on
    ``Y_00``) and P (the product of two degree-0 polynomials), least squares on a Fibonacci
    grid for BG (approximate)."""
    return _constant(basis).copy()


@lru_cache(maxsize=16)
def _constant(basis: Basis) -> FloatArray:
    p = basis.n_coef
    out: FloatArray = np.zeros(p)
    if basis.kind == "sh":
        out[0] = np.sqrt(4.0 * np.pi)
    elif basis.kind == "poly":
        out[0] = 1.0
    else:
        from rplearn.core.bases import fibonacci_grid_nodes

        az, el = fibonacci_grid_nodes(max(4 * p, 400))
        out = np.asarray(np.linalg.lstsq(basis.design(az, el), np.ones(az.size), rcond=None)[0], np.float64)
    out.flags.writeable = False
    return out


def pattern_shape(coef: FloatArray, basis: Basis, n_nodes: int) -> FloatArray:
    """Coefficients (one block per node) with each node's sphere-mean gain removed: the shape."""
    c = np.asarray(coef, np.float64).reshape(n_nodes, basis.n_coef)
    return (c - np.outer(c @ basis.sphere_mean, _constant(basis))).ravel()


def _free_constants(components: Sequence[tuple[list[int], Any]], n_nodes: int) -> FloatArray:
    """Per bipartite component (in the order of the gauge constraints), the constants ``+1`` on
    one side and ``-1`` on the other: the direction the data leave free."""
    cols = []
    for comp, side_b in components:
        if side_b is None or len(comp) < 2:
            continue
        v = np.zeros(n_nodes)
        v[list(comp)] = 1.0
        v[list(side_b)] = -1.0
        cols.append(v)
    return np.array(cols).T if cols else np.zeros((n_nodes, 0))


def shrink_target(
    gram: FloatArray,
    rhs: FloatArray,
    basis: Basis,
    n_nodes: int,
    prior: FloatArray | None = None,
    constraints: tuple[FloatArray, FloatArray] | None = None,
    components: Sequence[tuple[list[int], Any]] | None = None,
) -> FloatArray:
    """The coefficients a regularised fit shrinks toward (see the module docstring).

    Parameters
    ----------
    gram, rhs : ndarray
        ``X^T X`` and ``X^T y`` of the fit: ``n_nodes`` pattern blocks of ``basis``, then any
        shared columns.
    basis : Basis
    n_nodes : int
    prior : ndarray, optional
        Prior coefficients of the pattern columns; only their shape is kept.
    constraints : (matrix, values), optional
        The solve's gauge constraints on every column; the target satisfies them.
    components : sequence, optional
        The link graph's components (:func:`rplearn.core.lsq.solver.link_components`), in the
        order of the constraints.

    Returns
    -------
    ndarray
        One value per column of ``gram``: the shape plus each node's constant, zero at the
        shared columns (they are not shrunk).
    """
    p = basis.n_coef
    pat = n_nodes * p
    n_cols = gram.shape[0]
    q = _constant(basis)
    nz = np.flatnonzero(q)
    qz = q[nz]
    cols = np.arange(n_nodes)[:, None] * p + nz[None, :]  # (n_nodes, nonzeros): the constant's columns
    target = np.zeros(n_cols)
    if prior is not None:
        target[:pat] = pattern_shape(np.asarray(prior, np.float64)[:pat], basis, n_nodes)
    rest = rhs - gram @ target if prior is not None else np.asarray(rhs, np.float64)
    # the free columns [Q, shared]: their normal equations, the shared ones eliminated (a
    # Schur complement: one LU of the shared block, a swarm's many link offsets included)
    level_gram = np.empty((n_cols, n_nodes))  # G Q
    for n in range(n_nodes):
        level_gram[:, n] = gram[:, cols[n]] @ qz
    h = np.stack([qz @ level_gram[cols[n]] for n in range(n_nodes)])  # Q^T G Q
    b = np.array([qz @ rest[cols[n]] for n in range(n_nodes)])
    if n_cols > pat:
        shared = np.array(gram[pat:, pat:], np.float64)
        d = np.diag(shared)
        shared[np.diag_indices_from(shared)] += np.where(d > 0, _SHARED_FLOOR * d, 1.0)
        cross = level_gram[pat:]  # X_shared^T X Q
        eliminated = np.linalg.solve(shared, np.column_stack([cross, rest[pat:]]))
        h = h - cross.T @ eliminated[:, :n_nodes]
        b = b - cross.T @ eliminated[:, n_nodes]
    h = 0.5 * (h + h.T)
    diag = np.diag(h)
    scale = 1.0 / np.sqrt(np.where(diag > 0, diag, 1.0))
    level = scale * np.linalg.lstsq(h * scale[:, None] * scale[None, :], b * scale, rcond=1e-10)[0]  # least norm
    if constraints is not None and constraints[0].shape[0]:
        cmat, cval = constraints
        on_level = np.stack([cmat[:, cols[n]] @ qz for n in range(n_nodes)], axis=1)  # (constraints, n_nodes)
        free = _free_constants(components or [], n_nodes)
        lhs = on_level @ free
        wanted = np.asarray(cval, np.float64) - cmat @ target - on_level @ level
        if free.shape[1] == cmat.shape[0] and np.linalg.matrix_rank(lhs) == lhs.shape[0]:
            level = level + free @ np.linalg.solve(lhs, wanted)
        else:  # not the solver's constraints, or ones the level does not reach (a basis that holds no
            # constant, e.g. BG kernels far narrower than their spacing): the least change that meets them
            level = level + np.linalg.lstsq(on_level, wanted, rcond=None)[0]
    target[cols] += level[:, None] * qz[None, :]
    return target


__all__ = ["constant_coefficients", "pattern_shape", "shrink_target"]
