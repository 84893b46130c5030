"""The files ``rplearn inspect`` reads (:func:`rplearn.io.inspect.inspect_logs`), each with the readers of
:mod:`rplearn.io` in a forgiving mode: NaN pose rows dropped and counted, unsorted times accepted, placeholders for
the settings inspection does not need; a pose table's rows kept in file order, with the facts the readers found."""

from __future__ import annotations

import os
from dataclasses import replace
from typing import Any

import numpy as np
import pandas as pd

from rplearn.data.tables import non_unit_quaternion_rows
from rplearn.io._csv_headers import REPEATED_HEADER_AT
from rplearn.io._pose_checks import same_rows
from rplearn.io.damage import signal_row_problems
from rplearn.io.options import ReaderOptions

#: The value columns of a pose table (any variant): a row with one of them not a finite number is a NaN row.
_POSE_VALUE_COLUMNS = ("t", "x", "y", "z", "lat", "lon", "alt", "qw", "qx", "qy", "qz", "roll_deg",
                       "pitch_deg", "yaw_deg", "roll_ned_deg", "pitch_ned_deg", "yaw_ned_deg")


def _read_pose_table(path: str, options: ReaderOptions) -> tuple[pd.DataFrame, dict[str, Any], dict[str, int],
                                                                 pd.DataFrame]:
    """A pose table in file order (``t``, ``node``), its facts, its NaN rows per node, and the
    canonical pose log (sorted, for the flight checks).

    The table is read forgivingly (NaN rows dropped, unsorted times accepted) to check it,
    then its valid rows are returned unsorted: inspection wants the file order.
    """
    from rplearn.io import tables as _tables

    node_of_file = (options.nodes or {}).get(path)
    raw = _tables.read_table_rows(path, path)
    pose, meta = _tables.canonical_pose(
        raw, source=path, columns=options.columns, node=node_of_file, nan_policy="drop",
        allow_unsorted=True, origin_geodetic=options.origin_geodetic,
    )
    info: dict[str, Any] = {"format": _tables.table_format(path), "kind": "pose",
                            "non_unit_quaternion_rows": non_unit_quaternion_rows(pose)}
    dropped = {k: int(n) for k, n in meta["dropped"].items() if n and k != "nan_pose"}  # NaN rows: nan_rows
    if dropped:  # a coordinate beyond any place, a position jump: said, as sync would drop them
        info["dropped"] = dropped
        info.update({k: v for k, v in meta.items() if k == REPEATED_HEADER_AT})  # where the first header lines were
        info["notes"] = [str(n).removeprefix(f"{path}: ") for n in meta.get("notes", ())]
    df = _tables.rename_columns(raw, options.columns)
    node = (df["node"].astype(str) if "node" in df.columns
            else pd.Series([node_of_file if node_of_file is not None else "?"] * len(df)))
    cols = [c for c in _POSE_VALUE_COLUMNS if c in df.columns]
    values = df[cols].apply(pd.to_numeric, errors="coerce").to_numpy(np.float64)
    bad = ~np.isfinite(values).all(axis=1)
    nan_rows = {str(k): int(v) for k, v in node[bad].value_counts().items()}
    copies = same_rows(df.assign(node=node.to_numpy()))  # duplicate_pose: no step back
    file_order = pd.DataFrame({"t": values[~bad & ~copies, cols.index("t")], "node": node[~bad & ~copies].to_numpy()})
    return file_order, info, nan_rows, pose


def _forgiving_options(path: str, kind: str, options: ReaderOptions) -> ReaderOptions:
    """Options with placeholders for what inspection does not need: node id of a ULog (its
    file name), receiver of a pcap (``capture``), tx power [dBm] and frequency [Hz]."""
    if kind == "ulog":
        nodes = {path: os.path.splitext(os.path.basename(path))[0], **(options.nodes or {})}
        if not options.ulog_radio:
            return replace(options, nodes=nodes)
        return replace(options, nodes=nodes, tx_power_dbm=0.0 if options.tx_power_dbm is None else options.tx_power_dbm,
                       frequency_hz=1e9 if options.frequency_hz is None else options.frequency_hz)
    if kind == "pcap":
        return replace(
            options,
            tx_power_dbm=0.0 if options.tx_power_dbm is None else options.tx_power_dbm,
            receivers={path: "capture"} if options.receivers is None else options.receivers,
        )
    if kind == "mavlink":
        return replace(
            options,
            tx_power_dbm=0.0 if options.tx_power_dbm is None else options.tx_power_dbm,
            frequency_hz=1e9 if options.frequency_hz is None else options.frequency_hz,
        )
    if kind in ("ros1", "ros2") and options.rssi_topics:
        return replace(
            options,
            tx_power_dbm=0.0 if options.tx_power_dbm is None else options.tx_power_dbm,
            frequency_hz=1.0 if options.frequency_hz is None else options.frequency_hz,
        )
    return options


