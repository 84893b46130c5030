"""Canonical tables: pose logs, signal logs and matched link datasets (docs/conventions.md).

All three are :class:`pandas.DataFrame` objects with fixed column names, so that every reader,
the simulator and the synchroniser speak the same language:

- pose log: ``t, node, x, y, z, qw, qx, qy, qz`` (ENU metres, FLU -> ENU quaternion);
- signal log: ``t, tx, rx, rssi_dbm, tx_power_dbm, frequency_hz`` and optional ``unit`` and ``outage``;
- matched dataset: every signal-log column plus ``tx_x .. tx_qz`` and ``rx_x .. rx_qz`` (and
  ``rssi_scale`` = ``relative`` for uncalibrated received power, from ``sync --rssi-scale``).

A boolean ``outage`` column (from logs that mark a lost link: a MAVLink ground station's
zero RSSI while the vehicle is silent) marks *outage events*: rows whose ``rssi_dbm`` is NaN
because no packet arrived. Their RSSI is not checked; :func:`link_samples` leaves them out of
the learning samples and counts them (``LinkSamples.outages``).

Node ids are strings. Times are float seconds since an epoch the log states.
:func:`link_samples` turns a matched dataset into the arrays the learning code needs
(directions of both ends, node indices, observed joint gain, paper eqs. 3 and 5).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.geometry import Directions, distance_m, link_directions
from rplearn.core.link import check_far_field, observed_joint_gain_db
from rplearn.core.plausible import PLAUSIBLE, check_frequency_hz, check_plausible
from rplearn.errors import InputError

POSE_COLUMNS: tuple[str, ...] = ("t", "node", "x", "y", "z", "qw", "qx", "qy", "qz")
SIGNAL_COLUMNS: tuple[str, ...] = ("t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz")
OPTIONAL_SIGNAL_COLUMNS: tuple[str, ...] = ("unit", "outage")
#: Boolean column marking outage events (link lost, ``rssi_dbm`` NaN): module docstring.
OUTAGE_COLUMN: str = "outage"
POSE_FIELDS: tuple[str, ...] = ("x", "y", "z", "qw", "qx", "qy", "qz")
MATCHED_COLUMNS: tuple[str, ...] = SIGNAL_COLUMNS + tuple(f"{end}_{f}" for end in ("tx", "rx") for f in POSE_FIELDS)
#: Columns holding labels: read from CSV as text, so that node "01" stays "01", not 1.
STRING_COLUMNS: tuple[str, ...] = ("node", "tx", "rx", "unit", "rssi_scale")
CSV_DTYPES: dict[str, type] = {c: str for c in STRING_COLUMNS}
#: RSSI values that mean "no measurement" in drivers and capture tools [dBm].
SENTINEL_RSSI_DBM: tuple[float, ...] = (0.0, -127.0, -128.0, 127.0)
#: A pose quaternion whose norm differs from 1 by more than this is counted as non-unit
#: (it is still normalised): a unit or scaling mistake rather than rounding.
QUATERNION_NORM_TOLERANCE: float = 1e-3
#: Key of ``DataFrame.attrs`` where :func:`validate_pose_log` records how many rows had a
#: non-unit quaternion before normalisation (carried over from an input that has it).
NON_UNIT_QUATERNION_ATTR: str = "non_unit_quaternion_rows"


@check_types
def normalise_times(df: pd.DataFrame, source: str = "table") -> pd.DataFrame:
    """Turn a datetime ``t`` column into float seconds since the UNIX epoch (UTC).

    Naive datetimes are taken as UTC. Other columns are left alone.
    """
    if "t" in df.columns and pd.api.types.is_datetime64_any_dtype(df["t"]):
        t = df["t"]
        if getattr(t.dt, "tz", None) is None:
            t = t.dt.tz_localize("UTC")
        df = df.copy()
        df["t"] = (t - pd.Timestamp(0, tz="UTC")).dt.total_seconds()
    return df


def _require_columns(df: pd.DataFrame, columns: Sequence[str], source: str) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise InputError(f"{source}: missing column(s) {', '.join(missing)}; expected {', '.join(columns)}")


def _require_finite(df: pd.DataFrame, columns: Sequence[str], source: str) -> None:
    for c in columns:
        col = df[c]  # once: a column read from a frame is a new Series each time
        with np.errstate(over="ignore"):  # huge values: their sum overflows, and the full check runs
            whole = col.dtype == np.float64 and np.isfinite(np.sum(col.to_numpy()))
        if whole:
            continue  # a finite sum: no NaN and no infinity (an overflow only sends it to the full check)
        values = pd.to_numeric(col, errors="coerce").to_numpy(np.float64)
        bad = ~np.isfinite(values)
        if np.any(bad):
            row = int(np.flatnonzero(bad)[0])
            raise InputError(
                f"{source}: column {c} has {int(bad.sum())} non-numeric, NaN or infinite value(s) "
                f"(first at row {row})"
            )


@check_types
def outage_mask(df: pd.DataFrame, source: str = "table") -> np.ndarray:
    """Rows of a signal log or matched dataset that are outage events (:data:`OUTAGE_COLUMN`
    True); all False without the column, a missing cell is False.

    Raises
    ------
    InputError
        When the column holds something other than true/false (or 1/0).
    """
    if OUTAGE_COLUMN not in df.columns:
        return np.zeros(len(df), bool)
    col = df[OUTAGE_COLUMN]
    try:
        if pd.api.types.is_object_dtype(col) or pd.api.types.is_string_dtype(col):
            col = col.map(lambda v: {"true": True, "false": False, "1": True, "0": False}.get(str(v).strip().lower(), v)
                          if isinstance(v, str) else v)
        return col.astype("boolean").fillna(False).to_numpy(bool)
    except (TypeError, ValueError):
        raise InputError(f"{source}: column {OUTAGE_COLUMN}: expected true/false (or 1/0) values") from None


def node_ids(values: Any) -> np.ndarray:
    """Node ids as an object array of ``str``; a missing cell (None, NaN, NA) becomes ``""``.

    ``astype(str)`` alone would make a missing id the node ``"nan"`` (or keep a float NaN
    with pandas' string dtype): a node that does not exist, learned from.
    """
    series = values if isinstance(values, pd.Series) else pd.Series(values)
    missing = series.isna().to_numpy()
    if missing.any():
        series = series.astype(object).where(~missing, "")
    return series.astype(str).to_numpy(dtype=object)


def node_id_codes(
    values: pd.Series, sort: bool = False, factorized: tuple[np.ndarray, Any] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``(codes, ids)``: :func:`node_ids` of ``values`` as ``ids[codes]``, ``ids`` distinct (sorted
    with ``sort``), the text of each distinct cell made once rather than once per row
    (``factorized``: ``pd.factorize(values, use_na_sentinel=True)``, when already made)."""
    codes, uniques = factorized if factorized is not None else pd.factorize(values, use_na_sentinel=True)  # missing: -1
    text = np.append(node_ids(pd.Series(uniques)), np.array([""], dtype=object))
    merged, ids = pd.factorize(text, sort=sort)  # distinct cells with the same text are one node
    missing = codes.size > 0 and int(codes.min()) < 0
    return merged[np.where(codes < 0, text.size - 1, codes) if missing else codes], np.asarray(ids, dtype=object)


def empty_ids(ids: np.ndarray) -> np.ndarray:
    """Mask of node ids that are empty or only white space."""
    if not ids.size:
        return np.zeros(0, bool)
    codes, uniques = pd.factorize(np.asarray(ids, dtype=object), use_na_sentinel=False)  # a few nodes, many rows
    return (np.char.str_len(np.char.strip(np.asarray(uniques, dtype=object).astype(str))) == 0)[codes]


def check_unit_labels(df: pd.DataFrame, source: str, first_row: int = 0) -> None:
    """Refuse a ``unit`` column with an empty cell (missing, NaN or white space), naming the row.

    ``first_row`` is the file row of ``df``'s first row (a chunk of a file). A table without a
    ``unit`` column passes.

    Raises
    ------
    InputError
        Naming ``source``, the column and the first empty row.
    """
    if "unit" not in df.columns:
        return
    empty = empty_ids(node_ids(df["unit"]))
    if np.any(empty):
        row = int(np.flatnonzero(empty)[0]) + first_row
        raise InputError(f"{source}: column unit is empty at row {row} ({int(empty.sum())} row(s)); "
                         "label every row's trajectory unit, or drop the column")


@check_types
def validate_pose_log(df: pd.DataFrame, source: str = "pose log") -> pd.DataFrame:
    """Check a canonical pose log and return it typed, sorted by (node, t), quaternions normalised.

    An optional ``armed`` column (whether the vehicle was armed, as an ArduPilot log says) is
    kept: ``bool``, or pandas' nullable ``boolean`` where some rows (logs that do not say) miss it.

    The number of rows whose quaternion norm was off 1 by more than
    :data:`QUATERNION_NORM_TOLERANCE` (plus any count the input carries) is recorded in
    ``attrs["non_unit_quaternion_rows"]`` of the result; read it with
    :func:`non_unit_quaternion_rows`.

    Raises
    ------
    InputError
        On a missing column, a NaN or infinite value, a zero quaternion, or a duplicate
        timestamp within one node (with the file/source name and the first offending row).
    """
    c = checked_pose_arrays(df, source)
    node = pd.Series(c.names.astype(str)).array.take(c.codes)  # one text per node, taken per row
    cols: dict[str, Any] = {"t": c.t, "node": node}
    for j, name in enumerate(("x", "y", "z")):
        cols[name] = c.position_xyz[:, j]
    for j, name in enumerate(("qw", "qx", "qy", "qz")):
        cols[name] = c.quat_wxyz[:, j]
    out = pd.DataFrame(cols, columns=list(POSE_COLUMNS))
    if c.armed is not None:
        out["armed"] = c.armed
    out.attrs[NON_UNIT_QUATERNION_ATTR] = c.non_unit
    return out


@dataclass(frozen=True)
class CheckedPose:
    """The arrays of a pose log checked by :func:`checked_pose_arrays`, sorted by (node, t).

    ``names``: the distinct node ids, sorted; ``codes``: each row's node as an index into
    ``names``; ``quat_wxyz`` normalised; ``non_unit``: the rows whose quaternion was not unit
    (plus the input's count); ``still_off``: those still not unit after normalisation (an
    overflowing norm; :func:`non_unit_quaternion_rows` of the checked log adds them);
    ``armed``: the optional column as :func:`validate_pose_log` keeps it.
    """

    t: np.ndarray
    codes: np.ndarray
    names: np.ndarray
    position_xyz: np.ndarray
    quat_wxyz: np.ndarray
    non_unit: int
    still_off: int = 0
    armed: Any = None


def quaternion_norms(q: np.ndarray) -> np.ndarray:
    """``numpy.linalg.norm(q, axis=1)`` of quaternions ``q`` (n, 4), bit for bit (its order of
    summation, ``((s0 + s1) + s2) + s3``), one component at a time."""
    return _norms_of_columns([q[:, j] for j in range(4)])


def _norms_of_columns(q: Sequence[np.ndarray]) -> np.ndarray:
    """:func:`quaternion_norms` of the quaternions whose components are the arrays ``q``."""
    with np.errstate(over="ignore"):  # a corrupt component (1e200): an infinite norm (checked_pose_arrays refuses it)
        norm = q[0] * q[0]
        for j in range(1, 4):
            norm += q[j] * q[j]
    return np.sqrt(norm, out=norm)


def checked_pose_arrays(df: pd.DataFrame, source: str = "pose log") -> CheckedPose:
    """The checks of :func:`validate_pose_log` and its sorted, normalised arrays, without the
    DataFrame (:func:`rplearn.data.poses.tracks_of_pose_log` makes the tracks from them).

    Raises
    ------
    InputError
        As :func:`validate_pose_log`.
    """
    _require_columns(df, POSE_COLUMNS, source)
    df = normalise_times(df, source)
    _require_finite(df, [c for c in POSE_COLUMNS if c != "node"], source)
    for c in ("x", "y", "z"):  # a sentinel (1e308) or a corrupt value: no place, and distances overflow
        check_plausible("coordinate_m", df[c].to_numpy(np.float64), source, field=c)
    t = df["t"].to_numpy(np.float64)
    codes, names = node_id_codes(df["node"], sort=True)  # codes in the order of sorted ids
    empty = empty_ids(names)[codes]
    if np.any(empty):
        row = int(np.flatnonzero(empty)[0])
        raise InputError(f"{source}: column node is empty at row {row} (every pose row needs its node id)")
    step, dt = np.diff(codes), np.diff(t)  # t is finite: dt == 0 where equal, dt >= 0 where in order
    in_order = bool(np.all((step > 0) | ((step == 0) & (dt >= 0))))  # np.lexsort((t, codes)) is the identity
    order = np.arange(0) if in_order else np.lexsort((t, codes))  # stable: by node id, then time
    take = slice(None) if in_order else order
    components = [df[c].to_numpy(np.float64)[take] for c in ("qw", "qx", "qy", "qz")]  # no copy when in order
    norm = _norms_of_columns(components)
    check_attitude_norms(norm, source, None if in_order else order)
    non_unit = count_non_unit_quaternions(norm) + int(df.attrs.get(NON_UNIT_QUATERNION_ATTR, 0))
    q = np.empty((t.size, 4))
    for j, component in enumerate(components):
        np.divide(component, norm, out=q[:, j])
    # q / norm is unit to a few ulp wherever the norm is finite (and, here, at least 1e-6): only an
    # overflowing norm leaves rows that are not
    still_off = 0 if np.isfinite(np.sum(norm)) else _non_unit_finite(quaternion_norms(q))
    sorted_codes, ts = codes[take], t[take]
    if in_order:
        dup = (step == 0) & (dt == 0)
    else:
        dup = (sorted_codes[1:] == sorted_codes[:-1]) & (ts[1:] == ts[:-1])
    if np.any(dup):
        i = int(np.flatnonzero(dup)[0]) + 1
        raise InputError(
            f"{source}: field t: {int(dup.sum())} duplicate timestamp(s) within a node "
            f"(first: node {names.astype(str)[sorted_codes[i]]}, t = {float(ts[i])!r})"
        )
    position = np.empty((t.size, 3))
    for j, c in enumerate(("x", "y", "z")):
        position[:, j] = df[c].to_numpy(np.float64)[take]
    armed = None
    if "armed" in df.columns:  # optional: the vehicle armed (bool; missing where a log does not say)
        try:
            flags = df["armed"].astype("boolean").to_numpy()[take]
        except (TypeError, ValueError):
            raise InputError(f"{source}: column armed: expected true/false (or 1/0) values") from None
        armed = flags.astype(bool) if not pd.isna(flags).any() else pd.array(flags, dtype="boolean")
    return CheckedPose(ts, sorted_codes, names, position, q, non_unit, still_off, armed)


def check_attitude_norms(norm: np.ndarray, source: str, rows: np.ndarray | None = None) -> None:
    """Refuse the first quaternion of norm ``norm`` zero or beyond any float (no attitude, or a corrupt component whose
    square overflows), naming its row: ``rows[i]`` (the file's rows, some dropped before), else its position."""
    if np.any(bad := (norm < 1e-6) | np.isinf(norm)):
        i = int(np.flatnonzero(bad)[0])
        what = "zero norm" if norm[i] < 1e-6 else "a norm beyond any float (a corrupt value)"
        raise InputError(f"{source}: quaternion (qw, qx, qy, qz) has {what} at row {i if rows is None else int(rows[i])}")


def count_non_unit_quaternions(norm: np.ndarray, tolerance: float = QUATERNION_NORM_TOLERANCE) -> int:
    """Number of quaternions whose norm differs from 1 by more than ``tolerance``.

    Parameters
    ----------
    norm : ndarray
        Quaternion norms (dimensionless).
    tolerance : float
        Allowed deviation |norm - 1| (default :data:`QUATERNION_NORM_TOLERANCE`).
    """
    return int(np.sum(np.abs(np.asarray(norm, np.float64) - 1.0) > tolerance))


def non_unit_quaternion_rows(pose_log: pd.DataFrame) -> int:
    """Rows of a pose log that had a non-unit quaternion before :func:`validate_pose_log`.

    Reads the count :func:`validate_pose_log` records in ``pose_log.attrs`` and adds the rows
    of ``pose_log`` itself that are still not unit (a log that was never validated).
    """
    q = pose_log[["qw", "qx", "qy", "qz"]].to_numpy(np.float64)
    return int(pose_log.attrs.get(NON_UNIT_QUATERNION_ATTR, 0)) + _non_unit_finite(quaternion_norms(q))


def _non_unit_finite(norm: np.ndarray) -> int:
    """:func:`count_non_unit_quaternions` of the finite ``norm`` values."""
    return count_non_unit_quaternions(norm[np.isfinite(norm)])


#: Plausible transmit powers [dBm] (the row ``tx_power_dbm`` of :data:`rplearn.core.plausible.PLAUSIBLE`).
TX_POWER_BAND_DBM: tuple[float, float] = (PLAUSIBLE["tx_power_dbm"].low, PLAUSIBLE["tx_power_dbm"].high)


def check_tx_power_dbm(values: Any, where: str, param: str | None = "tx_power_dbm", row_offset: int = 0) -> None:
    """Refuse transmit powers outside :data:`TX_POWER_BAND_DBM` (1e6 dBm is no radio); rows are
    numbered from ``row_offset``."""
    p = np.atleast_1d(np.asarray(values, np.float64))
    lo, hi = TX_POWER_BAND_DBM
    bad = ~((p >= lo) & (p <= hi))
    if np.any(bad):
        row = int(np.flatnonzero(bad)[0])
        at = f" at row {row + row_offset}" if p.size > 1 or row_offset else ""
        raise InputError(f"{where}: tx_power_dbm {float(p[row]):g}{at} is outside {lo:g} to {hi:g} dBm", param=param)


def _check_link_columns(df: pd.DataFrame, source: str, with_rssi: bool) -> None:
    """Node ids present, plausible carriers and powers, and no packet received stronger than
    it was sent."""
    for col in ("tx", "rx"):
        ids = df[col]
        empty = ids.isna().to_numpy() | (ids.astype(str).str.strip() == "").to_numpy()
        if np.any(empty):
            row = int(np.flatnonzero(empty)[0])
            raise InputError(f"{source}: column {col} is empty at row {row} (every packet needs its node ids)")
    check_frequency_hz(df["frequency_hz"].to_numpy(np.float64), source, None)
    check_tx_power_dbm(df["tx_power_dbm"].to_numpy(np.float64), source, None)
    if with_rssi:
        above = df["rssi_dbm"].to_numpy(np.float64) > df["tx_power_dbm"].to_numpy(np.float64)
        if "rssi_scale" in df.columns:  # uncalibrated power (sync --rssi-scale relative): no such bound
            above &= (df["rssi_scale"].astype(str).str.lower() != "relative").to_numpy()
        if np.any(above):
            row = int(np.flatnonzero(above)[0])
            raise InputError(
                f"{source}: rssi_dbm {df['rssi_dbm'].iloc[row]:g} dBm is above tx_power_dbm {df['tx_power_dbm'].iloc[row]:g} dBm "
                f"at row {row} ({int(above.sum())} row(s)): no packet arrives stronger than it was sent"
            )


@check_types
def validate_signal_log(df: pd.DataFrame, source: str = "signal log") -> pd.DataFrame:
    """Check a canonical signal log and return it typed and sorted by time (stable).

    Raises
    ------
    InputError
        On a missing column, a NaN or infinite value, a non-positive frequency, or a
        transmitter equal to its receiver.
    """
    _require_columns(df, SIGNAL_COLUMNS, source)
    df = normalise_times(df, source)
    outage = outage_mask(df, source)
    _require_finite(df, ["t", "tx_power_dbm", "frequency_hz"], source)
    _require_finite(df[~outage], ["rssi_dbm"], source)  # an outage event has no RSSI
    _check_link_columns(df, source, with_rssi=False)
    cols = list(SIGNAL_COLUMNS) + [c for c in OPTIONAL_SIGNAL_COLUMNS if c in df.columns]
    out = df.loc[:, cols].copy()
    if OUTAGE_COLUMN in out.columns:
        out[OUTAGE_COLUMN] = outage
    out["tx"] = out["tx"].astype(str)
    out["rx"] = out["rx"].astype(str)
    for c in ("t", "rssi_dbm", "tx_power_dbm", "frequency_hz"):
        out[c] = out[c].astype(np.float64)
    if "unit" in out.columns:
        out["unit"] = out["unit"].astype(str)
    if np.any(out["frequency_hz"].to_numpy() <= 0):
        raise InputError(f"{source}: column frequency_hz must be positive (Hz)")
    same = out["tx"].to_numpy() == out["rx"].to_numpy()
    if np.any(same):
        row = int(np.flatnonzero(same)[0])
        raise InputError(f"{source}: tx equals rx ({out['tx'].iloc[row]}) at row {row}")
    return out.sort_values("t", kind="stable").reset_index(drop=True)


def repeated_rows_message(source: str, count: int, first_row: int, copy_of: tuple[str, int] | None = None,
                          files: int = 1) -> str:
    """The one-line refusal of rows that repeat earlier rows in every column: ``count`` of them,
    the first at ``first_row`` of ``source``; ``copy_of`` the file and row it repeats when that
    is another file, ``files`` the files holding repeated rows (when more than one)."""
    where = f"first at row {first_row}"
    if copy_of is not None:
        where += f", a copy of row {copy_of[1]} of {copy_of[0]}"
    if files > 1:
        where += f"; {files} files hold such rows"
    return (f"{source}: {count:,} row(s) repeat an earlier row in every column ({where}): "
            "the same samples twice (a dataset in the file twice, or parts that overlap) would count double; "
            "drop the copies (synchronising the logs drops them)")


def _refuse_repeated_rows(df: pd.DataFrame, source: str) -> None:
    """Refuse a dataset whose rows repeat earlier rows in every column: one sample twice (a
    dataset in the file twice, parts that overlap) would be learned from or scored twice,
    weighing it double and making the spreads too narrow. ``synchronise`` never writes such
    rows (it drops and counts exact copies of a signal row). A dataset read in chunks or parts
    is checked across them by :mod:`rplearn.data.row_copies`, with the same message."""
    from rplearn.data.readings import duplicate_rows

    repeated = duplicate_rows(df)
    if np.any(repeated):
        row = int(np.flatnonzero(repeated)[0])
        raise InputError(repeated_rows_message(source, int(repeated.sum()), row))


@check_types
def validate_matched(df: pd.DataFrame, source: str = "dataset", require_rssi: bool = True) -> pd.DataFrame:
    """Check a matched link dataset (columns of :data:`MATCHED_COLUMNS`).

    With ``require_rssi=False`` (poses of links to predict, not yet measured) the ``rssi_dbm``
    column may be absent or hold NaN or sentinel values; it is neither checked nor used. Outage
    events (``outage`` True) need no RSSI either.
    """
    required = MATCHED_COLUMNS if require_rssi else tuple(c for c in MATCHED_COLUMNS if c != "rssi_dbm")
    _require_columns(df, required, source)
    df = normalise_times(df, source)
    outage = outage_mask(df, source)
    numeric = [c for c in required if c not in ("tx", "rx", "rssi_dbm")]
    _require_finite(df, numeric, source)
    if require_rssi:
        _require_finite(df[~outage], ["rssi_dbm"], source)  # rows counted among the up samples
    rssi = np.where(outage, np.nan, df["rssi_dbm"].to_numpy(np.float64)) if require_rssi else np.empty(0)
    sentinel = np.isin(rssi, SENTINEL_RSSI_DBM)
    if np.any(sentinel):
        row = int(np.flatnonzero(sentinel)[0])
        raise InputError(
            f"{source}: column rssi_dbm holds {int(sentinel.sum())} sentinel value(s) meaning 'no measurement' "
            f"(first {rssi[row]:g} dBm at row {row}); synchronising the logs (synchronise) drops and counts them"
        )
    for c in ("tx_x", "tx_y", "tx_z", "rx_x", "rx_y", "rx_z"):  # as a pose log's: no place, distances overflow
        check_plausible("coordinate_m", df[c].to_numpy(np.float64), source, field=c)
    _check_link_columns(df[~outage] if outage.any() else df, source, with_rssi=require_rssi)
    same = node_ids(df["tx"]) == node_ids(df["rx"])  # no link from a node to itself (sync drops them: tx_equals_rx)
    if np.any(same):
        row = int(np.flatnonzero(same)[0])
        raise InputError(f"{source}: tx equals rx ({df['tx'].iloc[row]}) at row {row} ({int(same.sum())} row(s))")
    if require_rssi:
        _refuse_repeated_rows(df, source)
    check_unit_labels(df, source)
    out = df.copy()
    out["tx"] = out["tx"].astype(str)
    out["rx"] = out["rx"].astype(str)
    if "unit" in out.columns:
        out["unit"] = out["unit"].astype(str)
    if OUTAGE_COLUMN in out.columns:
        out[OUTAGE_COLUMN] = outage
    return out


@check_types
@dataclass(frozen=True)
class LinkSamples:
    """Learning-ready samples of a matched dataset.

    Attributes
    ----------
    directions : Directions
        Direction of the other end in each end's body frame [rad] (paper eq. 3).
    tx_index, rx_index : ndarray of int
        Index into ``nodes`` of the transmitter and the receiver of every sample.
    nodes : tuple of str
        Node ids, sorted.
    joint_gain_db : ndarray
        Observed joint gain ``G_tx + G_rx`` [dB] (paper eq. 5).
    distance_m : ndarray
        Distance between the ends [m].
    frequency_hz : ndarray or None
        Carrier frequency of every sample [Hz].
    non_unit_quaternions : int
        Samples whose tx or rx quaternion norm was off 1 by more than
        :data:`QUATERNION_NORM_TOLERANCE` (normalised, as in matching; reported by ``fit``).
    tx_z_m, rx_z_m : ndarray or None
        ENU heights of both ends [m] (for the two-ray environment term); None when unknown.
    outages : int
        Outage events of the dataset left out (``outage`` True: no RSSI to learn from).
    t_s : ndarray or None
        Time of every sample [s] (the matched dataset's ``t``); None when unknown.
    """

    directions: Directions
    tx_index: np.ndarray
    rx_index: np.ndarray
    nodes: tuple[str, ...]
    joint_gain_db: np.ndarray
    distance_m: np.ndarray
    frequency_hz: np.ndarray | None = None
    non_unit_quaternions: int = 0
    tx_z_m: np.ndarray | None = None
    rx_z_m: np.ndarray | None = None
    outages: int = 0
    t_s: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.joint_gain_db.shape[0])


