"""Factorisations of the regularised normal matrix of a large joint solve, and its constrained inverse.

Above :data:`rplearn.core.lsq.solver.LARGE_COLUMNS` columns (swarms of tens of nodes) the
solver factorises the regularised, gauge-constrained system once instead of inverting the KKT
matrix (3,000 columns: 2.5 s of inverse). :class:`ConstrainedFactor` keeps the constraints and
the diagonal scaling; the factorisation itself is one of four :class:`Factor` variants, chosen
by the matrix's layout when it is built (:meth:`ConstrainedFactor.of`):

=====================  ======================================================================
variant                when
=====================  ======================================================================
:class:`BandedCholesky`  nodes that link to their neighbours (a band after reordering them)
:class:`SparseLU`        at most :data:`SPARSE_BLOCK_FRACTION` of the node blocks non-zero
:class:`DenseCholesky`   otherwise, in float64
:class:`RefinedCholesky` otherwise, from :data:`~rplearn.core.lsq.solver_large.REFINED_COLUMNS`
                         columns: float32 with solves refined to float64
                         (:mod:`rplearn.core.lsq.refined`); replaced by the float64 factor when
                         a solve does not converge or the whole inverse is asked for
=====================  ======================================================================
"""

from __future__ import annotations

import threading
from typing import Any, ClassVar, Protocol

import numpy as np
from numpy.typing import NDArray

from rplearn.core.lsq.node_blocks import NodeBlocks
from rplearn.core.lsq.refined import RefinedCholesky, scaled_double
from rplearn.errors import NotPositiveDefinite

FloatArray = NDArray[np.float64]

#: A normal matrix with at most this fraction of its node blocks non-zero (nodes that link to
#: few others) is factorised as a sparse matrix (:meth:`ConstrainedFactor.of`).
SPARSE_BLOCK_FRACTION = 0.25
#: ... or as a band when its nodes can be ordered so that the band's half-width is at most this
#: fraction of the columns (the work is then at most 1/8 of a dense Cholesky's: ``n kd^2``
#: against ``n^3 / 3``).
BAND_FRACTION = 0.2


def band_of(source: FloatArray, s: FloatArray, diagonal: FloatArray, order: NDArray[np.intp], kd: int,
            p: int) -> FloatArray:
    """The lower band (half-width ``kd``) of ``diag(s) source diag(s) + diag(diagonal)`` with
    its columns in ``order`` (whole node blocks of ``p`` columns, as
    :meth:`~rplearn.core.lsq.node_blocks.NodeBlocks.band` gives), in LAPACK's band storage (row
    ``k`` the ``k``-th subdiagonal, as a Fortran-ordered array).

    Band column ``j`` is a stretch of row ``order[j]`` of the symmetric ``source``: per node,
    its rows' stretches are windows into the node's rows at the next few nodes' columns
    (contiguous runs of ``p``), read once (an element-wise gather took 35 ms at 50 drones on a
    ring, this about a fifth)."""
    n = source.shape[0]
    nodes = order[::p] // p
    n_nodes = nodes.size
    reach = (kd + 1 + p - 1) // p + 1  # node blocks a block row's band touches (its own included)
    band_t = np.empty((n, kd + 1))
    rows_buf = np.zeros((p, reach * p))
    window = np.lib.stride_tricks.as_strided(
        rows_buf, shape=(p, kd + 1), strides=(rows_buf.strides[0] + rows_buf.strides[1], rows_buf.strides[1]))
    for b in range(n_nodes):
        rows = slice(nodes[b] * p, (nodes[b] + 1) * p)
        cols = (nodes[b : b + reach, None] * p + np.arange(p)[None, :]).ravel()
        np.multiply(np.take(source[rows], cols, axis=1), np.multiply.outer(s[rows], s[cols]), out=rows_buf[:, : cols.size])
        rows_buf[:, cols.size :] = 0.0  # past the last node: outside the matrix
        band_t[b * p : (b + 1) * p] = window
    band_t[:, 0] += diagonal[order]
    return band_t.T


