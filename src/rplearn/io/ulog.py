"""PX4 ULog flight-controller logs -> canonical pose logs, through ``pyulog``.

Topics used:

- ``vehicle_local_position``: ``x, y, z`` in the EKF's local NED frame [m], converted to ENU
  (``(n, e, d) -> (e, n, -d)``, :func:`rplearn.core.geometry.ned_to_enu`);
- ``vehicle_attitude``: ``q[0..3]`` = (w, x, y, z), FRD body -> NED world, converted to
  FLU body -> ENU world (:func:`rplearn.core.geometry.quat_ned_frd_to_enu_flu`);
- the geodetic anchor of the local frame: the EKF reference (``ref_lat, ref_lon, ref_alt``
  when ``xy_global`` and ``z_global`` are set), else the first fix of
  ``vehicle_global_position``, else of ``vehicle_gps_position`` / ``sensor_gps``, with the
  local position at that instant subtracted;
- the clock: PX4 stamps every message in microseconds since boot. The offset to UTC is the
  median of ``time_utc_usec - timestamp`` over GPS messages with a UTC time, so that two
  drones' logs share one clock (GPS time is what the autopilots agree on).

Position and attitude are logged at different instants. With ``timebase="attitude"`` (the
default; attitude is the faster topic and matters most for radiation patterns) the pose rows
are the attitude samples, their position interpolated linearly; with ``timebase="position"``
the rows are the position samples, their attitude interpolated by slerp. Rows outside the
other topic's span, or inside a gap longer than ``max_gap_s`` of it, are dropped and counted.

With ``origin_geodetic`` (lat [deg], lon [deg], alt [m]) the positions are expressed in ENU
around that origin (pymap3d), which puts several drones in one frame; without it they stay
in the log's own local frame (its origin reported as ``metadata["anchor_geodetic"]``).

A file holding the log again after it (a second file header starting the same bytes) is read
once, the messages after it counted (``metadata["repeated_messages"]``); a different log after
it (logs concatenated) is refused naming the byte where it starts (:func:`ulog_layout`).
"""

from __future__ import annotations

import io
import os
import threading
from typing import Any, BinaryIO

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.geometry import quat_ned_frd_to_enu_flu
from rplearn.data.tables import validate_pose_log
from rplearn.errors import InputError, LogFormatError
from rplearn.io.geodetic import local_ned_to_enu, local_ned_to_geodetic


def _pyulog() -> Any:
    try:
        from pyulog import ULog
    except ImportError:  # pragma: no cover - pyulog is a dependency
        raise InputError("reading PX4 logs needs the 'pyulog' package (pip install pyulog)") from None
    return ULog


def _topic(ulog: Any, name: str, multi_id: int = 0) -> dict[str, np.ndarray] | None:
    for d in ulog.data_list:
        if d.name == name and d.multi_id == multi_id:
            return d.data
    return None


def utc_offset_us(ulog: Any) -> tuple[int | None, str | None]:
    """Offset [us] to add to a ULog's boot-relative timestamps to get UTC, and its source topic.

    Median of ``time_utc_usec - timestamp`` over GPS messages that carry a UTC time.
    """
    for name in ("vehicle_gps_position", "sensor_gps"):
        g = _topic(ulog, name)
        if g is None or "time_utc_usec" not in g:
            continue
        utc = g["time_utc_usec"].astype(np.int64)
        ts = g["timestamp"].astype(np.int64)
        ok = utc > 0
        if ok.any():
            return int(np.round(np.median(utc[ok] - ts[ok]))), name
    return None, None


