"""One pass over an ArduPilot ``.tlog`` into plain arrays, for :mod:`rplearn.io.mavlink` (which documents the
messages and their units), and what the DataFlash pass shares with it (:class:`Raw`, the boots that are copies:
:func:`merge_copied_boots`; :mod:`rplearn.io._dataflash_records`)."""

from __future__ import annotations

import os
import sys
from bisect import bisect_left, bisect_right, insort
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rplearn.errors import InputError, LogFormatError
from rplearn.io._log_schema import library_quiet
from rplearn.io.mavlink_phases import REBOOT_STEP_S

_RADIO_TYPES = ("RADIO_STATUS", "RADIO")
ORIGIN_TYPES = ("HOME_POSITION", "GPS_GLOBAL_ORIGIN")
_TLOG_TYPES = ["ATTITUDE", "GLOBAL_POSITION_INT", *ORIGIN_TYPES, "GPS_RAW_INT", "HEARTBEAT", *_RADIO_TYPES]
#: ``base_mode`` bit of an armed vehicle (MAV_MODE_FLAG_SAFETY_ARMED) and the GCS's MAV_TYPE.
_ARMED_FLAG, MAV_TYPE_GCS = 128, 6


@dataclass
class Raw:
    """What one pass over a log gave, as plain arrays (times [s] on the log's clock)."""

    fmt: str
    att: np.ndarray  # (n, 5): t, roll, pitch, yaw [rad], boot
    pos: np.ndarray  # (n, 7): t, lat [deg], lon [deg], alt [m], horizontal, vertical speed [m/s] (NaN: none), boot
    radio: np.ndarray  # (n, 7): t, rssi, remrssi (raw SiK units), noise, remnoise, rxerrors, fixed
    vehicle_t: np.ndarray  # receive times of the vehicle's messages (tlog) [s]
    home: tuple[float, float, float] | None
    boot_last_t: np.ndarray = field(default_factory=lambda: np.zeros(0))  # last vehicle message per boot [s]
    origin_t: np.ndarray = field(default_factory=lambda: np.zeros(0))  # times of origin messages [s]
    fix: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # (n, 2): t, 3-D fix (1) or not (0)
    armed: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # (n, 2): t, armed (1) or not (0)
    # (n, 3): t, the GPS accuracy the log reports [m] (horizontal, vertical standard deviations; 0 or NaN: none), and
    # the time of the home message (``home``'s) [s]
    accuracy: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    home_t: float | None = None
    counts: dict[str, int] = field(default_factory=dict)
    notes: dict[str, Any] = field(default_factory=dict)
    boot_offsets: dict[int, tuple[float, int]] = field(default_factory=dict)  # tlog: boot -> (offset [s], messages)
    # a window of a growing log (rplearn.io.tlog_window): fixes read earlier (rows of ``pos``,
    # the two ends of each piece of the boot, ``prefix_joined`` True at a piece's last fix), the
    # geodetic origin of the step test (the log's first fix), and the radio reports' copy verdicts
    # (aligned with ``radio``) with the report period they were judged by
    prefix: np.ndarray | None = None
    prefix_joined: np.ndarray | None = None
    step_origin: tuple[float, float, float] | None = None
    radio_copy: np.ndarray | None = None
    radio_period: float | None = None


def rows_array(rows: list[tuple[float, ...]], width: int) -> np.ndarray:
    return np.asarray(rows, np.float64).reshape(-1, width)


def mavutil_module() -> Any:
    try:
        from pymavlink import mavutil
    except ImportError:  # pragma: no cover - pymavlink is a dependency
        raise InputError("reading MAVLink logs needs the 'pymavlink' package (pip install pymavlink)") from None
    return mavutil


def _first_tlog_record_cut(head: bytes) -> bool:
    """Whether a ``.tlog`` whose first bytes are ``head`` ends inside its first record (the 8-byte
    receive time and one MAVLink 1 or 2 frame)."""
    if len(head) < 8 + 2:
        return True
    magic, length = head[8], head[9]
    if magic == 0xFE:
        return len(head) < 8 + 6 + length + 2
    if magic == 0xFD:
        signed = len(head) > 10 and head[10] & 0x01
        return len(head) < 8 + 10 + length + 2 + (13 if signed else 0)
    return False


