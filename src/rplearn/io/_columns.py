"""The columns of CSV and Parquet logs (:mod:`rplearn.io.tables`): vendor names renamed to the canonical ones
(:data:`COLUMN_ALIASES`), a CSV's missing-value words, and which columns give a pose table's node, position and
attitude (ENU or geodetic positions; a quaternion or Euler angles in either frame), with the quaternions they make."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from rplearn.core.geometry import quat_wxyz_from_euler_enu_flu_deg, quat_wxyz_from_euler_ned_frd_deg
from rplearn.data.tables import POSE_COLUMNS
from rplearn.errors import InputError

#: Vendor column names -> canonical names (the one renaming mapping of rplearn.io).
COLUMN_ALIASES: dict[str, str] = {
    "time": "t",
    "time_s": "t",
    "timestamp_s": "t",
    "node_id": "node",
    "drone": "node",
    "latitude": "lat",
    "latitude_deg": "lat",
    "longitude": "lon",
    "longitude_deg": "lon",
    "altitude": "alt",
    "altitude_m": "alt",
    "rssi": "rssi_dbm",
    "signal_dbm": "rssi_dbm",
    "txpower_dbm": "tx_power_dbm",
    "freq_hz": "frequency_hz",
    "transmitter": "tx",
    "receiver": "rx",
}

GEODETIC_COLUMNS: tuple[str, ...] = ("lat", "lon", "alt")
EULER_ENU_FLU_COLUMNS: tuple[str, ...] = ("roll_deg", "pitch_deg", "yaw_deg")
EULER_NED_FRD_COLUMNS: tuple[str, ...] = ("roll_ned_deg", "pitch_ned_deg", "yaw_ned_deg")

def rename_columns(df: pd.DataFrame, columns: Mapping[str, str] | None = None) -> pd.DataFrame:
    """Rename vendor columns to canonical names: :data:`COLUMN_ALIASES`, then ``columns``.

    A canonical name already present is never overwritten by an alias.
    """
    mapping = {k: v for k, v in COLUMN_ALIASES.items() if v not in df.columns}
    mapping.update(dict(columns or {}))
    df = df.rename(columns={c: mapping.get(str(c), str(c)) for c in df.columns})
    if df.columns.duplicated().any():
        dup = sorted({str(c) for c in df.columns[df.columns.duplicated()]})
        raise InputError(f"column(s) {', '.join(dup)} appear twice after renaming")
    return df

#: The only cells of an RSSI column a CSV reader takes for missing (``nan_rssi``): other text
#: ("n/a", "NULL", "-70dBm") is kept, counted by ``sync`` as ``unparsable_rssi``, as
#: :func:`rplearn.data.sync.synchronise` counts it in a table it is given.
RSSI_MISSING_TEXT: tuple[str, ...] = ("", "nan", "NaN", "NAN", "-nan", "-NaN", "+nan", "+NaN")
#: The words :func:`pandas.read_csv` takes for missing by default (its documented ``na_values``).
_PANDAS_MISSING_TEXT: tuple[str, ...] = (
    "", "#N/A", "#N/A N/A", "#NA", "-1.#IND", "-1.#QNAN", "-NaN", "-nan", "1.#IND", "1.#QNAN", "<NA>", "N/A", "NA",
    "NULL", "NaN", "None", "n/a", "nan", "null",
)


def csv_missing_values(header: Any, columns: Mapping[str, str] | None = None) -> dict[str, Any]:
    """Options of :func:`pandas.read_csv` for a table with the column names ``header`` (as pandas
    reads them): pandas' missing-value words in every column but the RSSI one
    (:data:`RSSI_MISSING_TEXT` there); none for a table without an RSSI column."""
    names = [str(c) for c in header]
    try:
        renamed = list(rename_columns(pd.DataFrame(columns=names), columns).columns)
    except InputError:  # two columns of one name: refused when the table is read
        return {}
    rssi = {h for h, c in zip(names, renamed, strict=True) if c == "rssi_dbm"}
    if not rssi:
        return {}
    return {"keep_default_na": False,
            "na_values": {h: list(RSSI_MISSING_TEXT if h in rssi else _PANDAS_MISSING_TEXT) for h in names}}

def level_if_yaw_only(df: pd.DataFrame) -> pd.DataFrame | None:
    """The table with zero roll and pitch added when it gives a yaw but no roll, pitch or quaternion."""
    if has_columns(df, ("qw", "qx", "qy", "qz")):
        return None
    for yaw, roll, pitch in (("yaw_deg", "roll_deg", "pitch_deg"), ("yaw_ned_deg", "roll_ned_deg", "pitch_ned_deg")):
        if yaw in df.columns and roll not in df.columns and pitch not in df.columns:
            return df.assign(**{roll: 0.0, pitch: 0.0})
    return None


def has_columns(df: pd.DataFrame, names: tuple[str, ...]) -> bool:
    return all(n in df.columns for n in names)

def with_node(df: pd.DataFrame, node: str | None, source: str) -> pd.DataFrame:
    """The table with a ``node`` column (``node`` for every row when it has none) and a ``t``."""
    if "node" not in df.columns:
        if node is None:
            raise InputError(
                f"{source}: missing column node; for a one-node log give its node id "
                "(ReaderOptions.nodes={path: node}, or node= for one table)",
                param="nodes",
            )
        df = df.assign(node=str(node))
    if "t" not in df.columns:
        raise InputError(f"{source}: missing column t; expected {', '.join(POSE_COLUMNS)}")
    return df


def position_columns(df: pd.DataFrame, source: str) -> tuple[tuple[str, ...], str]:
    """Position columns of a pose table and their kind, ``"enu"`` or ``"geodetic"``."""
    if has_columns(df, ("x", "y", "z")):
        return ("x", "y", "z"), "enu"
    if has_columns(df, GEODETIC_COLUMNS):
        return GEODETIC_COLUMNS, "geodetic"
    raise InputError(f"{source}: missing position columns: expected x, y, z (ENU m) or lat, lon, alt")


def attitude_columns(df: pd.DataFrame, source: str) -> tuple[pd.DataFrame, tuple[str, ...], str, bool]:
    """Attitude columns of a pose table and their kind; a yaw-only table gets zero roll and pitch.

    Returns ``(table, columns, kind, level_assumed)`` with kind ``"quaternion"``,
    ``"euler_enu_flu"`` or ``"euler_ned_frd"``.
    """
    enu = [c for c in EULER_ENU_FLU_COLUMNS if c in df.columns]
    ned = [c for c in EULER_NED_FRD_COLUMNS if c in df.columns]
    if enu and ned and not has_columns(df, ("qw", "qx", "qy", "qz")):
        raise InputError(
            f"{source}: attitude columns mix frames: {', '.join(enu)} (ENU/FLU) with {', '.join(ned)} (NED/FRD); "
            "give one complete set, roll_deg, pitch_deg, yaw_deg or roll_ned_deg, pitch_ned_deg, yaw_ned_deg"
        )
    level = level_if_yaw_only(df)
    if level is not None:  # plans (rplearn.plan) give yaw only: level flight is meant
        df = level
    if has_columns(df, ("qw", "qx", "qy", "qz")):
        return df, ("qw", "qx", "qy", "qz"), "quaternion", level is not None
    if has_columns(df, EULER_ENU_FLU_COLUMNS):
        return df, EULER_ENU_FLU_COLUMNS, "euler_enu_flu", level is not None
    if has_columns(df, EULER_NED_FRD_COLUMNS):
        return df, EULER_NED_FRD_COLUMNS, "euler_ned_frd", level is not None
    raise InputError(
        f"{source}: missing attitude columns: expected qw, qx, qy, qz or "
        "roll_deg, pitch_deg, yaw_deg (ENU/FLU) or roll_ned_deg, pitch_ned_deg, yaw_ned_deg"
    )

def quaternions_wxyz(values: dict[str, np.ndarray], att_cols: tuple[str, ...], attitude: str) -> np.ndarray:
    """Quaternions (w, x, y, z), body FLU -> world ENU, shape (n, 4), from any attitude variant."""
    if attitude == "quaternion":
        return np.stack([values[c] for c in att_cols], axis=-1)
    if attitude == "euler_enu_flu":
        return quat_wxyz_from_euler_enu_flu_deg(*(values[c] for c in att_cols))
    return quat_wxyz_from_euler_ned_frd_deg(*(values[c] for c in att_cols))


__all__ = [
    "COLUMN_ALIASES", "EULER_ENU_FLU_COLUMNS", "EULER_NED_FRD_COLUMNS", "GEODETIC_COLUMNS", "RSSI_MISSING_TEXT",
    "attitude_columns", "csv_missing_values", "has_columns", "level_if_yaw_only", "position_columns",
    "quaternions_wxyz", "rename_columns", "with_node",
]
