"""The availability section of ``rplearn report --sensitivity``: the model's predicted
availability scored on the held-out units (:mod:`rplearn.models.availability_score`) and its
reliability diagram (:mod:`rplearn.viz.reliability`)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import pandas as pd

from rplearn._argtypes import check_types
from rplearn.models.availability_score import AvailabilityScore, score_models_availability
from rplearn.models.base import Model


@check_types
def availability_section(model: Model, df: pd.DataFrame, test_units: Sequence[str], sensitivity_dbm: float,
                         out_dir: str, files: dict[str, str]) -> tuple[Any, AvailabilityScore]:
    """Score ``model`` on the ``test_units`` of ``df`` at ``sensitivity_dbm`` [dBm] (the base rate
    from the units it learned from), draw ``reliability.png`` into ``out_dir`` (its path added to
    ``files``) and return the report section with the score."""
    from rplearn.viz.reliability import plot_reliability
    from rplearn.viz.report import ReportSection

    [score] = score_models_availability([model], df, list(test_units), sensitivity_dbm, [model.label])
    files["reliability"] = plot_reliability(os.path.join(out_dir, "reliability.png"), score.table, score.model,
                                            sensitivity_dbm, score.skill)
    return ReportSection(f"Availability at {sensitivity_dbm:g} dBm", score.markdown(), [files["reliability"]]), score


__all__ = ["availability_section"]
