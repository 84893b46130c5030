"""The joint solve above :data:`rplearn.core.lsq.solver.LARGE_COLUMNS` columns (swarms of tens of nodes).

One Cholesky factorisation of the regularised, gauge-constrained system
(:class:`~rplearn.core.lsq.factor.ConstrainedFactor`) gives the coefficients and the spectrum
estimate (:func:`~rplearn.core.lsq.spectrum.spectrum_from_factor`, reusing the factor); the
covariance, an ``n^3`` inverse, is formed only when ``JointSolution.covariance`` is first
read (:class:`FactorInverse`; the closing arithmetic is the dense path's,
:func:`~rplearn.core.lsq.closing.close_solution`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from rplearn.core.lsq.closing import Regularisation, close_solution
from rplearn.core.lsq.factor import ConstrainedFactor, symmetric_from_lower
from rplearn.core.lsq.node_blocks import NodeBlocks
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.products import symmetric_product
from rplearn.core.lsq.solution import GaugeNote, JointSolution
from rplearn.core.lsq.spectrum import null_directions, spectrum_estimate, spectrum_from_factor
from rplearn.core.threads import numpy_blas_one_thread
from rplearn.errors import NotPositiveDefinite

FloatArray = NDArray[np.float64]

#: From this many columns a dense system is factorised in single precision with refined solves
#: (:meth:`~rplearn.core.lsq.factor.ConstrainedFactor.refined`): there the factorisation's
#: ``n^3 / 3`` dominates; below it the refinement's matrix products would not pay for themselves.
REFINED_COLUMNS = 2000


def solve_large(
    normal: NormalEquations, n_nodes: int, components: list[tuple[list[int], Any]],
    constraints: tuple[FloatArray, FloatArray], rhs: FloatArray, penalty: FloatArray | None,
    regularisation: Regularisation, notes: list[GaugeNote],
) -> JointSolution | None:
    """:func:`solve` above :data:`LARGE_COLUMNS` columns: one Cholesky factorisation of the
    regularised system (:class:`~rplearn.core.lsq.factor.ConstrainedFactor`) gives the
    coefficients, the spectrum estimate (reusing the factor when the only regularisation is
    the ridge) and, on first use only, the covariance. None when the regularised matrix is not
    positive definite (the KKT path then decides).

    ``constraints`` are the gauge constraints ``(C, d)`` (``C p = d``), ``penalty`` the
    smoothness weights per column (or None), ``regularisation`` the ridge and what it implies
    for the covariance.

    The heavy work runs in scipy's BLAS, with numpy's (a second library in the wheels) held to
    one thread meanwhile (:func:`~rplearn.core.threads.numpy_blas_one_thread`)."""
    import scipy.linalg  # noqa: F401  (loaded before the limit looks for scipy's BLAS)

    with numpy_blas_one_thread():
        try:
            return _solve_large(normal, n_nodes, components, constraints, rhs, penalty, regularisation, notes)
        except NotPositiveDefinite:  # single precision solved what float64 cannot factorise: the KKT path decides
            return None


def _solve_large(
    normal: NormalEquations, n_nodes: int, components: list[tuple[list[int], Any]],
    constraints: tuple[FloatArray, FloatArray], rhs: FloatArray, penalty: FloatArray | None,
    regularisation: Regularisation, notes: list[GaugeNote],
) -> JointSolution | None:
    cmat, cval = constraints
    ridge = regularisation.ridge
    pcols, pat = normal.n_columns, normal.n_pattern_columns
    added = np.zeros(pcols)
    added[:pat] = ridge  # the shared columns are not shrunk
    if penalty is not None:
        added += penalty
    scale = 1.0 / np.sqrt(np.maximum(np.diag(normal.gram) + added, 1e-300))  # a unit diagonal
    blocks = NodeBlocks.of(n_nodes, normal.basis.n_coef, normal.link_counts)
    factor = ConstrainedFactor.of_gram(normal.gram, added, scale, cmat, blocks, refined=pcols >= REFINED_COLUMNS)
    if factor is None:
        return None
    if factor.single_precision:  # its solves and the lazy covariance read the Gram: the next add copies it
        normal.gram.flags.writeable = False
    gram_u, unit = unit_shared_scaling(normal)
    null = null_directions(normal.basis, n_nodes, components, pcols)
    if penalty is None and ridge > 0:
        sv, rank, cond = spectrum_from_factor(gram_u, null, factor, 1.0 / unit, ridge=ridge,
                                              product=blocks.product(gram_u) if factor.structured else None)
    else:
        sv, rank, cond = spectrum_estimate(gram_u, null)
    del gram_u
    # more free directions than the gauge fixes: the regularised matrix is positive definite, so
    # the ridge decides them, as on the KKT path, and the report warns (fit_warnings)
    coef = factor.solve(rhs) + factor.particular(cval)
    return close_solution(normal, coef, (sv, rank, cond), notes, cmat.shape[0], regularisation,
                          FactorInverse(factor, ridge, pat))


class FactorInverse:
    """The large path's :class:`~rplearn.core.lsq.closing.SolvedSystem`: the constrained
    inverse ``M`` kept as its factor, the covariance formed when first read."""

    lazy: ClassVar[bool] = True

    def __init__(self, factor: ConstrainedFactor, ridge: float, n_pattern_columns: int) -> None:
        self.factor, self.ridge, self.n_pattern_columns = factor, ridge, n_pattern_columns

    def fitted_square(self, gram: FloatArray, coef: FloatArray) -> float:
        return float(coef @ symmetric_product(gram)(coef))  # scipy's BLAS, as the rest of the path

    def inverse_diagonal(self, index: NDArray[np.intp]) -> FloatArray:
        return self.factor.diagonal_at(index)

    def covariance(self, variance: float, sandwich: bool) -> FloatArray:
        m = self.factor.inverse()  # exactly symmetric
        if not sandwich:
            m *= variance  # the posterior's, or no regularisation at all
            return m
        # M G M = M - M D M for the constrained inverse M of G + D (D the ridge on the pattern
        # columns): one symmetric rank-k product instead of two general ones, its columns read
        # in Fortran order without a copy (M is symmetric: M^T's columns are M's)
        from scipy.linalg import blas

        pat = self.n_pattern_columns
        columns = m[:, :pat] if m.flags.f_contiguous else m.T[:, :pat]
        cov = blas.dsyrk(-self.ridge, columns, lower=1)  # its lower triangle
        cov += m
        cov *= variance
        del m
        return symmetric_from_lower(cov)


def unit_shared_scaling(normal: NormalEquations) -> tuple[FloatArray, FloatArray]:
    """``X^T X`` with every shared column scaled to the pattern columns' mean square, so that the
    rank and condition number reported say how well the samples identify the model, not in
    which units a shared column (dB per unit of exponent) happens to be written; and the
    column scale applied."""
    pat = normal.n_pattern_columns
    scale = np.ones(normal.n_columns)
    if pat == normal.n_columns:
        return normal.gram, scale
    diag = np.diag(normal.gram)
    unit = float(np.mean(diag[:pat])) if pat else 1.0
    scale[pat:] = np.sqrt(unit / np.maximum(diag[pat:], 1e-300))
    return normal.gram * scale[:, None] * scale[None, :], scale


__all__ = ["REFINED_COLUMNS", "FactorInverse", "solve_large", "unit_shared_scaling"]
