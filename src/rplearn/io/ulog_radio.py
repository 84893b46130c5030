"""The telemetry radio of a PX4 ULog -> both directions of the link to the ground station.

PX4 logs every ``RADIO_STATUS`` packet its telemetry radio (a SiK radio on a telemetry port)
sends to the autopilot as the uORB topic ``radio_status`` (PX4 1.11 and later; one of the
logger's default topics, ``src/modules/logger/logged_topics.cpp``), with the packet's fields
``rssi``, ``remote_rssi``, ``txbuf``, ``noise``, ``remote_noise``, ``rxerrors``, ``fix``.
Older PX4 kept the same fields in ``telemetry_status`` (its rows of ``type`` 1, a 3DR/SiK
radio). The autopilot's *own* (air) radio sends the packet, so, as in an ArduPilot DataFlash
``RAD`` record (:mod:`rplearn.io.mavlink`), ``rssi`` is the vehicle receiving (link station ->
vehicle) and ``remote_rssi`` the station receiving (link vehicle -> station). SiK units become
dBm with the SiK formula (:func:`rplearn.io.mavlink.sik_rssi_to_dbm`); 255 ("unknown") drops
that direction's row (counted); a 0 in the vehicle's own log means the link dropped: both rows
of that packet are kept as outage events (``outage`` True, ``rssi_dbm`` NaN), never learned
from. A packet logged twice is one reading (:func:`rplearn.io.mavlink_phases.repeated_readings`).

The radio readings are on the ULog's clock, put on the pose log's (UTC through the GPS offset,
else seconds since boot: :func:`rplearn.io.ulog.read_ulog`). The ground station is a static
node (one pose row, level, facing east unless a heading is given): at ``station_geodetic`` when
given, else at the first valid ``home_position`` (its local ``x, y, z``: the frame of the
vehicle's positions), else at the vehicle's first position; the metadata's notes say which.

:func:`read_ulog_logs` reads a ULog's poses and, with ``radio`` given, its radio readings;
``ReaderOptions.ulog_radio`` (``--ulog-radio``) asks :func:`rplearn.io.read.read_logs` for it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn.core.geometry import ned_to_enu, quat_wxyz_from_euler_ned_frd_deg
from rplearn.core.plausible import check_plausible
from rplearn.data.tables import validate_pose_log, validate_signal_log
from rplearn.errors import InputError, LogFormatError
from rplearn.io._common import Logs
from rplearn.io.geodetic import geodetic_to_enu, local_ned_to_enu
from rplearn.io.mavlink import sik_rssi_to_dbm
from rplearn.io.mavlink_phases import repeated_readings

#: Raw SiK value meaning "unknown" in RADIO_STATUS.
SIK_UNKNOWN = 255
#: ``telemetry_status.type`` of a 3DR/SiK radio (older PX4, ``TELEMETRY_STATUS_RADIO_TYPE_3DR_RADIO``).
TELEMETRY_TYPE_SIK = 1


@dataclass(frozen=True)
class UlogRadio:
    """How to read a ULog's telemetry radio (module docstring).

    Attributes
    ----------
    tx_power_dbm : float
        Both radios' transmit power [dBm] (a ULog does not log it).
    frequency_hz : float
        Carrier frequency [Hz].
    station : str
        Node id of the ground station.
    station_geodetic : (float, float, float), optional
        The station's position (lat [deg], lon [deg], alt [m] AMSL); by default the home position.
    station_heading_deg : float, optional
        Compass heading of the station's body x axis [deg]; by default 90 (east, assumed).
    """

    tx_power_dbm: float
    frequency_hz: float
    station: str = "gcs"
    station_geodetic: tuple[float, float, float] | None = None
    station_heading_deg: float | None = None


@dataclass(frozen=True)
class RadioReadings:
    """The raw telemetry-radio readings of a ULog, sorted by time.

    Attributes
    ----------
    t_us : ndarray of int64
        Times [us] on the ULog's clock.
    rssi, remote_rssi : ndarray of int64
        The air radio's and the ground radio's RSSI [SiK units 0-255].
    topic : str
        The topic read (``radio_status`` or ``telemetry_status``).
    """

    t_us: np.ndarray
    rssi: np.ndarray
    remote_rssi: np.ndarray
    topic: str


def _instances(ulog: Any, name: str) -> list[dict[str, np.ndarray]]:
    return [d.data for d in ulog.data_list if d.name == name]


def radio_readings(ulog: Any) -> RadioReadings | None:
    """The readings of ``radio_status`` (all instances), else of ``telemetry_status`` rows of a
    SiK radio (older PX4); None when the log holds none."""
    for topic in ("radio_status", "telemetry_status"):
        t, a, b = [], [], []
        for data in _instances(ulog, topic):
            if not all(k in data for k in ("timestamp", "rssi", "remote_rssi")):
                continue
            keep = np.ones(len(data["timestamp"]), bool)
            if topic == "telemetry_status" and "type" in data:
                keep &= np.asarray(data["type"]) == TELEMETRY_TYPE_SIK
            t.append(np.asarray(data["timestamp"], np.int64)[keep])
            a.append(np.asarray(data["rssi"], np.int64)[keep])
            b.append(np.asarray(data["remote_rssi"], np.int64)[keep])
        if t and sum(len(x) for x in t):
            t_all, a_all, b_all = np.concatenate(t), np.concatenate(a), np.concatenate(b)
            order = np.argsort(t_all, kind="stable")
            return RadioReadings(t_all[order], a_all[order], b_all[order], topic)
    return None


def home_local_ned(ulog: Any) -> np.ndarray | None:
    """The first valid home position in the vehicle's local NED frame [m], or None."""
    home = _home(ulog)
    return None if home is None else home[0]


