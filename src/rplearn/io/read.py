"""Reading logs of any supported format: detect each file's format and read it into one
canonical pose log and one signal log (:func:`read_logs`)."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from rplearn._argtypes import check_types
from rplearn.data.tables import NON_UNIT_QUATERNION_ATTR, validate_pose_log
from rplearn.errors import InputError, RplearnError
from rplearn.io._common import Logs
from rplearn.io.damage import drop_repeated_across, one_station, refuse_overlaps
from rplearn.io.options import ReaderOptions
from rplearn.io.partitions import refuse_repeated
from rplearn.io.sniff import detect_format


def _bag_needs_topics(path: str, msg_definitions: Mapping[str, str] | None) -> str:
    """Message for a bag read without topics: how to name them, and the topics it has."""
    from rplearn.io.rosbag import bag_topics, describe_topics

    head = (
        f"{path}: a ROS bag needs its pose topics and RSSI topics named "
        "(ReaderOptions.pose_topics={topic: node}, ReaderOptions.rssi_topics={topic: (tx, rx)})"
    )
    try:
        topics = bag_topics(path, msg_definitions)
    except RplearnError as exc:
        return f"{head}; its topics cannot be listed ({str(exc).splitlines()[0]})"
    return f"{head}; it has {describe_topics(topics)}"


@dataclass
class _Gathered:
    """What :func:`read_logs` has read so far: logs, per-file metadata, the common origin."""

    origin: tuple[float, float, float] | None
    poses: list[pd.DataFrame] = field(default_factory=list)
    signals: list[pd.DataFrame] = field(default_factory=list)
    files: list[dict[str, Any]] = field(default_factory=list)
    pose_files: list[int] = field(default_factory=list)  # the file (index in files) of each pose log
    signal_files: list[int] = field(default_factory=list)

    def add(self, logs: Logs) -> None:
        """Keep the pose and the signal log a reader gave (either may be None)."""
        if logs.pose is not None:
            self.poses.append(logs.pose)
        if logs.signal is not None:
            self.signals.append(logs.signal)


def _path_list(paths: str | os.PathLike | Iterable[str | os.PathLike]) -> list[str]:
    """The paths as a non-empty list of strings."""
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    out = [str(p) for p in paths]
    if not out:
        raise InputError("read_logs: no paths given", param="paths")
    return out


def _read_table(path: str, options: ReaderOptions, got: _Gathered) -> dict[str, Any]:
    """Read a CSV/Parquet pose or signal table; a geodetic one may fix the common origin."""
    from rplearn.io import tables as _tables

    what = _tables.table_kind(path, options.columns)
    if what == "pose":
        pose, meta = _tables.read_pose_table(
            path, columns=options.columns, node=(options.nodes or {}).get(path),
            origin_geodetic=got.origin, nan_policy=options.nan_policy,
            allow_unsorted=options.allow_unsorted,
        )
        if meta.get("origin_geodetic") is not None and got.origin is None:
            got.origin = meta["origin_geodetic"]
        got.poses.append(pose)
    else:
        ptx = options.tx_power_dbm if not isinstance(options.tx_power_dbm, Mapping) else None
        signal, meta = _tables.read_signal_table(
            path, columns=options.columns, tx_power_dbm=ptx, frequency_hz=options.frequency_hz,
            rx=(options.receivers or {}).get(path), allow_unsorted=options.allow_unsorted,
        )
        got.signals.append(signal)
    meta["kind"] = what
    return meta


def _read_bag(path: str, options: ReaderOptions, got: _Gathered) -> dict[str, Any]:
    """Read the named pose and RSSI topics of a ROS 1 or ROS 2 bag."""
    from rplearn.io import rosbag as _rosbag

    if not options.pose_topics and not options.rssi_topics:
        raise InputError(_bag_needs_topics(path, options.msg_definitions), param="pose_topics")
    if isinstance(options.tx_power_dbm, Mapping):
        raise InputError(
            f"{path}: the transmit power for a bag must be one number [dBm] (ReaderOptions.tx_power_dbm)",
            param="tx_power_dbm",
        )
    logs, meta = _rosbag.read_rosbag(
        path, options.pose_topics or {}, options.rssi_topics, options.rssi_field, options.tx_power_dbm,
        options.frequency_hz, _rosbag.RosbagOptions(msg_definitions=options.msg_definitions),
    )
    got.add(logs)
    meta["kind"] = "pose+signal"
    return meta


def _require_radio_settings(path: str, options: ReaderOptions, why: str) -> None:
    """Refuse, naming the options, a telemetry-radio log read without the radios' transmit power
    and carrier frequency (``why``: the words after "frequency [Hz]")."""
    missing = [f for f in ("tx_power_dbm", "frequency_hz") if getattr(options, f) is None]
    if missing:
        raise InputError(
            f"{path}: give the telemetry radios' transmit power [dBm] and carrier frequency [Hz]{why} "
            f"(ReaderOptions.{' and ReaderOptions.'.join(missing)})",
            param=missing[0], related=missing[1:],
        )


def _read_ulog(path: str, options: ReaderOptions, got: _Gathered) -> dict[str, Any]:
    """Read a PX4 ULog of a named node (with ``ulog_radio``, its telemetry radio too: both links
    to the ground station, :mod:`rplearn.io.ulog_radio`); its geodetic anchor may fix the common
    origin."""
    from rplearn.io import ulog_radio as _radio

    node = (options.nodes or {}).get(path)
    if node is None:
        raise InputError(
            f"{path}: give the node id of this ULog (ReaderOptions.nodes={{path: node}})", param="nodes"
        )
    radio = None
    if options.ulog_radio:
        _require_radio_settings(path, options, " to read its radio, a ULog carries neither")
        if isinstance(options.tx_power_dbm, Mapping):
            raise InputError(f"{path}: the transmit power of a ULog's radio must be one number [dBm] "
                             "(ReaderOptions.tx_power_dbm)", param="tx_power_dbm")
        assert options.tx_power_dbm is not None and options.frequency_hz is not None  # refused above
        radio = _radio.UlogRadio(float(options.tx_power_dbm), float(options.frequency_hz), options.station,
                                 options.station_geodetic, options.station_heading_deg)
    logs, meta = _radio.read_ulog_logs(path, node, radio, got.origin, options.require_valid)
    if got.origin is None and meta["anchor_geodetic"] is not None:
        # re-express on the anchor so that later logs share it (no-op for this one)
        got.origin = meta["anchor_geodetic"]
    got.add(logs)
    meta["kind"] = "pose" if logs.signal is None else "pose+signal"
    return meta


def _read_pcap(path: str, options: ReaderOptions, got: _Gathered) -> dict[str, Any]:
    """Read a radiotap capture of a named receiver with a known transmit power."""
    from rplearn.io import pcap as _pcap

    rx = (options.receivers or {}).get(path)
    if rx is None:
        raise InputError(
            f"{path}: give the capturing node (ReaderOptions.receivers={{path: node}})", param="receivers"
        )
    if options.tx_power_dbm is None:
        raise InputError(
            f"{path}: give the transmit power [dBm], radiotap does not carry the sender's power "
            "(ReaderOptions.tx_power_dbm)",
            param="tx_power_dbm",
        )
    signal, meta = _pcap.read_pcap(
        path, rx, options.tx_power_dbm, address_map=options.address_map, frequency_hz=options.frequency_hz
    )
    got.signals.append(signal)
    meta["kind"] = "signal"
    return meta


def _read_mavlink(path: str, options: ReaderOptions, got: _Gathered) -> dict[str, Any]:
    """Read an ArduPilot telemetry or DataFlash log: the vehicle's poses, the station, both links."""
    from rplearn.io import mavlink as _mavlink

    _require_radio_settings(path, options, ", a MAVLink log carries neither")
    assert options.tx_power_dbm is not None and options.frequency_hz is not None  # refused above
    logs, meta = _mavlink.read_mavlink(
        path, options.tx_power_dbm, options.frequency_hz, (options.nodes or {}).get(path), options.station,
        _mavlink.MavlinkOptions(station_geodetic=options.station_geodetic, origin_geodetic=got.origin,
                                station_heading_deg=options.station_heading_deg),
    )
    if got.origin is None:
        got.origin = meta["origin_geodetic"]
    got.add(logs)
    meta["kind"] = "pose+signal"
    return meta