def open_mavlink_log(source: str, tlog: bool = True) -> Any:
    """A pymavlink reader of the log file ``source`` (a ``.tlog``, or with ``tlog`` False a binary
    or text DataFlash log, told apart by its bytes); a log pymavlink cannot open is refused naming
    the file.

    The reader's class is chosen here, never by ``mavutil.mavlink_connection``, which takes its
    argument for a connection string first: a path holding ``/bin/`` is executed as a program, one
    starting ``tcp:`` or ``udpin:`` opens a socket, one not ending ``.bin`` is read as a ``.tlog``
    whatever it holds, and a ``.tlog``'s memory-mapped reader indexes the whole file first and
    fails inside pymavlink on a first message of its type cut off. The streaming ``.tlog`` reader
    parses the same messages in the same order.
    """
    mavutil = mavutil_module()
    with open(source, "rb") as fh:
        head = fh.read(8 + 10 + 255 + 2 + 13)
    if tlog and _first_tlog_record_cut(head):
        raise LogFormatError(f"{source}: the file ends inside its first record ({len(head)} byte(s)): "
                             "no complete MAVLink message (a log cut off, or not a .tlog)")
    try:
        if tlog:
            mavutil.set_dialect("ardupilotmega")
            return mavutil.mavlogfile(source)
        from pymavlink import DFReader

        with open(source, "rb") as fh:
            head = fh.read(8000)
        if not head.startswith(b"\xa3\x95") and b"FMT," in head:  # a text log (pymavlink's test, on bytes)
            return DFReader.DFReader_text(source)
        return DFReader.DFReader_binary(source)
    except Exception as exc:
        msg = str(exc).splitlines()[0] if str(exc) else ""
        raise LogFormatError(f"{source}: cannot read MAVLink log ({type(exc).__name__}: {msg})") from None


