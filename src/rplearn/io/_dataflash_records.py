"""One pass over an ArduPilot DataFlash log (binary ``.bin`` or text ``.log``) into plain arrays, for
:mod:`rplearn.io.mavlink` (which documents the messages and their units).

A record that repeats one of its kind (and instance) read shortly before it (:class:`_Recent`), every field but
its time the same and its time at most :data:`~rplearn.io._mavlink_records.CLOSE_COPY_S` later (TimeUS the same,
or within 1 ms), is that record written twice (a logger or a router duplicating the stream, record by record or a
buffer at a time): it is read once and counted (``close_copies``), as a ``.tlog``'s messages received twice are
(:func:`~rplearn.io._mavlink_records.close_in_time`, the same bound). A later stretch that repeats an earlier one
(the log in the file twice) is undone by :func:`~rplearn.io._mavlink_records.merge_copied_boots`
(``repeated_messages``).
"""

from __future__ import annotations

from bisect import bisect_left, insort
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rplearn.errors import LogFormatError
from rplearn.io._log_schema import check_dataflash_lengths, dataflash_time_field, library_quiet, number
from rplearn.io._mavlink_records import CLOSE_COPY_S, Raw, close_in_time, merge_copied_boots, open_mavlink_log, rows_array
from rplearn.io.mavlink_phases import REBOOT_STEP_S

DF_TYPES = ["ATT", "POS", "GPS", "ORGN", "RAD", "ARM", "EV"]
#: DataFlash EV ids of arming and disarming (ArduPilot LogEvent ARMED = 10, DISARMED = 11).
_EV_ARMED, _EV_DISARMED = 10, 11
#: Fields naming a message's instance (a second GPS, ...): each instance's records are compared with its own.
_INSTANCE_FIELDS = ("I", "Instance")


#: How many of the records read last (of the types read) a record's earlier copy is looked among: a logger
#: writing each buffer of records twice, the copies up to 1 ms later, writes buffers up to this many records. A
#: stretch of the log written again farther back (a download resumed from its start) is merge_copied_boots's.
COPY_WINDOW_RECORDS = 1024


@dataclass
class _Recent:
    """The last :data:`COPY_WINDOW_RECORDS` records read: per kind, instance and fields but the time, their times
    (sorted: a record whose fields repeat often, a vehicle at rest, is looked up by bisection, not against each of
    up to :data:`COPY_WINDOW_RECORDS` times). A record repeating one of them at most
    :data:`~rplearn.io._mavlink_records.CLOSE_COPY_S` after it is that record written twice
    (:func:`~rplearn.io._mavlink_records.close_in_time`, the ``.tlog``'s bound)."""

    seen: dict[tuple[Any, ...], list[float]] = field(default_factory=dict)
    order: deque[tuple[float, tuple[Any, ...]]] = field(default_factory=deque)

    def is_copy(self, key: tuple[Any, ...], t: float) -> bool:
        times = self.seen.get(key, ())
        i = bisect_left(times, t - 2.0 * CLOSE_COPY_S)  # every time close_in_time could take, and more
        while i < len(times) and times[i] <= t:
            if close_in_time(t - times[i]):
                return True
            i += 1
        return False

    def add(self, key: tuple[Any, ...], t: float) -> None:
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


def _fields(msg: Any, time_name: str) -> tuple[Any, ...]:
    """A DataFlash message's fields but its time, as read (NaN as one value: a record written twice with a NaN
    is still one record)."""
    elements = getattr(msg, "_elements", None)  # pymavlink's DFMessage: the values as unpacked
    names = list(getattr(getattr(msg, "fmt", None), "columns", None) or msg.get_fieldnames())
    values = list(elements) if elements is not None and len(elements) == len(names) else [getattr(msg, n) for n in names]
    return tuple("nan" if isinstance(v, float) and v != v else v
                 for n, v in zip(names, values, strict=True) if n != time_name)


def _instance(msg: Any, names: tuple[str, ...]) -> int:
    """The instance number of a message (0 for a message type without one)."""
    for name in names:
        try:
            return int(getattr(msg, name))
        except (AttributeError, TypeError, ValueError):
            continue
    return 0


def _df_chain(boot_t: list[tuple[float, int]]) -> tuple[dict[int, float], np.ndarray]:
    """Offsets [s] that put each later boot's TimeUS right after the previous boot's last record
    (a DataFlash log holds no clock across a reboot), and each boot's last time on that clock."""
    last: dict[int, float] = {}
    first: dict[int, float] = {}
    for t, b in boot_t:
        last[b] = max(last.get(b, t), t)
        first[b] = min(first.get(b, t), t)
    offsets: dict[int, float] = {0: 0.0}
    ends: list[float] = []
    for b in range(max(last) + 1 if last else 0):
        if b > 0:
            offsets[b] = ends[-1] + REBOOT_STEP_S - first.get(b, 0.0)
        ends.append(last.get(b, first.get(b, 0.0)) + offsets[b])
    return offsets, np.asarray(ends, np.float64)


@dataclass(frozen=True)
class _DfMessage:
    """One DataFlash message whose fields are read as numbers (:func:`rplearn.io._log_schema.number`)."""

    msg: Any
    kind: str
    source: str

    def __call__(self, name: str, default: float | None = None) -> float:
        return number(self.msg, self.kind, name, self.source, default)