_READERS: dict[str, Callable[[str, ReaderOptions, _Gathered], dict[str, Any]]] = {
    "table": _read_table,
    "ros1": _read_bag,
    "ros2": _read_bag,
    "ulog": _read_ulog,
    "pcap": _read_pcap,
    "mavlink": _read_mavlink,
}


def _merge(got: _Gathered) -> tuple[Logs, dict[str, Any]]:
    """One validated pose log and one time-sorted signal log from everything read; rows that
    repeat another file's are read once (counted), different rows of one stream from two files
    over the same times are refused."""
    poses = drop_repeated_across(one_station(got.poses, got.pose_files, got.files), got.pose_files, got.files, "pose")
    signals = drop_repeated_across(got.signals, got.signal_files, got.files, "signal")
    refuse_overlaps(poses, got.pose_files, got.files, "pose")
    refuse_overlaps(signals, got.signal_files, got.files, "signal")
    pose = None
    if poses:
        merged = pd.concat(poses, ignore_index=True)
        merged.attrs[NON_UNIT_QUATERNION_ATTR] = sum(
            int(p.attrs.get(NON_UNIT_QUATERNION_ATTR, 0)) for p in got.poses
        )
        pose = validate_pose_log(merged, "pose logs")
    signal = None
    if signals:
        signal = pd.concat(signals, ignore_index=True).sort_values("t", kind="stable").reset_index(drop=True)
    return Logs(pose=pose, signal=signal), {"files": got.files, "origin_geodetic": got.origin}