def _home(ulog: Any) -> tuple[np.ndarray, int | None] | None:
    """The first valid home position in the local NED frame [m] and its timestamp [us since boot], or None."""
    for data in _instances(ulog, "home_position"):
        if not all(k in data for k in ("x", "y", "z")):
            continue
        ned = np.stack([np.asarray(data[k], np.float64) for k in ("x", "y", "z")], axis=-1)
        ok = np.all(np.isfinite(ned), axis=1)
        for flag in ("valid_hpos", "valid_lpos"):
            if flag in data:
                ok &= np.asarray(data[flag]) != 0
        if ok.any():
            i = int(np.flatnonzero(ok)[0])
            return ned[i], int(data["timestamp"][i]) if "timestamp" in data else None
    return None


def fix_accuracy(ulog: Any, t_us: int | None) -> tuple[float, float] | None:
    """The GPS accuracy the log reports (``eph``, ``epv``: standard deviations [m], horizontal and vertical)
    of its fix at or last before ``t_us`` [us since boot] (``vehicle_gps_position``, else ``sensor_gps``, the
    first instance holding them), or None (no such fix, or not a positive finite accuracy)."""
    if t_us is None:
        return None
    for name in ("vehicle_gps_position", "sensor_gps"):
        for data in _instances(ulog, name):
            if not all(k in data for k in ("timestamp", "eph", "epv")) or not len(data["timestamp"]):
                continue
            i = max(int(np.searchsorted(np.asarray(data["timestamp"], np.int64), t_us, side="right")) - 1, 0)
            eph, epv = float(data["eph"][i]), float(data["epv"][i])
            if np.isfinite(eph) and np.isfinite(epv) and eph > 0 and epv > 0:
                return eph, epv
    return None


def radio_signal_log(t_s: np.ndarray, readings: RadioReadings, vehicle: str, radio: UlogRadio
                     ) -> tuple[pd.DataFrame, dict[str, int]]:
    """Both directions of the link, one row per reading (module docstring), and the counts:
    ``duplicate_reading``, ``link_lost``, ``unknown_*`` / ``rows_*`` / ``outage_*`` per direction
    (``vehicle_to_station``, ``station_to_vehicle``)."""
    values = np.stack([readings.rssi, readings.remote_rssi], axis=1)
    copy, _ = repeated_readings(t_s, values)
    counts = {"duplicate_reading": int(copy.sum())}
    t, rssi, remote = t_s[~copy], readings.rssi[~copy], readings.remote_rssi[~copy]
    lost = (rssi == 0) | (remote == 0)  # the vehicle's own log: a zero is the link dropped
    counts["link_lost"] = int(lost.sum())
    parts = []
    for tx, rx, value, name in ((vehicle, radio.station, remote, "vehicle_to_station"),
                                (radio.station, vehicle, rssi, "station_to_vehicle")):
        unknown = (value == SIK_UNKNOWN) & ~lost
        counts[f"unknown_{name}"] = int(unknown.sum())
        keep = ~unknown
        counts[f"rows_{name}"] = int((keep & ~lost).sum())
        counts[f"outage_{name}"] = int((keep & lost).sum())
        parts.append(pd.DataFrame({
            "t": t[keep], "tx": tx, "rx": rx,
            "rssi_dbm": np.where(lost[keep], np.nan, sik_rssi_to_dbm(value[keep])),
            "tx_power_dbm": float(radio.tx_power_dbm), "frequency_hz": float(radio.frequency_hz),
            "rssi_raw": value[keep].astype(np.int64), "outage": lost[keep],
        }))
    signal = pd.concat(parts, ignore_index=True).sort_values("t", kind="stable").reset_index(drop=True)
    return signal, counts