def _df_record(get: _DfMessage, t: float, boot: int, out: tuple[dict[str, list[tuple[float, ...]]], list[tuple[float, ...]],
               list[tuple[float, ...]], list[float]], home: tuple[float, float, float] | None
               ) -> tuple[float, float, float] | None:
    """Add one DataFlash message's row to ``out`` (rows per kind, fix rows, armed rows, UTC
    offsets); the home position (the first ORGN of type 1) returned."""
    rows, fix_rows, arm_rows, utc = out
    kind = get.kind
    if kind == "ATT":
        rows[kind].append((t, *np.radians([get("Roll"), get("Pitch"), get("Yaw")]), boot))
    elif kind == "POS":
        rows[kind].append((t, get("Lat"), get("Lng"), get("Alt"), np.nan, np.nan, boot))
    elif kind == "GPS" and get("I", 0.0) == 0:
        status = get("Status")
        fix_rows.append((t, float(status >= 3), boot))
        if status >= 3:
            rows[kind].append((t, get("Lat"), get("Lng"), get("Alt"), get("Spd", np.nan), abs(get("VZ", np.nan)), boot))
            utc.append(float(get.msg._timestamp) - t)
    elif kind == "RAD":
        rows[kind].append((t, *(get(f) for f in ("RSSI", "RemRSSI", "Noise", "RemNoise", "RxErrors", "Fixed")), boot))
    elif kind == "ORGN":
        rows[kind].append((t, boot))
        if get("Type") == 1 and home is None:
            return (get("Lat"), get("Lng"), get("Alt"))
    elif kind == "ARM":
        arm_rows.append((t, float(get("ArmState") != 0), boot))
    elif kind == "EV" and get("Id") in (_EV_ARMED, _EV_DISARMED):
        arm_rows.append((t, float(get("Id") == _EV_ARMED), boot))
    return home


def collect_dataflash(source: str) -> Raw:
    """One pass over a DataFlash log: ATT, POS (else GPS), RAD, ORGN, GPS status, ARM and EV
    (each message type's fields checked on its first record: :mod:`rplearn.io._log_schema`)."""
    rows: dict[str, list[tuple[float, ...]]] = {k: [] for k in DF_TYPES}
    home = None
    utc: list[float] = []
    boot, last_t, boot_t = 0, -np.inf, []
    minor: set[int] = set()  # the stretches after a step back of the time too small for a reboot
    last_kind = ""
    fix_rows: list[tuple[float, ...]] = []
    arm_rows: list[tuple[float, ...]] = []
    times: dict[str, tuple[str, float]] = {}
    instance: dict[str, tuple[str, ...]] = {}
    recent = _Recent()
    close = 0
    with library_quiet():  # pymavlink prints what it cannot parse
        conn = open_mavlink_log(source, tlog=False)
        check_dataflash_lengths(conn, source)
        while True:
            try:
                msg = conn.recv_match(type=DF_TYPES)
            except Exception as exc:
                raise LogFormatError(f"{source}: corrupt DataFlash data ({type(exc).__name__}: {exc})") from None
            if msg is None:
                break
            kind = msg.get_type()
            if kind not in times:
                times[kind] = dataflash_time_field(msg, kind, source)
                instance[kind] = tuple(n for n in _INSTANCE_FIELDS if n in (getattr(msg, "fmt", None) and msg.fmt.columns
                                                                            or msg.get_fieldnames()))
            t = number(msg, kind, times[kind][0], source) * times[kind][1]
            which = _instance(msg, instance[kind])
            key = (kind, which, *_fields(msg, times[kind][0]))
            if recent.is_copy(key, t):
                close += 1  # the record written twice: read once
                continue
            recent.add(key, t)
            if t < last_t or (t == last_t and kind == last_kind):  # the latter: maybe a copy of the last record
                boot += 1
                if t >= last_t - REBOOT_STEP_S:
                    minor.add(boot)
            last_t, last_kind = t, kind
            boot_t.append((t, boot))
            home = _df_record(_DfMessage(msg, kind, source), t, boot, (rows, fix_rows, arm_rows, utc), home)
    tables = {**rows, "GPS status": fix_rows, "ARM/EV": arm_rows}
    repeated = merge_copied_boots(tables, boot_t, frozenset(minor)) if boot else 0
    rows = {k: tables[k] for k in rows}
    fix_rows, arm_rows = tables["GPS status"], tables["ARM/EV"]
    offsets, ends = _df_chain(boot_t)

    def chained(a: np.ndarray, tcol: int, bcol: int) -> np.ndarray:
        if len(a):
            a[:, tcol] += np.array([offsets[int(b)] for b in a[:, bcol]])
        return a

    counts = {k: len(v) for k, v in rows.items() if v}
    if not rows["ATT"]:
        raise LogFormatError(f"{source}: no ATT messages (the vehicle's attitude)")
    pos_kind = "POS" if rows["POS"] else "GPS"
    orgn = chained(rows_array(rows["ORGN"], 2), 0, 1)
    # the vehicle logs itself throughout: its stream is never absent
    return Raw(
        fmt="dataflash", att=chained(rows_array(rows["ATT"], 5), 0, 4), pos=chained(rows_array(rows[pos_kind], 7), 0, 6),
        radio=chained(rows_array(rows["RAD"], 8), 0, 7)[:, :7], vehicle_t=np.array([]), home=home, counts=counts,
        boot_last_t=ends, origin_t=orgn[:, 0],
        fix=chained(rows_array(fix_rows, 3), 0, 2)[:, :2], armed=chained(rows_array(arm_rows, 3), 0, 2)[:, :2],
        notes={"position_message": pos_kind, "repeated_messages": repeated, "close_copies": close,
               "time_reference": "TimeUS, seconds since the autopilot booted"
                                 + (" (later boots placed right after the previous one)" if len(ends) > 1 else ""),
               "utc_offset_s": float(np.median(utc)) if utc else None},
    )



__all__ = ["DF_TYPES", "collect_dataflash"]
