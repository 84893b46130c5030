"""The closing arithmetic of a joint solve, one for both of the solver's paths: residual,
residual variance, the covariance the regularisation calls for, the fit report, the solution.

The dense path (the KKT inverse, :mod:`rplearn.core.lsq.solver`) and the large path (one
factor, :mod:`rplearn.core.lsq.solver_large`) each give what they solved as a
:class:`SolvedSystem`; :func:`close_solution` does the rest.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np
from numpy.typing import NDArray

from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.solution import FitReport, GaugeNote, JointSolution, fit_warnings

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Regularisation:
    """How a joint solve was regularised.

    Attributes
    ----------
    ridge : float
        The ridge on the pattern columns.
    penalised : bool
        A smoothness penalty (or a prior) was added: the covariance is the posterior's.
    shrunk : bool
        Any regularisation at all (a ridge or a penalty above zero).
    """

    ridge: float
    penalised: bool
    shrunk: bool

    @property
    def sandwich(self) -> bool:
        """Whether the covariance is the sandwich ``s^2 M X^T X M`` (a ridge alone: the estimate's
        sampling covariance), not ``s^2 M`` (a penalty read as a Gaussian prior, whose posterior
        covariance returns to the prior's variance where the data are absent; or no
        regularisation, where the two agree). ``M`` is the constrained inverse of the
        regularised normal matrix."""
        return self.shrunk and not self.penalised


class SolvedSystem(Protocol):
    """What :func:`close_solution` needs from a solve path: the dense path's KKT inverse
    (:mod:`rplearn.core.lsq.solver`) or the large path's factor
    (:mod:`rplearn.core.lsq.solver_large`)."""

    #: whether the covariance is formed only when first read (an ``n^3`` inverse nobody may need)
    lazy: ClassVar[bool]

    def fitted_square(self, gram: FloatArray, coef: FloatArray) -> float:
        """``coef^T X^T X coef`` (``gram``: ``X^T X``), in the BLAS of the path."""
        ...

    def inverse_diagonal(self, index: NDArray[np.intp]) -> FloatArray:
        """The constrained inverse's diagonal ``M[i, i]`` at the given columns."""
        ...

    def covariance(self, variance: float, sandwich: bool) -> FloatArray:
        """``variance * M X^T X M`` when ``sandwich``, else ``variance * M`` (exactly symmetric)."""
        ...


def close_solution(
    normal: NormalEquations, coef: FloatArray, spectrum: tuple[FloatArray, int, float],
    gauges: Sequence[GaugeNote], n_constraints: int, regularisation: Regularisation, system: SolvedSystem,
) -> JointSolution:
    """The solution of both solve paths from its coefficients: training residual, residual
    variance (over ``n_samples - rank`` degrees of freedom), the covariance the
    ``regularisation`` calls for (:attr:`Regularisation.sandwich`), the fit report and its
    warnings, and each shared column's unexplained fraction.

    Parameters
    ----------
    normal : NormalEquations
        The statistics solved.
    coef : ndarray
        Every column's coefficient (patterns, then shared columns).
    spectrum : (singular values, rank, condition number)
        Of the design matrix (exact or estimated).
    gauges : sequence of GaugeNote
        How each free constant was fixed.
    n_constraints : int
        Gauge constraints (the null dimension the link graph predicts).
    regularisation : Regularisation
    system : SolvedSystem
        What the path solved.
    """
    sv, rank, cond = spectrum
    pcols, pat = normal.n_columns, normal.n_pattern_columns
    ridge = regularisation.ridge
    unexplained = unexplained_fraction(normal, system.inverse_diagonal(np.arange(pat, pcols)))
    sse = max(float(normal.yty - 2.0 * coef @ normal.rhs + system.fitted_square(normal.gram, coef)), 0.0)
    resid_var = sse / max(normal.n_samples - min(rank, pcols), 1)
    sandwich = regularisation.sandwich

    def covariance() -> FloatArray:
        return system.covariance(resid_var, sandwich)

    report = FitReport(
        n_samples=normal.n_samples, n_columns=pcols, rank=rank, null_dim=pcols - rank, condition_number=cond,
        expected_null_dim=n_constraints, gauges=tuple(gauges), ridge=float(ridge),
        rmse_db=float(np.sqrt(sse / normal.n_samples)), singular_values=sv,
        warnings=tuple(fit_warnings(normal.basis.label, pcols, rank, n_constraints, cond, ridge)),
    )
    return JointSolution(coef[:pat].reshape(normal.n_nodes, normal.basis.n_coef),
                         None if system.lazy else covariance(), float(resid_var), report,
                         tuple(normal.shared), coef[pat:].copy(), unexplained,
                         covariance_fn=covariance if system.lazy else None)


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


__all__ = ["Regularisation", "SolvedSystem", "close_solution", "unexplained_fraction"]