def _station_xyz(ulog: Any, pose: pd.DataFrame, meta: dict[str, Any], radio: UlogRadio,
                 origin_geodetic: tuple[float, float, float] | None, source: str) -> tuple[np.ndarray, str]:
    """The station's position in the pose log's frame [m] and where it came from."""
    anchor = meta.get("anchor_geodetic")
    if radio.station_geodetic is not None:
        frame = origin_geodetic if origin_geodetic is not None else anchor
        if frame is None:
            raise InputError(f"{source}: a station position is given but the log has no geodetic anchor to place it "
                             "(no EKF reference, no global position, no GPS fix)", param="station_geodetic")
        return (np.asarray(geodetic_to_enu(*radio.station_geodetic, frame, where="the station"), np.float64),
                "station position given (ReaderOptions.station_geodetic)")
    found = _home(ulog)
    # in the frame of the vehicle's positions (rplearn.io.ulog: the log's own, or around the origin through the anchor)
    placed = "station placed at the vehicle's home (home_position)"
    if found is not None and origin_geodetic is None:
        return np.asarray(ned_to_enu(found[0]), np.float64).reshape(3), placed
    if found is not None and anchor is not None:
        return np.asarray(local_ned_to_enu(found[0][None, :], tuple(anchor), origin_geodetic), np.float64).reshape(3), placed
    first = pose[["x", "y", "z"]].to_numpy(np.float64)[0]
    return first, "station placed at the vehicle's first position (no valid home_position in the log)"


def _station_accuracy(ulog: Any, pose: pd.DataFrame, meta: dict[str, Any], note: str) -> tuple[float, float] | None:
    """The GPS accuracy (eph, epv [m]) of the fix the station was placed at (:func:`_station_xyz`'s ``note``): the
    home's, else the first position's; None for a given position or a log reporting none."""
    if "given" in note:
        return None
    found = _home(ulog)
    if found is not None and note.startswith("station placed at the vehicle's home"):
        return fix_accuracy(ulog, found[1])
    offset = meta.get("utc_offset_us") if meta.get("time_reference") == "utc" else 0
    return fix_accuracy(ulog, int(round(float(pose["t"].iloc[0]) * 1e6 - float(offset or 0))))


