"""Spectra and factorisations of the joint problem's normal matrix, for the solver.

:func:`spectrum_report` is exact (a full eigendecomposition): the rank and condition number the
fit report gives for every problem of up to :data:`rplearn.core.solver.LARGE_COLUMNS`
columns. Above that (swarms of tens of nodes) the solver uses :func:`spectrum_estimate`
(block Krylov iterations: a few matrix products and triangular solves) and
:class:`ConstrainedFactor` (one Cholesky, the covariance only when read) instead of a full eigendecomposition and the inverse of
the KKT matrix, which grow as the cube of the columns with large constants (3,000 columns:
3.3 s of eigenvalues and 2.5 s of inverse).
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn.core.bases import Basis
from rplearn.core.blas import symmetric_product
from rplearn.core.node_blocks import NodeBlocks

FloatArray = NDArray[np.float64]


def spectrum_report(gram: FloatArray) -> tuple[FloatArray, int, float]:
    """Singular values of X (from X^T X), numerical rank and condition number."""
    eig = np.linalg.eigvalsh(gram)[::-1]
    eig = np.clip(eig, 0.0, None)
    sv = np.sqrt(eig)
    if sv.size == 0 or sv[0] == 0:
        return sv, 0, float("inf")
    tol = sv[0] * np.sqrt(gram.shape[0] * np.finfo(np.float64).eps)
    rank = int(np.sum(sv > tol))
    cond = float(sv[0] / sv[rank - 1]) if rank > 0 else float("inf")
    return sv, rank, cond


def null_directions(basis: Basis, n_nodes: int, components: list[tuple[list[int], Any]], n_columns: int) -> FloatArray:
    """The gauge's null directions of ``X^T X``: per bipartite component, the constant
    function +1 on one side's patterns and -1 on the other's (columns of unit norm)."""
    from rplearn.core.bases import fibonacci_grid_nodes

    p = basis.n_coef
    const = None
    cols = []
    for comp, side_b in components:
        if side_b is None or len(comp) < 2:
            continue
        if const is None:  # the coefficients of the constant function (only for bipartite components)
            az, el = fibonacci_grid_nodes(max(4 * p, 400))
            const = np.linalg.lstsq(basis.design(az, el), np.ones(az.size), rcond=None)[0]
        v = np.zeros(n_columns)
        for node in comp:
            v[node * p : (node + 1) * p] = -const if node in side_b else const
        cols.append(v / np.linalg.norm(v))
    return np.array(cols).T if cols else np.zeros((n_columns, 0))


def _krylov_ritz(
    apply: Any, start: FloatArray, steps: int, product: Any, project: Any = None, apply_is_gram: bool = False
) -> FloatArray:
    """Ritz values of ``gram`` on the block Krylov space ``span{X, KX, ..., K^steps X}`` of
    the operator ``apply`` (``K``) from the block ``start``, within the complement ``project``
    keeps (ascending); ``product`` multiplies by ``gram`` (:func:`symmetric_product`).

    Every block is kept (not only the last, as subspace iteration does), so ``steps``
    applications give a space ``steps + 1`` blocks wide whose extreme Ritz values converge
    like a Chebyshev polynomial of the spectrum: far faster on clustered eigenvalues. Each
    new block is orthogonalised against the earlier ones (twice); the Ritz values come from
    the space's orthonormal basis (its well-determined singular directions), so that they
    bound the extreme eigenvalues of ``gram`` on that complement from inside. When the
    operator is ``gram`` itself (``apply_is_gram``), its products with the blocks are reused.
    """
    keep = project if project is not None else (lambda x: x)
    blocks = [np.linalg.qr(keep(start))[0]]
    products = []
    for _ in range(steps):
        z = apply(blocks[-1])
        if apply_is_gram:
            products.append(z.copy())
        z = keep(z)
        for _ in range(2):
            for b in blocks:
                z -= b @ (b.T @ z)
        blocks.append(np.linalg.qr(z)[0])
    v = keep(np.hstack(blocks))
    u, s, wt = np.linalg.svd(v, full_matrices=False)
    good = s > s[0] * 1e-8
    u = u[:, good]
    if apply_is_gram and project is None:  # G u = (G v) w s^-1, G v known but for the last block
        gv = np.hstack([*products, product(blocks[-1])])
        gu = gv @ (wt[good].T / s[good])
    else:
        gu = product(u)
    return np.linalg.eigvalsh(u.T @ gu)


#: Krylov steps for the largest eigenvalue (usually well apart from the next: a few suffice).
LARGEST_STEPS = 3


def _largest_eigenvalue(product: Any, n: int, iterations: int, block: int, rng: np.random.Generator) -> float:
    start = rng.standard_normal((n, min(block, n)))
    return float(_krylov_ritz(product, start, min(iterations, LARGEST_STEPS), product, apply_is_gram=True)[-1])


def _rank_deficient(gram: FloatArray, lam_max: float, tol: float) -> tuple[FloatArray, int, float]:
    """More free directions than the gauge: the rank from a pivoted Cholesky (``dpstrf``)."""
    from scipy.linalg import lapack

    rank = int(lapack.dpstrf(gram.copy(), tol=tol)[2])
    return np.sqrt(np.array([lam_max, 0.0])), rank, float("inf")


#: The spectrum read through the regularised factor is trusted down to this many times the
#: ridge (there ``1 / (lam + ridge)`` differs from ``1 / lam`` by 1%); below it a factor of the
#: unregularised matrix decides (:func:`spectrum_from_factor`).
RIDGE_RESOLVES = 100.0
#: Smallest eigenvalue ratio ``lam_min / lam_max`` that the spectrum trusts from a
#: single-precision inverse (a hundred times float32's resolution); below it the smallest
#: eigenvalue is estimated again with refined solves (:func:`spectrum_from_factor`).
SINGLE_RESOLVES = 100 * float(np.finfo(np.float32).eps)


def spectrum_from_factor(
    gram: FloatArray, null: FloatArray, factor: ConstrainedFactor, scale: FloatArray, iterations: int = 4,
    block: int = 8, ridge: float = 0.0, product: Any = None,
) -> tuple[FloatArray, int, float]:
    """:func:`spectrum_estimate` reusing the Cholesky factor of the regularised system
    ``A = S^-1 G S^-1 + R`` (``G`` = ``gram``, the columns scaled by ``S``; ``R`` a ridge equal
    on the pattern columns, where the gauge's null directions lie), so that no second
    factorisation is needed: inverse block Krylov iterations with ``S A^-1 S = (G + R)^-1`` on the
    complement of the null directions (which are eigenvectors of both), then Rayleigh-Ritz
    with ``G`` itself. For fits whose only regularisation is that ridge; a smoothness penalty
    shifts the eigenvectors, and :func:`spectrum_estimate` is used instead. The products with
    ``gram`` are dense BLAS ones (:func:`~rplearn.core.blas.symmetric_product`) unless
    ``product`` (``x -> gram @ x``) is given: for drones that link to few others, one that reads
    only the blocks that can be non-zero (:meth:`~rplearn.core.node_blocks.NodeBlocks.product`;
    at 50 drones on a ring 1.3 ms per product against 8.4 ms dense, where a scipy sparse copy
    cost 53 ms to build and 8 ms per product).

    Where the smallest eigenvalue found is within :data:`RIDGE_RESOLVES` times the ``ridge``,
    the ridge masks the small end of the spectrum (``1 / (lam + ridge)`` no longer tells small
    eigenvalues apart: on a test matrix whose exact condition number was 1e5 the estimate was
    1.1e4), and :func:`spectrum_estimate` estimates it again through a factor of ``G`` itself.
    """
    n = gram.shape[0]
    rng = np.random.default_rng(0)
    product = symmetric_product(gram) if product is None else product
    lam_max = _largest_eigenvalue(product, n, iterations, block, rng)
    if not lam_max > 0:
        return np.zeros(1), 0, float("inf")
    tol = lam_max * n * np.finfo(np.float64).eps
    b = min(block, n)

    def project(x: FloatArray) -> FloatArray:
        return x - null @ (null.T @ x) if null.size else x

    def inverse(x: FloatArray) -> FloatArray:
        return factor.approximate_a(x * scale[:, None]) * scale[:, None]

    def refined_inverse(x: FloatArray) -> FloatArray:
        return factor.solve_a(x * scale[:, None]) * scale[:, None]

    start = rng.standard_normal((n, b))
    lam_min = float(_krylov_ritz(inverse, start, iterations, product, project)[0])
    if lam_min > tol and not lam_min > RIDGE_RESOLVES * ridge:
        return spectrum_estimate(gram, null, lam_max=lam_max)
    if factor.kind == "refined" and not lam_min > lam_max * SINGLE_RESOLVES:
        # beyond what a single-precision inverse resolves (its Krylov vectors carry errors of
        # eps32 times the condition number, which can lift a free direction's Ritz value above
        # the rank tolerance): again with refined solves
        lam_min = float(_krylov_ritz(refined_inverse, start, iterations, product, project)[0])
    if not lam_min > tol:
        return _rank_deficient(gram, lam_max, tol)
    sv = np.sqrt(np.array([lam_max, lam_min]))
    return sv, n - null.shape[1], float(sv[0] / sv[1])


def spectrum_estimate(
    gram: FloatArray, null: FloatArray, iterations: int = 8, block: int = 8, lam_max: float | None = None
) -> tuple[FloatArray, int, float]:
    """:func:`spectrum_report` for large systems, estimated: ``(sv, rank, cond)`` with ``sv``
    the largest and smallest non-zero singular values of the design matrix.

    The largest eigenvalue of ``X^T X`` by block Krylov iterations from ``block`` vectors
    (matrix products, not matrix-vector ones: the matrix is read ``iterations`` times, not
    hundreds), then Rayleigh-Ritz; the smallest non-zero one by inverse block Krylov iterations on
    ``X^T X + lam_max N N^T`` (``N`` the gauge's null directions, which it lifts out of the
    way) through its Cholesky factor. When that matrix is not positive definite, or its
    smallest eigenvalue is below the rank tolerance, the samples leave more directions free
    than the gauge: the rank then comes from a pivoted Cholesky factorisation (LAPACK
    ``dpstrf``) and the condition number is infinite. Within 3% of the exact condition number
    on the tested problems.
    """
    from scipy.linalg import solve_triangular

    n = gram.shape[0]
    b = min(block, n)
    rng = np.random.default_rng(0)
    product = symmetric_product(gram)
    if lam_max is None:  # (given when already estimated)
        lam_max = _largest_eigenvalue(product, n, iterations, block, rng)
    if not lam_max > 0:
        return np.zeros(1), 0, float("inf")
    tol = lam_max * n * np.finfo(np.float64).eps  # the eigenvalue form of spectrum_report's tolerance
    from scipy.linalg import lapack

    lifted = gram + lam_max * (null @ null.T) if null.size else gram
    # scipy's LAPACK, as the rest of a large solve (numpy's BLAS is held to one thread there);
    # a copy unless ``lifted`` is already one
    lower, info = lapack.dpotrf(lifted.T, lower=1, clean=0, overwrite_a=int(lifted is not gram))
    if info != 0:
        lower = None
    lam_min = 0.0
    if lower is not None:
        def inverse(x: FloatArray) -> FloatArray:
            z = solve_triangular(lower, x, lower=True, check_finite=False)
            return solve_triangular(lower, z, lower=True, trans="T", check_finite=False)

        def project(x: FloatArray) -> FloatArray:
            return x - null @ (null.T @ x) if null.size else x

        lam_min = float(_krylov_ritz(inverse, rng.standard_normal((n, b)), iterations, product, project)[0])
    if not lam_min > tol:
        return _rank_deficient(gram, lam_max, tol)
    sv = np.sqrt(np.array([lam_max, lam_min]))
    return sv, n - null.shape[1], float(sv[0] / sv[1])


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
    :meth:`~rplearn.core.node_blocks.NodeBlocks.band` gives), in LAPACK's band storage (row
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


class NotPositiveDefinite(ValueError):
    """The regularised matrix turned out not positive definite in float64 (after its
    single-precision factor's solves did not converge)."""


class ConstrainedFactor:
    """The constrained inverse ``M = A^-1 - A^-1 C^T (C A^-1 C^T)^-1 C A^-1`` of a symmetric
    positive definite ``A`` (the regularised normal matrix) and constraints ``C`` (the gauge),
    kept as a Cholesky factor of the diagonally scaled ``A``: products with ``M`` cost two
    triangular solves, and ``M`` itself is formed only when asked for (:meth:`inverse`).

    Build it with :meth:`of`, which gives None when ``A`` is not positive definite.
    """

    def __init__(self, factor: Any, scale: FloatArray, cmat: FloatArray, kind: str = "dense") -> None:
        self.factor, self.scale, self.cmat, self.kind = factor, scale, cmat, kind
        self.sparse_a: Any = None  # then also the scaled matrix itself (for the dense inverse)
        self.band: tuple[FloatArray, NDArray[np.intp]] | None = None  # "banded": the band and the column order
        self._lock = threading.Lock()  # a lazy covariance may be read from several threads
        self.y = self.solve_a(cmat.T) if cmat.shape[0] else np.zeros((scale.size, 0))  # A^-1 C^T
        self.s = cmat @ self.y if cmat.shape[0] else np.zeros((0, 0))  # C A^-1 C^T

    @property
    def sparse(self) -> bool:
        """Whether the factor is SuperLU's, of a block-sparse matrix."""
        return self.kind == "sparse"

    @classmethod
    def of(
        cls, a: FloatArray, cmat: FloatArray, blocks: NodeBlocks | None = None, scale: FloatArray | None = None
    ) -> "ConstrainedFactor | None":
        """Factorise ``A`` (overwritten with its scaled form; or given already scaled as
        ``diag(scale) A diag(scale)``, ``scale`` the inverse square roots of its diagonal).

        With the node ``blocks`` of ``A`` (:class:`~rplearn.core.node_blocks.NodeBlocks`), a
        matrix whose nodes link to few others is factorised for what it is: as a band (LAPACK
        ``dpbtrf``, ``n kd^2`` work) when a reordering of the nodes makes the band at most
        :data:`BAND_FRACTION` of the columns wide (drones that link to their neighbours on a
        ring or a line; no shared columns), else, with at most :data:`SPARSE_BLOCK_FRACTION`
        of the node blocks non-zero, as a sparse matrix (SuperLU with a minimum-degree ordering
        of ``A + A^T``, symmetric mode), whose fill stays near the links instead of the
        ``n^3 / 3`` of a dense Cholesky.
        """
        if scale is None:
            d = 1.0 / np.sqrt(np.maximum(np.diag(a), 1e-300))
            a *= d[:, None]
            a *= d[None, :]
        else:
            d = scale
        n = a.shape[0]
        layout = cls.layout(blocks, n)
        if layout != "dense" and blocks is not None:  # (a band or sparse layout needs the blocks)
            return cls._structured(a, np.ones(n), np.zeros(n), cmat, blocks, layout, d)
        from scipy.linalg import lapack

        # a is symmetric: its transpose is the same matrix in Fortran order, factorised in place
        factor, info = lapack.dpotrf(a.T, lower=1, clean=0, overwrite_a=1)
        if info != 0:
            return None
        return cls(factor, d, cmat)

    @classmethod
    def of_gram(cls, gram: FloatArray, added: FloatArray, scale: FloatArray, cmat: FloatArray,
                blocks: NodeBlocks | None, refined: bool = False) -> "ConstrainedFactor | None":
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
        from rplearn.core.refined import scaled_double

        return cls.of(scaled_double(gram, scale, added), cmat, scale=scale)

    @classmethod
    def _structured(cls, source: FloatArray, s: FloatArray, diagonal: FloatArray, cmat: FloatArray,
                    blocks: NodeBlocks, layout: str, scale: FloatArray) -> "ConstrainedFactor | None":
        """The banded or sparse factor of ``diag(s) source diag(s) + diag(diagonal)`` (the
        scaled matrix ``A``; ``scale`` its scaling from the unscaled system)."""
        if layout == "banded":
            order, kd = blocks.band()
            return cls._banded(band_of(source, s, diagonal, order, kd, blocks.n_coef), cmat, scale, order)
        from scipy.sparse.linalg import splu

        sparse_a = blocks.sparse(source, s, diagonal)
        try:
            lu = splu(sparse_a, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        except RuntimeError:  # exactly singular
            return None
        if not np.all(lu.U.diagonal() > 0):  # pivots of a positive definite matrix are positive
            return None
        out = cls(lu, scale, cmat, "sparse")
        out.sparse_a = sparse_a
        return out

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
                cmat: FloatArray) -> "ConstrainedFactor | None":
        """The dense factor of ``A = S (G + diag(added)) S`` (``S = diag(scale)``) in single
        precision, solves refined to double (:class:`~rplearn.core.refined.RefinedCholesky`):
        about half the time of :meth:`of`'s float64 factor for thousands of columns. None when
        the single-precision factorisation fails (then use :meth:`of`). ``gram`` is read, not
        copied, and must not change while the factor is in use."""
        from rplearn.core.refined import RefinedCholesky

        factor = RefinedCholesky.of(gram, scale, added)
        if factor is None:
            return None
        return cls(factor, scale, cmat, "refined")

    def _to_double(self) -> None:
        """Replace a refined factor by the float64 one (a solve did not converge, or the whole
        inverse is asked for)."""
        from scipy.linalg import lapack

        from rplearn.core.refined import scaled_double

        refined = self.factor
        a = scaled_double(refined.gram, self.scale, refined.added)
        factor, info = lapack.dpotrf(a.T, lower=1, clean=0, overwrite_a=1)
        if info != 0:
            raise NotPositiveDefinite("the regularised matrix is not positive definite")
        self.factor, self.kind = factor, "dense"
        if self.cmat.shape[0]:  # the constraint's products again, consistent with the new factor
            self.y = self.solve_a(self.cmat.T)
            self.s = self.cmat @ self.y

    def approximate_a(self, b: FloatArray) -> FloatArray:
        """``A^-1 b`` to single precision when the factor is refined (no corrections: for the
        spectrum's Krylov iterations, whose Ritz values come from ``G`` itself), else
        :meth:`solve_a`."""
        if self.kind != "refined":
            return self.solve_a(b)
        d = self.scale if b.ndim == 1 else self.scale[:, None]
        return self.factor.approximate(b * d) * d

    @classmethod
    def _banded(cls, band: FloatArray, cmat: FloatArray, d: FloatArray,
                order: NDArray[np.intp]) -> "ConstrainedFactor | None":
        """The factor of a band (:func:`band_of`) by ``dpbtrf``."""
        from scipy.linalg import lapack

        factor, info = lapack.dpbtrf(band, lower=1)
        if info != 0:
            return None
        out = cls((factor, order), d, cmat, "banded")
        out.band = (band, order)
        return out

    def solve_a(self, b: FloatArray) -> FloatArray:
        """``A^-1 b`` (``b`` a vector or a block of columns)."""
        d = self.scale if b.ndim == 1 else self.scale[:, None]
        if self.kind == "refined":
            x = self.factor.solve(b * d)
            if x is None:  # too ill-conditioned for single precision: the float64 factor
                self._to_double()
                return self.solve_a(b)
            return x * d
        if self.sparse:
            return self.factor.solve(np.asfortranarray(b * d)) * d
        from scipy.linalg import lapack

        if self.kind == "banded":
            factor, order = self.factor
            x = np.empty_like(b, dtype=np.float64)
            xo, info = lapack.dpbtrs(factor, np.asfortranarray((b * d)[order]), lower=1)
            if info != 0:
                raise ValueError(f"dpbtrs failed ({info})")
            x[order] = xo
            return x * d
        x, info = lapack.dpotrs(self.factor, np.asfortranarray(b * d), lower=1)
        if info != 0:
            raise ValueError(f"dpotrs failed ({info})")
        return x * d

    def scaled_dense(self) -> FloatArray:
        """The scaled matrix ``A`` as a dense array (sparse and banded factors)."""
        if self.sparse:
            return self.sparse_a.toarray()
        assert self.band is not None  # a factor is dense, sparse or banded
        band, order = self.band
        kd, n = band.shape[0] - 1, band.shape[1]
        dense = np.zeros((n, n))
        for k in range(kd + 1):
            rows, cols = order[k:], order[: n - k]
            dense[rows, cols] = band[k, : n - k]
            dense[cols, rows] = band[k, : n - k]
        return dense

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
            if self.kind == "refined":
                self._to_double()
        if self.kind != "dense":  # the inverse is dense: factorise densely now (n sparse solves are slow)
            dense = ConstrainedFactor.of(self.scaled_dense() / np.outer(self.scale, self.scale), self.cmat)
            if dense is None:
                raise ValueError("the regularised matrix is not positive definite")
            return dense.inverse()
        else:
            from scipy.linalg import lapack

            inv, info = lapack.dpotri(self.factor, lower=1)  # its lower triangle
            if info != 0:
                raise ValueError(f"dpotri failed ({info})")
            inv *= self.scale[:, None]
            inv *= self.scale[None, :]
        if self.cmat.shape[0]:
            inv -= self.y @ np.linalg.solve(self.s, self.y.T)
        return symmetric_from_lower(inv)


__all__ = ["BAND_FRACTION", "RIDGE_RESOLVES", "SINGLE_RESOLVES", "SPARSE_BLOCK_FRACTION", "ConstrainedFactor", "NotPositiveDefinite", "null_directions", "spectrum_estimate", "spectrum_from_factor", "spectrum_report",
           "symmetric_from_lower"]
