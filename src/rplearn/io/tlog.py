"""Canonical pose and signal logs -> a MAVLink telemetry log (``.tlog``), through ``pymavlink``.

The inverse of :func:`rplearn.io.mavlink.read_mavlink` for a ground station's log: a vehicle
flying around a static ground station, the two linked by a 3DR/SiK telemetry radio. It lets a
simulated flight (:func:`rplearn.sim.flight.simulate`) go through the same path as a real one,
and gives ground-station tools (MAVExplorer, Mission Planner) a file to replay.

What is written (MAVLink 2 frames of the ``ardupilotmega`` dialect, each after the tlog's
8-byte big-endian receive time [us since the UNIX epoch]):

- per vehicle pose row, ``ATTITUDE`` (NED/FRD roll, pitch, yaw [rad] from the FLU -> ENU
  quaternion) and ``GLOBAL_POSITION_INT`` (lat, lon [1e-7 deg], alt [mm], NED velocity vx,
  vy, vz [cm/s] from finite differences of the positions) from system ``system_id``,
  component 1, with ``time_boot_ms`` = the row's time on a boot clock; a ``HEARTBEAT`` (a
  quadrotor, ``base_mode`` armed) at the first row of each second;
- one ``HOME_POSITION`` and one ``GPS_GLOBAL_ORIGIN`` with the station's position (the median
  of its pose rows, which may spread by estimator noise but not move: :func:`station_pose`);
  its attitude is not loggable: pass the returned ``station_heading_deg`` back to the reader;
- per signal row, one ``RADIO_STATUS`` from the ground radio (system 51, component 68, as SiK
  firmware sends it) with the row's RSSI in SiK units, ``round((dBm + 127) * 1.9)`` clipped to
  1-254 (0 means link lost and 255 unknown), in ``rssi`` when the station received it and in
  ``remrssi`` when the vehicle did; the other field is 255 (unknown).

:class:`TlogDefects` writes what real logs hold into such a clean flight: positions before
the EKF origin is set (the altitude at a fixed wrong value, no ``HOME_POSITION`` yet, the
vehicle disarmed), a reboot (``time_boot_ms`` restarts after a silent gap, then positions
invalid again until the origin is set anew), every radio reading written twice (as
``RADIO_STATUS`` and as ``RADIO``), and lost links (the vehicle silent, each radio report a
zero ``rssi`` and ``remrssi``, as SiK radios report a dropped link).

Positions go through WGS-84 geodetic coordinates around ``origin_geodetic``; ``tx_power_dbm``
and ``frequency_hz`` are not loggable and must be given to the reader again.
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn.core.geometry import enu_to_ned, euler_from_quat_wxyz, quat_enu_flu_to_ned_frd, yaw_from_quat_wxyz
from rplearn.errors import InputError
from rplearn.io._common import Logs
from rplearn.io.geodetic import local_ned_to_geodetic
from rplearn.io.mavlink import SIK_UNITS_PER_DB, SIK_ZERO_DBM

#: The MAVLink system and component ids SiK radios send ``RADIO_STATUS`` with.
SIK_SYSTEM_ID, SIK_COMPONENT_ID = 51, 68
#: Receive time of the log's first message [s since the UNIX epoch] (2026-01-01T00:00:00Z).
DEFAULT_START_UNIX_S = 1_767_225_600.0
#: The boot clock reads this at the first row [s].
BOOT_LEAD_S = 1.0


@check_types
def dbm_to_sik_rssi(rssi_dbm: Any) -> tuple[np.ndarray, int]:
    """Received power [dBm] -> SiK RSSI units (1-254) and the count of values clipped to that range.

    Raises
    ------
    InputError
        When ``rssi_dbm`` is not finite real numbers.
    """
    try:
        dbm = np.asarray(rssi_dbm, np.float64)
    except (TypeError, ValueError):
        raise InputError(f"rssi_dbm: expected received powers [dBm] (real numbers), got {type(rssi_dbm).__name__}",
                         param="rssi_dbm") from None
    if not np.all(np.isfinite(dbm)):
        raise InputError(f"rssi_dbm: {int(np.count_nonzero(~np.isfinite(dbm)))} value(s) are NaN or infinite, "
                         "which SiK units cannot hold", param="rssi_dbm")
    raw = np.rint((dbm - SIK_ZERO_DBM) * SIK_UNITS_PER_DB)
    clipped = int(np.count_nonzero((raw < 1) | (raw > 254)))
    return np.clip(raw, 1, 254).astype(np.int64), clipped


def _dialect() -> Any:
    try:
        from pymavlink.dialects.v20 import ardupilotmega
    except ImportError:  # pragma: no cover - pymavlink is a dependency
        raise InputError("writing MAVLink logs needs the 'pymavlink' package (pip install pymavlink)") from None
    return ardupilotmega


def checked_logs(logs: Logs, vehicle: str, station: str, origin_geodetic: Any) -> tuple[pd.DataFrame, pd.DataFrame]:
    if logs.pose is None or logs.signal is None:
        raise InputError("write_tlog: needs both a pose log and a signal log", param="logs")
    pose, signal = logs.pose, logs.signal
    if vehicle == station:
        raise InputError(f"vehicle and station must differ, both are {vehicle!r}", param="station")
    for node in (vehicle, station):
        if not (pose["node"] == node).any():
            raise InputError(f"write_tlog: node {node!r} has no pose rows", param="vehicle" if node == vehicle else "station")
    pair = {vehicle, station}
    other = ~(signal["tx"].isin(pair) & signal["rx"].isin(pair) & (signal["tx"] != signal["rx"]))
    if other.any():
        row = signal[other].iloc[0]
        raise InputError(f"write_tlog: a telemetry log holds the link {vehicle} <-> {station} only, "
                         f"the signal log has {int(other.sum())} row(s) of others (e.g. {row['tx']} -> {row['rx']})",
                         param="signal")
    if not len(signal):
        raise InputError("write_tlog: the signal log is empty: a telemetry log without RADIO_STATUS holds no link",
                         param="signal")
    for name, frame, cols in (("pose", pose, ["t", "x", "y", "z", "qw", "qx", "qy", "qz"]),
                              ("signal", signal, ["t", "rssi_dbm"])):
        bad = ~np.isfinite(frame[cols].to_numpy(np.float64)).all(axis=1)
        if bad.any():
            raise InputError(f"write_tlog: {int(bad.sum())} {name} row(s) hold NaN or infinite values in "
                             f"{', '.join(cols)} (drop them first)", param=name)
    try:
        origin = np.asarray(origin_geodetic, np.float64)
    except (TypeError, ValueError):
        origin = np.zeros(0)
    if origin.shape != (3,) or not np.all(np.isfinite(origin)):
        raise InputError(f"origin_geodetic: expected (lat, lon, alt), got {origin_geodetic!r}", param="origin_geodetic")
    return pose, signal


#: A station whose pose rows spread farther than this from their median is moving [m].
STATION_SPREAD_LIMIT_M = 5.0


def station_pose(pose: pd.DataFrame, station: str) -> tuple[np.ndarray, float, float]:
    """The static station a tlog can hold: median ENU position [m], compass heading of its body
    x axis [deg, clockwise from north] (from the mean of its rows' yaws) and how far its rows
    spread from that position [m] (estimator noise).

    Raises
    ------
    InputError
        When the rows spread farther than :data:`STATION_SPREAD_LIMIT_M`: a moving node.
    """
    rows = pose[pose["node"] == station]
    xyz = rows[["x", "y", "z"]].to_numpy(np.float64)
    centre = np.median(xyz, axis=0)
    spread = float(np.max(np.linalg.norm(xyz - centre, axis=1)))
    if spread > STATION_SPREAD_LIMIT_M:
        raise InputError(f"write_tlog: station {station!r} moves ({spread:.1f} m from its median position); "
                         "a telemetry log holds a static ground station", param="station")
    yaw = yaw_from_quat_wxyz(rows[["qw", "qx", "qy", "qz"]].to_numpy(np.float64))
    mean_yaw = float(np.arctan2(np.mean(np.sin(yaw)), np.mean(np.cos(yaw))))
    return centre, float(np.mod(90.0 - np.degrees(mean_yaw), 360.0)), spread


@check_types
@dataclass(frozen=True)
class TlogDefects:
    """Defects of real ground-station logs to write into a clean simulated flight (all off by default).

    Attributes
    ----------
    invalid_until_s : float
        For this long from the vehicle's first row [s], ``GLOBAL_POSITION_INT.alt`` reads
        ``invalid_alt_m`` and no ``HOME_POSITION`` / ``GPS_GLOBAL_ORIGIN`` is sent (the EKF
        origin is not set yet); the vehicle is disarmed.
    invalid_alt_m : float
        The altitude [m AMSL] an estimator without origin reports (0.8 m in a real log).
    reboot_at_s : float or None
        A reboot this long after the vehicle's first row [s]: the vehicle falls silent for
        ``reboot_silence_s``, its ``time_boot_ms`` restarts, and the altitude reads
        ``invalid_alt_m`` for ``invalid_after_reboot_s`` until the origin is set again.
    reboot_silence_s, invalid_after_reboot_s : float
        See ``reboot_at_s`` [s].
    radio_twice : bool
        Every radio reading is written as ``RADIO_STATUS`` and again as ``RADIO`` (id 166).
    copy_delay_s : float
        How long after the ``RADIO_STATUS`` its ``RADIO`` copy is received [s].
    link_lost : tuple of (from_s, to_s)
        Windows of time since the vehicle's first row [s] in which the link is lost: none of
        the vehicle's messages is written, and every radio report in the window (one per
        instant) reads 0 in ``rssi`` and ``remrssi``.
    fix_accuracy_m : (float, float) or None
        The GPS accuracy the log reports, horizontal and vertical standard deviations [m]: a ``GPS_RAW_INT``
        (3-D fix, ``h_acc``/``v_acc`` [mm], ``eph``/``epv`` unknown) with each of the vehicle's rows (a
        DataFlash log: a ``GPA``, ``HAcc``/``VAcc``); None (the default): none written, as in MAVLink 1 logs.
    """

    invalid_until_s: float = 0.0
    invalid_alt_m: float = 0.8
    reboot_at_s: float | None = None
    reboot_silence_s: float = 10.0
    invalid_after_reboot_s: float = 60.0
    radio_twice: bool = False
    copy_delay_s: float = 0.004
    link_lost: tuple[tuple[float, float], ...] = ()
    fix_accuracy_m: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if self.fix_accuracy_m is not None:
            try:
                acc = tuple(float(v) for v in self.fix_accuracy_m)
            except (TypeError, ValueError):
                acc = ()
            if len(acc) != 2 or not all(np.isfinite(v) and 0 < v < 600 for v in acc):
                raise InputError(f"fix_accuracy_m: expected (horizontal, vertical) standard deviations in metres "
                                 f"(0 to 600 m), got {self.fix_accuracy_m!r}", param="fix_accuracy_m")
            object.__setattr__(self, "fix_accuracy_m", acc)
        try:
            windows = tuple((float(a), float(b)) for a, b in self.link_lost)
        except (TypeError, ValueError):
            windows = ((1.0, 0.0),)
        if not all(np.isfinite(a) and np.isfinite(b) and a < b for a, b in windows):
            raise InputError(f"link_lost: expected windows (from_s, to_s) with from_s < to_s, got {self.link_lost!r}",
                             param="link_lost")
        object.__setattr__(self, "link_lost", windows)
        for name in ("invalid_until_s", "reboot_silence_s", "invalid_after_reboot_s", "copy_delay_s", "reboot_at_s"):
            value = getattr(self, name)
            if value is None and name == "reboot_at_s":
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value < 0:
                raise InputError(f"{name}: expected a non-negative number of seconds, got {value!r}", param=name)
        if isinstance(self.invalid_alt_m, bool) or not isinstance(self.invalid_alt_m, (int, float)) \
                or not np.isfinite(self.invalid_alt_m):
            raise InputError(f"invalid_alt_m: expected metres, got {self.invalid_alt_m!r}", param="invalid_alt_m")

    def phases(self, rel_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per time since the vehicle's first row [s]: silent (rebooting), position invalid,
        and the boot (0, or 1 after the reboot)."""
        rel = np.asarray(rel_s, np.float64)
        invalid = rel < self.invalid_until_s
        silent = np.zeros(len(rel), bool)
        boot = np.zeros(len(rel), np.int64)
        if self.reboot_at_s is not None:
            back = self.reboot_at_s + self.reboot_silence_s
            silent = (rel >= self.reboot_at_s) & (rel < back)
            invalid |= (rel >= back) & (rel < back + self.invalid_after_reboot_s)
            boot = (rel >= self.reboot_at_s).astype(np.int64)
        return silent | self.lost(rel), invalid, boot

    def lost(self, rel_s: np.ndarray) -> np.ndarray:
        """Whether each time since the vehicle's first row [s] lies in a ``link_lost`` window."""
        rel = np.asarray(rel_s, np.float64)
        out = np.zeros(len(rel), bool)
        for a, b in self.link_lost:
            out |= (rel >= a) & (rel < b)
        return out


