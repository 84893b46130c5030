"""Spectra of the joint problem's normal matrix: the rank and condition number of a fit report.

:func:`spectrum_report` is exact (a full eigendecomposition): the rank and condition number the
fit report gives for every problem of up to :data:`rplearn.core.lsq.solver.LARGE_COLUMNS`
columns. Above that (swarms of tens of nodes) the solver uses :func:`spectrum_estimate`
(block Krylov iterations: a few matrix products and triangular solves), or
:func:`spectrum_from_factor` through the factor the solve made
(:class:`~rplearn.core.lsq.factor.ConstrainedFactor`), instead of a full eigendecomposition,
which grows as the cube of the columns with a large constant (3,000 columns: 3.3 s).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rplearn.core.bases import Basis
from rplearn.core.lsq.products import symmetric_product

if TYPE_CHECKING:
    from rplearn.core.lsq.factor import ConstrainedFactor

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


def _projector(null: FloatArray) -> Callable[[FloatArray], FloatArray]:
    """``x -> x`` with its components along the orthonormal columns of ``null`` removed."""
    def project(x: FloatArray) -> FloatArray:
        return x - null @ (null.T @ x) if null.size else x

    return project


def _from_extremes(gram: FloatArray, null: FloatArray, lam_max: float, lam_min: float, tol: float) -> tuple[FloatArray, int, float]:
    """``(sv, rank, cond)`` from the largest and the smallest non-zero eigenvalue found; the
    pivoted-Cholesky rank (:func:`_rank_deficient`) when the smallest is not above ``tol``."""
    if not lam_min > tol:
        return _rank_deficient(gram, lam_max, tol)
    sv = np.sqrt(np.array([lam_max, lam_min]))
    return sv, gram.shape[0] - null.shape[1], float(sv[0] / sv[1])


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
    ``gram`` are dense BLAS ones (:func:`~rplearn.core.lsq.products.symmetric_product`) unless
    ``product`` (``x -> gram @ x``) is given: for drones that link to few others, one that reads
    only the blocks that can be non-zero (:meth:`~rplearn.core.lsq.node_blocks.NodeBlocks.product`;
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
    project = _projector(null)

    def inverse(x: FloatArray) -> FloatArray:
        return factor.approximate_a(x * scale[:, None]) * scale[:, None]

    def refined_inverse(x: FloatArray) -> FloatArray:
        return factor.solve_a(x * scale[:, None]) * scale[:, None]

    start = rng.standard_normal((n, b))
    lam_min = float(_krylov_ritz(inverse, start, iterations, product, project)[0])
    if lam_min > tol and not lam_min > RIDGE_RESOLVES * ridge:
        return spectrum_estimate(gram, null, lam_max=lam_max)
    if factor.single_precision and not lam_min > lam_max * SINGLE_RESOLVES:
        # beyond what a single-precision inverse resolves (its Krylov vectors carry errors of
        # eps32 times the condition number, which can lift a free direction's Ritz value above
        # the rank tolerance): again with refined solves
        lam_min = float(_krylov_ritz(refined_inverse, start, iterations, product, project)[0])
    return _from_extremes(gram, null, lam_max, lam_min, tol)


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

        lam_min = float(_krylov_ritz(inverse, rng.standard_normal((n, b)), iterations, product, _projector(null))[0])
    return _from_extremes(gram, null, lam_max, lam_min, tol)


__all__ = ["RIDGE_RESOLVES", "SINGLE_RESOLVES", "null_directions", "spectrum_estimate", "spectrum_from_factor", "spectrum_report"]
