"""Cholesky factors of a regularised normal matrix, for the order selection and the posteriors it reads.

The selection (:mod:`rplearn.core.lsq.selection`) solves the penalised normal equations of every
fold at many points, reads the variance inflation of a few from their inverses, and the
automatic fit reads posterior covariances at other smoothings (the near ties' own-pattern
posterior, the capped prior). All of it is one factor ``A = U^T U`` of a symmetric positive
definite matrix and then:

- :func:`factor_solve`: ``A^-1 b`` (two triangular solves);
- :func:`factor_inverse`: the whole ``A^-1`` from the factor (LAPACK ``potri``: a third of the
  work of an LU inverse, which ``numpy.linalg.inv`` does, and no second factorisation);
- :func:`constrained_inverse`: the top-left block of the inverse of the KKT matrix
  ``[[A, C^T], [C, 0]]`` (linear equality constraints, the gauge), ``A^-1 - Z (C Z)^-1 Z^T`` with
  ``Z = A^-1 C^T``: what :func:`rplearn.core.lsq.solver.solve` inverts the whole KKT matrix for.

They run in scipy's LAPACK (numpy has no triangular solves), whose calls hold the interpreter
lock; callers keep them on one BLAS thread (:func:`rplearn.core.threads.one_blas_thread`): an
OpenBLAS pool of scipy's left spinning after a call slows numpy's next factorisation on a 2-core
machine. ``numpy.linalg.cholesky`` was also slower on the sizes of these problems (measured on
this kind of machine with one thread: 4.4 ms against 2.1 ms at 512 columns, where the leading
dimension is a power of two, 1.2 against 1.0 ms at 450).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def spd_factor(matrix: FloatArray, overwrite: bool = False) -> FloatArray | None:
    """The upper Cholesky factor ``U`` (``matrix = U^T U``, Fortran-ordered; the strict lower
    triangle is left as it was) of a symmetric positive definite ``matrix``, or None when it is
    not positive definite. Only one triangle of ``matrix`` is read. ``overwrite``: the factor
    may take ``matrix``'s memory (a C- or Fortran-contiguous float64 matrix the caller no longer needs).
    """
    from scipy.linalg import lapack

    a = np.asarray(matrix, np.float64)
    fortran = a.T if a.flags.c_contiguous else a  # symmetric: a C-ordered matrix is its transpose in Fortran order
    factor, info = lapack.dpotrf(fortran, lower=0, clean=0, overwrite_a=int(bool(overwrite)))
    return factor if info == 0 else None


def factor_solve(factor: FloatArray, rhs: FloatArray) -> FloatArray:
    """``A^-1 rhs`` from the factor of :func:`spd_factor` (one vector or the columns of a matrix)."""
    from scipy.linalg import lapack

    out, info = lapack.dpotrs(factor, rhs, lower=0)
    if info != 0:  # pragma: no cover - only on an argument error
        raise ValueError(f"dpotrs: argument {-info} is invalid")
    return np.asarray(out, np.float64)


def factor_inverse(factor: FloatArray) -> FloatArray:
    """The whole ``A^-1`` (symmetric to the last bit) from the factor of :func:`spd_factor`."""
    from scipy.linalg import lapack

    upper, info = lapack.dpotri(factor, lower=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"dpotri: the factor is singular (info {info})")
    inverse = np.triu(upper)  # the upper triangle of A^-1 (the rest of ``upper`` is the factor's)
    inverse += inverse.T  # the diagonal twice (exactly: a power of two) ...
    inverse[np.diag_indices_from(inverse)] *= 0.5  # ... and back
    return inverse


def constrained_inverse(matrix: FloatArray, constraints: FloatArray) -> FloatArray | None:
    """The top-left block ``M`` of the inverse of ``[[matrix, C^T], [C, 0]]`` (``C`` =
    ``constraints``, one row per constraint, of full row rank): ``A^-1 - Z (C Z)^-1 Z^T`` with
    ``Z = A^-1 C^T``, symmetric to the last bit; None when ``matrix`` is not positive definite
    (or the constraints are dependent on it)."""
    factor = spd_factor(matrix)
    if factor is None:
        return None
    inverse = factor_inverse(factor)
    c = np.asarray(constraints, np.float64).reshape(-1, inverse.shape[0])
    if not c.shape[0]:
        return inverse
    z = inverse @ c.T
    s = c @ z
    s = 0.5 * (s + s.T)
    try:
        correction = z @ np.linalg.solve(s, z.T)
    except np.linalg.LinAlgError:
        return None
    out = inverse - 0.5 * (correction + correction.T)
    return out if np.all(np.isfinite(out)) else None


__all__ = ["constrained_inverse", "factor_inverse", "factor_solve", "spd_factor"]
