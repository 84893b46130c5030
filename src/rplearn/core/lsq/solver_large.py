"""The joint solve above :data:`rplearn.core.lsq.solver.LARGE_COLUMNS` columns (swarms of tens of nodes).

One Cholesky factorisation of the regularised, gauge-constrained system
(:class:`~rplearn.core.lsq.spectrum.ConstrainedFactor`) gives the coefficients and the spectrum
estimate (:func:`~rplearn.core.lsq.spectrum.spectrum_from_factor`, reusing the factor); the
covariance, an ``n^3`` inverse, is formed only when ``JointSolution.covariance`` is first
read.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.solution import FitReport, GaugeNote, JointSolution, fit_warnings
from rplearn.core.lsq.node_blocks import NodeBlocks
from rplearn.core.threads import numpy_blas_one_thread, symmetric_product
from rplearn.core.lsq.spectrum import (
    ConstrainedFactor, NotPositiveDefinite, null_directions, spectrum_estimate, spectrum_from_factor,
    symmetric_from_lower,
)

FloatArray = NDArray[np.float64]

#: From this many columns a dense system is factorised in single precision with refined solves
#: (:meth:`~rplearn.core.lsq.spectrum.ConstrainedFactor.refined`): there the factorisation's
#: ``n^3 / 3`` dominates; below it the refinement's matrix products would not pay for themselves.
REFINED_COLUMNS = 2000


def solve_large(
    normal: NormalEquations, n_nodes: int, components: list[tuple[list[int], Any]], cmat: FloatArray,
    cval: FloatArray, rhs: FloatArray, ridge: float, penalty: FloatArray | None, shrunk: bool,
    notes: list[GaugeNote],
) -> JointSolution | None:
    """:func:`solve` above :data:`LARGE_COLUMNS` columns: one Cholesky factorisation of the
    regularised system (:class:`~rplearn.core.lsq.spectrum.ConstrainedFactor`) gives the
    coefficients, the spectrum estimate (reusing the factor when the only regularisation is
    the ridge) and, on first use only, the covariance. None when the regularised matrix is not
    positive definite (the KKT path then decides).

    The heavy work runs in scipy's BLAS, with numpy's (a second library in the wheels) held to
    one thread meanwhile (:func:`~rplearn.core.threads.numpy_blas_one_thread`)."""
    import scipy.linalg  # noqa: F401  (loaded before the limit looks for scipy's BLAS)

    with numpy_blas_one_thread():
        try:
            return _solve_large(normal, n_nodes, components, cmat, cval, rhs, ridge, penalty, shrunk, notes)
        except NotPositiveDefinite:  # single precision solved what float64 cannot factorise: the KKT path decides
            return None


def _solve_large(
    normal: NormalEquations, n_nodes: int, components: list[tuple[list[int], Any]], cmat: FloatArray,
    cval: FloatArray, rhs: FloatArray, ridge: float, penalty: FloatArray | None, shrunk: bool,
    notes: list[GaugeNote],
) -> JointSolution | None:
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
    if factor.kind == "refined":  # its solves and the lazy covariance read the Gram: the next add copies it
        normal.gram.flags.writeable = False
    gram_u, unit = unit_shared_scaling(normal)
    null = null_directions(normal.basis, n_nodes, components, pcols)
    if penalty is None and ridge > 0:
        few_links = factor.kind in ("banded", "sparse")  # products of the linked blocks only
        sv, rank, cond = spectrum_from_factor(gram_u, null, factor, 1.0 / unit, ridge=ridge,
                                              product=blocks.product(gram_u) if few_links else None)
    else:
        sv, rank, cond = spectrum_estimate(gram_u, null)
    del gram_u
    k = cmat.shape[0]
    # more free directions than the gauge fixes: the regularised matrix is positive definite, so
    # the ridge decides them, as on the KKT path, and the report warns (fit_warnings)
    coef = factor.solve(rhs) + factor.particular(cval)
    unexplained = unexplained_fraction(normal, factor.diagonal_at(np.arange(pat, pcols)))
    sse = max(normal.yty - 2.0 * coef @ normal.rhs + coef @ symmetric_product(normal.gram)(coef), 0.0)
    resid_var = sse / max(normal.n_samples - min(rank, pcols), 1)

    def covariance() -> FloatArray:
        m = factor.inverse()  # exactly symmetric
        if penalty is not None or not shrunk:
            m *= resid_var  # the posterior's (see solve), or no regularisation at all
            return m
        # M G M = M - M D M for the constrained inverse M of G + D (D the ridge on the pattern
        # columns): one symmetric rank-k product instead of two general ones, its columns read
        # in Fortran order without a copy (M is symmetric: M^T's columns are M's)
        from scipy.linalg import blas

        columns = m[:, :pat] if m.flags.f_contiguous else m.T[:, :pat]
        cov = blas.dsyrk(-ridge, columns, lower=1)  # its lower triangle
        cov += m
        cov *= resid_var
        del m
        return symmetric_from_lower(cov)

    report = FitReport(
        n_samples=normal.n_samples, n_columns=pcols, rank=rank, null_dim=pcols - rank, condition_number=cond,
        expected_null_dim=k, gauges=tuple(notes), ridge=float(ridge), rmse_db=float(np.sqrt(sse / normal.n_samples)),
        singular_values=sv, warnings=tuple(fit_warnings(normal.basis.label, pcols, rank, k, cond, ridge)),
    )
    return JointSolution(coef[:pat].reshape(n_nodes, normal.basis.n_coef), None, float(resid_var), report,
                         tuple(normal.shared), coef[pat:].copy(), unexplained, covariance_fn=covariance)


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


def unexplained_fraction(normal: NormalEquations, shared_diag: FloatArray) -> FloatArray:
    """Per shared column, the fraction of its centred spread the other columns leave unexplained
    (``1 - R^2``): the Schur complement ``1 / (K^-1)_jj`` over ``sum (x - mean x)^2``
    (``shared_diag``: the diagonal of ``K^-1`` at the shared columns)."""
    pat = normal.n_pattern_columns
    out = np.ones(len(normal.shared))
    n = max(normal.n_samples, 1)
    for j, col in enumerate(normal.shared):
        i = pat + j
        total = float(normal.gram[i, i])
        if col[0] == "exponent":
            centred = total - normal.environment_sum**2 / n
        else:
            centred = total  # +-1 columns: their level is what they describe
        inv = float(shared_diag[j])
        if not (centred > 1e-9 * max(total, 1e-300)) or not (inv > 0):
            out[j] = 0.0
        else:
            out[j] = float(min(1.0, 1.0 / (inv * centred)))
    return out


__all__ = ["REFINED_COLUMNS", "solve_large", "unexplained_fraction", "unit_shared_scaling"]