def read_ulog_logs(path: str | os.PathLike, node: str, radio: UlogRadio | None = None,
                   origin_geodetic: tuple[float, float, float] | None = None,
                   require_valid: bool = False) -> tuple[Logs, dict[str, Any]]:
    """A ULog's pose log (:func:`rplearn.io.ulog.read_ulog`, clock ``"auto"``) and, with
    ``radio``, its telemetry radio's signal log with the ground station's pose row.

    Returns
    -------
    logs : Logs
        ``pose`` (the vehicle, and the station with ``radio``) and ``signal`` (None without ``radio``).
    metadata : dict
        :func:`~rplearn.io.ulog.read_ulog`'s, with ``notes``, ``radio_readings`` (the readings
        the log holds, 0 when none) and ``radio_topic``; with ``radio`` also ``station``,
        ``station_note``, ``station_accuracy_m`` (the GPS accuracy, eph and epv [m], the log reports for
        the fix the station was placed at, or None: :func:`rplearn.io.damage.one_station` takes two such fixes
        for one station within their noise), ``vehicle`` and ``signal`` (the counts of :func:`radio_signal_log`).

    Raises
    ------
    LogFormatError
        ``radio`` given and the log holds no telemetry-radio readings.
    InputError
        As :func:`~rplearn.io.ulog.read_ulog`; the station named as the vehicle; a station
        implausibly far from the flight.
    """
    from rplearn.io.ulog import parsed_ulog, read_ulog, release_parsed

    source = str(path)
    try:
        pose, meta = read_ulog(source, node, origin_geodetic, time_reference="auto", require_valid=require_valid)
        ulog = parsed_ulog(source)  # the parse read_ulog made (kept until here)
    finally:
        release_parsed()
    readings = radio_readings(ulog)
    meta.update(notes=[], radio_readings=0 if readings is None else len(readings.t_us),
                radio_topic=None if readings is None else readings.topic)
    if radio is None:
        if readings is not None:
            meta["notes"].append(f"{source}: {len(readings.t_us):,} telemetry-radio reading(s) ({readings.topic}) not read: "
                                 "ReaderOptions.ulog_radio reads them as both directions of the link to the ground station")
        return Logs(pose=pose), meta
    if readings is None:
        raise LogFormatError(f"{source}: no radio_status (or telemetry_status of a SiK radio) messages: the log holds "
                             "no telemetry-radio RSSI")
    if radio.station == str(node):
        raise InputError(f"vehicle and station must differ, both are {node!r}", param="station")
    offset = meta["utc_offset_us"] if meta["time_reference"] == "utc" else 0
    t_s = (readings.t_us + int(offset or 0)) * 1e-6
    xyz, station_note = _station_xyz(ulog, pose, meta, radio, origin_geodetic, source)
    meta["station_accuracy_m"] = _station_accuracy(ulog, pose, meta, station_note)
    far = np.linalg.norm(pose[["x", "y", "z"]].to_numpy(np.float64) - xyz, axis=1)
    try:
        check_plausible("link_distance_m", far, "the vehicle", field="distance from the station [m]")
    except InputError as exc:
        raise InputError(f"{source}: {exc} ({station_note})", param=exc.param) from None
    heading = 90.0 if radio.station_heading_deg is None else float(radio.station_heading_deg)
    q = quat_wxyz_from_euler_ned_frd_deg(0.0, 0.0, heading)
    t0 = float(min(t_s[0], pose["t"].iloc[0]))
    row = pd.DataFrame({"t": [t0], "node": [radio.station], "x": [xyz[0]], "y": [xyz[1]], "z": [xyz[2]],
                        "qw": [q[0]], "qx": [q[1]], "qy": [q[2]], "qz": [q[3]]})
    pose = validate_pose_log(pd.concat([pose, row], ignore_index=True), source)
    signal, counts = radio_signal_log(t_s, readings, str(node), radio)
    signal = validate_signal_log(signal, source)
    heading_note = ("assumed level and facing east (heading 90 deg): its attitude is not logged"
                    if radio.station_heading_deg is None else f"level, heading {heading:g} deg (given)")
    meta["notes"] += [f"{source}: {station_note}", f"{source}: station {radio.station!r} {heading_note}"]
    if counts["duplicate_reading"]:
        meta["notes"].append(f"{source}: {counts['duplicate_reading']:,} radio reading(s) logged twice: read once")
    unknown = {name: counts[f"unknown_{name}"] for name in ("vehicle_to_station", "station_to_vehicle")}
    if any(unknown.values()):
        meta["notes"].append(f"{source}: radio readings of 255 (unknown) dropped: {unknown['vehicle_to_station']:,} "
                             f"{node} -> {radio.station}, {unknown['station_to_vehicle']:,} {radio.station} -> {node}")
    if counts["link_lost"]:
        meta["notes"].append(f"{source}: {counts['link_lost']:,} radio reading(s) with a zero RSSI (link lost): kept as "
                             "outage events (column outage, no RSSI), both directions")
    meta.update(vehicle=str(node), station=radio.station, station_note=station_note, signal=counts)
    return Logs(pose=pose, signal=signal), meta


__all__ = ["SIK_UNKNOWN", "RadioReadings", "UlogRadio", "fix_accuracy", "home_local_ned", "radio_readings",
           "radio_signal_log", "read_ulog_logs"]
