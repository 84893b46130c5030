"""One pass over an ArduPilot DataFlash log (binary ``.bin`` or text ``.log``) into plain arrays, for
:mod:`rplearn.io.mavlink` (which documents the messages and their units).

A record that repeats one of its kind (and instance) read shortly before it (among the last records read,
:class:`~rplearn.io._mavlink_records.RecentRecords`, the window a ``.tlog``'s messages received twice are sought in),
every field but its time the same, is that record written twice (a logger or a router duplicating the stream,
record by record or a buffer at a time) when its TimeUS is the same, or up to
:data:`~rplearn.io._mavlink_records.CLOSE_COPY_S` later and far below (less than
:data:`~rplearn.io.mavlink_phases.DUPLICATE_FRACTION_OF_PERIOD` of) the local interval between the records with its fields
(kind, instance and fields): the median over a sliding span of :data:`CADENCE_SPAN` of their intervals about it, so that a
message whose logging rate changes within a boot (ATT at 10 Hz, then at 1 kHz) is judged at its rate of the moment. It is read
once and counted (``close_copies``). A kind logged every millisecond while the vehicle rests repeats its fields 1 ms later
at its own interval: those records are no copies, the last of them before its rate is lowered too (:func:`_judge`;
the log is then read a second time, with them). A later stretch that repeats an earlier one (the log in the file twice) is undone by
:func:`~rplearn.io._mavlink_records.merge_copied_boots` (``repeated_messages``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rplearn.errors import LogFormatError
from rplearn.io._log_schema import check_dataflash_lengths, dataflash_time_field, library_quiet, number
from rplearn.io._mavlink_records import Raw, RecentRecords, merge_copied_boots, open_mavlink_log, rows_array
from rplearn.io.mavlink_phases import DUPLICATE_FRACTION_OF_PERIOD, REBOOT_STEP_S

DF_TYPES = ["ATT", "POS", "GPS", "GPA", "ORGN", "RAD", "ARM", "EV"]
#: DataFlash EV ids of arming and disarming (ArduPilot LogEvent ARMED = 10, DISARMED = 11).
_EV_ARMED, _EV_DISARMED = 10, 11
#: Fields naming a message's instance (a second GPS, ...): each instance's records are compared with its own.
_INSTANCE_FIELDS = ("I", "Instance")
#: How many intervals between the records of one key (kind, instance and fields) a record repeating one up to 1 ms
#: before it is judged by (:func:`_judge`): the key's cadence where the record is, not over the whole log.
CADENCE_SPAN = 16


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

    @property
    def columns(self) -> list[str]:
        """The message's field names."""
        return list(getattr(getattr(self.msg, "fmt", None), "columns", None) or self.msg.get_fieldnames())

    def __call__(self, name: str, default: float | None = None) -> float:
        return number(self.msg, self.kind, name, self.source, default)


def _df_record(get: _DfMessage, t: float, boot: int, out: _Pass) -> None:
    """Add one DataFlash message's row to ``out`` (rows per kind, fix rows, GPS accuracy rows, armed rows, UTC
    offsets; the home position: the first ORGN of type 1)."""
    rows, fix_rows, arm_rows, utc = out.rows, out.fix_rows, out.arm_rows, out.utc
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
    elif kind == "GPA" and get("I", 0.0) == 0 and "HAcc" in get.columns and "VAcc" in get.columns:
        # the GPS accuracy [m] (0: none reported); VDop, and the GPS record's HDop: dilutions, no metres
        h, v = get("HAcc"), get("VAcc")
        out.acc_rows.append((t, h if h > 0 else 0.0, v if v > 0 else 0.0, boot))
    elif kind == "RAD":
        rows[kind].append((t, *(get(f) for f in ("RSSI", "RemRSSI", "Noise", "RemNoise", "RxErrors", "Fixed")), boot))
    elif kind == "ORGN":
        rows[kind].append((t, boot))
        if get("Type") == 1 and out.home is None:
            out.home, out.home_at = (get("Lat"), get("Lng"), get("Alt")), (t, boot)
    elif kind == "ARM":
        arm_rows.append((t, float(get("ArmState") != 0), boot))
    elif kind == "EV" and get("Id") in (_EV_ARMED, _EV_DISARMED):
        arm_rows.append((t, float(get("Id") == _EV_ARMED), boot))