def boot_offsets(t_recv: np.ndarray, t_boot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per message, the median ``t_recv - t_boot`` [s] of its boot and the boot's number (a
    new boot where the boot clock steps back by more than ``REBOOT_STEP_S``, in receive order)."""
    order = np.argsort(t_recv, kind="stable")
    boot_sorted = t_boot[order]
    seg_sorted = np.concatenate([[0], np.cumsum(np.diff(boot_sorted) < -REBOOT_STEP_S)])
    seg = np.empty_like(seg_sorted)
    seg[order] = seg_sorted
    out = np.empty(len(t_recv))
    for s in np.unique(seg):
        m = seg == s
        out[m] = np.median(t_recv[m] - t_boot[m])
    return out, seg


def _tlog_cut_off(conn: Any, source: str, whole_to: int) -> dict[str, Any]:
    """Where a tlog ends inside a record (its 8-byte time or its MAVLink frame), given the byte
    ``whole_to`` where its last whole record ends: ``cut_off_at_byte`` (the cut record's start;
    None when the file ends whole) and ``cut_off_record`` (the message name when its frame's
    header is there, else None)."""
    size = os.path.getsize(source)
    if size <= whole_to:
        return {"cut_off_at_byte": None, "cut_off_record": None}
    try:
        head = bytes(conn.mav.buf[conn.mav.buf_index:conn.mav.buf_index + 10]) if conn.mav.buf_len() else b""
    except (AttributeError, TypeError, ValueError):  # pragma: no cover - a pymavlink without these
        head = b""
    msgid = head[5] if head[:1] == b"\xfe" and len(head) > 5 else (
        int.from_bytes(head[7:10], "little") if head[:1] == b"\xfd" and len(head) >= 10 else None)
    table = getattr(sys.modules.get(type(conn.mav).__module__), "mavlink_map", {})
    kind = table.get(msgid) if msgid is not None else None
    return {"cut_off_at_byte": int(whole_to), "cut_off_record": getattr(kind, "msgname", None) if kind is not None else None}


#: ``h_acc``/``v_acc`` of a GPS_RAW_INT that reports no accuracy (UINT32_MAX; 0 in a MAVLink 1 frame, which lacks them).
_UNKNOWN_ACC = 2**32 - 1


def _gps_raw_accuracy_m(msg: Any) -> tuple[float, float]:
    """The GPS accuracy a ``GPS_RAW_INT`` reports [m]: ``h_acc``, ``v_acc`` [mm] (MAVLink 2 extension fields;
    0.0 when absent, 0 or unknown: a number equal to itself, so that a message in the file twice is found). Its
    ``eph``/``epv`` are dilutions of precision (HDOP, VDOP x 100, unitless), no accuracy in metres: not used."""
    out = []
    for name in ("h_acc", "v_acc"):
        value = getattr(msg, name, 0)
        out.append(float(value) * 1e-3 if isinstance(value, int) and 0 < value < _UNKNOWN_ACC else 0.0)
    return out[0], out[1]


def _tlog_row(kind: str, msg: Any, src: int, t: float) -> tuple[Any, ...]:
    """The fields of one tlog message the reader uses (units: module docstring of mavlink.py)."""
    if kind == "ATTITUDE":
        return (src, t, msg.time_boot_ms * 1e-3, msg.roll, msg.pitch, msg.yaw)
    if kind == "GLOBAL_POSITION_INT":
        return (src, t, msg.time_boot_ms * 1e-3, msg.lat * 1e-7, msg.lon * 1e-7, msg.alt * 1e-3,
                np.hypot(msg.vx, msg.vy) * 1e-2, abs(msg.vz) * 1e-2)
    if kind == "HOME_POSITION":
        return (src, t, msg.latitude * 1e-7, msg.longitude * 1e-7, msg.altitude * 1e-3)
    if kind == "GPS_GLOBAL_ORIGIN":
        return (src, t, msg.latitude * 1e-7, msg.longitude * 1e-7, msg.altitude * 1e-3)
    if kind == "GPS_RAW_INT":
        return (src, t, float(msg.fix_type >= 3), *_gps_raw_accuracy_m(msg))
    if kind == "HEARTBEAT":
        return (src, t, float(msg.base_mode & _ARMED_FLAG != 0), msg.type)
    return (t, msg.rssi, msg.remrssi, msg.noise, msg.remnoise, msg.rxerrors, msg.fixed)


@dataclass
class TlogRows:
    """The fields of the ``.tlog`` messages read so far (:func:`_tlog_row`), added one message at
    a time, so that a growing log is read only where it grew (:mod:`rplearn.io.tlog_tail`)."""

    rows: dict[str, list[tuple[Any, ...]]] = field(default_factory=lambda: {k: [] for k in _TLOG_TYPES})
    by_sys: dict[int, list[float]] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    radio_senders: dict[str, int] = field(default_factory=dict)
    radio_from: dict[str, list[str]] = field(default_factory=lambda: {k: [] for k in _RADIO_TYPES})  # per radio row
    #: Drop one message received twice as it is added (:func:`is_close_copy`: the live tail, which has
    #: skipped a stretch written again before); offline after those stretches (:func:`drop_close_copies`).
    close_as_added: bool = False
    #: Attitude and position messages left out as copies of the one before them (:meth:`add`).
    close_copies: int = 0
    #: Per kind of :data:`_BOOT_TIMED`, its last messages (:class:`RecentRecords`; shared by the parts of a
    #: growing log read one after another: :mod:`rplearn.io.tlog_tail`).
    recent: dict[str, RecentRecords] = field(default_factory=dict)
    _arrays: dict[Any, np.ndarray] = field(default_factory=dict)

    def array(self, kind: str, width: int) -> np.ndarray:
        """The rows of a message kind as an array, converting only those added since the last call."""
        rows, done = self.rows[kind], self._arrays.get(kind, np.zeros((0, width)))
        if len(done) < len(rows):
            done = self._arrays[kind] = np.concatenate([done, rows_array(rows[len(done):], width)])
        return done

    def times(self, sysid: int) -> np.ndarray:
        """The receive times of a system's messages [s], as :meth:`array` converts rows."""
        rows, done = self.by_sys.get(sysid, []), self._arrays.get(sysid, np.zeros(0))
        if len(done) < len(rows):
            done = self._arrays[sysid] = np.concatenate([done, np.asarray(rows[len(done):], np.float64)])
        return done

    def add(self, msg: Any, source: str) -> None:
        """Add one parsed message (``BAD_DATA`` counted)."""
        kind = msg.get_type()
        if kind == "BAD_DATA":
            self.counts["BAD_DATA"] = self.counts.get("BAD_DATA", 0) + 1
            return
        t, sysid = float(msg._timestamp), int(msg.get_srcSystem())
        self.by_sys.setdefault(sysid, []).append(t)
        if kind not in self.rows:
            return
        src = sysid * 256 + int(msg.get_srcComponent())  # a gimbal may send ATTITUDE too
        try:
            row = _tlog_row(kind, msg, src, t)
        except (AttributeError, TypeError, ValueError) as exc:  # a field the dialect of the file lacks
            name = getattr(exc, "name", None)
            raise LogFormatError(f"{source}: a {kind} message has no {name} field" if name else
                                 f"{source}: a {kind} message has a field that is not a number ({exc})") from None
        if self.close_as_added and kind in _BOOT_TIMED and is_close_copy(self.recent, kind, row):
            self.close_copies += 1
            return
        self.counts[kind] = self.counts.get(kind, 0) + 1
        self.rows[kind].append(row)
        if kind in _RADIO_TYPES:
            key = f"{sysid}/{msg.get_srcComponent()}"
            self.radio_senders[key] = self.radio_senders.get(key, 0) + 1
            self.radio_from[kind].append(key)


