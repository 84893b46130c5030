"""A Cholesky factor in single precision with solves refined to double precision.

The dense normal matrix of a swarm (50 drones at SH-10: 5,000 columns) is factorised in
float32 and every solve is corrected with residuals computed in float64 against the float64
matrix itself, until the residual is that of a backward-stable float64 solve: mixed-precision
iterative refinement, as LAPACK's ``DSPOSV`` does (Langou et al., "Exploiting the performance
of 32 bit floating point arithmetic in obtaining 64 bit accuracy", SC 2006). At 5,000 columns
``spotrf`` took 131-139 ms where ``dpotrf`` took 271-280 ms on the same machine, and a refined
solve needs two or three corrections of about 15 ms each. A matrix whose single-precision
factorisation fails, or whose solves do not converge within :data:`MAX_STEPS` corrections
(condition numbers near ``1 / eps32``), is left to the float64 factor
(:class:`~rplearn.core.lsq.factor.ConstrainedFactor` decides).

The matrix is ``A = S (G + diag(added)) S``: the Gram ``G`` (kept by its owner, read here, never
copied in float64), a ridge or penalty on the diagonal, and ``S`` the diagonal scaling that
gives ``A`` a unit diagonal.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from rplearn.core.lsq.products import symmetric_product
from rplearn.errors import NotPositiveDefinite

FloatArray = NDArray[np.float64]

#: Corrections before a solve is declared not to converge (LAPACK's ``DSPOSV`` allows 30;
#: a well-posed swarm needs 2-3, and one needing more is better served by the float64 factor).
MAX_STEPS = 10
#: Rows per step when the scaled single-precision copy is written (their float64 product stays
#: in the cache).
COPY_ROWS = 64


def _scaled(gram: FloatArray, scale: FloatArray, added: FloatArray, dtype: Any) -> tuple[Any, float]:
    """``S (G + diag(added)) S`` in ``dtype`` and its infinity norm (from the float64 values), in
    one pass over ``gram``, a few rows at a time (two whole-matrix passes measured 41 ms at
    5,000 columns, one pass 21-25 ms)."""
    n = gram.shape[0]
    out = np.empty((n, n), dtype)
    rows_buf = np.empty((min(COPY_ROWS, n), n))
    diag = added * scale**2
    norm = 0.0
    for i in range(0, n, COPY_ROWS):
        rows = slice(i, min(n, i + COPY_ROWS))
        k = rows.stop - i
        block = rows_buf[:k]
        np.multiply(gram[rows], np.multiply.outer(scale[rows], scale), out=block)
        block[np.arange(k), np.arange(i, i + k)] += diag[rows]
        out[rows] = block
        np.abs(block, out=block)
        norm = max(norm, float(block.sum(axis=1).max()))
    return out, norm


def scaled_single(gram: FloatArray, scale: FloatArray, added: FloatArray) -> tuple[NDArray[np.float32], float]:
    """``S (G + diag(added)) S`` in float32, and its infinity norm."""
    return _scaled(gram, scale, added, np.float32)


def scaled_double(gram: FloatArray, scale: FloatArray, added: FloatArray) -> FloatArray:
    """``S (G + diag(added)) S`` in float64."""
    return _scaled(gram, scale, added, np.float64)[0]


class RefinedCholesky:
    """Solves with ``A = S (G + diag(added)) S`` through a float32 Cholesky factor of ``A``,
    refined in float64 against ``G``. Build it with :meth:`of`. A
    :class:`~rplearn.core.lsq.factor.Factor` (its solves take and give scaled vectors)."""

    kind: ClassVar[str] = "refined"
    single_precision: ClassVar[bool] = True
    structured: ClassVar[bool] = False

    def __init__(self, gram: FloatArray, scale: FloatArray, added: FloatArray, factor32: Any, norm_inf: float) -> None:
        self.gram, self.scale, self.added = gram, scale, added
        self.factor32, self.norm_inf = factor32, norm_inf
        self._product = symmetric_product(gram)
        self._diag = added * scale**2
        self.steps: list[int] = []  # corrections each solve took (for tests and diagnostics)

    @classmethod
    def of(cls, gram: FloatArray, scale: FloatArray, added: FloatArray) -> RefinedCholesky | None:
        """Factorise ``A`` in float32; None when that fails (not positive definite in single
        precision: the float64 factor may still succeed)."""
        from scipy.linalg import lapack

        a32, norm = scaled_single(gram, scale, added)
        factor, info = lapack.spotrf(a32.T, lower=1, clean=0, overwrite_a=1)
        if info != 0 or not np.isfinite(norm):
            return None
        return cls(gram, scale, added, factor, norm)

    def as_double(self) -> FloatArray:
        """``A`` in float64 (for the float64 factor that replaces this one)."""
        return scaled_double(self.gram, self.scale, self.added)

    def apply(self, u: FloatArray) -> FloatArray:
        """``A u`` in float64 (``u`` a vector or a block of columns)."""
        s = self.scale if u.ndim == 1 else self.scale[:, None]
        d = self._diag if u.ndim == 1 else self._diag[:, None]
        return s * self._product(s * u) + d * u

    def approximate(self, c: FloatArray) -> FloatArray:
        """``A^-1 c`` through the float32 factor alone (about 7 digits)."""
        from scipy.linalg import lapack

        x, info = lapack.spotrs(self.factor32, np.asfortranarray(c, np.float32), lower=1)
        if info != 0:
            raise NotPositiveDefinite(f"LAPACK spotrs failed (info {info})")
        return x.astype(np.float64)

    def solve(self, c: FloatArray) -> FloatArray | None:
        """``A^-1 c`` to float64 accuracy: corrections until every column's residual is at most
        ``||u||_inf ||A||_inf eps sqrt(n)`` (LAPACK ``DSPOSV``'s test); None when that takes
        more than :data:`MAX_STEPS` corrections."""
        c = np.asarray(c, np.float64)
        n = self.scale.size
        tol = self.norm_inf * np.finfo(np.float64).eps * np.sqrt(n)
        u = self.approximate(c)
        for step in range(MAX_STEPS + 1):
            r = c - self.apply(u)
            if np.all(np.abs(r).max(axis=0) <= np.abs(u).max(axis=0) * tol):
                self.steps.append(step)
                return u
            if not np.all(np.isfinite(r)):
                return None
            if step < MAX_STEPS:
                u += self.approximate(r)
        return None


__all__ = ["COPY_ROWS", "MAX_STEPS", "RefinedCholesky", "scaled_double", "scaled_single"]