@dataclass
class _Pass:
    """What one pass over a DataFlash log read (:func:`_read_pass`)."""

    rows: dict[str, list[tuple[float, ...]]] = field(default_factory=lambda: {k: [] for k in DF_TYPES})
    fix_rows: list[tuple[float, ...]] = field(default_factory=list)
    arm_rows: list[tuple[float, ...]] = field(default_factory=list)
    utc: list[float] = field(default_factory=list)
    acc_rows: list[tuple[float, ...]] = field(default_factory=list)
    home: tuple[float, float, float] | None = None
    home_at: tuple[float, int] | None = None  # the home's time and boot
    boot: int = 0
    boot_t: list[tuple[float, int]] = field(default_factory=list)
    minor: set[int] = field(default_factory=set)  # the stretches after a step back of the time too small for a reboot
    #: records left out as copies (their numbers among the records of the types read): at the same TimeUS
    copies: set[int] = field(default_factory=set)
    #: records repeating one shortly before (0 < interval <= 1 ms): number, key (kind, instance, fields), interval [s],
    #: and how many intervals of its key were read before it (the next one read is the interval it falls in)
    maybe: list[tuple[int, tuple[Any, ...], float, int]] = field(default_factory=list)
    #: per key (kind, instance and fields), the intervals [s] between the records read with it (copies and maybes
    #: left out, the earlier among the last records read: :class:`~rplearn.io._mavlink_records.RecentRecords`), in the
    #: order read
    steps: dict[tuple[Any, ...], list[float]] = field(default_factory=dict)


def _read_pass(source: str, drop: frozenset[int] | None) -> _Pass:
    """One pass over a DataFlash log: every record but the copies. ``drop`` None: the copies found as read
    (:class:`~rplearn.io._mavlink_records.RecentRecords`: at the same TimeUS a copy; up to 1 ms later a maybe,
    left out and judged after the pass, :func:`_judge`); else the records numbered in ``drop`` left out."""
    out = _Pass()
    last_t, last_kind = -np.inf, ""
    times: dict[str, tuple[str, float]] = {}
    instance: dict[str, tuple[str, ...]] = {}
    recent, maybes = RecentRecords(), RecentRecords()  # the records read; the maybes (kept apart: steps)
    index = -1
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
            index += 1
            kind = msg.get_type()
            if kind not in times:
                times[kind] = dataflash_time_field(msg, kind, source)
                instance[kind] = tuple(n for n in _INSTANCE_FIELDS if n in (getattr(msg, "fmt", None) and msg.fmt.columns
                                                                            or msg.get_fieldnames()))
            t = number(msg, kind, times[kind][0], source) * times[kind][1]
            which = _instance(msg, instance[kind])
            if drop is not None:
                if index in drop:
                    continue
            else:
                key = (kind, which, *_fields(msg, times[kind][0]))
                gap = recent.copy_gap(key, t)
                if gap == 0.0 or maybes.copy_gap(key, t) == 0.0:
                    out.copies.add(index)  # the record (or a maybe) written twice: read once
                    continue
                if gap is not None:
                    out.maybe.append((index, key, gap, len(out.steps.get(key, ()))))
                    maybes.add(key, t)
                    continue
                step = recent.since(key, t)
                if step:
                    out.steps.setdefault(key, []).append(step)
                recent.add(key, t)
            if t < last_t or (t == last_t and kind == last_kind):  # the latter: maybe a copy of the last record
                out.boot += 1
                if t >= last_t - REBOOT_STEP_S:
                    out.minor.add(out.boot)
            last_t, last_kind = t, kind
            out.boot_t.append((t, out.boot))
            _df_record(_DfMessage(msg, kind, source), t, out.boot, out)
    return out


def _judge(first: _Pass) -> set[int]:
    """The records of ``first.maybe`` that are copies: those whose interval is below
    :data:`~rplearn.io.mavlink_phases.DUPLICATE_FRACTION_OF_PERIOD` of the local interval between the records with
    their own fields (kind, instance and fields: ``first.steps``, the maybes left out; any interval when they have
    none: a record whose fields no other record repeats, as a moving vehicle's, is judged by itself, not by the
    intervals of a rest before or after it). The local interval is the median of the :data:`CADENCE_SPAN` intervals
    of its key about it, half before, half after the interval it falls in, which counts twice (the span's majority
    is on its side of a change of rate): a message logged at 10 Hz then at 1 kHz (or the reverse) is judged at the
    rate it had where the record is. A kind logged every millisecond while the vehicle rests repeats its fields
    1 ms later at its own interval: every other record a maybe, the records read 2 ms apart, the maybes no copies;
    the last of them before the rate is lowered, whose interval reaches the slow records, too
    (:func:`_ends_a_fast_run`)."""
    by_key: dict[tuple[Any, ...], list[tuple[int, float, int]]] = {}
    for index, key, gap, i in first.maybe:
        by_key.setdefault(key, []).append((index, gap, i))
    copies: set[int] = set()
    for key, maybes in by_key.items():
        numbers, gaps, at = (np.asarray(v) for v in zip(*maybes, strict=True))
        if key not in first.steps:
            copies.update(numbers.tolist())
            continue
        local = _local_interval(np.asarray(first.steps[key], np.float64), at.astype(np.int64))
        copy = gaps < DUPLICATE_FRACTION_OF_PERIOD * local
        copies.update(numbers[copy & ~_ends_a_fast_run(gaps, at.astype(np.int64), copy)].tolist())
    return copies