#: A ``.tlog`` record's time before its MAVLink frame (big-endian microseconds) [bytes].
_TLOG_TIME_BYTES = 8


def collect_tlog(source: str, system_id: int | None) -> Raw:
    """One pass over a ``.tlog``: attitude, position, origin, fix, armed state, radio, and the
    corrupt stretches (bytes between two whole records that are none: ``corrupt_stretches``,
    ``corrupt_bytes`` in ``notes``)."""
    acc = TlogRows()
    with library_quiet():  # pymavlink prints what it cannot parse
        conn = open_mavlink_log(source)
        whole_to, good_to, stretches, skipped = 0, 0, 0, 0
        while True:
            try:
                msg = conn.recv_msg()
            except Exception as exc:
                raise LogFormatError(f"{source}: corrupt MAVLink data ({type(exc).__name__}: {exc})") from None
            if msg is None:
                break
            whole_to = conn.f.tell() - conn.mav.buf_len()  # where the records read so far end
            if msg.get_type() != "BAD_DATA":
                # bytes between the last whole record and this one's 8-byte time: a corrupt
                # stretch (pymavlink says most with one BAD_DATA, however many frames it held)
                start = whole_to - len(msg.get_msgbuf()) - _TLOG_TIME_BYTES
                if start > good_to:
                    stretches, skipped = stretches + 1, skipped + start - good_to
                good_to = whole_to
            acc.add(msg, source)
        cut_off = _tlog_cut_off(conn, source, whole_to)
    repeated = drop_repeated_rows(acc)
    close = drop_close_copies(acc)
    raw = tlog_raw(acc, source, system_id, cut_off)
    if whole_to > good_to:  # BAD_DATA after the last whole record
        stretches, skipped = stretches + 1, skipped + whole_to - good_to
    raw.notes.update(corrupt_stretches=stretches, corrupt_bytes=skipped, repeated_messages=repeated, close_copies=close,
                     records_read=sum(n for k, n in acc.counts.items() if k != "BAD_DATA"))
    return raw