def symmetric_from_lower(x: FloatArray, rows: int = 256) -> FloatArray:
    """``x`` (square) made exactly symmetric from its lower triangle, in place, a block of rows
    at a time (at 5,000 columns, index arrays of the upper triangle took 200 MB and the
    averaging ``(x + x^T) / 2`` another pass over two copies)."""
    n = x.shape[0]
    for i in range(0, n, rows):
        j = min(n, i + rows)
        x[i:j, j:] = x[j:, i:j].T
        diag = x[i:j, i:j]
        upper = np.triu_indices(j - i, 1)
        diag[upper] = diag.T[upper]
    return x




class Factor(Protocol):
    """A factorisation of the scaled regularised matrix ``A`` (unit diagonal): one of
    :class:`DenseCholesky`, :class:`BandedCholesky`, :class:`SparseLU`, :class:`RefinedCholesky`."""

    #: its name, for reports and tests: "dense", "banded", "sparse" or "refined"
    kind: ClassVar[str]
    #: solves through a float32 factor, refined in float64 against the Gram (which must then
    #: not change while the factor is in use)
    single_precision: ClassVar[bool]
    #: reads only the node blocks that can be non-zero (products through
    #: :meth:`~rplearn.core.lsq.node_blocks.NodeBlocks.product` then suffice)
    structured: ClassVar[bool]

    def solve(self, b: FloatArray) -> FloatArray | None:
        """``A^-1 b`` (``b`` a vector or a block of columns) to float64 accuracy; None when this
        factor cannot reach it (then factorise in float64)."""
        ...

    def approximate(self, b: FloatArray) -> FloatArray:
        """``A^-1 b`` to the factor's own precision (for Krylov iterations)."""
        ...


class DenseCholesky:
    """The float64 Cholesky factor of a dense ``A`` (LAPACK ``dpotrf``, lower triangle)."""

    kind: ClassVar[str] = "dense"
    single_precision: ClassVar[bool] = False
    structured: ClassVar[bool] = False

    def __init__(self, lower: FloatArray) -> None:
        self.lower = lower

    @classmethod
    def of(cls, a: FloatArray) -> DenseCholesky | None:
        """Factorise the symmetric ``a`` in place (its transpose is the same matrix in Fortran
        order); None when it is not positive definite."""
        from scipy.linalg import lapack

        factor, info = lapack.dpotrf(a.T, lower=1, clean=0, overwrite_a=1)
        if info != 0:
            return None
        return cls(factor)

    def solve(self, b: FloatArray) -> FloatArray:
        from scipy.linalg import lapack

        x, info = lapack.dpotrs(self.lower, np.asfortranarray(b), lower=1)
        if info != 0:
            raise NotPositiveDefinite(f"LAPACK dpotrs failed (info {info})")
        return x

    def approximate(self, b: FloatArray) -> FloatArray:
        return self.solve(b)

    def inverse(self) -> FloatArray:
        """The lower triangle of ``A^-1`` (``n^3`` work)."""
        from scipy.linalg import lapack

        inv, info = lapack.dpotri(self.lower, lower=1)
        if info != 0:
            raise NotPositiveDefinite(f"LAPACK dpotri failed (info {info}): the regularised matrix is singular")
        return inv


class StructuredFactor:
    """A factor of a matrix whose nodes link to few others; it keeps ``A`` itself, whose dense
    form the whole inverse needs (:meth:`scaled_dense`)."""

    kind: ClassVar[str] = ""
    single_precision: ClassVar[bool] = False
    structured: ClassVar[bool] = True

    def solve(self, b: FloatArray) -> FloatArray:
        raise NotImplementedError

    def approximate(self, b: FloatArray) -> FloatArray:
        return self.solve(b)

    def scaled_dense(self) -> FloatArray:
        """The scaled matrix ``A`` as a dense array."""
        raise NotImplementedError


