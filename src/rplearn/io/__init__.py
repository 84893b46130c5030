"""Readers of flight and signal logs, each giving canonical pose and signal logs (DESIGN.md).

=================  =========================================  ==================================
format             reader                                     gives
=================  =========================================  ==================================
CSV, Parquet       :func:`rplearn.io.tables.read_pose_table`,  pose or signal log
                   :func:`rplearn.io.tables.read_signal_table`
ROS 2 / ROS 1 bag  :func:`rplearn.io.rosbag.read_rosbag`       pose and signal logs
PX4 ULog           :func:`rplearn.io.ulog.read_ulog`           pose log
pcap / pcapng      :func:`rplearn.io.pcap.read_pcap`           signal log
=================  =========================================  ==================================

:func:`read_logs` chooses the reader of every path by its content (magic bytes) and, failing
that, its extension, and concatenates the results. Each format library (rosbags, pyulog,
dpkt, pymap3d) is imported only when a file of its format is read.
"""

from __future__ import annotations

import os
from typing import Any, Iterable, Mapping

import pandas as pd

from rplearn.data.tables import NON_UNIT_QUATERNION_ATTR, validate_pose_log
from rplearn.errors import InputError, LogFormatError, RplearnError
from rplearn.io._common import Logs

_MAGIC: tuple[tuple[bytes, str], ...] = (
    (b"ULog\x01\x12\x35", "ulog"),
    (b"#ROSBAG V2.0", "ros1"),
    (b"\x89MCAP", "ros2"),
    (b"SQLite format 3\x00", "ros2"),
    (b"\x0a\x0d\x0d\x0a", "pcap"),
    (b"\xd4\xc3\xb2\xa1", "pcap"),
    (b"\xa1\xb2\xc3\xd4", "pcap"),
    (b"\x4d\x3c\xb2\xa1", "pcap"),
    (b"\xa1\xb2\x3c\x4d", "pcap"),
    (b"PAR1", "table"),
)
_EXTENSIONS: dict[str, str] = {
    ".ulg": "ulog",
    ".bag": "ros1",
    ".mcap": "ros2",
    ".db3": "ros2",
    ".pcap": "pcap",
    ".pcapng": "pcap",
    ".cap": "pcap",
    ".csv": "table",
    ".parquet": "table",
    ".pq": "table",
}


def detect_format(path: str | os.PathLike) -> str:
    """Format of a log: ``"ulog"``, ``"ros1"``, ``"ros2"``, ``"pcap"`` or ``"table"``.

    A directory holding ``metadata.yaml`` is a ROS 2 bag. Files are judged by their first
    bytes, then by extension.
    """
    p = str(path)
    if not os.path.exists(p):
        raise InputError(f"{p}: no such file or directory")
    if os.path.isdir(p):
        if os.path.exists(os.path.join(p, "metadata.yaml")):
            return "ros2"
        raise InputError(f"{p}: a directory but not a ROS 2 bag (no metadata.yaml)")
    with open(p, "rb") as fh:
        head = fh.read(16)
    for magic, kind in _MAGIC:
        if head.startswith(magic):
            return kind
    ext = os.path.splitext(p)[1].lower()
    if ext in _EXTENSIONS:
        return _EXTENSIONS[ext]
    raise InputError(
        f"{p}: unknown log format; expected one of {', '.join(sorted(set(_EXTENSIONS)))} "
        "or a ROS 2 bag directory"
    )


def _bag_needs_topics(path: str, msg_definitions: Mapping[str, str] | None) -> str:
    """Message for a bag read without topics: how to name them, and the topics it has."""
    from rplearn.io.rosbag import bag_topics, describe_topics

    head = (
        f"{path}: a ROS bag needs its pose topics and RSSI topics named (rplearn sync "
        "--pose-topic TOPIC=NODE --rssi-topic TOPIC=TX:RX, or pose_topics={topic: node}, "
        "rssi_topics={topic: (tx, rx)})"
    )
    try:
        topics = bag_topics(path, msg_definitions)
    except RplearnError as exc:
        return f"{head}; its topics cannot be listed ({str(exc).splitlines()[0]})"
    return f"{head}; it has {describe_topics(topics)}"