def drop_repeated_rows(acc: TlogRows) -> int:
    """Keep the first of the messages that repeat an earlier one exactly (same kind, sender,
    receive time [s] and fields): a copy of part of the log inside the file (logs concatenated,
    a copy resumed from its start). Two such messages hold one reading, so dropping the copy
    loses nothing; without it a log in the file twice would read as a reboot and a second
    flight. Returns how many were dropped (their kinds' counts are lowered)."""
    dropped = 0
    for kind, rows in acc.rows.items():
        senders = acc.radio_from.get(kind)  # a radio row holds no sender: compared with its sender's
        keyed = list(zip(rows, senders, strict=True)) if senders is not None else rows
        unique = list(dict.fromkeys(keyed))
        if len(unique) < len(rows):
            dropped += len(rows) - len(unique)
            acc.counts[kind] -= len(rows) - len(unique)
            if senders is not None:
                for key in senders:
                    acc.radio_senders[key] -= 1
                acc.rows[kind], acc.radio_from[kind] = [r for r, _ in unique], [k for _, k in unique]
                for key in acc.radio_from[kind]:
                    acc.radio_senders[key] += 1
            else:
                acc.rows[kind] = unique
            acc._arrays.pop(kind, None)
    return dropped


#: Largest receive-time difference [s] between a message and the same one (kind, sender, fields) among the
#: last read (:class:`RecentRecords`) for the two to be one message received twice: far below any report period.
CLOSE_COPY_S = 1e-3


#: Rounding of a difference of two times in whole microseconds held as seconds (a float of UNIX seconds: 0.24 us).
_TIME_ROUNDING_S = 5e-7

#: Kinds whose fields hold the sender's boot time: two with the same fields are one message (a radio
#: report holds no time: two of equal values may come close; ``sync`` merges copies, ``duplicate_reading``).
_BOOT_TIMED = ("ATTITUDE", "GLOBAL_POSITION_INT")


def close_in_time(dt: float) -> bool:
    """Whether a message ``dt`` [s] after another with the same fields is that message again (at most
    :data:`CLOSE_COPY_S` later, times in whole microseconds)."""
    return 0.0 <= dt <= CLOSE_COPY_S + _TIME_ROUNDING_S


#: How many of the records read last a record's earlier copy is looked among (:class:`RecentRecords`): a logger
#: writing each buffer of records twice, or a burst of messages received twice, the copies up to 1 ms later,
#: repeats up to this many records. A stretch of the log written again farther back (a download resumed from its
#: start) is :func:`merge_copied_boots`'s (DataFlash) or :func:`drop_repeated_rows`'s (``.tlog``).
COPY_WINDOW_RECORDS = 1024


@dataclass
class RecentRecords:
    """The last :data:`COPY_WINDOW_RECORDS` records added: per key (kind, instance or sender, fields but the time)
    their times, sorted (a record whose fields repeat often, a vehicle at rest, is looked up by bisection, not
    against each of up to :data:`COPY_WINDOW_RECORDS` times). A record repeating one of them at most
    :data:`CLOSE_COPY_S` after it (:func:`close_in_time`) may be that record written or received twice; the
    DataFlash and ``.tlog`` passes share this window."""

    seen: dict[tuple[Any, ...], list[float]] = field(default_factory=dict)
    order: deque[tuple[float, tuple[Any, ...]]] = field(default_factory=deque)

    def copy_gap(self, key: tuple[Any, ...], t: float) -> float | None:
        """How long [s] after the latest record of ``key`` within :func:`close_in_time` of ``t`` a record at ``t``
        comes (0.0: at the same time); None when none is."""
        times = self.seen.get(key, ())
        i = bisect_left(times, t - 2.0 * CLOSE_COPY_S)  # every time close_in_time could take, and more
        gap = None
        while i < len(times) and times[i] <= t:
            if close_in_time(t - times[i]):
                gap = t - times[i]
            i += 1
        return gap

    def since(self, key: tuple[Any, ...], t: float) -> float | None:
        """How long [s] before ``t`` the latest record of ``key`` at or before it was added (None: none)."""
        times = self.seen.get(key, ())
        i = bisect_right(times, t) if t == t else 0  # a time that is not a number follows none
        return t - times[i - 1] if i else None

    def add(self, key: tuple[Any, ...], t: float) -> None:
        """Add a record (the oldest of more than :data:`COPY_WINDOW_RECORDS` forgotten)."""
        if t == t:  # a time that is not a number is no copy's (close_in_time) and keeps the times sorted out
            insort(self.seen.setdefault(key, []), t)
        self.order.append((t, key))
        if len(self.order) > COPY_WINDOW_RECORDS:
            old_t, old_key = self.order.popleft()
            if old_t != old_t:
                return
            times = self.seen[old_key]
            del times[bisect_left(times, old_t)]  # one of the times equal to old_t: which one does not matter
            if not times:
                del self.seen[old_key]


