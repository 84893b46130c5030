"""ArduPilot / MAVLink logs -> canonical pose and signal logs, through ``pymavlink``.

Two kinds of file are read with ``mavutil.mavlink_connection(path, dialect="ardupilotmega")``:

- a ground station's telemetry log (``.tlog``: every MAVLink packet the ground station
  received, each after an 8-byte big-endian receive time [us since the UNIX epoch]);
- the autopilot's own DataFlash log (binary ``.bin``/``.BIN``, or its text ``.log`` form).

Pose of the vehicle (docs/conventions.md: ENU world, FLU body, quaternion wxyz FLU -> ENU):

- attitude: ``ATTITUDE`` (roll, pitch, yaw [rad]) or DataFlash ``ATT`` (Roll, Pitch, Yaw
  [deg]), aerospace yaw-pitch-roll of the FRD body in the NED world (yaw = heading clockwise
  from north), converted once by
  :func:`rplearn.core.geometry.quat_wxyz_from_euler_ned_frd_deg` (the conversion the PX4 and
  table readers use);
- position: ``GLOBAL_POSITION_INT`` (lat, lon [1e-7 deg], alt [mm] AMSL) or DataFlash ``POS``
  (Lat, Lng [deg], Alt [m] AMSL), else ``GPS`` (3-D fixes), converted to ENU around
  ``origin_geodetic`` (default: the ground station) by :func:`rplearn.io.geodetic.geodetic_to_enu`
  and interpolated linearly at the attitude instants (rows outside the position span or in a
  position gap longer than ``max_gap_s`` are dropped and counted, as in :mod:`rplearn.io.ulog`).

Signal log of both directions of a 3DR/SiK telemetry link, from ``RADIO_STATUS`` (id 109,
common dialect) or ``RADIO`` (id 166, ardupilotmega dialect; same fields) or DataFlash ``RAD``.
The MAVLink definitions (https://mavlink.io/en/messages/common.html#RADIO_STATUS) say
``rssi`` = "Local (message sender) received signal strength" and ``remrssi`` = "Remote (message
receiver) signal strength", values 0-254, 255 = unknown. Which radio sends the message fixes
the direction:

- in a ``.tlog`` the message comes from the ground radio, injected into the ground station's
  stream (SiK: system 51, component 68; ``metadata["radio_senders"]`` lists the senders seen):
  ``rssi`` is the station receiving (link vehicle -> station, rx = station) and ``remrssi`` the
  vehicle receiving (link station -> vehicle, rx = vehicle);
- in a DataFlash log ``RAD`` records the message the *air* radio sent to the autopilot
  (ArduPilot ``GCS_MAVLINK::handle_radio_status`` in libraries/GCS_MAVLink/GCS_Common.cpp,
  https://github.com/ArduPilot/ardupilot, logs the decoded packet and takes a non-zero
  ``remrssi`` to mean "the GCS has been receiving radio messages from the aircraft"), so
  ``RSSI`` is the vehicle receiving and ``RemRSSI`` the station receiving: the opposite
  assignment.

Each direction is its own link (``tx``, ``rx``). SiK units are converted to dBm with the SiK
formula ``signal_dBm = rssi / 1.9 - 127`` (ArduPilot wiki, SiK Radio - Advanced Configuration,
https://ardupilot.org/copter/docs/common-3dr-radio-advanced-configuration-and-technical-information.html;
also mavros' ``3dr_radio`` plugin). SiK zeroes the remote statistics when the link drops, so a
message with ``rssi`` or ``remrssi`` = 0 while the vehicle's own messages are absent (none
within ``stream_timeout_s``; in a DataFlash log always) is *link-lost*: both of its rows are
kept as outage events (column ``outage`` True, ``rssi_dbm`` NaN, counted; never learned from,
used to score availability: :mod:`rplearn.data.outages`); every other row has ``outage`` False. A 0 while the vehicle streams is a censored sample
(below sensitivity) and dropped for that direction only; 255 (unknown) likewise.

Clock: tlog rows are on the ground station's receive clock [s, UNIX]; the vehicle's messages
are placed there through their ``time_boot_ms`` plus the median receive-minus-boot offset (per
boot), which avoids the receive clock's coarse ticks and queueing jitter. DataFlash rows use
``TimeUS`` [s since boot] for both logs.

Flight phases and record hygiene (:mod:`rplearn.io.mavlink_phases`): position fixes before a
valid position solution (GPS fix below 3-D from ``GPS_RAW_INT.fix_type`` / DataFlash
``GPS.Status``; a position step the logged speed, ``GLOBAL_POSITION_INT`` vx, vy, vz, else a
plausible maximum, does not explain, the stretch from the log start or a reboot up to it
being invalid) and the stretch after each reboot (the boot clock stepping back) until the
position is valid again are excluded: their pose and signal rows are dropped and counted
under the period's reason, and ``metadata["excluded_periods"]`` lists each period (``reason``,
``from_t``, ``to_t`` on the log's clock, ``pose_rows``, ``signal_rows``, ``detail``), with a
line in ``notes``; ``metadata["reboots"]`` counts reboots. A radio reading reported twice
(DataFlash ``RAD`` twice; ``RADIO`` and ``RADIO_STATUS``) gives one row
(``metadata["signal"]["duplicate_reading"]`` counts the copies merged,
``metadata["radio_report_period_s"]`` the report period). A log in the file twice (files
concatenated, a copy resumed from its start) is read once: a ``.tlog`` message that repeats an
earlier one exactly (kind, sender, receive time, fields), and a DataFlash boot whose records
repeat an earlier boot's (same TimeUS and fields: the same boot again, not a reboot), are
dropped and counted in ``metadata["repeated_messages"]``; a record written twice (a ``.tlog``'s attitude or
position message, a DataFlash record: one of the last read again, time the same or up to 1 ms later, a DataFlash
record's far below the interval of records with its fields) is read once,
counted in ``metadata["close_copies"]``. Bytes of a ``.tlog`` that are no
whole record (a frame whose checksum fails, framing broken by a damaged length byte, junk) are
skipped: ``metadata["corrupt_stretches"]`` counts the stretches of such bytes between two whole
records (each lost one frame or more: pymavlink's parser says most with one ``BAD_DATA``
message, however many frames it swallowed) and ``metadata["corrupt_bytes"]`` their bytes. Both are said in one line
each (:func:`rplearn.io.inspect.file_damage`).

Armed state: when the log says it (a ``.tlog``'s ``HEARTBEAT`` of the vehicle, ``base_mode &
MAV_MODE_FLAG_SAFETY_ARMED``; DataFlash ``ARM`` records or ``EV`` armed/disarmed events), the
pose log has a boolean ``armed`` column: the latest state at or before each row (before the
first report, the first report's state); the station's row is False.

The ground station is a static node (one pose row, level, its body x axis facing east, or
``station_heading_deg``: its attitude is not logged) at ``station_geodetic`` if given, else ``HOME_POSITION`` (tlog) / ``ORGN`` type 1
(DataFlash home), else the vehicle's first fix; ``metadata["station_note"]`` says which.
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.geometry import quat_wxyz_from_euler_ned_frd_deg
from rplearn.core.plausible import check_plausible
from rplearn.data.tables import check_frequency_hz, check_tx_power_dbm, validate_pose_log, validate_signal_log
from rplearn.errors import InputError, LogFormatError
from rplearn.io import mavlink_phases as phases
from rplearn.io._common import Logs
from rplearn.io._dataflash_records import collect_dataflash
from rplearn.io._mavlink_records import Raw, collect_tlog
from rplearn.io._mavlink_station import station_fix
from rplearn.io.geodetic import geodetic_to_enu
from rplearn.io.options import check_origin

#: SiK RSSI units per dB and the dBm of a raw 0 (``dBm = raw / 1.9 - 127``, see the module docstring).
SIK_UNITS_PER_DB = 1.9
SIK_ZERO_DBM = -127.0
#: Raw value meaning "unknown" in RADIO_STATUS.
_UNKNOWN = 255

_DF_HEAD = b"\xa3\x95"
_DF_FMT_TYPE = 128


@check_types
def sik_rssi_to_dbm(raw: Any) -> np.ndarray:
    """SiK radio RSSI units -> received power [dBm]: ``raw / 1.9 - 127`` (module docstring).

    Raises
    ------
    InputError
        When ``raw`` is not real numbers.
    """
    try:
        values = np.asarray(raw, np.float64)
    except (TypeError, ValueError):
        raise InputError(f"raw: expected SiK RSSI units (real numbers 0-254), got {type(raw).__name__}",
                         param="raw") from None
    return values / SIK_UNITS_PER_DB + SIK_ZERO_DBM


def quat_from_ned_euler_rad(roll_rad: Any, pitch_rad: Any, yaw_rad: Any) -> np.ndarray:
    """FLU -> ENU quaternions (w, x, y, z) of ArduPilot attitudes: NED/FRD roll, pitch, yaw [rad]."""
    return quat_wxyz_from_euler_ned_frd_deg(np.degrees(roll_rad), np.degrees(pitch_rad), np.degrees(yaw_rad))


def dataflash_cut_off_at(path: str | os.PathLike) -> tuple[int | None, str | None, int]:
    """Where a binary DataFlash log ends inside a record: its byte offset (None if the file
    ends whole), the record's message name, and the bytes skipped as corrupt before it.

    A binary DataFlash log is a sequence of records ``A3 95 <type> <payload>`` whose lengths
    (header included) are declared by ``FMT`` records (type 128, 89 bytes: ``B type, B length,
    4s name, 16s format, 64s columns``). A log cut off by a power loss or a failed copy ends
    inside a record; pymavlink then stops without a word. Text logs (``FMT, ...``) and other
    files give ``(None, None, 0)``.
    """

    return _dataflash_walk(path)[:3]


def _dataflash_walk(path: str | os.PathLike) -> tuple[int | None, str | None, int, int | None]:
    """:func:`dataflash_cut_off_at` and the complete records of the log (None: not binary)."""
    import mmap

    with open(path, "rb") as fh:
        if os.fstat(fh.fileno()).st_size < 3 or fh.read(2) != _DF_HEAD:
            return None, None, 0, None
        with mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as data:
            return _walk_records(data, len(data))


def _walk_records(data: Any, size: int) -> tuple[int | None, str | None, int, int]:
    """:func:`dataflash_cut_off_at` on the bytes ``data`` (``size`` long), and the complete
    records."""
    formats = {_DF_FMT_TYPE: (89, "FMT")}
    pos, skipped, n = 0, 0, 0
    while pos < size:
        if size - pos < 3:
            if data[pos:size] == _DF_HEAD[: size - pos]:
                return pos, None, skipped, n
            return None, None, skipped + size - pos, n
        known = data[pos:pos + 2] == _DF_HEAD and data[pos + 2] in formats
        if not known or formats[data[pos + 2]][0] < 3:
            nxt = data.find(_DF_HEAD, pos + 1)
            nxt = size if nxt < 0 else nxt
            skipped += nxt - pos
            pos = nxt
            continue
        length, name = formats[data[pos + 2]]
        if pos + length > size:
            return pos, name, skipped, n
        if data[pos + 2] == _DF_FMT_TYPE:
            formats[data[pos + 3]] = (data[pos + 4], bytes(data[pos + 5:pos + 9]).rstrip(b"\0").decode("ascii", "replace"))
        pos += length
        n += 1
    return None, None, skipped, n


def increasing_times(t: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Strictly increasing times with their values, the first of repeated instants kept."""
    t_u, first = np.unique(t, return_index=True)
    return t_u, values[first]