def _first_fix(ulog: Any) -> tuple[int, float, float, float, str] | None:
    g = _topic(ulog, "vehicle_global_position")
    if g is not None and all(k in g for k in ("lat", "lon", "alt")):
        ok = np.isfinite(g["lat"]) & np.isfinite(g["lon"]) & (g["lat"] != 0) & np.isfinite(g["alt"])
        if ok.any():
            i = int(np.flatnonzero(ok)[0])
            return (int(g["timestamp"][i]), float(g["lat"][i]), float(g["lon"][i]), float(g["alt"][i]),
                    "vehicle_global_position")
    for name in ("vehicle_gps_position", "sensor_gps"):
        g = _topic(ulog, name)
        if g is None:
            continue
        if "latitude_deg" in g:
            lat, lon, alt = g["latitude_deg"], g["longitude_deg"], g["altitude_msl_m"]
        elif "lat" in g:  # older PX4: 1e-7 degrees and millimetres
            lat, lon, alt = g["lat"] * 1e-7, g["lon"] * 1e-7, g["alt"] * 1e-3
        else:
            continue
        lat, lon, alt = (np.asarray(v, np.float64) for v in (lat, lon, alt))
        ok = np.isfinite(lat) & np.isfinite(lon) & (lat != 0) & np.isfinite(alt)
        if ok.any():
            i = int(np.flatnonzero(ok)[0])
            return int(g["timestamp"][i]), float(lat[i]), float(lon[i]), float(alt[i]), name
    return None


def _interp_linear(t_key: np.ndarray, v_key: np.ndarray, t: np.ndarray) -> np.ndarray:
    return np.stack([np.interp(t, t_key, v_key[:, j]) for j in range(v_key.shape[1])], axis=-1)


def _interp_slerp(t_key: np.ndarray, q_key: np.ndarray, t: np.ndarray) -> np.ndarray:
    from rplearn.core.geometry import slerp_wxyz

    i = np.clip(np.searchsorted(t_key, t, side="right") - 1, 0, len(t_key) - 2)
    frac = np.clip((t - t_key[i]) / (t_key[i + 1] - t_key[i]), 0.0, 1.0)
    return slerp_wxyz(q_key[i], q_key[i + 1], frac)


def _span_and_gaps(t_key: np.ndarray, t: np.ndarray, max_gap: float) -> tuple[np.ndarray, np.ndarray]:
    out = (t < t_key[0]) | (t > t_key[-1])
    i = np.clip(np.searchsorted(t_key, t, side="right") - 1, 0, max(len(t_key) - 2, 0))
    gap = np.zeros(len(t), bool) if len(t_key) < 2 else (t_key[i + 1] - t_key[i]) > max_gap
    return out, gap & ~out


#: The topics of the telemetry radio and the home position (:mod:`rplearn.io.ulog_radio`).
RADIO_TOPICS: tuple[str, ...] = ("radio_status", "telemetry_status", "home_position")
_TOPICS: tuple[str, ...] = (*RADIO_TOPICS, "vehicle_local_position", "vehicle_attitude", "vehicle_global_position",
                            "vehicle_gps_position", "sensor_gps")


#: Bytes of the ULog file header (magic, version, timestamp) and of each message header.
_ULOG_FILE_HEADER_BYTES = 16
_ULOG_MSG_HEADER_BYTES = 3


#: The first bytes of every ULog file (magic ``ULog`` and version byte 1, ULog file format).
_ULOG_MAGIC = b"ULog\x01\x12\x35"


#: The ULog message types (ULog file format): flag bits, format, info, info multiple,
#: parameter, default parameter, add/remove logged, data, logging, tagged logging, sync, dropout.
_ULOG_TYPES = frozenset(b"BFIMPQARDLCSO")


def _walk_messages(data: Any, start: int, end: int) -> tuple[int, int | None, int | None]:
    """Walk the ULog messages in ``data[start:end]``: ``(complete messages, offset of the one
    it ends inside or None, offset of the first message of no ULog type or None)``; the walk
    stops at such a message (its size cannot be trusted: the bytes are damaged)."""
    pos, n = start, 0
    while pos + _ULOG_MSG_HEADER_BYTES <= end:
        if data[pos + 2] not in _ULOG_TYPES:
            return n, None, pos
        nxt = pos + _ULOG_MSG_HEADER_BYTES + (data[pos] | (data[pos + 1] << 8))
        if nxt > end:
            return n, pos, None
        pos, n = nxt, n + 1
    return n, None if pos == end else pos, None