class BandedCholesky(StructuredFactor):
    """The Cholesky factor of ``A`` as a band after reordering its columns (LAPACK ``dpbtrf``)."""

    kind: ClassVar[str] = "banded"

    def __init__(self, factor: FloatArray, band: FloatArray, order: NDArray[np.intp]) -> None:
        self.factor, self.band, self.order = factor, band, order

    @classmethod
    def of(cls, band: FloatArray, order: NDArray[np.intp]) -> BandedCholesky | None:
        """Factorise a band (:func:`band_of`) of the columns in ``order``; None when it is not
        positive definite."""
        from scipy.linalg import lapack

        factor, info = lapack.dpbtrf(band, lower=1)
        if info != 0:
            return None
        return cls(factor, band, order)

    def solve(self, b: FloatArray) -> FloatArray:
        from scipy.linalg import lapack

        x = np.empty_like(b, dtype=np.float64)
        xo, info = lapack.dpbtrs(self.factor, np.asfortranarray(b[self.order]), lower=1)
        if info != 0:
            raise NotPositiveDefinite(f"LAPACK dpbtrs failed (info {info})")
        x[self.order] = xo
        return x

    def scaled_dense(self) -> FloatArray:
        band, order = self.band, self.order
        kd, n = band.shape[0] - 1, band.shape[1]
        dense = np.zeros((n, n))
        for k in range(kd + 1):
            rows, cols = order[k:], order[: n - k]
            dense[rows, cols] = band[k, : n - k]
            dense[cols, rows] = band[k, : n - k]
        return dense


