"""Predicted availability scored against what a log observed: ``evaluate --sensitivity``.

A sample is observed *up* when a packet arrived at or above the sensitivity ``s``
(``rssi_dbm >= s``) and *down* when it arrived weaker or the log marked the link lost there
(an outage event, ``outage`` True: :mod:`rplearn.data.outages`). The model's predicted
availability of every sample is ``P(RSSI >= s)`` from its predicted RSSI and spread
(:func:`rplearn.core.availability.link_availability`; a model without a spread, a baseline,
predicts a step). The scores (:mod:`rplearn.core.reliability`): the Brier score, its skill
against a constant forecast (the share of up samples in the data the model learned from) and
the reliability table.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.availability import link_availability
from rplearn.core.reliability import ReliabilityTable, brier_score, brier_skill, reliability_table
from rplearn.data.tables import outage_mask
from rplearn.data.units import dataset_units, select_units, trained_units
from rplearn.errors import InputError
from rplearn.models.base import Model
from rplearn.models.predict import predict_dataset


@check_types
def observed_up(df: pd.DataFrame, sensitivity_dbm: float, source: str = "dataset") -> np.ndarray:
    """Whether each row of a matched dataset was up: RSSI at or above ``sensitivity_dbm`` [dBm]
    and not an outage event."""
    if not np.isfinite(sensitivity_dbm):
        raise InputError(f"sensitivity_dbm: expected a finite level in dBm, got {sensitivity_dbm!r}",
                         param="sensitivity_dbm")
    rssi = pd.to_numeric(df["rssi_dbm"], errors="coerce").to_numpy(np.float64)
    with np.errstate(invalid="ignore"):
        return ~outage_mask(df, source) & (rssi >= float(sensitivity_dbm))


@check_types
@dataclass(frozen=True)
class AvailabilityScore:
    """One model's predicted availability scored on a dataset's samples (module docstring).

    Attributes
    ----------
    model : str
        The model's label.
    sensitivity_dbm : float
        The threshold [dBm].
    n_samples, n_outages, n_below : int
        Samples scored; of them outage events, and packets below the sensitivity.
    base_rate : float
        The constant forecast: the share of up samples in the learning data.
    brier, reference_brier, skill : float
        Brier score of the model, of the constant, and the skill ``1 - brier / reference_brier``.
    table : ReliabilityTable
        Mean prediction, observed share and count per bin of predicted availability.
    stepped : bool
        True when the model gives no spread (a step forecast).
    """

    model: str
    sensitivity_dbm: float
    n_samples: int
    n_outages: int
    n_below: int
    base_rate: float
    brier: float
    reference_brier: float
    skill: float
    table: ReliabilityTable
    stepped: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {"model": self.model, "sensitivity_dbm": self.sensitivity_dbm, "n_samples": self.n_samples,
                "n_outages": self.n_outages, "n_below": self.n_below, "base_rate": self.base_rate,
                "brier": self.brier, "reference_brier": self.reference_brier, "brier_skill": self.skill,
                "stepped": self.stepped, "reliability": self.table.rows()}

    def markdown(self) -> str:
        """A paragraph and the reliability table."""
        how = " (no predictive spread: a step forecast)" if self.stepped else ""
        return (f"**{self.model}**{how}: {self.n_samples:,} samples, {self.n_samples - self.n_outages - self.n_below:,} "
                f"up, {self.n_below:,} below {self.sensitivity_dbm:g} dBm, {self.n_outages:,} outage events; "
                f"Brier score {self.brier:.4f}, constant {self.base_rate:.3f} (the learning data's share up) "
                f"{self.reference_brier:.4f}, skill {self.skill:.3f}\n\n{self.table.markdown()}")


@check_types
def score_availability(model: Model, df: pd.DataFrame, sensitivity_dbm: float, base_rate: float,
                       source: str = "dataset") -> AvailabilityScore:
    """Score ``model``'s predicted availability on the rows of ``df`` (outage events included).

    Parameters
    ----------
    model : Model
        Any model; pattern models predict a spread, baselines a step.
    df : DataFrame
        Matched dataset rows to score (its ``outage`` column, if any, marks outage events).
    sensitivity_dbm : float
        The threshold [dBm].
    base_rate : float
        The constant forecast the skill is measured against (:func:`base_rate_of`).
    source : str
        Name of the dataset in messages.
    """
    up = observed_up(df, sensitivity_dbm, source)
    table = predict_dataset(model, df, source).table
    mean = table["rssi_pred_dbm"].to_numpy(np.float64)
    stepped = "rssi_pred_std_db" not in table
    std = np.zeros(len(table)) if stepped else table["rssi_pred_std_db"].to_numpy(np.float64)
    p = link_availability(mean, std, float(sensitivity_dbm))
    down = outage_mask(df, source)
    return AvailabilityScore(
        model.label, float(sensitivity_dbm), int(len(df)), int(down.sum()), int((~down & ~up).sum()),
        float(base_rate), brier_score(p, up), brier_score(np.full(len(up), float(base_rate)), up),
        brier_skill(p, up, float(base_rate)), reliability_table(p, up), stepped)


@check_types
def base_rate_of(df: pd.DataFrame, sensitivity_dbm: float, source: str = "dataset") -> float:
    """Share of up samples (outage events count as down) in ``df``: the constant forecast.

    Raises
    ------
    InputError
        When ``df`` has no rows.
    """
    if not len(df):
        raise InputError(f"{source}: no learning samples to take the base rate of availability from", param="units")
    return float(np.mean(observed_up(df, sensitivity_dbm, source)))


@check_types
def availability_markdown(scores: Sequence[AvailabilityScore]) -> str:
    """The scores of several models as a Markdown section."""
    if not scores:
        return ""
    s = scores[0]
    return (f"## Availability at {s.sensitivity_dbm:g} dBm\n\n"
            "Predicted P(RSSI >= sensitivity) against the observed outcome (up: a packet at or above it; down: "
            "weaker, or an outage event); skill against the constant share up of the learning data.\n\n"
            + "\n\n".join(x.markdown() for x in scores))


@check_types
def score_models_availability(models: Sequence[Model], df: pd.DataFrame, units: Sequence[str] | None,
                              sensitivity_dbm: float, labels: Sequence[str], source: str = "dataset",
                              ) -> list[AvailabilityScore]:
    """Every model's availability scored on the ``units`` of ``df`` (all rows when None),
    against the base rate of the units they learned from (those of ``df`` named in their
    provenance, else every other unit of ``df``).

    Raises
    ------
    InputError
        When no learning unit of ``df`` is left to take the base rate from.
    """
    known = set(dataset_units(df))
    learn = [u for u in trained_units([m.provenance for m in models]) if u in known]
    learn = learn or sorted(known - {str(u) for u in units or []})
    if not learn:
        raise InputError(f"{source}: sensitivity: no learning unit in the dataset to take the base rate of "
                         "availability from (score on held-out units of the learning dataset)", param="sensitivity_dbm")
    rate = base_rate_of(select_units(df, learn, source), sensitivity_dbm, source)
    test = select_units(df, units, source)
    return [replace(score_availability(m, test, sensitivity_dbm, rate, source), model=label)
            for m, label in zip(models, labels)]


__all__ = ["AvailabilityScore", "availability_markdown", "base_rate_of", "observed_up", "score_availability",
           "score_models_availability"]