@check_types
def link_samples(
    df: pd.DataFrame, source: str = "dataset", nodes: Sequence[str] | None = None, require_rssi: bool = True
) -> LinkSamples:
    """Directions of both ends, node indices and observed joint gain of a matched dataset.

    Parameters
    ----------
    df : DataFrame
        Matched dataset (:data:`MATCHED_COLUMNS`).
    source : str
        Name used in error messages.
    nodes : sequence of str, optional
        Node ids in model order; by default the sorted ids found in ``tx`` and ``rx``.
        A sample naming a node outside this list raises :class:`InputError`.
    require_rssi : bool
        False for poses of links to predict: the observed gain is then NaN where ``rssi_dbm``
        is absent, NaN or a sentinel value. True: outage events (``outage`` True) are left out
        and counted in ``LinkSamples.outages``.
    """
    df = validate_matched(df, source, require_rssi=require_rssi)
    n_outages = 0
    if require_rssi and OUTAGE_COLUMN in df.columns:
        down = df[OUTAGE_COLUMN].to_numpy(bool)
        n_outages = int(down.sum())
        df = df[~down] if n_outages else df
    tx = df["tx"].to_numpy(str)
    rx = df["rx"].to_numpy(str)
    if nodes is None:
        nodes_t = tuple(sorted(set(tx) | set(rx)))
    else:
        nodes_t = tuple(str(n) for n in nodes)
        unknown = sorted((set(tx) | set(rx)) - set(nodes_t))
        if unknown:
            raise InputError(
                f"{source}: unknown node id(s) {', '.join(unknown)}; the model knows {', '.join(nodes_t)}"
            )
    index = pd.Index(nodes_t)  # vectorised look-up (a dict per row took 40 ms per 100k rows)
    tx_index = index.get_indexer(tx).astype(np.intp)
    rx_index = index.get_indexer(rx).astype(np.intp)
    tx_pos = df[["tx_x", "tx_y", "tx_z"]].to_numpy(np.float64)
    rx_pos = df[["rx_x", "rx_y", "rx_z"]].to_numpy(np.float64)
    tx_q = df[["tx_qw", "tx_qx", "tx_qy", "tx_qz"]].to_numpy(np.float64)
    rx_q = df[["rx_qw", "rx_qx", "rx_qy", "rx_qz"]].to_numpy(np.float64)
    off = np.zeros(len(df), bool)
    for end, q in (("tx", tx_q), ("rx", rx_q)):
        norm = np.linalg.norm(q, axis=1)
        zero = norm < 1e-9
        if np.any(zero):
            row = int(np.flatnonzero(zero)[0])
            raise InputError(
                f"{source}: quaternion ({end}_qw, {end}_qx, {end}_qy, {end}_qz) has zero norm at row {row} "
                f"({int(zero.sum())} row(s)); no attitude can be read from it"
            )
        off |= np.abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE
    dirs = link_directions(tx_pos, tx_q, rx_pos, rx_q)
    dist = distance_m(tx_pos, rx_pos)
    if "rssi_dbm" in df.columns:
        rssi = pd.to_numeric(df["rssi_dbm"], errors="coerce").to_numpy(np.float64)
    else:
        rssi = np.full(len(df), np.nan)
    if not require_rssi:
        rssi = np.where(np.isin(rssi, SENTINEL_RSSI_DBM), np.nan, rssi)
    check_far_field(dist, df["frequency_hz"].to_numpy(np.float64), f"{source}: tx/rx positions")  # named by the file
    gain = observed_joint_gain_db(
        rssi,
        df["tx_power_dbm"].to_numpy(np.float64),
        dist,
        df["frequency_hz"].to_numpy(np.float64),
    )
    return LinkSamples(dirs, tx_index, rx_index, nodes_t, gain, dist, df["frequency_hz"].to_numpy(np.float64),
                       non_unit_quaternions=int(off.sum()), tx_z_m=tx_pos[:, 2].copy(), rx_z_m=rx_pos[:, 2].copy(),
                       outages=n_outages, t_s=df["t"].to_numpy(np.float64) if "t" in df.columns else None)
