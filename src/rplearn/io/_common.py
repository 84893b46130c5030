"""Result container shared by the readers of :mod:`rplearn.io`."""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd


@dataclass
class Logs:
    """Canonical logs read from one or more files (DESIGN.md schemas); either may be None.

    Attributes
    ----------
    pose : DataFrame or None
        Pose log ``t, node, x, y, z, qw, qx, qy, qz`` (ENU m, FLU -> ENU quaternion).
    signal : DataFrame or None
        Signal log ``t, tx, rx, rssi_dbm, tx_power_dbm, frequency_hz`` plus extra columns.
    """

    pose: pd.DataFrame | None = None
    signal: pd.DataFrame | None = None