def ulog_cut_off_at(path: str) -> int | None:
    """Byte offset of a ULog message that the file ends inside, or None if it ends whole.

    A ULog after its 16-byte header is a sequence of messages, each a 3-byte header
    (``uint16`` payload size, ``uint8`` type) and its payload (ULog file format, "Definitions"
    and "Data" sections, docs.px4.io/main/en/dev_log/ulog_file_format). A log cut off by a
    power loss or a failed copy ends inside a message; ``pyulog`` then stops without a word.
    """
    return ulog_layout(path)["cut_off_at_byte"]


def ulog_layout(path: str) -> dict[str, Any]:
    """What the bytes of a ULog hold, beyond what ``pyulog`` says: where its log ends, whether
    the file repeats it, where it is cut.

    Returns
    -------
    dict
        ``log_bytes`` (the bytes of the first log: the file up to a second file header
        :data:`_ULOG_MAGIC`, or all of it), ``repeated_messages`` (the messages after it when
        they are that log again, whole or cut: the log in the file twice), ``messages`` (the
        complete messages of the first log, up to a damaged one), ``cut_off_at_byte`` (the
        offset of the message the first log ends inside, or None), ``damaged_at_byte`` (the
        offset of the first message of no ULog type: damaged bytes, whose size cannot be
        trusted; ``pyulog`` skips a message of an unknown type without a word, or resyncs).

    Raises
    ------
    LogFormatError
        When a second, different log follows the first (logs concatenated), naming the byte.
    """
    # the pose and radio readers of one file walk it once
    return dict(_kept(_LAST_LAYOUT, _file_key(path, None), lambda: _walk_layout(path)))


#: Guards :data:`_LAST_LAYOUT` and :data:`_LAST_PARSED` (readers in several threads).
_CACHE_LOCK = threading.Lock()
def _kept(store: dict[tuple[Any, ...], Any], key: tuple[Any, ...], compute: Any) -> Any:
    """``store[key]``, computed by ``compute()`` and kept alone in ``store`` when it is not there."""
    with _CACHE_LOCK:
        value = store.get(key)
    if value is None:
        value = compute()
        with _CACHE_LOCK:
            store.clear()
            store[key] = value
    return value


#: The layout of the last ULog walked (:func:`ulog_layout`), keyed as :data:`_LAST_PARSED`.
_LAST_LAYOUT: dict[tuple[Any, ...], dict[str, Any]] = {}


def _walk_layout(path: str) -> dict[str, Any]:
    """:func:`ulog_layout`, walking the file."""
    import mmap

    with open(path, "rb") as fh:
        size = os.fstat(fh.fileno()).st_size
        if size <= _ULOG_FILE_HEADER_BYTES:
            return {"log_bytes": size, "repeated_messages": 0, "messages": 0, "damaged_at_byte": None,
                    "cut_off_at_byte": _ULOG_FILE_HEADER_BYTES if size < _ULOG_FILE_HEADER_BYTES else None}
        with mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as data:
            second = data.find(_ULOG_MAGIC, _ULOG_FILE_HEADER_BYTES)
            end = size if second < 0 else second
            messages, cut, damaged = _walk_messages(data, _ULOG_FILE_HEADER_BYTES, end)
            repeated = 0
            if second >= 0:
                repeated = _repeated_copies(data, end, size, path)
    return {"log_bytes": end, "repeated_messages": repeated, "messages": messages, "cut_off_at_byte": cut,
            "damaged_at_byte": damaged}


def _repeated_copies(data: Any, first_end: int, size: int, path: str) -> int:
    """Messages in ``data[first_end:]`` when they are the first log (``data[:first_end]``)
    again, once or more, the last copy possibly cut; :class:`LogFormatError` otherwise."""
    repeated, pos = 0, first_end
    while pos < size:
        n = min(first_end, size - pos)
        if data[pos:pos + n] != data[:n]:
            raise LogFormatError(
                f"{path}: a second ULog starts at byte {first_end:,} and is not the first one again "
                "(logs concatenated); give each log as its own file")
        repeated += _walk_messages(data, pos + _ULOG_FILE_HEADER_BYTES, pos + n)[0] if n > _ULOG_FILE_HEADER_BYTES else 0
        pos += n
    return repeated


