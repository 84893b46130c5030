"""What a joint solve returns (the solution, its report, its gauge notes and warnings), and the
closing arithmetic that makes it (:func:`close_solution`: residual, variance, covariance).

Kept apart from :mod:`rplearn.core.lsq.solver` so that the solver's two paths (the KKT inverse,
and the factor of :mod:`rplearn.core.lsq.solver_large` above ``LARGE_COLUMNS`` columns) share
them: each gives what it solved as a :class:`SolvedSystem`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol

import numpy as np
from numpy.typing import NDArray

from rplearn.core.lsq.normal_equations import NormalEquations

FloatArray = NDArray[np.float64]

#: Condition numbers above this get a warning in the fit report.
CONDITION_WARNING = 1e4


@dataclass(frozen=True)
class GaugeNote:
    """How the free constant of one bipartite component was fixed."""

    nodes: tuple[str, ...]
    side_a: tuple[str, ...]
    side_b: tuple[str, ...]
    rule: str
    text: str

    def to_dict(self) -> dict[str, Any]:
        return {"nodes": list(self.nodes), "side_a": list(self.side_a), "side_b": list(self.side_b), "rule": self.rule, "text": self.text}


@dataclass(frozen=True)
class FitReport:
    """Numerical health of a fit (paper Sec. V-A, V-C).

    Attributes
    ----------
    n_samples : int
    n_columns : int
        Columns of the joint design matrix (``n_nodes * n_coef``).
    rank : int
        Numerical rank of the design matrix (singular values above
        ``s_max * sqrt(n_columns * eps)``, judged on ``X^T X``).
    null_dim : int
        ``n_columns - rank``.
    condition_number : float
        Largest / smallest non-zero singular value of the design matrix.
    expected_null_dim : int
        Free constants the link graph predicts (one per bipartite component).
    gauges : tuple of GaugeNote
    ridge : float
    rmse_db : float
        Training RMSE [dB].
    singular_values : ndarray
        All singular values of the design matrix, descending.
    """

    n_samples: int
    n_columns: int
    rank: int
    null_dim: int
    condition_number: float
    expected_null_dim: int
    gauges: tuple[GaugeNote, ...]
    ridge: float
    rmse_db: float
    singular_values: FloatArray = field(repr=False)
    warnings: tuple[str, ...] = ()

    @property
    def decoupled(self) -> bool:
        """True when the only unidentified directions are the gauge constants."""
        return self.null_dim == self.expected_null_dim

    def to_dict(self) -> dict[str, Any]:
        return {
            "n_samples": self.n_samples,
            "n_columns": self.n_columns,
            "rank": self.rank,
            "null_dim": self.null_dim,
            "expected_null_dim": self.expected_null_dim,
            "condition_number": self.condition_number,
            "ridge": self.ridge,
            "rmse_db": self.rmse_db,
            "gauges": [g.to_dict() for g in self.gauges],
            "warnings": list(self.warnings),
        }


@dataclass(frozen=True)
class JointSolution:
    """Coefficients of every node's pattern and the fit's report.

    ``coef[k]`` are the coefficients of node ``k``; ``covariance`` is the estimated covariance
    of all coefficients (``n_columns x n_columns``, gauge-constrained), from the residual
    variance; it gives the standard error of any pattern value or prediction.
    """

    coef: FloatArray
    covariance_matrix: FloatArray | None
    residual_variance_db2: float
    report: FitReport
    shared: tuple[tuple[Any, ...], ...] = ()
    shared_coef: FloatArray = field(default_factory=lambda: np.zeros(0))
    #: per shared column, the fraction (0..1) of its spread the other columns do not explain
    shared_unexplained: FloatArray = field(default_factory=lambda: np.zeros(0))
    #: large systems: computes the covariance on first use (an ``n^3`` inverse nobody may need)
    covariance_fn: Callable[[], FloatArray] | None = field(default=None, repr=False, compare=False)

    @property
    def covariance(self) -> FloatArray:
        """The covariance of all coefficients; formed on first use for large systems."""
        if self.covariance_matrix is None and self.covariance_fn is not None:
            object.__setattr__(self, "covariance_matrix", self.covariance_fn())  # frozen: set once
            object.__setattr__(self, "covariance_fn", None)
        return self.covariance_matrix  # type: ignore[return-value]


def fit_warnings(label: str, n_columns: int, rank: int, n_gauges: int, cond: float, ridge: float) -> list[str]:
    """Plain-language warnings about a fit whose samples barely identify the model."""
    out = []
    if n_columns - rank > n_gauges:
        out.append(
            f"{n_columns - rank - n_gauges} direction(s) of {label} are not identified by the samples "
            f"(rank {rank} of {n_columns}); the ridge ({ridge:g}) decides them: add headings or lower the order"
        )
    if cond > CONDITION_WARNING:
        out.append(
            f"condition number {cond:.3g}: the flight left directions (nearly) uncovered, and predictions "
            "there are extrapolations; check the coverage, add headings, or lower the order"
        )
    return out


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


__all__ = ["CONDITION_WARNING", "FitReport", "GaugeNote", "JointSolution", "Regularisation", "SolvedSystem",
           "close_solution", "fit_warnings", "unexplained_fraction"]