def vehicle_fields(pose: pd.DataFrame, vehicle: str, origin: tuple[float, float, float]) -> dict[str, np.ndarray]:
    """The vehicle's rows as an autopilot logs them: ``t`` [s], ``lat``, ``lon`` [deg], ``alt``
    [m AMSL], NED/FRD ``roll``, ``pitch``, ``yaw`` [rad] and NED velocity ``vel`` (n, 3) [m/s]
    (finite differences of the positions)."""
    veh = pose[pose["node"] == vehicle].sort_values("t", kind="stable")
    t = veh["t"].to_numpy(np.float64)
    ned = enu_to_ned(veh[["x", "y", "z"]].to_numpy(np.float64))
    lat, lon, alt = local_ned_to_geodetic(ned, origin)
    roll, pitch, yaw = euler_from_quat_wxyz(quat_enu_flu_to_ned_frd(veh[["qw", "qx", "qy", "qz"]].to_numpy(np.float64)))
    with np.errstate(divide="ignore", invalid="ignore"):
        vel = np.stack([np.gradient(ned[:, j], t) for j in range(3)], axis=-1) if len(t) > 1 else np.zeros((len(t), 3))
    vel = np.nan_to_num(vel, nan=0.0, posinf=0.0, neginf=0.0)
    return {"t": t, "lat": lat, "lon": lon, "alt": alt, "roll": roll, "pitch": pitch, "yaw": yaw, "vel": vel}