def is_close_copy(recent: dict[str, RecentRecords], kind: str, row: tuple[Any, ...]) -> bool:
    """Whether ``row`` (:func:`_tlog_row`: sender, receive time, fields) repeats one of the last
    :data:`COPY_WINDOW_RECORDS` messages of its kind (``recent``, per kind; the row added when it does not), boot
    time and sender included, within :data:`CLOSE_COPY_S`: one message received twice (a router, or two links
    forwarding each, a burst of messages at a time). Kept, they would be two poses of one instant."""
    window = recent.setdefault(kind, RecentRecords())
    key = row[:1] + row[2:]
    if window.copy_gap(key, row[1]) is not None:
        return True
    window.add(key, row[1])
    return False


def drop_close_copies(acc: TlogRows) -> int:
    """Drop the later of two attitude or position messages that are one received twice (:func:`is_close_copy`),
    after the stretches written again (as the live tail meets them); how many (their kinds' counts lowered)."""
    dropped, recent = 0, dict[str, RecentRecords]()
    for kind in _BOOT_TIMED:
        rows = acc.rows.get(kind, [])
        keep = [not is_close_copy(recent, kind, row) for row in rows]
        n = len(keep) - sum(keep)
        if n:
            dropped += n
            acc.counts[kind] -= n
            acc.rows[kind] = [r for r, k in zip(rows, keep, strict=True) if k]
            acc._arrays.pop(kind, None)
    return dropped


