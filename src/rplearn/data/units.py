"""Unit selection: which trajectory units a model learns from and which it is tested on.

The one place that decides it: units labelled ``test...`` (any case) are held out for testing
by default, every other unit is for learning.
"""

from __future__ import annotations

from typing import Sequence

import pandas as pd

from rplearn.data.tables import LinkSamples, link_samples
from rplearn.errors import InputError


def select_units(df: pd.DataFrame, units: Sequence[str] | None, source: str = "dataset") -> pd.DataFrame:
    """Rows whose ``unit`` label is among ``units`` (all rows when ``units`` is None)."""
    if not units:
        return df
    if "unit" not in df.columns:
        raise InputError(f"{source}: --units needs a 'unit' column, which this dataset lacks")
    wanted = [str(u) for u in units]
    known = sorted(df["unit"].astype(str).unique())
    unknown = [u for u in wanted if u not in known]
    if unknown:
        raise InputError(f"{source}: unknown unit(s) {', '.join(unknown)}; the dataset has {', '.join(known)}")
    return df[df["unit"].astype(str).isin(wanted)]


def samples_of(df: pd.DataFrame, units: Sequence[str] | None = None, source: str = "dataset", nodes: Sequence[str] | None = None) -> LinkSamples:
    """Learning-ready samples of the chosen units of a matched dataset."""
    part = select_units(df, units, source)
    if len(part) == 0:
        raise InputError(f"{source}: no samples selected")
    return link_samples(part, source, nodes=nodes)
