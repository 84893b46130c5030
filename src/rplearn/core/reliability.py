"""Scores of probability forecasts of a binary event: a link up or down.

A forecast ``p`` in [0, 1] (the predicted availability, :mod:`rplearn.core.availability`) is
scored against the outcome ``o`` (1 when the link was up: a packet arrived at or above the
sensitivity; 0 when it arrived weaker or the log marked the link lost) by the Brier score
``BS = mean((p - o)^2)`` (Brier 1950, Monthly Weather Review 78(1)), 0 for a perfect forecast.
Its skill against a reference forecast, here a constant: the base rate ``b`` of the learning
data, is ``BSS = 1 - BS / BS_ref`` with ``BS_ref = mean((b - o)^2)``: above 0 the forecast
beats the constant, 1 is perfect. The reliability table bins the forecasts (equal widths in
[0, 1]) and gives per bin the mean forecast, the observed share of up outcomes and the count:
a reliable forecast has the two alike (Wilks, Statistical Methods in the Atmospheric Sciences,
ch. 8).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from rplearn._argtypes import check_types
from rplearn.errors import InputError

#: Bins of the reliability table (equal widths in [0, 1]).
RELIABILITY_BINS = 10


def _pair(forecast: ArrayLike, outcome: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Finite forecasts in [0, 1] and their 0/1 outcomes, checked (NaN forecasts left out)."""
    p = np.asarray(forecast, np.float64).ravel()
    o = np.asarray(outcome, np.float64).ravel()
    if p.shape != o.shape:
        raise InputError(f"outcome: {o.size} outcome(s) for {p.size} forecast(s)", param="outcome")
    if np.any((p < 0) | (p > 1)):
        raise InputError("forecast: a probability is outside [0, 1]", param="forecast")
    if not np.all((o == 0) | (o == 1)):
        raise InputError("outcome: expected 0/1 (or False/True) outcomes", param="outcome")
    ok = np.isfinite(p)
    return p[ok], o[ok]


@check_types
def brier_score(forecast: ArrayLike, outcome: ArrayLike) -> float:
    """Mean squared difference between probability forecasts and 0/1 outcomes (NaN when none).

    Raises
    ------
    InputError
        Forecasts outside [0, 1], outcomes other than 0/1, or different lengths.
    """
    p, o = _pair(forecast, outcome)
    return float(np.mean((p - o) ** 2)) if p.size else float("nan")


@check_types
def brier_skill(forecast: ArrayLike, outcome: ArrayLike, reference: float) -> float:
    """Skill ``1 - BS / BS_ref`` of the forecasts against a constant forecast ``reference`` in
    [0, 1] (NaN when the reference scores 0: every outcome equal to it).

    Raises
    ------
    InputError
        As :func:`brier_score`, or a reference outside [0, 1].
    """
    if not 0.0 <= reference <= 1.0:
        raise InputError(f"reference: expected a probability in [0, 1], got {reference!r}", param="reference")
    p, o = _pair(forecast, outcome)
    ref = float(np.mean((reference - o) ** 2)) if o.size else float("nan")
    if not ref > 0:
        return float("nan")
    return 1.0 - float(np.mean((p - o) ** 2)) / ref


@check_types
@dataclass(frozen=True)
class ReliabilityTable:
    """Forecasts binned by value: per bin, the mean forecast, the observed share and the count.

    Attributes
    ----------
    edges : ndarray (bins + 1,)
        Bin edges in [0, 1]; a forecast of exactly 1 falls in the last bin.
    mean_forecast, observed_share : ndarray (bins,)
        Mean forecast and share of up outcomes per bin (NaN for an empty bin).
    count : ndarray (bins,) of int
        Forecasts per bin.
    """

    edges: np.ndarray
    mean_forecast: np.ndarray
    observed_share: np.ndarray
    count: np.ndarray

    def rows(self) -> list[dict[str, float | int]]:
        """The non-empty bins as rows: ``from``, ``to``, ``mean_forecast``, ``observed_share``, ``count``."""
        return [{"from": float(self.edges[i]), "to": float(self.edges[i + 1]),
                 "mean_forecast": float(self.mean_forecast[i]), "observed_share": float(self.observed_share[i]),
                 "count": int(self.count[i])} for i in np.flatnonzero(self.count)]

    def markdown(self) -> str:
        """The non-empty bins as a Markdown table."""
        lines = ["| predicted availability | mean prediction | observed share up | samples |", "|---|---:|---:|---:|"]
        lines += [f"| {r['from']:.1f}-{r['to']:.1f} | {r['mean_forecast']:.3f} | {r['observed_share']:.3f} | "
                  f"{r['count']:,} |" for r in self.rows()]
        return "\n".join(lines)


@check_types
def reliability_table(forecast: ArrayLike, outcome: ArrayLike, bins: int = RELIABILITY_BINS) -> ReliabilityTable:
    """Bin forecasts into ``bins`` equal widths of [0, 1]: mean forecast, observed share, count.

    Raises
    ------
    InputError
        As :func:`brier_score`, or fewer than 1 bin.
    """
    if bins < 1:
        raise InputError(f"bins: expected at least 1, got {bins!r}", param="bins")
    p, o = _pair(forecast, outcome)
    edges = np.linspace(0.0, 1.0, bins + 1)
    which = np.clip(np.searchsorted(edges, p, side="right") - 1, 0, bins - 1)
    count = np.bincount(which, minlength=bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_p = np.bincount(which, p, bins) / count
        share = np.bincount(which, o, bins) / count
    return ReliabilityTable(edges, np.where(count > 0, mean_p, np.nan), np.where(count > 0, share, np.nan),
                            count.astype(np.int64))


__all__ = ["RELIABILITY_BINS", "ReliabilityTable", "brier_score", "brier_skill", "reliability_table"]