def read_for_inspection(path: str, options: ReaderOptions) -> tuple[pd.DataFrame | None, pd.DataFrame | None,
                                                                    dict[str, Any], dict[str, int], pd.DataFrame | None]:
    """A file's poses in file order, signals, facts (``frequency_hz`` [Hz] when the log or the
    options give it), NaN pose rows per node, and canonical poses."""
    from rplearn.io import tables as _tables
    from rplearn.io.read import detect_format, read_logs

    kind = detect_format(path)
    if kind == "table":
        if _tables.table_kind(path, options.columns) == "pose":
            pose, info, nan_rows, canonical = _read_pose_table(path, options)
            return pose, None, info, nan_rows, canonical
        sig, meta = _tables.read_signal_table(
            path, columns=options.columns, rx=(options.receivers or {}).get(path),
            tx_power_dbm=0.0, frequency_hz=1.0, allow_unsorted=True)  # 1 Hz: a placeholder; backward steps reported below
        facts = {"format": meta["format"], "kind": "signal", "frequency_hz": _frequency_hz(sig),
                 **({"signal_dropped": meta["dropped"]} if any(meta["dropped"].values()) else {}),
                 **{k: v for k, v in meta.items() if k == REPEATED_HEADER_AT}}
        rows = signal_row_problems(sig)  # said only when there are some (JSON: the key only then)
        return None, sig, {**facts, **({"signal_row_problems": rows} if rows else {})}, {}, None
    logs, meta = read_logs(path, _forgiving_options(path, kind, options))
    f = meta["files"][0]
    info = {"format": f.get("format", kind), "kind": f.get("kind")}
    if logs.signal is not None and (kind not in ("mavlink", "ulog") or options.frequency_hz is not None):
        info["frequency_hz"] = _frequency_hz(logs.signal)
    if f.get("excluded_periods"):
        info["excluded_periods"] = f["excluded_periods"]
    if f.get("dropped"):  # a signal-only reader's (pcap's) drops are frames, not pose rows
        info["signal_dropped" if f.get("kind") == "signal" else "dropped"] = f["dropped"]
    if isinstance(f.get("signal"), dict):
        info["signal_dropped"] = _signal_drops(f["signal"])
    if f.get("invalid_flag_rows"):
        info["invalid_flag_rows"] = int(f["invalid_flag_rows"])
    for key in ("cut_off_at_byte", "cut_off_record", "records_read", "corrupt", "corrupt_at_byte", "corrupt_bytes",
                "corrupt_stretches",
                "repeated_messages", "close_copies", "unindexed", "trailing_bytes", "trailing_bag", "damaged_chunks",
                "damaged_chunk_messages", "damaged_index", "station", "station_note", "station_accuracy_m",
                "anchor_geodetic", "origin_geodetic"):
        if f.get(key):
            info[key] = f[key]
    if f.get("notes"):
        info["notes"] = [str(n).removeprefix(f"{path}: ") for n in f["notes"]]
    if logs.pose is not None:
        info["non_unit_quaternion_rows"] = non_unit_quaternion_rows(logs.pose)
    return logs.pose, logs.signal, info, {}, logs.pose


def _signal_drops(counts: dict[str, int]) -> dict[str, int]:
    """The counts of signal rows a MAVLink reader dropped, from all its signal counts: ``rows_*``
    are kept readings, and ``link_lost`` / ``outage_*`` count the link-lost messages it kept as
    outage events (said in the file's notes), so neither is a drop."""
    kept = ("rows_", "outage_", "link_lost")
    return {k: v for k, v in counts.items() if not str(k).startswith(kept)}


def _frequency_hz(signal: pd.DataFrame) -> float | None:
    """The lowest carrier frequency a signal log gives [Hz] (None for placeholders below 1 MHz)."""
    f = pd.to_numeric(signal["frequency_hz"], errors="coerce").to_numpy(np.float64) if len(signal) else np.zeros(0)
    f = f[np.isfinite(f) & (f >= 1e6)]
    return float(f.min()) if f.size else None


__all__ = ["read_for_inspection"]