def _cm_s(v: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(v * 100.0), -32767, 32767).astype(np.int64)


def _records(pose: pd.DataFrame, signal: pd.DataFrame, vehicle: str, station: str,
             origin: tuple[float, float, float], start_unix_s: float, system_id: int,
             defects: TlogDefects) -> tuple[list[tuple[float, int, bytes]], dict[str, Any]]:
    """(receive time [us], order, frame) of every message, and what was written."""
    mav = _dialect()
    air = mav.MAVLink(None, srcSystem=system_id, srcComponent=1)
    radio = mav.MAVLink(None, srcSystem=SIK_SYSTEM_ID, srcComponent=SIK_COMPONENT_ID)
    v = vehicle_fields(pose, vehicle, origin)
    t0 = float(min(v["t"][0], signal["t"].min())) - BOOT_LEAD_S
    rel = v["t"] - v["t"][0]
    silent, invalid, boot = defects.phases(rel)
    boot_zero = np.where(boot > 0, v["t"][0] + (defects.reboot_at_s or 0.0) + 0.5 * defects.reboot_silence_s, t0)
    boot_ms = np.rint((v["t"] - boot_zero) * 1e3).astype(np.int64)
    recv_us = start_unix_s * 1e6 + np.rint((v["t"] - t0) * 1e6)
    alt = np.where(invalid, defects.invalid_alt_m, v["alt"])
    vx, vy, vz = (_cm_s(v["vel"][:, j]) for j in range(3))
    out: list[tuple[float, int, bytes]] = []
    sxyz, heading, spread = station_pose(pose, station)
    slat, slon, salt = (float(v_) for v_ in local_ned_to_geodetic(enu_to_ned(sxyz), origin))
    home_lat, home_lon, home_alt = int(round(slat * 1e7)), int(round(slon * 1e7)), int(round(salt * 1e3))
    valid = ~invalid & ~silent
    # the origin is set (HOME_POSITION, GPS_GLOBAL_ORIGIN) at the first valid row of each boot
    origin_rows = [int(np.flatnonzero(valid & (boot == b))[0]) for b in np.unique(boot) if np.any(valid & (boot == b))]
    for i in origin_rows:
        at = recv_us[i] if invalid.any() or i > 0 else start_unix_s * 1e6
        out.append((float(at), 0, air.home_position_encode(home_lat, home_lon, home_alt, 0.0, 0.0, 0.0,
                                                           [1.0, 0.0, 0.0, 0.0], 0.0, 0.0, 0.0).pack(air)))
        out.append((float(at), 0, air.gps_global_origin_encode(home_lat, home_lon, home_alt).pack(air)))
    second = np.floor(v["t"] - t0)
    beat = np.concatenate([[True], second[1:] != second[:-1]]) & ~silent
    counts = {"attitude": 0, "heartbeat": 0}
    for i in np.flatnonzero(~silent).tolist():
        b = int(boot_ms[i])
        if beat[i]:
            base = 128 if valid[i] else 0  # MAV_MODE_FLAG_SAFETY_ARMED once the origin is set
            out.append((float(recv_us[i]), 0, air.heartbeat_encode(2, 3, base | 1, 0, 4).pack(air)))
            counts["heartbeat"] += 1
        att = air.attitude_encode(b, float(v["roll"][i]), float(v["pitch"][i]), float(v["yaw"][i]), 0.0, 0.0, 0.0)
        gpi = air.global_position_int_encode(b, int(round(v["lat"][i] * 1e7)), int(round(v["lon"][i] * 1e7)),
                                             int(round(alt[i] * 1e3)), int(round((alt[i] - salt) * 1e3)),
                                             int(vx[i]), int(vy[i]), int(vz[i]), 65535)
        out.append((float(recv_us[i]), 1, att.pack(air)))
        out.append((float(recv_us[i]), 2, gpi.pack(air)))
        if defects.fix_accuracy_m is not None:
            h_mm, v_mm = (int(round(a * 1e3)) for a in defects.fix_accuracy_m)
            gps = air.gps_raw_int_encode(b * 1000, 3, int(round(v["lat"][i] * 1e7)), int(round(v["lon"][i] * 1e7)),
                                         int(round(alt[i] * 1e3)), 65535, 65535, 65535, 65535, 10, h_acc=h_mm, v_acc=v_mm)
            out.append((float(recv_us[i]), 2, gps.pack(air)))
        counts["attitude"] += 1
    raw, clipped = dbm_to_sik_rssi(signal["rssi_dbm"].to_numpy(np.float64))
    to_station = (signal["rx"] == station).to_numpy()
    sig_us = np.rint((signal["t"].to_numpy(np.float64) - t0) * 1e6) + start_unix_s * 1e6
    lost = defects.lost(signal["t"].to_numpy(np.float64) - v["t"][0])
    repeat = lost & np.concatenate([[False], sig_us[1:] == sig_us[:-1]]) & np.concatenate([[False], lost[:-1]])
    for i in np.flatnonzero(~repeat).tolist():
        rssi, rem = (0, 0) if lost[i] else (int(raw[i]), 255) if to_station[i] else (255, int(raw[i]))
        out.append((float(sig_us[i]), 3, radio.radio_status_encode(rssi, rem, 100, 0, 0, 0, 0).pack(radio)))
        if defects.radio_twice:
            out.append((float(sig_us[i] + round(defects.copy_delay_s * 1e6)), 3,
                        radio.radio_encode(rssi, rem, 100, 0, 0, 0, 0).pack(radio)))
    n_radio = int((~repeat).sum())
    written = {"attitude": counts["attitude"], "global_position_int": counts["attitude"], "radio_status": n_radio,
               "radio": n_radio if defects.radio_twice else 0, "link_lost_reports": int((lost & ~repeat).sum()), "heartbeat": counts["heartbeat"],
               "gps_raw_int": counts["attitude"] if defects.fix_accuracy_m is not None else 0,
               "home_position": len(origin_rows), "invalid_position_rows": int((invalid & ~silent).sum()),
               "silent_rows": int(silent.sum()),
               "rssi_clipped": clipped, "station_geodetic": (slat, slon, salt), "start_unix_s": start_unix_s,
               "station_heading_deg": heading, "station_spread_m": spread, "clock_offset_s": start_unix_s - t0}
    return out, written