def _ends_a_fast_run(gaps: np.ndarray, at: np.ndarray, copy: np.ndarray) -> np.ndarray:
    """Which maybes of one key (``gaps`` [s] after the record before them, falling in the intervals numbered ``at``,
    in the order read; ``copy``: judged copies by the local cadence) go on with the records of a fast logger at rest
    just before them: the latest maybe of the interval before theirs was no copy, and they come at least
    ``1 - DUPLICATE_FRACTION_OF_PERIOD`` of its gap after their record. Such a record is the last at the fast rate
    before a rate lowered (the interval it falls in reaching the first slow record, the local cadence is the slow
    one's); a copy of that record comes far sooner than the fast records did."""
    before = np.searchsorted(at, at - 1, side="right") - 1  # the latest maybe of the interval before (at: sorted)
    ok = before >= 0
    ok[ok] &= at[before[ok]] == at[ok] - 1
    ok[ok] &= ~copy[before[ok]] & (gaps[ok] >= (1.0 - DUPLICATE_FRACTION_OF_PERIOD) * gaps[before[ok]])
    return ok


def _local_interval(steps: np.ndarray, at: np.ndarray) -> np.ndarray:
    """For records falling in the intervals numbered ``at`` of ``steps`` (a key's intervals [s], in the order
    read; ``len(steps)``: after the last), the median of the :data:`CADENCE_SPAN` intervals about each, half before,
    half from the one it falls in, that one counted twice (the majority on its side of a change of rate)."""
    half = CADENCE_SPAN // 2
    padded = np.concatenate([np.full(half, np.nan), steps, np.full(half + 1, np.nan)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, CADENCE_SPAN + 1)[at]  # steps[at - half : at + half + 1]
    span = windows.copy()
    span[:, -1] = padded[at + half]  # the last replaced by the interval the record falls in (NaN after the last)
    return np.nanmedian(span, axis=1)


def collect_dataflash(source: str) -> Raw:
    """One pass over a DataFlash log: ATT, POS (else GPS), RAD, ORGN, GPS status and accuracy (GPA), ARM and EV
    (each message type's fields checked on its first record: :mod:`rplearn.io._log_schema`); a second
    when records repeating one 1 ms before them or less are no copies (:func:`_judge`)."""
    read = _read_pass(source, None)
    copies = read.copies | _judge(read)
    if len(copies) < len(read.copies) + len(read.maybe):  # some are no copies (a fast logger at rest): read again
        read = _read_pass(source, frozenset(copies))
    close = len(copies)  # the records written twice: read once
    rows, utc, home, boot, boot_t = read.rows, read.utc, read.home, read.boot, read.boot_t
    home_rows: list[tuple[float, ...]] = [read.home_at] if read.home_at is not None else []
    tables: dict[str, list[tuple[float, ...]]] = {**rows, "GPS status": read.fix_rows, "ARM/EV": read.arm_rows, "GPS accuracy": read.acc_rows,
              "home": home_rows}
    repeated = merge_copied_boots(tables, boot_t, frozenset(read.minor)) if boot else 0
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
    home_t = chained(rows_array(tables["home"], 2), 0, 1)[:, 0]
    # the vehicle logs itself throughout: its stream is never absent
    return Raw(
        fmt="dataflash", att=chained(rows_array(rows["ATT"], 5), 0, 4), pos=chained(rows_array(rows[pos_kind], 7), 0, 6),
        radio=chained(rows_array(rows["RAD"], 8), 0, 7)[:, :7], vehicle_t=np.array([]), home=home, counts=counts,
        boot_last_t=ends, origin_t=orgn[:, 0],
        fix=chained(rows_array(fix_rows, 3), 0, 2)[:, :2], armed=chained(rows_array(arm_rows, 3), 0, 2)[:, :2],
        accuracy=chained(rows_array(tables["GPS accuracy"], 4), 0, 3)[:, :3], home_t=float(home_t[0]) if len(home_t) else None,
        notes={"position_message": pos_kind, "repeated_messages": repeated, "close_copies": close,
               "time_reference": "TimeUS, seconds since the autopilot booted"
                                 + (" (later boots placed right after the previous one)" if len(ends) > 1 else ""),
               "utc_offset_s": float(np.median(utc)) if utc else None},
    )



__all__ = ["DF_TYPES", "collect_dataflash"]
