"""What the readers of :mod:`rplearn.io` share: the result container, lean Parquet reading."""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from rplearn._argtypes import check_types


@check_types
@dataclass
class Logs:
    """Canonical logs read from one or more files (docs/conventions.md schemas); either may be None.

    Attributes
    ----------
    pose : DataFrame or None
        Pose log ``t, node, x, y, z, qw, qx, qy, qz`` (ENU m, FLU -> ENU quaternion).
    signal : DataFrame or None
        Signal log ``t, tx, rx, rssi_dbm, tx_power_dbm, frequency_hz`` plus extra columns.
    """

    pose: pd.DataFrame | None = None
    signal: pd.DataFrame | None = None


def read_parquet_lean(path: str) -> pd.DataFrame:
    """A Parquet file as a DataFrame, holding its data about once in memory.

    ``pyarrow.parquet.read_table(...).to_pandas(self_destruct=True)`` frees each Arrow column
    once converted, where ``pandas.read_parquet`` holds both copies at its peak.
    """
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    return table.to_pandas(self_destruct=True, split_blocks=True)
