"""What a joint solve returns: the solution, its report, its gauge notes and warnings.

Kept apart from :mod:`rplearn.core.lsq.solver` so that the solver's paths (the KKT inverse and
the large-system Cholesky of :mod:`rplearn.core.lsq.solver_large`) share them; they make it
through :func:`rplearn.core.lsq.closing.close_solution`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rplearn._argtypes import check_types

FloatArray = NDArray[np.float64]

#: Condition numbers above this get a warning in the fit report.
CONDITION_WARNING = 1e4


@check_types
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


@check_types
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


@check_types
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


__all__ = ["CONDITION_WARNING", "FitReport", "GaugeNote", "JointSolution", "fit_warnings"]