class SparseLU(StructuredFactor):
    """SuperLU's factor of a block-sparse ``A`` (a minimum-degree ordering of ``A + A^T``,
    symmetric mode), whose fill stays near the links."""

    kind: ClassVar[str] = "sparse"

    def __init__(self, lu: Any, sparse_a: Any) -> None:
        self.lu, self.sparse_a = lu, sparse_a

    @classmethod
    def of(cls, sparse_a: Any) -> SparseLU | None:
        """Factorise a sparse ``A``; None when it is singular or not positive definite."""
        from scipy.sparse.linalg import splu

        try:
            lu = splu(sparse_a, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        except RuntimeError:  # exactly singular
            return None
        if not np.all(lu.U.diagonal() > 0):  # pivots of a positive definite matrix are positive
            return None
        return cls(lu, sparse_a)

    def solve(self, b: FloatArray) -> FloatArray:
        return self.lu.solve(np.asfortranarray(b))

    def scaled_dense(self) -> FloatArray:
        return self.sparse_a.toarray()


class ConstrainedFactor:
    """The constrained inverse ``M = A^-1 - A^-1 C^T (C A^-1 C^T)^-1 C A^-1`` of a symmetric
    positive definite ``A`` (the regularised normal matrix) and constraints ``C`` (the gauge),
    kept as a factor of the diagonally scaled ``A`` (a :class:`Factor`): products with ``M``
    cost two triangular solves, and ``M`` itself is formed only when asked for (:meth:`inverse`).

    Build it with :meth:`of` or :meth:`of_gram`, which give None when ``A`` is not positive
    definite.
    """

    def __init__(self, factor: Factor, scale: FloatArray, cmat: FloatArray) -> None:
        self.factor, self.scale, self.cmat = factor, scale, cmat
        self._lock = threading.Lock()  # a lazy covariance may be read from several threads
        self.y = self.solve_a(cmat.T) if cmat.shape[0] else np.zeros((scale.size, 0))  # A^-1 C^T
        self.s = cmat @ self.y if cmat.shape[0] else np.zeros((0, 0))  # C A^-1 C^T

    @property
    def kind(self) -> str:
        """The factor's variant (:attr:`Factor.kind`)."""
        return self.factor.kind

    @property
    def single_precision(self) -> bool:
        """Whether its solves go through a float32 factor (:attr:`Factor.single_precision`)."""
        return self.factor.single_precision

    @property
    def structured(self) -> bool:
        """Whether it reads only the linked node blocks (:attr:`Factor.structured`)."""
        return self.factor.structured

    @classmethod
    def of(
        cls, a: FloatArray, cmat: FloatArray, blocks: NodeBlocks | None = None, scale: FloatArray | None = None
    ) -> ConstrainedFactor | None:
        """Factorise ``A`` (overwritten with its scaled form; or given already scaled as
        ``diag(scale) A diag(scale)``, ``scale`` the inverse square roots of its diagonal).

        With the node ``blocks`` of ``A`` (:class:`~rplearn.core.lsq.node_blocks.NodeBlocks`), a
        matrix whose nodes link to few others is factorised for what it is: as a band
        (:class:`BandedCholesky`, ``n kd^2`` work) when a reordering of the nodes makes the band
        at most :data:`BAND_FRACTION` of the columns wide (drones that link to their neighbours
        on a ring or a line; no shared columns), else, with at most
        :data:`SPARSE_BLOCK_FRACTION` of the node blocks non-zero, as a sparse matrix
        (:class:`SparseLU`), whose fill stays near the links instead of the ``n^3 / 3`` of a
        dense Cholesky (:class:`DenseCholesky`).
        """
        if scale is None:
            d = 1.0 / np.sqrt(np.maximum(np.diag(a), 1e-300))
            a *= d[:, None]
            a *= d[None, :]
        else:
            d = scale
        n = a.shape[0]
        layout = cls.layout(blocks, n)
        if layout != "dense" and blocks is not None:
            return cls._structured(a, np.ones(n), np.zeros(n), cmat, blocks, layout, d)
        factor = DenseCholesky.of(a)
        return None if factor is None else cls(factor, d, cmat)

    @classmethod
    def of_gram(cls, gram: FloatArray, added: FloatArray, scale: FloatArray, cmat: FloatArray,
                blocks: NodeBlocks | None, refined: bool = False) -> ConstrainedFactor | None:
        """:meth:`of` for ``A = S (G + diag(added)) S`` (``S = diag(scale)``), reading from the
        Gram ``G`` only what the layout needs: a band or the linked blocks, scaled on the way
        (no scaled copy of the whole matrix); a dense matrix in single precision with refined
        solves when ``refined`` and every column is regularised (``added > 0``: a matrix only
        positive semi-definite could pass in single precision and be solved where float64 would
        refuse it; :meth:`refined`, float64 when that fails)."""
        n = gram.shape[0]
        layout = cls.layout(blocks, n)
        if layout != "dense" and blocks is not None:
            return cls._structured(gram, scale, added * scale**2, cmat, blocks, layout, scale)
        if refined and np.all(added > 0):  # positive definite in exact arithmetic: else float64 decides
            out = cls.refined(gram, added, scale, cmat)
            if out is not None:
                return out
        return cls.of(scaled_double(gram, scale, added), cmat, scale=scale)

    @classmethod
    def _structured(cls, source: FloatArray, s: FloatArray, diagonal: FloatArray, cmat: FloatArray,
                    blocks: NodeBlocks, layout: str, scale: FloatArray) -> ConstrainedFactor | None:
        """The banded or sparse factor of ``diag(s) source diag(s) + diag(diagonal)`` (the
        scaled matrix ``A``; ``scale`` its scaling from the unscaled system)."""
        factor: StructuredFactor | None
        if layout == "banded":
            order, kd = blocks.band()
            factor = BandedCholesky.of(band_of(source, s, diagonal, order, kd, blocks.n_coef), order)
        else:
            factor = SparseLU.of(blocks.sparse(source, s, diagonal))
        return None if factor is None else cls(factor, scale, cmat)

    @staticmethod
    def layout(blocks: NodeBlocks | None, n: int) -> str:
        """How :meth:`of` factorises a matrix of ``n`` columns with these node ``blocks``:
        ``"banded"``, ``"sparse"`` or ``"dense"``."""
        if blocks is not None and blocks.n_nodes * blocks.n_coef == n and blocks.band()[1] < BAND_FRACTION * n:
            return "banded"
        if blocks is not None and blocks.fraction <= SPARSE_BLOCK_FRACTION:
            return "sparse"
        return "dense"

    @classmethod
    def refined(cls, gram: FloatArray, added: FloatArray, scale: FloatArray,
                cmat: FloatArray) -> ConstrainedFactor | None:
        """The dense factor of ``A = S (G + diag(added)) S`` (``S = diag(scale)``) in single
        precision, solves refined to double (:class:`~rplearn.core.lsq.refined.RefinedCholesky`):
        about half the time of :meth:`of`'s float64 factor for thousands of columns. None when
        the single-precision factorisation fails (then use :meth:`of`). ``gram`` is read, not
        copied, and must not change while the factor is in use."""
        factor = RefinedCholesky.of(gram, scale, added)
        if factor is None:
            return None
        return cls(factor, scale, cmat)

    def _to_double(self) -> None:
        """Replace a single-precision factor by the float64 one (a solve did not converge, or the
        whole inverse is asked for)."""
        if not isinstance(self.factor, RefinedCholesky):
            return
        dense = DenseCholesky.of(self.factor.as_double())
        if dense is None:
            raise NotPositiveDefinite("the regularised matrix is not positive definite")
        self.factor = dense
        if self.cmat.shape[0]:  # the constraint's products again, consistent with the new factor
            self.y = self.solve_a(self.cmat.T)
            self.s = self.cmat @ self.y

    def approximate_a(self, b: FloatArray) -> FloatArray:
        """``A^-1 b`` to single precision when the factor is (no corrections: for the spectrum's
        Krylov iterations, whose Ritz values come from ``G`` itself), else :meth:`solve_a`."""
        d = self.scale if b.ndim == 1 else self.scale[:, None]
        return self.factor.approximate(b * d) * d

    def solve_a(self, b: FloatArray) -> FloatArray:
        """``A^-1 b`` (``b`` a vector or a block of columns)."""
        d = self.scale if b.ndim == 1 else self.scale[:, None]
        x = self.factor.solve(b * d)
        if x is None:  # too ill-conditioned for single precision: the float64 factor
            self._to_double()
            return self.solve_a(b)
        return x * d

    def solve(self, b: FloatArray) -> FloatArray:
        """``M b``: the constrained solution of ``A x = b`` with ``C x = 0``."""
        x = self.solve_a(b)
        if self.cmat.shape[0]:
            x = x - self.y @ np.linalg.solve(self.s, self.cmat @ x)
        return x

    def particular(self, value: FloatArray) -> FloatArray:
        """The part of the constrained solution a constraint value ``C x = value`` adds."""
        if not self.cmat.shape[0] or not np.any(value != 0):
            return np.zeros(self.scale.size)
        return self.y @ np.linalg.solve(self.s, value)

    def diagonal_at(self, index: NDArray[np.intp]) -> FloatArray:
        """``M[i, i]`` for the given columns (a solve each)."""
        if not len(index):
            return np.zeros(0)
        e = np.zeros((self.scale.size, len(index)))
        e[np.asarray(index), np.arange(len(index))] = 1.0
        return np.einsum("ij,ij->j", e, self.solve(e))

    def inverse(self) -> FloatArray:
        """``M`` itself (``n^3`` work: only when the whole covariance is asked for)."""
        with self._lock:  # one conversion, and no reader between its two assignments
            if self.factor.single_precision:
                self._to_double()
        factor = self.factor
        if isinstance(factor, StructuredFactor):  # the inverse is dense: factorise densely now (n sparse solves are slow)
            dense = ConstrainedFactor.of(factor.scaled_dense() / np.outer(self.scale, self.scale), self.cmat)
            if dense is None:
                raise NotPositiveDefinite("the regularised matrix is not positive definite")
            return dense.inverse()
        if not isinstance(factor, DenseCholesky):
            raise NotImplementedError(f"no inverse from a {type(factor).__name__} factor")
        inv = factor.inverse()  # its lower triangle
        inv *= self.scale[:, None]
        inv *= self.scale[None, :]
        if self.cmat.shape[0]:
            inv -= self.y @ np.linalg.solve(self.s, self.y.T)
        return symmetric_from_lower(inv)


__all__ = ["BAND_FRACTION", "SPARSE_BLOCK_FRACTION", "BandedCholesky", "ConstrainedFactor", "DenseCholesky", "Factor",
           "NotPositiveDefinite", "SparseLU", "StructuredFactor", "band_of", "symmetric_from_lower"]