@check_types
def write_tlog(
    logs: Logs,
    path: str | os.PathLike,
    vehicle: str,
    station: str,
    origin_geodetic: tuple[float, float, float],
    start_unix_s: float = DEFAULT_START_UNIX_S,
    system_id: int = 1,
    defects: TlogDefects | None = None,
) -> dict[str, Any]:
    """Write a vehicle's poses and its telemetry link to a static station as a ``.tlog`` (module docstring).

    Parameters
    ----------
    logs : Logs
        Pose log (the vehicle's rows and the station's) and signal log (rows of the two
        directions between them only), canonical schemas (docs/conventions.md).
    path : str or PathLike
        Output ``.tlog``; written atomically (a failed write leaves no partial file).
    vehicle, station : str
        Node ids of the vehicle and the ground station.
    origin_geodetic : (lat_deg, lon_deg, alt_m)
        Geodetic position of the logs' ENU origin (altitude AMSL).
    start_unix_s : float
        Receive time of the vehicle's boot-clock zero [s since the UNIX epoch].
    system_id : int
        MAVLink system id of the vehicle (1-255).
    defects : TlogDefects, optional
        Defects of real logs to write (a position before the origin is set, a reboot, radio
        readings written twice); none by default.

    Returns
    -------
    dict
        Messages written per type, ``link_lost_reports`` (radio reports of a lost link), ``rssi_clipped`` (values outside SiK's 1-254 range),
        ``station_geodetic`` (the HOME_POSITION written), ``station_heading_deg`` (compass, for
        the reader's ``station_heading_deg``), ``station_spread_m`` and ``clock_offset_s`` (the
        tlog's time minus the logs' time [s]). Extra signal columns (``unit``) are not written.

    Raises
    ------
    InputError
        On a missing log or node, rows of other links, or a bad argument (``param`` names it).
    """
    if not (isinstance(system_id, (int, np.integer)) and not isinstance(system_id, bool)
            and 1 <= system_id <= 255 and system_id != SIK_SYSTEM_ID):
        raise InputError(f"system_id: expected 1-255 other than the radio's {SIK_SYSTEM_ID}, got {system_id!r}",
                         param="system_id")
    if not (isinstance(start_unix_s, (int, float, np.number)) and 0 <= float(start_unix_s) < 2**63 / 1e6):
        raise InputError(f"start_unix_s: expected a time in seconds since the UNIX epoch, got {start_unix_s!r}",
                         param="start_unix_s")
    pose, signal = checked_logs(logs, vehicle, station, origin_geodetic)
    origin = tuple(float(v) for v in origin_geodetic)
    if defects is not None and not isinstance(defects, TlogDefects):
        raise InputError(f"defects: expected a TlogDefects, got {type(defects).__name__}", param="defects")
    records, written = _records(pose, signal, vehicle, station, origin, float(start_unix_s), int(system_id),  # type: ignore[arg-type]
                                defects or TlogDefects())
    records.sort(key=lambda r: (r[0], r[1]))
    with atomic_open(path, "wb", param="path") as fh:
        for t_us, _, frame in records:
            fh.write(struct.pack(">Q", int(round(t_us))) + frame)
    return written


__all__ = ["STATION_SPREAD_LIMIT_M", "TlogDefects", "dbm_to_sik_rssi", "station_pose", "vehicle_fields", "write_tlog"]
