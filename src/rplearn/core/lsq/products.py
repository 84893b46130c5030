"""Products with the symmetric normal matrix of a large solve, in the BLAS that factorises it."""

from __future__ import annotations

from typing import Any

import numpy as np


def symmetric_product(matrix: Any) -> Any:
    """``x -> matrix @ x`` for a symmetric ``matrix`` and blocks (or vectors) ``x``.

    A dense float64 matrix is multiplied by scipy's BLAS (the library that factorises it:
    numpy's is held to one thread meanwhile, :func:`~rplearn.core.threads.numpy_blas_one_thread`),
    read in its own memory order (symmetric: a C-ordered matrix is its own transpose in Fortran
    order), which measured 8.5 ms per 5,000 x 8 block against numpy's 14 ms; anything else (a
    sparse matrix) by its own ``@``.
    """
    if not (isinstance(matrix, np.ndarray) and matrix.ndim == 2 and matrix.dtype == np.float64
            and (matrix.flags.c_contiguous or matrix.flags.f_contiguous)):
        return lambda x: matrix @ x
    from scipy.linalg import blas

    fortran = matrix if matrix.flags.f_contiguous else matrix.T

    def product(x: Any) -> Any:
        if x.ndim == 1:
            return blas.dgemv(1.0, fortran, x)
        return blas.dgemm(1.0, fortran, np.asfortranarray(x))

    return product


def spd_inverse(matrix: np.ndarray) -> np.ndarray:
    """Inverse of a symmetric positive definite matrix (its symmetric part) through its Cholesky
    factor ``L``: ``L^-T L^-1``, symmetric to the last bit.

    Raises
    ------
    numpy.linalg.LinAlgError
        When the matrix is not positive definite.
    """
    sym = 0.5 * (matrix + matrix.T)
    chol = np.linalg.cholesky(sym)
    inv_l = np.linalg.solve(chol, np.eye(sym.shape[0]))
    return np.asarray(inv_l.T @ inv_l, np.float64)


__all__ = ["spd_inverse", "symmetric_product"]
