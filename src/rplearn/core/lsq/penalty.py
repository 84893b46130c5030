"""The smoothness penalty of a pattern fit and the nested sub-problems of smaller SH orders.

Split from :mod:`rplearn.core.lsq.selection` (which re-exports these names): the weights of the
penalty, its unit, and the statistics of a smaller, nested basis taken from a larger one's.
"""

from __future__ import annotations

import numpy as np

from rplearn.core.basis_base import Basis
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.errors import InputError

#: Exponent ``p`` of the SH roughness weights ``(l (l+1))^p``: 2 penalises the squared
#: Laplacian of the pattern (spherical smoothing splines).
DEFAULT_PENALTY_POWER: float = 2.0


def penalty_scale(gram: np.ndarray, n_columns: int | None = None) -> float:
    """``mean(diag(X^T X))`` over the pattern columns (the first ``n_columns``; all by default,
    shared columns such as link offsets excluded when given): the unit of the relative smoothing."""
    d = np.diag(gram)
    if n_columns is not None:
        d = d[:n_columns]
    return penalty_scale_of_diagonal(d)


def penalty_scale_of_diagonal(diagonal: np.ndarray) -> float:
    """:func:`penalty_scale` from the diagonal of ``X^T X`` over the columns it averages.

    Parameters
    ----------
    diagonal : 1-D float64 array
        The diagonal entries of the Gram matrix of the pattern columns in question (e.g. of
        a nested sub-block, read off the larger problem's diagonal).

    Returns
    -------
    float
        Their mean, or 1 when there are none or the mean is not positive.
    """
    d = np.asarray(diagonal, np.float64)
    return float(np.mean(d)) if d.size and np.mean(d) > 0 else 1.0


def penalty_vector(basis: Basis, n_nodes: int, smoothing: float, scale: float, power: float = DEFAULT_PENALTY_POWER) -> np.ndarray:
    """Absolute penalty weight of every column (``n_nodes`` blocks of the basis's roughness)."""
    if not (np.isfinite(smoothing) and smoothing >= 0):
        raise InputError(f"smoothing: expected a non-negative number, got {smoothing!r}", param="smoothing")
    return np.tile(basis.roughness(power), n_nodes) * (float(smoothing) * float(scale))


def nested_columns(big: Basis, small: Basis, n_nodes: int) -> np.ndarray:
    """Columns of ``small``'s joint problem inside ``big``'s (SH orders nest: first ``N^2`` of each block)."""
    if big.kind != small.kind or (big.kind == "sh" and small.n_coef > big.n_coef):
        raise InputError(f"{small.label} is not nested in {big.label}")
    if big.kind != "sh" and small != big:
        raise InputError(f"only spherical harmonics nest; {small.label} is not {big.label}")
    return np.concatenate([k * big.n_coef + np.arange(small.n_coef) for k in range(n_nodes)])


def sub_statistics(normal: NormalEquations, small: Basis) -> NormalEquations:
    """The statistics of a nested smaller basis, taken from ``normal`` (no samples re-read)."""
    if small == normal.basis:
        return normal
    idx = with_shared_columns(nested_columns(normal.basis, small, normal.n_nodes), normal)
    out = NormalEquations(small, normal.n_nodes, normal.environment)
    out.shared = normal.shared
    out.gram = normal.gram[np.ix_(idx, idx)].copy()
    out.rhs = normal.rhs[idx].copy()
    out.yty = normal.yty
    out.n_samples = normal.n_samples
    out.link_counts = dict(normal.link_counts)
    out.env_sq, out.env_y = normal.env_sq, normal.env_y
    p_big, p_small = normal.basis.n_coef, small.n_coef
    out.env_cross = normal.env_cross.reshape(normal.n_nodes, p_big)[:, :p_small].ravel().copy()
    out.directed = {k: np.concatenate([v[:p_small], v[p_big : p_big + p_small], v[2 * p_big :]])
                    for k, v in normal.directed.items()}
    return out


def with_shared_columns(pattern_idx: np.ndarray, normal: NormalEquations) -> np.ndarray:
    """Column indices of a sub-problem: ``pattern_idx`` and then every shared column of ``normal``."""
    return np.concatenate([pattern_idx, normal.n_pattern_columns + np.arange(len(normal.shared))]).astype(np.intp)


__all__ = ["DEFAULT_PENALTY_POWER", "nested_columns", "penalty_scale", "penalty_scale_of_diagonal", "penalty_vector", "sub_statistics",
           "with_shared_columns"]