def read_logs(
    paths: str | os.PathLike | Iterable[str | os.PathLike],
    *,
    columns: Mapping[str, str] | None = None,
    origin_geodetic: tuple[float, float, float] | None = None,
    nodes: Mapping[str, str] | None = None,
    pose_topics: Mapping[str, str] | None = None,
    rssi_topics: Mapping[str, tuple[str, str]] | None = None,
    rssi_field: str = "rssi",
    msg_definitions: Mapping[str, str] | None = None,
    receivers: Mapping[str, str] | None = None,
    address_map: Mapping[str, str] | None = None,
    tx_power_dbm: float | Mapping[str, float] | None = None,
    frequency_hz: float | None = None,
    nan_policy: str = "error",
    allow_unsorted: bool = False,
    require_valid: bool = False,
) -> tuple[Logs, dict[str, Any]]:
    """Read logs of any supported format into one pose log and one signal log.

    Parameters
    ----------
    paths : path or iterable of paths
        Files (or ROS 2 bag directories).
    columns : mapping, optional
        Column renaming for CSV/Parquet tables (``{"their name": "canonical"}``).
    origin_geodetic : (lat_deg, lon_deg, alt_m), optional
        Common ENU origin for geodetic tables and ULogs. By default the first geodetic
        file's origin (its first fix, or a ULog's anchor) is used for all the others.
    nodes : mapping of path to node id, optional
        Node id of a ULog or of a one-node table without a ``node`` column.
    pose_topics, rssi_topics, rssi_field, msg_definitions
        ROS bag options (:func:`rplearn.io.rosbag.read_rosbag`).
    receivers : mapping of path to node id, optional
        Capturing node of every pcap file.
    address_map : mapping of MAC address to node id, optional
        Transmitter addresses of pcap files.
    tx_power_dbm, frequency_hz
        Constants for formats that do not log them (pcap, bags, tables without the column).
    nan_policy : {"error", "drop"}
        NaN pose rows in tables (``rplearn sync --nan-policy``).
    allow_unsorted : bool
        Accept pose tables whose times go backwards within a node; they are sorted
        (``rplearn sync --allow-unsorted``).
    require_valid : bool
        Drop ULog local-position rows flagged invalid by the autopilot (``xy_valid`` or
        ``z_valid`` = 0; ``rplearn sync --require-valid``).

    Returns
    -------
    logs : Logs
        ``pose`` and ``signal`` (None if no file gave one).
    metadata : dict
        ``files``: a list of the per-file metadata (with ``format`` and ``kind``),
        ``origin_geodetic``: the common origin used (or None).
    """
    from rplearn.io import pcap as _pcap
    from rplearn.io import rosbag as _rosbag
    from rplearn.io import tables as _tables
    from rplearn.io import ulog as _ulog

    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    paths = [str(p) for p in paths]
    if not paths:
        raise InputError("read_logs: no paths given")
    nodes = {str(k): v for k, v in (nodes or {}).items()}
    receivers = {str(k): v for k, v in (receivers or {}).items()}
    poses: list[pd.DataFrame] = []
    signals: list[pd.DataFrame] = []
    files: list[dict[str, Any]] = []
    origin = origin_geodetic
    for path in paths:
        kind = detect_format(path)
        if kind == "table":
            what = _tables.table_kind(path, columns)
            if what == "pose":
                pose, meta = _tables.read_pose_table(
                    path, columns=columns, node=nodes.get(path), origin_geodetic=origin,
                    nan_policy=nan_policy, allow_unsorted=allow_unsorted,
                )
                if meta.get("origin_geodetic") is not None and origin is None:
                    origin = meta["origin_geodetic"]
                poses.append(pose)
            else:
                ptx = tx_power_dbm if not isinstance(tx_power_dbm, Mapping) else None
                signal, meta = _tables.read_signal_table(
                    path, columns=columns, tx_power_dbm=ptx, frequency_hz=frequency_hz,
                    rx=receivers.get(path),
                )
                signals.append(signal)
            meta["kind"] = what
        elif kind in ("ros1", "ros2"):
            if not pose_topics and not rssi_topics:
                raise InputError(_bag_needs_topics(path, msg_definitions))
            if isinstance(tx_power_dbm, Mapping):
                raise InputError(f"{path}: the transmit power for a bag must be one number [dBm] (--tx-power, tx_power_dbm=)")
            logs, meta = _rosbag.read_rosbag(
                path, pose_topics or {}, rssi_topics, rssi_field=rssi_field,
                tx_power_dbm=tx_power_dbm, frequency_hz=frequency_hz,
                msg_definitions=msg_definitions,
            )
            if logs.pose is not None:
                poses.append(logs.pose)
            if logs.signal is not None:
                signals.append(logs.signal)
            meta["kind"] = "pose+signal"
        elif kind == "ulog":
            node = nodes.get(path)
            if node is None:
                raise InputError(
                    f"{path}: give the node id of this ULog (rplearn sync --node {path}=NODE, "
                    "or nodes={path: node})"
                )
            pose, meta = _ulog.read_ulog(path, node, origin, time_reference="auto", require_valid=require_valid)
            if origin is None and meta["anchor_geodetic"] is not None:
                # re-express on the anchor so that later logs share it (no-op for this one)
                origin = meta["anchor_geodetic"]
            poses.append(pose)
            meta["kind"] = "pose"
        else:  # pcap
            rx = receivers.get(path)
            if rx is None:
                raise InputError(
                    f"{path}: give the capturing node (rplearn sync --receiver {path}=NODE, "
                    "or receivers={path: node})"
                )
            if tx_power_dbm is None:
                raise InputError(
                    f"{path}: give the transmit power, radiotap does not carry the sender's power "
                    "(rplearn sync --tx-power DBM, or tx_power_dbm=)"
                )
            signal, meta = _pcap.read_pcap(
                path, rx, tx_power_dbm, address_map=address_map, frequency_hz=frequency_hz
            )
            signals.append(signal)
            meta["kind"] = "signal"
        files.append(meta)
    pose = None
    if poses:
        merged = pd.concat(poses, ignore_index=True)
        merged.attrs[NON_UNIT_QUATERNION_ATTR] = sum(int(p.attrs.get(NON_UNIT_QUATERNION_ATTR, 0)) for p in poses)
        pose = validate_pose_log(merged, "pose logs")
    signal = None
    if signals:
        signal = pd.concat(signals, ignore_index=True).sort_values("t", kind="stable").reset_index(drop=True)
    return Logs(pose=pose, signal=signal), {"files": files, "origin_geodetic": origin}


__all__ = ["Logs", "LogFormatError", "detect_format", "read_logs"]