class _Head(io.RawIOBase):
    """The first ``limit`` bytes of an open binary file, as a file (for ``pyulog``)."""

    def __init__(self, fh: BinaryIO, limit: int) -> None:
        super().__init__()
        self._fh, self._limit = fh, limit

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def read(self, n: int | None = -1) -> bytes:
        left = max(self._limit - self._fh.tell(), 0)
        return self._fh.read(left if n is None or n < 0 else min(n, left))

    def seek(self, offset: int, whence: int = 0) -> int:
        if whence == 2:
            return self._fh.seek(self._limit + offset)
        return self._fh.seek(offset, whence)

    def tell(self) -> int:
        return self._fh.tell()

    def close(self) -> None:
        self._fh.close()
        super().close()


#: The last ULog parsed, keyed by its file's identity and size and the bytes read: the pose
#: reader and the radio reader (:mod:`rplearn.io.ulog_radio`) of one file parse it once.
_LAST_PARSED: dict[tuple[Any, ...], Any] = {}


def _file_key(source: str, log_bytes: int | None) -> tuple[Any, ...]:
    st = os.stat(source)
    return (os.path.realpath(source), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, log_bytes)


def parsed_ulog(source: str) -> Any:
    """The parsed ULog of ``source`` as :func:`read_ulog` reads it (a log in the file twice read
    once; the topics of the pose and radio readers only), from its last parse when the file is
    unchanged."""
    layout = ulog_layout(source)
    return _open_ulog(source, layout["log_bytes"] if layout["repeated_messages"] else None)


def release_parsed() -> None:
    """Forget the last parsed ULog (:func:`parsed_ulog`): its topics' arrays are not kept in
    memory once the readers of a file are done with it."""
    with _CACHE_LOCK:
        _LAST_PARSED.clear()


def _open_ulog(source: str, log_bytes: int | None = None) -> Any:
    """The parsed ULog (the topics rplearn uses only; its first ``log_bytes`` bytes when given);
    :class:`LogFormatError` when unreadable. The last one parsed is kept (:data:`_LAST_PARSED`)."""
    if not os.path.exists(source):
        raise InputError(f"{source}: no such file")
    return _kept(_LAST_PARSED, _file_key(source, log_bytes), lambda: _parse_ulog(source, log_bytes))


def _parse_ulog(source: str, log_bytes: int | None) -> Any:
    from rplearn.io._log_schema import library_quiet

    ULog = _pyulog()
    try:
        with library_quiet():  # pyulog prints what it finds corrupt; the metadata says it (``corrupt``)
            if log_bytes is None:
                return ULog(source, list(_TOPICS))
            return ULog(_Head(open(source, "rb"), log_bytes), list(_TOPICS))
    except Exception as exc:
        msg = str(exc).splitlines()[0] if str(exc) else ""
        raise LogFormatError(f"{source}: cannot read ULog ({type(exc).__name__}: {msg})") from None


def _pose_topics(ulog: Any, source: str) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """``vehicle_local_position`` and ``vehicle_attitude``, checked for the fields used."""
    lp = _topic(ulog, "vehicle_local_position")
    att = _topic(ulog, "vehicle_attitude")
    if lp is None or len(lp.get("timestamp", ())) < 1:
        raise LogFormatError(f"{source}: topic vehicle_local_position missing or empty")
    if att is None or len(att.get("timestamp", ())) < 1:
        raise LogFormatError(f"{source}: topic vehicle_attitude missing or empty")
    for k in ("x", "y", "z"):
        if k not in lp:
            raise LogFormatError(f"{source}: vehicle_local_position has no field {k}")
    for k in ("q[0]", "q[1]", "q[2]", "q[3]"):
        if k not in att:
            raise LogFormatError(f"{source}: vehicle_attitude has no field {k}")
    return lp, att