@check_types
def read_logs(
    paths: str | os.PathLike | Iterable[str | os.PathLike],
    options: ReaderOptions | None = None,
) -> tuple[Logs, dict[str, Any]]:
    """Read logs of any supported format into one pose log and one signal log.

    Parameters
    ----------
    paths : path or iterable of paths
        Files (or ROS 2 bag directories); each one's format is detected by
        :func:`detect_format`.
    options : ReaderOptions, optional
        Column renaming, common geodetic origin, node ids, bag topics, pcap receivers and
        addresses, constant tx power [dBm] and frequency [Hz], and the NaN / unsorted /
        invalid-row policies; ``ReaderOptions()`` by default.

    Returns
    -------
    logs : Logs
        ``pose`` and ``signal`` (None if no file gave one).
    metadata : dict
        ``files``: a list of the per-file metadata (with ``format`` and ``kind``; a file
        whose rows repeat an earlier file's exactly, the same log given twice under two names
        or overlapping exports, has them read once and counted in ``repeated_rows``),
        ``origin_geodetic``: the common origin used (or None).

    Raises
    ------
    InputError
        On a missing file, an unknown format, an option a file needs but was not given
        (``param`` names the :class:`ReaderOptions` field), or two files giving one node's
        poses (one link's readings) over overlapping times with different rows.
    """
    if options is None:
        options = ReaderOptions()
    elif not isinstance(options, ReaderOptions):
        raise InputError(
            f"options: expected a ReaderOptions, got {type(options).__name__}", param="options"
        )
    got = _Gathered(origin=options.origin_geodetic)
    files = _path_list(paths)
    refuse_repeated(files, ", ".join(files), param="paths")  # one log named twice would count twice
    for path in files:
        n_pose, n_signal = len(got.poses), len(got.signals)
        meta = _READERS[detect_format(path)](path, options, got)
        meta.setdefault("source", path)
        got.pose_files += [len(got.files)] * (len(got.poses) - n_pose)
        got.signal_files += [len(got.files)] * (len(got.signals) - n_signal)
        got.files.append(meta)
    return _merge(got)


#: Public names of the subpackage defined in its modules, imported on first use.
