"""The result of choosing a pattern's order and smoothing (:mod:`rplearn.core.lsq.selection`,
which re-exports these names): the choice and the validation curve behind it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rplearn.core.lsq.penalty import DEFAULT_PENALTY_POWER


@dataclass(frozen=True)
class CurvePoint:
    """Validation error of one (order, smoothing) pair."""

    order: int
    smoothing: float
    rmse_db: float

    def to_dict(self) -> dict[str, Any]:
        return {"order": self.order, "smoothing": self.smoothing, "rmse_db": self.rmse_db}


@dataclass
class Selection:
    """The chosen order and smoothing, and the validation curve behind the choice.

    Attributes
    ----------
    method : str
        ``"grouped-cv"`` (held-out flight units) or ``"gcv"`` (one unit).
    order : int
    smoothing : float
        Relative smoothing (see the module docstring).
    rmse_db : float
        Validation RMSE at the choice [dB] (GCV: its RMSE-equivalent ``sqrt(GCV)``).
    curve : list of CurvePoint
        Every (order, smoothing) evaluated, in the order of the search.
    units : list of str
        The units held out in turn (empty for GCV).
    power : float
        Exponent of the SH roughness weights.
    variance_inflation : float
        Factor (at least 1) by which the held-out units' squared errors *within* each unit
        (each unit's mean residual removed) exceed what the posterior covariance of the folds'
        fits predicts (see :func:`rplearn.core.lsq.selection.variance_inflation`); 1 for GCV.
    flight_level_std_db : float
        Standard deviation [dB] of a unit's (flight's) own level about the common level, from
        the held-out units' mean residuals (see :func:`rplearn.core.lsq.selection.variance_inflation`); 0 for GCV.
    held_out_excess_db2 : float
        Mean square [dB^2] per held-out sample by which the held-out units' errors about their
        own means exceed the folds' within-unit noise (the part of the held-out error that is
        the pattern's: the folds' posterior variance and any misfit the model cannot represent;
        :func:`rplearn.models.auto_spread.held_out_misfit_var`); 0 for GCV.
    ties : list of (int, float, float)
        ``(order, smoothing, variance_inflation)`` of every evaluated point the held-out units
        cannot tell from the best (:func:`rplearn.core.lsq.ties.tied_points`), the best first;
        the own-pattern spread averages their posteriors. Empty for GCV.
    """

    method: str
    order: int
    smoothing: float
    rmse_db: float
    curve: list[CurvePoint] = field(default_factory=list)
    units: list[str] = field(default_factory=list)
    power: float = DEFAULT_PENALTY_POWER
    variance_inflation: float = 1.0
    flight_level_std_db: float = 0.0
    held_out_excess_db2: float = 0.0
    ties: list[tuple[int, float, float]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {"method": self.method, "order": self.order, "smoothing": self.smoothing, "rmse_db": self.rmse_db,
                "power": self.power, "units": list(self.units), "variance_inflation": self.variance_inflation,
                "flight_level_std_db": self.flight_level_std_db,
                "held_out_excess_db2": self.held_out_excess_db2, "curve": [p.to_dict() for p in self.curve],
                "ties": [list(t) for t in self.ties]}

    def curve_text(self) -> str:
        """The validation curve as a small table (order, smoothing, RMSE), the choice marked."""
        lines = [f"{'order':>5} {'smoothing':>10} {'rmse_db':>8}"]
        for p in sorted(self.curve, key=lambda q: (q.order, q.smoothing)):
            mark = "  <- chosen" if (p.order, p.smoothing) == (self.order, self.smoothing) else ""
            lines.append(f"{p.order:>5} {p.smoothing:>10.1e} {p.rmse_db:>8.3f}{mark}")
        return "\n".join(lines)


__all__ = ["CurvePoint", "Selection"]