def tlog_raw(acc: TlogRows, source: str, system_id: int | None, cut_off: dict[str, Any],
             time_base: dict[int, float] | None = None) -> Raw:
    """The :class:`Raw` arrays of the messages in ``acc``. ``time_base`` (boot number -> receive
    minus boot time [s]) fixes the offsets of the boots it holds; the others take their median
    (:func:`boot_offsets`)."""
    rows, counts, radio_senders = acc.rows, acc.counts, acc.radio_senders
    att = acc.array("ATTITUDE", 6)
    if not len(att):
        raise LogFormatError(f"{source}: no ATTITUDE messages (the vehicle's attitude)")
    srcs, n = np.unique(att[:, 0].astype(int), return_counts=True)
    if system_id is not None:
        if int(system_id) not in srcs // 256:
            raise InputError(f"{source}: no ATTITUDE messages from system id {system_id} "
                             f"(it has {', '.join(map(str, np.unique(srcs // 256)))})", param="system_id")
        srcs, n = srcs[srcs // 256 == int(system_id)], n[srcs // 256 == int(system_id)]
    chosen = int(srcs[np.argmax(n)])  # the (system, component) sending most ATTITUDE
    vehicle = chosen // 256
    every = np.unique(att[:, 0].astype(int), return_counts=True)
    others = {int(s): int(k) for s, k in zip(every[0] // 256, every[1], strict=True) if int(s) != vehicle}
    att = att[att[:, 0] == chosen]
    gpi = acc.array("GLOBAL_POSITION_INT", 8)
    gpi = gpi[(gpi[:, 0] == chosen) & ((gpi[:, 3] != 0) | (gpi[:, 4] != 0))]
    both = np.concatenate([att[:, 1:3], gpi[:, 1:3]])
    boot_clock = len(np.unique(att[:, 2])) >= 0.9 * len(att)  # some senders leave time_boot_ms at 0
    if boot_clock:
        offset, boot = boot_offsets(both[:, 0], both[:, 1])
        for b, fixed in (time_base or {}).items():
            offset[boot == b] = fixed
    else:
        offset, boot = both[:, 0] - both[:, 1], np.zeros(len(both), np.int64)
    t_log = both[:, 1] + offset
    per_boot = {int(b): (float(offset[boot == b][0]), int((boot == b).sum())) for b in np.unique(boot)} if boot_clock else {}
    boot_last_t = np.array([t_log[boot == b].max() for b in range(int(boot.max()) + 1)]) if len(boot) else np.zeros(0)
    home = [h for h in rows["HOME_POSITION"] if h[0] // 256 == vehicle and (h[2] != 0 or h[3] != 0)]
    origin = [h[1] for k in ORIGIN_TYPES for h in rows[k] if h[0] // 256 == vehicle and (h[2] != 0 or h[3] != 0)]
    fix = [r[1:3] for r in rows["GPS_RAW_INT"] if r[0] // 256 == vehicle]
    accuracy = [(r[1], r[3], r[4]) for r in rows["GPS_RAW_INT"] if r[0] // 256 == vehicle and r[3] > 0 and r[4] > 0]
    beats = [r[1:3] for r in rows["HEARTBEAT"] if r[0] // 256 == vehicle and r[3] != MAV_TYPE_GCS]
    radio = np.concatenate([acc.array("RADIO_STATUS", 7), acc.array("RADIO", 7)])
    radio = radio[np.lexsort(radio.T[::-1])]  # as the rows' tuples sort
    n_att = len(att)
    return Raw(
        fmt="tlog",
        att=np.column_stack([t_log[:n_att], att[:, 3:6], boot[:n_att]]),
        pos=np.column_stack([t_log[n_att:], gpi[:, 3:8], boot[n_att:]]),
        radio=radio, vehicle_t=np.sort(acc.times(vehicle)),
        home=(float(home[0][2]), float(home[0][3]), float(home[0][4])) if home else None, counts=dict(counts),
        home_t=float(home[0][1]) if home else None, accuracy=rows_array(sorted(accuracy), 3),
        boot_last_t=boot_last_t, origin_t=np.sort(np.asarray(origin, np.float64)), fix=rows_array(sorted(fix), 2),
        armed=rows_array(sorted(beats), 2), boot_offsets=per_boot,
        notes={"system_id": vehicle, "component_id": chosen % 256, "radio_senders": dict(radio_senders), **cut_off,
               "other_vehicles": others,
               "clock_offset_s": float(np.median(offset)) if len(offset) and boot_clock else None,
               "time_reference": "ground station receive time, seconds since the UNIX epoch"
                                 + (" (vehicle messages through time_boot_ms + median offset)" if boot_clock else "")},
    )


#: The share of the records of the smaller of two boots that must repeat exactly for the later
#: boot to be a copy of the earlier (:func:`merge_copied_boots`); a real reboot repeats none,
#: save by chance.
COPY_SHARE = 0.5


def _is_copy(votes: int, size_earlier: int, size_later: int) -> bool:
    """Whether a later stretch repeating ``votes`` records of an earlier one is a copy of it: a
    share (:data:`COPY_SHARE`) of the smaller's records, and either two or more of them or
    every record of the later stretch (a copy of one record), not a few equal by chance (a
    whole log after a partial copy of it repeats all of the copy, but a small share of its
    own records)."""
    return votes >= COPY_SHARE * min(size_earlier, size_later) and (votes >= 2 or votes == size_later)


def _copy_groups(tables: dict[str, list[tuple[float, ...]]], minor: frozenset[int], stretches: set[int]
                 ) -> tuple[dict[int, int], set[int]]:
    """The group of each stretch (``stretches``, numbered in file order, and those of the
    rows of ``tables``; :func:`merge_copied_boots`) and the stretches that are copies."""
    first: dict[tuple[Any, ...], int] = {}
    votes: dict[int, dict[int, int]] = {}
    size: dict[int, int] = dict.fromkeys(stretches, 0)
    for kind, rows in tables.items():
        for row in rows:
            key, b = (kind, *row[:-1]), int(row[-1])
            size[b] = size.get(b, 0) + 1
            a = first.setdefault(key, b)
            if a < b:
                votes.setdefault(b, {}).setdefault(a, 0)
                votes[b][a] += 1
    group: dict[int, int] = {}
    group_size: dict[int, int] = {}
    copies: set[int] = set()
    for b in sorted(size):
        by_group: dict[int, int] = {}
        for a, n in votes.get(b, {}).items():
            by_group[group[a]] = by_group.get(group[a], 0) + n
        g = max(by_group, key=lambda k: (by_group[k], -k)) if by_group else None
        if g is not None and _is_copy(by_group[g], group_size[g], size[b]):
            group[b] = g
            copies.add(b)
        elif b in minor and b - 1 in group:  # time stepped back a little, no copy: the same boot
            group[b] = group[b - 1]
            group_size[group[b]] += size[b]
        else:
            group[b] = b
            group_size[b] = size[b]
    return group, copies


def merge_copied_boots(tables: dict[str, list[tuple[float, ...]]], boot_t: list[tuple[float, int]],
                       minor: frozenset[int] = frozenset()) -> int:
    """Undo the boots that are copies: a later stretch of the log (a boot, or the records after
    a small step back of the time: ``minor``) whose records repeat an earlier one's exactly
    (same kind, TimeUS and fields) runs on that stretch's clock, so it is that stretch again
    (logs concatenated, a copy resumed from its start, the last records written again), not a
    reboot. Its records join that stretch's boot, the repeats are dropped (two such records
    hold one reading); a ``minor`` stretch that is no copy stays in the boot before it (records
    a little out of time order), and the boots are numbered again from 0. ``tables`` (rows per
    kind, the stretch number last) and ``boot_t`` (time, stretch per message) are changed in
    place; returns the repeats dropped."""
    group, copies = _copy_groups(tables, minor, {b for _, b in boot_t})
    if not copies and len(set(group.values())) == len(group):
        return 0
    kept = sorted(set(group.values()))
    number = {b: kept.index(g) for b, g in group.items()}
    holder = {b: (b if b in copies else group[b]) for b in group}
    repeated = 0
    for rows in tables.values():
        # a row kept as often as the most any one holder of its group holds it (a copy holds
        # its own, a boot with the small steps back in it one): the copies go, not distinct
        # records that read alike (rows hold only some fields: two ORGN at one TimeUS), nor
        # rows of boots that are no copies
        per_boot: dict[tuple[Any, ...], dict[int, int]] = {}
        for row in rows:
            held = per_boot.setdefault((*row[:-1], number[int(row[-1])]), {})
            h = holder[int(row[-1])]
            held[h] = held.get(h, 0) + 1
        left = {key: max(held.values()) for key, held in per_boot.items()}
        renumbered: list[Any] = []
        for row in rows:
            key = (*row[:-1], number[int(row[-1])])
            if left[key] > 0:
                left[key] -= 1
                renumbered.append(key)
        repeated += len(rows) - len(renumbered)
        rows[:] = renumbered
    boot_t[:] = [(t, number[b]) for t, b in boot_t]
    return repeated


__all__ = ["CLOSE_COPY_S", "COPY_WINDOW_RECORDS", "Raw", "RecentRecords", "TlogRows", "boot_offsets", "close_in_time",
           "collect_tlog", "drop_close_copies", "drop_repeated_rows", "is_close_copy", "merge_copied_boots", "tlog_raw"]