def _local_positions(
    lp: dict[str, np.ndarray], require_valid: bool, dropped: dict[str, int]
) -> tuple[np.ndarray, np.ndarray, int]:
    """Finite local positions: times [us], NED positions [m] (n, 3), rows flagged invalid.

    Rows with a NaN are dropped (``nan_position``); with ``require_valid`` also rows whose
    ``xy_valid`` or ``z_valid`` is 0 (``invalid_flag``). Counts go into ``dropped``.
    """
    tp = lp["timestamp"].astype(np.int64)
    ned = np.stack([lp["x"], lp["y"], lp["z"]], axis=-1).astype(np.float64)
    keep = np.all(np.isfinite(ned), axis=1)
    dropped["nan_position"] = int((~keep).sum())
    flags_bad = np.zeros(len(tp), bool)
    for f in ("xy_valid", "z_valid"):
        if f in lp:
            flags_bad |= lp[f] == 0
    if require_valid:
        dropped["invalid_flag"] = int((flags_bad & keep).sum())
        keep &= ~flags_bad
    return tp[keep], ned[keep], int(flags_bad.sum())


def _attitudes(att: dict[str, np.ndarray], dropped: dict[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """Times [us] and FLU -> ENU quaternions (w, x, y, z) of the finite, non-zero attitudes."""
    ta = att["timestamp"].astype(np.int64)
    q_ned = np.stack([att[f"q[{i}]"] for i in range(4)], axis=-1).astype(np.float64)
    ok = np.all(np.isfinite(q_ned), axis=1) & (np.linalg.norm(q_ned, axis=1) > 1e-6)
    dropped["nan_attitude"] = int((~ok).sum())
    return ta[ok], q_ned[ok]


def _increasing(t_us: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Strictly increasing times [us] with their values, the first of repeated instants kept.

    PX4 can log one instant twice.
    """
    t_us, first = np.unique(t_us, return_index=True)
    return t_us, values[first]


def _anchor(
    ulog: Any, lp: dict[str, np.ndarray], tp: np.ndarray, ned: np.ndarray
) -> tuple[tuple[float, float, float] | None, str | None]:
    """Geodetic anchor (lat [deg], lon [deg], alt [m]) of the local NED frame and its source.

    The EKF reference when it is global, else the first fix minus the local position then.
    """
    if all(k in lp for k in ("ref_lat", "ref_lon", "ref_alt", "xy_global", "z_global")):
        good = (lp["xy_global"] != 0) & (lp["z_global"] != 0) & np.isfinite(lp["ref_lat"]) & np.isfinite(lp["ref_lon"])
        if good.any():
            i = int(np.flatnonzero(good)[0])
            return ((float(lp["ref_lat"][i]), float(lp["ref_lon"][i]), float(lp["ref_alt"][i])),
                    "vehicle_local_position.ref_lat/ref_lon/ref_alt")
    fix = _first_fix(ulog)
    if fix is None or len(tp) < 1:
        return None, None
    t_fix, lat, lon, alt, name = fix
    here = _interp_linear(tp.astype(np.float64), ned, np.array([float(t_fix)]))[0]
    a_lat, a_lon, a_alt = local_ned_to_geodetic(-here, (lat, lon, alt))
    return (float(a_lat), float(a_lon), float(a_alt)), f"first fix of {name} minus the local position at that time"


def _on_timebase(
    tp: np.ndarray, ned: np.ndarray, ta: np.ndarray, q_enu: np.ndarray, timebase: str,
    max_gap_s: float, source: str, dropped: dict[str, int],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows at the instants of one topic, the other interpolated: times [us], NED [m], quaternions.

    Rows outside the interpolated topic's span or inside its gaps longer than ``max_gap_s``
    [s] are dropped (``out_of_span``, ``gap``).
    """
    tp_f, ta_f = tp.astype(np.float64), ta.astype(np.float64)
    gap_us = max_gap_s * 1e6
    if timebase == "attitude":
        t_us, quat = ta_f, q_enu
        if len(tp) < 2:
            raise InputError(f"{source}: vehicle_local_position has fewer than 2 valid samples")
        out, gap = _span_and_gaps(tp_f, t_us, gap_us)
        pos_ned = _interp_linear(tp_f, ned, t_us)
    else:
        t_us, pos_ned = tp_f, ned
        if len(ta) < 2:
            raise InputError(f"{source}: vehicle_attitude has fewer than 2 valid samples")
        out, gap = _span_and_gaps(ta_f, t_us, gap_us)
        quat = _interp_slerp(ta_f, q_enu, t_us)
    dropped["out_of_span"] = int(out.sum())
    dropped["gap"] = int(gap.sum())
    sel = ~(out | gap)
    return t_us[sel], pos_ned[sel], quat[sel]


def _enu(
    pos_ned: np.ndarray, anchor: tuple[float, float, float] | None,
    origin_geodetic: tuple[float, float, float] | None, source: str,
) -> np.ndarray:
    """ENU positions [m]: around ``origin_geodetic`` through the anchor, else in the local frame."""
    if origin_geodetic is None:
        return local_ned_to_enu(pos_ned, (0.0, 0.0, 0.0), None)
    if anchor is None:
        raise InputError(
            f"{source}: origin_geodetic given but the log has no geodetic anchor "
            "(no EKF reference, no global position, no GPS fix)",
            param="origin_geodetic",
        )
    return local_ned_to_enu(pos_ned, anchor, origin_geodetic)


def _seconds(ulog: Any, t_us: np.ndarray, time_reference: str, source: str) -> tuple[np.ndarray, dict[str, Any]]:
    """Times [s] on UTC (through the GPS offset) or since boot, and the clock metadata."""
    offset, offset_src = utc_offset_us(ulog)
    if time_reference == "utc" and offset is None:
        raise InputError(
            f"{source}: time_reference='utc' but no GPS message carries time_utc_usec", param="time_reference"
        )
    use_utc = offset is not None and time_reference in ("auto", "utc")
    t_s = (t_us + (offset if use_utc else 0)) * 1e-6
    clock = {"time_reference": "utc" if use_utc else "boot", "utc_offset_us": offset,
             "utc_offset_source": offset_src}
    return t_s, clock


@check_types
def read_ulog(
    path: str | os.PathLike,
    node: str,
    origin_geodetic: tuple[float, float, float] | None = None,
    time_reference: str = "auto",
    timebase: str = "attitude",
    max_gap_s: float = 0.5,
    require_valid: bool = False,
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read a PX4 ULog into a canonical pose log (ENU / FLU).

    Parameters
    ----------
    path : str or PathLike
        ``.ulg`` file.
    node : str
        Node id of the vehicle.
    origin_geodetic : (lat_deg, lon_deg, alt_m), optional
        Common ENU origin; positions are converted through the log's geodetic anchor.
    time_reference : {"auto", "utc", "boot"}
        ``"utc"``: seconds since the UNIX epoch through the GPS UTC offset (error without
        one); ``"boot"``: seconds since boot; ``"auto"``: UTC when the log has it, else boot.
    timebase : {"attitude", "position"}
        Which topic's instants become the pose rows (see the module docstring).
    max_gap_s : float
        Longest gap of the interpolated topic bridged [s].
    require_valid : bool
        Drop local-position rows whose ``xy_valid`` or ``z_valid`` flag is 0 (counted).

    Returns
    -------
    pose : DataFrame
        Canonical pose log of ``node``.
    metadata : dict
        ``source``, ``format`` ("ulog"), ``time_reference`` ("utc" or "boot"),
        ``utc_offset_us`` and its source topic, ``anchor_geodetic`` (or None) and
        ``anchor_source``, ``origin_geodetic`` (or None), ``dropped`` per reason,
        ``invalid_flag_rows`` (rows with xy_valid or z_valid = 0), ``rows``,
        ``cut_off_at_byte`` (the offset of the message a cut-off file ends inside, whose
        data are lost, see :func:`ulog_cut_off_at`; None for a whole file), ``records_read``
        (the complete messages before it), ``corrupt`` (pyulog skipped corrupt bytes, or a
        message has no ULog type), ``corrupt_at_byte`` (the first message of no ULog type) and
        ``repeated_messages`` (the messages of the log in the file again after it, not read:
        a log in the file twice, see :func:`ulog_layout`).
    """
    source = str(path)
    if time_reference not in ("auto", "utc", "boot"):
        raise InputError(f"time_reference must be 'auto', 'utc' or 'boot', got {time_reference!r}",
                         param="time_reference")
    if timebase not in ("attitude", "position"):
        raise InputError(f"timebase must be 'attitude' or 'position', got {timebase!r}", param="timebase")
    if not os.path.exists(source):
        raise InputError(f"{source}: no such file")
    layout = ulog_layout(source)
    ulog = _open_ulog(source, layout["log_bytes"] if layout["repeated_messages"] else None)
    try:
        lp, att = _pose_topics(ulog, source)
    except LogFormatError as exc:
        cut_off = layout["cut_off_at_byte"] is not None
        cut = layout["cut_off_at_byte"] if cut_off else layout["damaged_at_byte"]
        if cut is None:
            raise
        raise LogFormatError(f"{exc}: the file is {'cut off' if cut_off else 'damaged'} "
                             f"at byte {cut:,} of {os.path.getsize(source):,}, before the topic's first message "
                             "(a log that ended early, or a damaged copy)") from None
    dropped = {"nan_position": 0, "nan_attitude": 0, "invalid_flag": 0, "out_of_span": 0, "gap": 0}
    tp, ned, invalid_flag_rows = _local_positions(lp, require_valid, dropped)
    ta, q_ned = _attitudes(att, dropped)
    if len(tp) < 1 or len(ta) < 1:
        raise InputError(f"{source}: no valid position or attitude samples left")
    tp, ned = _increasing(tp, ned)
    ta, q_enu = _increasing(ta, quat_ned_frd_to_enu_flu(q_ned))
    anchor, anchor_source = _anchor(ulog, lp, tp, ned)
    t_us, pos_ned, quat = _on_timebase(tp, ned, ta, q_enu, timebase, max_gap_s, source, dropped)
    xyz = _enu(pos_ned, anchor, origin_geodetic, source)
    t_s, clock = _seconds(ulog, t_us, time_reference, source)
    pose = pd.DataFrame({
        "t": t_s, "node": str(node), "x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2],
        "qw": quat[:, 0], "qx": quat[:, 1], "qy": quat[:, 2], "qz": quat[:, 3],
    })
    pose = validate_pose_log(pose, source)
    corrupt = bool(ulog.file_corruption) or layout["damaged_at_byte"] is not None
    meta = {
        "source": source, "format": "ulog", "node": str(node), **clock,
        "anchor_geodetic": anchor, "anchor_source": anchor_source,
        "origin_geodetic": None if origin_geodetic is None else tuple(float(v) for v in origin_geodetic),
        "timebase": timebase, "dropped": dropped, "invalid_flag_rows": invalid_flag_rows,
        "rows": int(len(pose)),
        "cut_off_at_byte": None if corrupt else layout["cut_off_at_byte"],
        "records_read": None if corrupt else int(layout["messages"]),
        "corrupt": corrupt,
        "corrupt_at_byte": layout["damaged_at_byte"],
        "repeated_messages": int(layout["repeated_messages"]),
    }
    return pose, meta


@check_types
def read_ulogs(
    paths_to_nodes: dict[str, str],
    origin_geodetic: tuple[float, float, float] | None = None,
    **options: Any,
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read several drones' ULogs into one pose log on a common origin and clock.

    The origin is ``origin_geodetic`` or the first log's geodetic anchor; every log must
    resolve to UTC time (``time_reference="utc"``) so that they share a clock.

    Returns ``(pose, {"origin_geodetic": ..., "logs": [metadata per file]})``.
    """
    metas = []
    poses = []
    origin = origin_geodetic
    for path, node in paths_to_nodes.items():
        if origin is None:
            _, m0 = read_ulog(path, node, None, time_reference="utc", **options)
            origin = m0["anchor_geodetic"]
            if origin is None:
                raise InputError(f"{path}: no geodetic anchor to serve as the common origin")
        pose, meta = read_ulog(path, node, origin, time_reference="utc", **options)
        poses.append(pose)
        metas.append(meta)
    pose = validate_pose_log(pd.concat(poses, ignore_index=True), "ULogs")
    return pose, {"origin_geodetic": origin, "logs": metas}


__all__ = ["RADIO_TOPICS", "parsed_ulog", "read_ulog", "release_parsed", "read_ulogs", "ulog_cut_off_at", "ulog_layout", "utc_offset_us"]