def step_state(t: np.ndarray, events: np.ndarray, default: float) -> np.ndarray:
    """The value of the latest event (rows ``t, value``) at or before each time; before the
    first event, the first event's value (``default`` without events)."""
    if not len(events):
        return np.full(len(t), default)
    order = np.argsort(events[:, 0], kind="stable")
    et, ev = events[order, 0], events[order, 1]
    return ev[np.clip(np.searchsorted(et, t, side="right") - 1, 0, len(et) - 1)]


def position_fixes(raw: Raw, source: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
    """The position fixes (times, rows of ``raw.pos``) sorted, which are valid, and the excluded
    periods (:mod:`rplearn.io.mavlink_phases`)."""
    pos = raw.pos[np.all(np.isfinite(raw.pos[:, :4]), axis=1)]
    if len(pos) < 2:
        what = "GLOBAL_POSITION_INT" if raw.fmt == "tlog" else "POS or GPS"
        raise LogFormatError(f"{source}: fewer than 2 {what} position fixes of the vehicle")
    tp, pos = increasing_times(pos[:, 0], pos)
    fix_ok = step_state(tp, raw.fix, 1.0) > 0.5
    joined = None
    if raw.prefix is not None and len(raw.prefix):  # a window: the fixes read earlier first
        pos = np.concatenate([raw.prefix, pos])
        tp, fix_ok = pos[:, 0], np.concatenate([np.ones(len(raw.prefix), bool), fix_ok])
        joined = np.concatenate([np.asarray(raw.prefix_joined, bool), np.zeros(len(pos) - len(raw.prefix), bool)])
    step_origin = raw.step_origin if raw.step_origin is not None else tuple(pos[0, 1:4])
    try:
        enu = geodetic_to_enu(pos[:, 1], pos[:, 2], pos[:, 3], step_origin)  # steps only: any origin
    except InputError as exc:
        raise InputError(f"{source}: {exc}", param=exc.param) from None
    times = np.concatenate([raw.att[:, 0], tp, raw.radio[:, 0]])
    boot = pos[:, 6].astype(np.int64)
    invalid, steps = phases.invalid_fixes(tp, enu, pos[:, 4], pos[:, 5], boot, fix_ok, joined)
    name = "HOME_POSITION or GPS_GLOBAL_ORIGIN" if raw.fmt == "tlog" else "ORGN"
    periods = phases.excluded_periods(
        phases.Fixes(tp, invalid, boot, fix_ok, steps),
        phases.LogClock(float(np.nanmin(times)), float(np.nanmax(times)), raw.boot_last_t, raw.origin_t, name))
    if (~invalid).sum() < 2:
        raise LogFormatError(f"{source}: fewer than 2 valid position fixes of the vehicle "
                             f"({int(invalid.sum())} before a valid position solution)")
    return tp, pos, ~invalid, periods


def _vehicle_pose(raw: Raw, fixes: tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]],
                  origin: tuple[float, float, float], max_gap_s: float, node: str,
                  dropped: dict[str, int]) -> pd.DataFrame:
    """Pose rows at the attitude instants, positions (ENU [m] around ``origin``) interpolated
    from the valid fixes, rows in excluded periods dropped (counted in the periods)."""
    tp, pos, valid, periods = fixes
    att = raw.att
    ok = np.all(np.isfinite(att[:, :4]), axis=1)
    dropped["nan_attitude"] = int((~ok).sum())
    att = att[ok]
    n_att = len(att)
    ta, att_v = increasing_times(att[:, 0], att[:, 1:4])
    dropped["duplicate_time"] = n_att - len(ta)
    where = phases.in_periods(ta, periods)
    for reason in phases.REASONS:
        dropped[reason] = 0
    for p, n in zip(periods, np.bincount(where[where >= 0], minlength=len(periods))):
        p["pose_rows"] = int(n)
        dropped[p["reason"]] += p["pose_rows"]
    tp, geo = tp[valid], pos[valid, 1:4]
    enu = geodetic_to_enu(geo[:, 0], geo[:, 1], geo[:, 2], origin)
    inside = where >= 0
    out = ((ta < tp[0]) | (ta > tp[-1])) & ~inside
    i = np.clip(np.searchsorted(tp, ta, side="right") - 1, 0, len(tp) - 2)
    gap = ((tp[i + 1] - tp[i]) > max_gap_s) & (ta != tp[i]) & (ta != tp[i + 1]) & ~out & ~inside  # an instant at a fix is not in a gap
    dropped["out_of_span"], dropped["gap"] = int(out.sum()), int(gap.sum())
    keep = ~(out | gap | inside)
    t = ta[keep]
    xyz = np.stack([np.interp(t, tp, enu[:, j]) for j in range(3)], axis=-1)
    q = quat_from_ned_euler_rad(att_v[keep, 0], att_v[keep, 1], att_v[keep, 2])
    frame = pd.DataFrame({"t": t, "node": node, "x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2],
                          "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3]})
    if len(raw.armed):
        frame["armed"] = step_state(t, raw.armed, 0.0) > 0.5
    return frame


def stream_present(t: np.ndarray, stream_t: np.ndarray, timeout_s: float) -> np.ndarray:
    """Whether a message of a stream (sorted times ``stream_t`` [s]) lies within ``timeout_s``
    [s] of each time ``t``."""
    t = np.asarray(t, np.float64)
    if len(stream_t) == 0:
        return np.zeros(len(t), bool)
    j = np.searchsorted(stream_t, t)
    before = np.abs(t - stream_t[np.clip(j - 1, 0, len(stream_t) - 1)])
    after = np.abs(stream_t[np.clip(j, 0, len(stream_t) - 1)] - t)
    return np.minimum(before, after) <= timeout_s


def _signal(raw: Raw, vehicle: str, station: str, tx_power_dbm: float | Mapping[str, float],
            frequency_hz: float, stream_timeout_s: float, counts: dict[str, int],
            periods: list[dict[str, Any]]) -> pd.DataFrame:
    """Both directions of the telemetry link: one row per reading, link-lost messages as outage
    rows (``rssi_dbm`` NaN, ``outage`` True), unusable values and rows in excluded periods dropped."""
    order = np.argsort(raw.radio[:, 0], kind="stable")
    radio = raw.radio[order]
    if raw.radio_copy is None:
        copy, period = phases.repeated_readings(radio[:, 0], radio[:, 1:])
    else:  # judged as the reports arrived (rplearn.io.tlog_window)
        copy, period = np.asarray(raw.radio_copy, bool)[order], raw.radio_period
    counts["duplicate_reading"] = int(copy.sum())
    raw.notes["radio_report_period_s"] = period
    radio = radio[~copy]
    t, rssi, remrssi = radio[:, 0], radio[:, 1], radio[:, 2]
    where = phases.in_periods(t, periods)
    zero = (rssi == 0) | (remrssi == 0)
    # in the vehicle's own (DataFlash) log a zero always means the link dropped
    present = (np.zeros(len(t), bool) if raw.fmt == "dataflash"
               else stream_present(t, raw.vehicle_t, stream_timeout_s))
    lost = zero & ~present
    counts["link_lost"] = int(lost.sum())
    # which raw field the station receives in (module docstring: tlog vs. DataFlash)
    at_station, at_vehicle = (rssi, remrssi) if raw.fmt == "tlog" else (remrssi, rssi)
    parts = []
    for tx, rx, value, name in ((vehicle, station, at_station, "vehicle_to_station"),
                                (station, vehicle, at_vehicle, "station_to_vehicle")):
        unknown, censored = (value == _UNKNOWN) & ~lost, (value == 0) & ~lost
        counts[f"unknown_{name}"], counts[f"zero_{name}"] = int(unknown.sum()), int(censored.sum())
        keep = ~(unknown | censored)  # link-lost rows are kept as outage events
        per_period = np.bincount(where[keep & (where >= 0)], minlength=len(periods))
        for p, n in zip(periods, per_period):
            p["signal_rows"] = p.get("signal_rows", 0) + int(n)
            counts[p["reason"]] = counts.get(p["reason"], 0) + int(n)
        keep &= where < 0
        ptx = tx_power_dbm.get(tx) if isinstance(tx_power_dbm, Mapping) else tx_power_dbm
        if ptx is None:
            raise InputError(f"tx_power_dbm: no transmit power [dBm] for node {tx}", param="tx_power_dbm")
        parts.append(pd.DataFrame({
            "t": t[keep], "tx": tx, "rx": rx, "rssi_dbm": np.where(lost[keep], np.nan, sik_rssi_to_dbm(value[keep])),
            "tx_power_dbm": float(ptx), "frequency_hz": float(frequency_hz),
            "rssi_raw": value[keep].astype(np.int64), "outage": lost[keep],
        }))
        counts[f"rows_{name}"] = int((keep & ~lost).sum())
        counts[f"outage_{name}"] = int((keep & lost).sum())
    return pd.concat(parts, ignore_index=True).sort_values("t", kind="stable").reset_index(drop=True)


def _hygiene_notes(source: str, periods: list[dict[str, Any]], counts: dict[str, int], raw: Raw) -> list[str]:
    """One line per excluded period and one for merged copies of radio readings."""
    notes = []
    for p in periods:
        p.setdefault("signal_rows", 0)
        notes.append(f"{source}: excluded {p['reason']} from t = {p['from_t']:.3f} to {p['to_t']:.3f} s "
                     f"({p['to_t'] - p['from_t']:.1f} s): {p['pose_rows']:,} pose row(s) and {p['signal_rows']:,} "
                     f"signal row(s) dropped ({p['detail']})")
    period = raw.notes.get("radio_report_period_s")
    if counts.get("duplicate_reading"):
        notes.append(f"{source}: {counts['duplicate_reading']:,} radio report(s) repeated the reading before them "
                     f"within a quarter of the {period:.3g} s report period and were merged: one row per reading")
    return notes


def _detect(source: str) -> str:
    """``"tlog"`` or ``"dataflash"`` from the extension (``.tlog``; ``.bin``, ``.log``) or the bytes."""
    ext = os.path.splitext(source)[1].lower()
    with open(source, "rb") as fh:
        head = fh.read(5)
    if head.startswith(_DF_HEAD) or head == b"FMT, " or ext in (".bin", ".log"):
        return "dataflash"
    return "tlog"


def _check_arguments(tx_power_dbm: Any, frequency_hz: Any, max_gap_s: Any, stream_timeout_s: Any,
                     vehicle: Any, station: Any, station_heading_deg: Any = None) -> None:
    """Refuse arguments out of their domain (:class:`InputError` naming the parameter)."""
    if station_heading_deg is not None and not (
            isinstance(station_heading_deg, numbers.Real) and not isinstance(station_heading_deg, bool)
            and math.isfinite(station_heading_deg)):
        raise InputError(f"station_heading_deg: expected degrees, got {station_heading_deg!r}", param="station_heading_deg")
    for name, value in (("max_gap_s", max_gap_s), ("stream_timeout_s", stream_timeout_s),
                        ("frequency_hz", frequency_hz)):
        if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
            raise InputError(f"{name}: expected a positive number, got {value!r}", param=name)
    check_frequency_hz(frequency_hz, "frequency_hz")
    powers = list(tx_power_dbm.values()) if isinstance(tx_power_dbm, Mapping) else [tx_power_dbm]
    check_tx_power_dbm(powers, "tx_power_dbm")
    for name, value in (("vehicle", vehicle), ("station", station)):
        if value is not None and (not isinstance(value, str) or not value.strip()):
            raise InputError(f"{name}: expected a node id, got {value!r}", param=name)


@check_types
@dataclass(frozen=True)
class MavlinkOptions:
    """How :func:`read_mavlink` places the station and reads the streams of a MAVLink log.

    Attributes
    ----------
    station_geodetic : (lat_deg, lon_deg, alt_m), optional
        Ground station position (altitude AMSL, the autopilot's datum); by default the home
        position, else the vehicle's first fix.
    origin_geodetic : (lat_deg, lon_deg, alt_m), optional
        ENU origin; the ground station's position by default.
    system_id : int, optional
        MAVLink system id of the vehicle in a tlog; by default the one sending most ATTITUDE.
    station_heading_deg : float, optional
        Compass heading of the station's body x axis (its antenna's forward direction)
        [deg, clockwise from north]; not logged, so by default 90 (east, said in the notes):
        the station's body frame is then the ENU world frame.
    max_gap_s : float
        Longest gap of the position fixes bridged by interpolation [s].
    stream_timeout_s : float
        A tlog's vehicle stream is absent at a radio message when none of the vehicle's
        messages lies within this many seconds [s].

    Raises
    ------
    InputError
        On the first invalid option, naming it (``param``).
    """

    station_geodetic: tuple[float, float, float] | None = None
    origin_geodetic: tuple[float, float, float] | None = None
    system_id: int | None = None
    station_heading_deg: float | None = None
    max_gap_s: float = 2.0
    stream_timeout_s: float = 2.0

    def __post_init__(self) -> None:
        for name in ("station_geodetic", "origin_geodetic"):
            object.__setattr__(self, name, check_origin(getattr(self, name), name))
        sid = self.system_id
        if sid is not None and (isinstance(sid, bool) or not isinstance(sid, numbers.Integral) or not 0 <= sid <= 255):
            raise InputError(f"system_id: expected a MAVLink system id 0-255, got {sid!r}", param="system_id")
        h = self.station_heading_deg
        if h is not None and not (isinstance(h, numbers.Real) and not isinstance(h, bool) and np.isfinite(h)):
            raise InputError(f"station_heading_deg: expected degrees, got {h!r}", param="station_heading_deg")
        for name in ("max_gap_s", "stream_timeout_s"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise InputError(f"{name}: expected a positive number, got {value!r}", param=name)


@check_types
def read_mavlink(
    path: str | os.PathLike,
    tx_power_dbm: float | Mapping[str, float],
    frequency_hz: float,
    vehicle: str | None = None,
    station: str = "gcs",
    options: MavlinkOptions | None = None,
) -> tuple[Logs, dict[str, Any]]:
    """Read an ArduPilot ``.tlog`` or DataFlash log into pose and signal logs (module docstring).

    Parameters
    ----------
    path : str or PathLike
        ``.tlog`` (telemetry log) or ``.bin`` / ``.log`` (DataFlash).
    tx_power_dbm : float or mapping of node id to float
        Transmit power of the SiK radios [dBm] (the ``TXPOWER`` setting; not logged).
    frequency_hz : float
        Carrier frequency [Hz] (433 or 915 MHz bands; not logged).
    vehicle : str, optional
        Node id of the vehicle; ``"sys<N>"`` from its MAVLink system id by default
        (``"sys1"`` for a DataFlash log).
    station : str
        Node id of the ground station.
    options : MavlinkOptions, optional
        Station and origin positions, station heading, the vehicle's system id, the longest
        bridged gap and the stream timeout (default ``MavlinkOptions()``).

    Returns
    -------
    logs : Logs
        ``pose`` (the vehicle's attitude rows and one static row of the station; a boolean
        ``armed`` column when the log holds the armed state) and
        ``signal`` (both link directions; ``outage`` True on the link-lost rows, whose
        ``rssi_dbm`` is NaN).
    metadata : dict
        ``source``, ``format`` ("tlog" or "dataflash"), ``notes`` (lines for the user: where
        the station was placed, link-lost messages kept as outage events), ``vehicle``, ``station``,
        ``station_geodetic``, ``station_note`` (where the station position came from),
        ``station_accuracy_m`` (the GPS accuracy, horizontal and vertical [m], the log reports for the fix that
        placed the station: ``GPS_RAW_INT`` h_acc/v_acc, DataFlash ``GPA`` HAcc/VAcc; None when given or none is
        reported: :mod:`rplearn.io._mavlink_station`), ``origin_geodetic``, ``messages`` (counts of the messages used), ``dropped`` (pose
        rows per reason), ``signal`` (rows per direction, ``link_lost`` messages, ``outage_*`` rows per direction, zero and
        unknown values per direction, ``duplicate_reading`` copies merged, rows dropped per
        excluded period's reason), ``excluded_periods``, ``reboots``,
        ``radio_report_period_s``, ``time_reference``, ``cut_off_at_byte`` and
        ``cut_off_record`` (offset and message name of the record a cut-off file ends inside,
        whose data are lost: a tlog's record is its 8-byte time and MAVLink frame, whose name is
        unknown when the cut is before the frame's header; None when whole), ``records_read``
        (the complete records: a DataFlash log's records, a tlog's messages; None for a text
        log), ``corrupt_bytes`` (skipped between DataFlash records or between whole ``.tlog``
        records), ``corrupt_stretches`` (``.tlog``: stretches of such bytes between two whole
        records, each one frame or more lost). A cut or a corrupt stretch
        is said by :func:`rplearn.io.inspect.file_damage`, not in ``notes``.

    Raises
    ------
    LogFormatError
        When the file cannot be parsed or lacks the attitude, position or radio messages.
    InputError
        On a missing file or a bad argument (``param`` names it).
    """
    options = MavlinkOptions() if options is None else options
    source = str(path)
    if not os.path.isfile(source):
        raise InputError(f"{source}: no such file")
    _check_arguments(tx_power_dbm, frequency_hz, options.max_gap_s, options.stream_timeout_s, vehicle, station,
                     options.station_heading_deg)
    fmt = _detect(source)
    raw = collect_tlog(source, options.system_id) if fmt == "tlog" else collect_dataflash(source)
    logs, meta = logs_from_raw(raw, source, (tx_power_dbm, float(frequency_hz)), vehicle, station, options)
    cut, cut_name, corrupt, records = (
        _dataflash_walk(source) if fmt == "dataflash"
        else (raw.notes.pop("cut_off_at_byte", None), raw.notes.pop("cut_off_record", None),
              raw.notes.pop("corrupt_bytes", 0), raw.notes.pop("records_read", None)))
    meta.update({"cut_off_at_byte": cut, "cut_off_record": cut_name, "corrupt_bytes": int(corrupt),
                 "records_read": records})
    return logs, meta


def logs_from_raw(raw: Raw, source: str, radio: tuple[float | Mapping[str, float], float], vehicle: str | None,
              station: str, options: MavlinkOptions) -> tuple[Logs, dict[str, Any]]:
    """Pose and signal logs and the metadata (without the cut-off record) of a log's :class:`Raw`
    arrays (:func:`read_mavlink`; also of a growing log read so far, :mod:`rplearn.io.tlog_tail`)."""
    tx_power_dbm, frequency_hz = radio
    station_geodetic, origin_geodetic = options.station_geodetic, options.origin_geodetic
    station_heading_deg, max_gap_s, stream_timeout_s = options.station_heading_deg, options.max_gap_s, options.stream_timeout_s
    fmt = raw.fmt
    if not len(raw.radio):
        what = "RADIO_STATUS (id 109) or RADIO (id 166)" if fmt == "tlog" else "RAD"
        raise LogFormatError(f"{source}: no {what} messages: the log holds no telemetry-radio RSSI")
    if not len(raw.pos):
        what = "GLOBAL_POSITION_INT" if fmt == "tlog" else "POS or GPS"
        raise LogFormatError(f"{source}: no {what} messages with a position fix")
    vehicle = vehicle or f"sys{raw.notes.get('system_id', 1)}"
    if vehicle == station:
        raise InputError(f"vehicle and station must differ, both are {vehicle!r}", param="station")
    fixes = position_fixes(raw, source)
    station_geo, station_note, station_accuracy = station_fix(raw, station_geodetic, fixes[1][fixes[2]][0])
    origin = station_geo if origin_geodetic is None else tuple(float(v) for v in origin_geodetic)
    dropped: dict[str, int] = {}
    try:  # positions, home and station against the plausibility table (core/plausible.py)
        pose = _vehicle_pose(raw, fixes, origin, float(max_gap_s), vehicle, dropped)  # type: ignore[arg-type]
        s_xyz = geodetic_to_enu(*station_geo, origin, where="the station")  # type: ignore[arg-type]
        far = np.linalg.norm(pose[["x", "y", "z"]].to_numpy(np.float64) - np.asarray(s_xyz, np.float64), axis=1)
        check_plausible("link_distance_m", np.nan_to_num(far), "the vehicle", field="distance from the station [m]")
    except InputError as exc:
        raise InputError(f"{source}: {exc} ({station_note})", param=exc.param) from None
    t0 = float(min(raw.radio[0, 0], pose["t"].iloc[0] if len(pose) else np.inf))
    heading = 90.0 if station_heading_deg is None else float(station_heading_deg)
    sq = quat_wxyz_from_euler_ned_frd_deg(0.0, 0.0, heading)
    station_row = pd.DataFrame({"t": [t0], "node": [station], "x": [s_xyz[0]], "y": [s_xyz[1]], "z": [s_xyz[2]],
                                "qw": [sq[0]], "qx": [sq[1]], "qy": [sq[2]], "qz": [sq[3]]})
    if "armed" in pose:
        station_row["armed"] = False
    pose = validate_pose_log(pd.concat([pose, station_row], ignore_index=True), source)
    sig_counts: dict[str, int] = {}
    periods = fixes[3]
    signal = _signal(raw, vehicle, station, tx_power_dbm, float(frequency_hz), float(stream_timeout_s), sig_counts,
                     periods)
    signal = validate_signal_log(signal, source)
    lost = sig_counts["link_lost"]
    heading_note = ("assumed level and facing east (heading 90 deg): its attitude is not logged"
                    if station_heading_deg is None else f"level, heading {heading:g} deg (given)")
    notes = [f"{source}: {station_note}", f"{source}: station {station!r} {heading_note}"]
    if lost:
        notes.append(f"{source}: {lost:,} radio message(s) with a zero RSSI while the vehicle was silent (link lost): "
                     "kept as outage events (column outage, no RSSI), both directions")
    notes += _hygiene_notes(source, periods, sig_counts, raw)
    others = raw.notes.get("other_vehicles") or {}
    if others:  # more vehicles than one in the log: counted and named, not read
        listed = ", ".join(f"system id {k} ({n:,} ATTITUDE message(s))" for k, n in sorted(others.items()))
        notes.append(f"{source}: {len(others) + 1} vehicles in one log: read system id {raw.notes.get('system_id')} "
                     f"(the most ATTITUDE messages) as {vehicle!r}; not read: {listed}; the radio reports are "
                     "not split between vehicles (MavlinkOptions.system_id reads another)")
    meta = {
        "source": source, "format": fmt, "notes": notes, "vehicle": vehicle, "station": station,
        "station_geodetic": station_geo, "station_note": station_note, "station_accuracy_m": station_accuracy,
        "origin_geodetic": origin, "messages": raw.counts, "dropped": dropped,
        "signal": sig_counts, "rows": int((pose["node"] == vehicle).sum()),
        "cut_off_at_byte": None, "cut_off_record": None, "corrupt_bytes": 0,
        "reboots": len(raw.boot_last_t) - 1 if len(raw.boot_last_t) else 0,
        "excluded_periods": [{k: p[k] for k in ("reason", "from_t", "to_t", "pose_rows", "signal_rows", "detail")}
                             for p in periods], **raw.notes,
    }
    return Logs(pose=pose, signal=signal), meta


__all__ = ["MavlinkOptions", "dataflash_cut_off_at", "quat_from_ned_euler_rad", "read_mavlink", "sik_rssi_to_dbm",
           "stream_present"]
