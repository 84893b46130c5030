"""A ``.tlog`` that is still being written, read where it grew (the MAVLink source of ``rplearn live``).

:class:`TlogTail` keeps one pymavlink connection on the file, with its file handle at the end of
the last whole record read: every poll parses only the records appended since (a record still
being written, its 8-byte time or its frame cut, waits for its end), each through the per-message
function of the offline reader (:class:`rplearn.io._mavlink_records.TlogRows`), and converts them
by the offline reader's own steps (``read_mavlink``'s conversion, :func:`rplearn.io.mavlink.logs_from_raw`),
so that a row is converted exactly as ``sync`` converts it.

Until the first rows are handed out, the conversion runs over every message so far; from then on
over a window only (:class:`rplearn.io.tlog_window.TlogWindow`): the messages since an *anchor*
fix :data:`rplearn.io.tlog_window.KEEP_S` before the rows handed out, with a bounded summary of
the past standing in for the reader's whole-log rules (the pieces of valid fixes of the boot, each
boot's times, the last GPS fix type and armed state, the copy rule of radio reports on running
binned counts: :mod:`rplearn.io.tlog_copies`). A poll's cost and the state kept do not grow with
the flight, nor with a gap of position fixes (the anchor moves into it).

What can still change once handed out is fixed before any row is handed out:

- the time base: the vehicle's rows are placed on the receive clock by each boot's median
  receive-minus-boot offset; a boot's offset is fixed once :data:`TIME_BASE_MESSAGES` of its
  messages have arrived, and no row of a boot whose offset is not fixed is handed out;
- the station (and so the ENU origin): the vehicle's ``HOME_POSITION``, or the reader's
  ``station_geodetic``; without either for :data:`HOME_WAIT_S` of flight, the first valid fix
  (what ``sync`` takes for a log without ``HOME_POSITION``), until a ``HOME_POSITION`` arrives
  or a step shows that fix invalid: ``sync`` places the whole log about the home or its first
  valid fix, so the tail moves its station there and counts every row handed out before as
  withdrawn;
- the vehicle (the sender of most ATTITUDE) and whether its boot clock is used;
- after a reboot, in a log with origin messages (``HOME_POSITION``, ``GPS_GLOBAL_ORIGIN``), the
  boot's rows wait for its first origin message (for up to :data:`HOME_WAIT_S`): the stretch
  before it may be found invalid only by the first valid fix after it; likewise the radio
  readings after the vehicle's last message wait for its next one (a reboot excludes them);
- the rows near the end of what was read (a position fix after an attitude instant, the vehicle
  stream around a zero RSSI, a copy of a radio report): rows are handed out only up to
  ``settle_s`` before the newest message.

A row handed out is never handed out again, and a difference from the offline reader's rows is
counted in :attr:`TlogTail.dropped`, never silent: a row that appears (or disappears) behind what
was handed out, a later message changing the reader's verdict on it (a period before a valid
position found later: ``late_pose_rows``, ``late_signal_rows``, ``withdrawn_pose_rows``,
``withdrawn_signal_rows``; behind the anchor counted per piece of fixes, by the rows handed out in
it or the messages it holds; a change of vehicle, or of the use of its boot clock, withdraws
every row handed out, before and after); a radio report whose copy verdict depends on the report
period beyond the precision of the running counts, dropped (``uncertain_copy_reports``); a report
handed out whose verdict a later period reverses (``changed_copy_reports``). A stretch of the log
written into the file again (a log in the file twice, its last records again) is read once, its messages counted in
``repeated_messages`` as the offline reader counts them (:class:`FileCopy`); an attitude or position
message received twice within a millisecond (a router, or two links forwarding each) is read once,
counted in ``close_copies``, as offline (:class:`~rplearn.io._mavlink_records.TlogRows`). The row counts are
net: rows given back after being withdrawn lower the withdrawn count, so a verdict that flips and
flips back (a short position glitch under way at a poll) leaves them where they were.

Not counted: the vehicle's times differ from ``sync``'s by one constant per boot (its time base,
from its first messages: 2e-4 s on the project's writer's logs, 0.09 s on the real fixture log);
rows handed out before the first ``HEARTBEAT`` lack the ``armed`` column, and fixes before the first
``GPS_RAW_INT`` behind the anchor are not judged again by its fix type.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.errors import InputError, LogFormatError
from rplearn.io._log_schema import library_quiet
from rplearn.io._mavlink_records import RecentRecords, TlogRows, open_mavlink_log, tlog_raw
from rplearn.io.mavlink import MavlinkOptions, logs_from_raw, position_fixes
from rplearn.io.options import ReaderOptions
from rplearn.io.tlog_window import KEEP_S, TlogWindow

#: A boot's receive-minus-boot offset is fixed once this many of its messages have arrived.
TIME_BASE_MESSAGES = 100
#: Without HOME_POSITION for this long of flight [s], the station is the first valid fix.
HOME_WAIT_S = 30.0
#: Rows are handed out up to this long before the newest message [s], beyond the reader's
#: longest bridged gap and stream timeout.
SETTLE_MARGIN_S = 1.0
#: What :attr:`TlogTail.dropped` counts (module docstring).
DROPS = ("late_pose_rows", "late_signal_rows", "withdrawn_pose_rows", "withdrawn_signal_rows",
         "uncertain_copy_reports", "changed_copy_reports", "close_copies", "repeated_messages")


class FileCopy:
    """Whether the records read repeat the file's own bytes before them: a stretch of the log
    written into the file again (a log in the file twice, a copy resumed from its start, the
    last records written again), which the offline reader reads once (its exact repeated
    messages dropped, ``repeated_messages``).

    A record whose 8-byte receive time steps back from the record before it (or equals it) may
    start a copy: the bytes before it are searched for an equal record, byte for byte (its
    receive time included; a search only at such steps, which a log written once does not
    take, the equal time checked against the record before only). Found at ``q``, the copy
    starts at offset ``L = p - q``; each record after it at ``p`` repeats the file while its
    bytes equal those at ``p - L``. The state is ``L``, the last time and the last record: it
    does not grow with the log.

    Parameters
    ----------
    path : str
        The log, read with its own handle (``os.pread``).
    """

    #: Bytes read at once when searching the file for a record.
    SEARCH_BLOCK = 1 << 22

    def __init__(self, path: str) -> None:
        self.path = path
        self._fd: int | None = None
        self._last_us = -1  # the receive time of the last record [us]
        self._last: tuple[int, int] | None = None  # its bytes' offsets
        self.offset: int | None = None  # where the copy being read started

    def _read(self, start: int, end: int) -> bytes:
        if self._fd is None:
            self._fd = os.open(self.path, os.O_RDONLY | getattr(os, "O_BINARY", 0))
        return os.pread(self._fd, end - start, start)

    def _find(self, record: bytes, before: int) -> int | None:
        """The first offset of ``record`` wholly before byte ``before``, or None."""
        at = 0
        while at < before:
            block = self._read(at, min(before, at + self.SEARCH_BLOCK + len(record) - 1))
            found = block.find(record)
            if found >= 0 and at + found + len(record) <= before:
                return at + found
            at += self.SEARCH_BLOCK
        return None

    def repeats(self, start: int, end: int) -> bool:
        """Whether the record in bytes ``[start, end)`` repeats the file's bytes before it."""
        record = self._read(start, end)
        t_us = int.from_bytes(record[:8], "big")
        last, last_us = self._last, self._last_us
        self._last, self._last_us = (start, end), t_us
        if self.offset is not None:
            if start - self.offset >= 0 and record == self._read(start - self.offset, end - self.offset):
                return True
            self.offset = None  # the copy ended: what follows is new, unless it starts another
        if t_us > last_us or last is None:
            return False
        if t_us == last_us:  # the record before written again, or two messages received at once
            found = last[0] if last[1] - last[0] == len(record) and self._read(*last) == record else None
        else:
            found = self._find(record, start)
        if found is None:
            return False
        self.offset = start - found
        return True

    def close(self) -> None:
        """Close the handle."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


def whole_records(data: bytes) -> int:
    """The length of the whole ``.tlog`` records (8-byte time, MAVLink 1 or 2 frame) at the
    start of ``data``; bytes that are no frame are left to pymavlink's parser (BAD_DATA)."""
    i, n = 0, len(data)
    while i + 10 <= n:
        magic = data[i + 8]
        if magic == 0xFD:
            if i + 11 > n:
                break
            size = 8 + 10 + data[i + 9] + 2 + (13 if data[i + 10] & 1 else 0)
        elif magic == 0xFE:
            size = 8 + 6 + data[i + 9] + 2
        else:
            return n
        if i + size > n:
            break
        i += size
    return i


@check_types
class TlogTail:
    """A growing ``.tlog`` read incrementally into canonical pose and signal rows (module docstring).

    Parameters
    ----------
    path : str
        The telemetry log (it may not exist yet).
    reader : ReaderOptions
        As ``sync`` reads a ``.tlog`` (transmit power and frequency at least).
    """

    def __init__(self, path: str, reader: ReaderOptions) -> None:
        missing = [f for f in ("tx_power_dbm", "frequency_hz") if getattr(reader, f) is None]
        if missing:
            raise InputError(f"{path}: give the telemetry radios' transmit power [dBm] and carrier frequency [Hz], "
                             f"a MAVLink log carries neither (ReaderOptions.{missing[0]})", param=missing[0])
        self.path, self.reader = path, reader
        self._recent: dict[str, RecentRecords] = {}  # the last attitude and position messages (close copies)
        self.rows: TlogRows | None = TlogRows(close_as_added=True, recent=self._recent)  # every message, until the first rows are handed out
        self.window: TlogWindow | None = None  # then the window (rplearn.io.tlog_window)
        self.parsed = 0  # messages parsed by the last poll
        self.dropped: dict[str, int] = {k: 0 for k in DROPS}
        self._conn: Any = None
        self._copy = FileCopy(path)
        self._end = 0
        self._time_base: dict[int, float] = {}
        self._station: tuple[float, float, float] | None = reader.station_geodetic
        self._last = {"pose": -math.inf, "signal": -math.inf}
        self._seen = {"pose": np.zeros(0), "signal": np.zeros(0)}  # times of the last conversion's rows after the anchor
        self._handed = {"pose": np.zeros(0), "signal": np.zeros(0)}  # times handed out after the anchor
        self._total = {"pose": 0, "signal": 0}
        self._vanished = {"pose": 0, "signal": 0}  # rows after the anchor counted withdrawn, not yet back
        self._covered = -math.inf  # every row up to here was handed out
        self._vehicle_changed = False
        self._station_from_fix = False  # the station taken from the first valid fix (no HOME_POSITION yet)
        self._station_fix_t = math.inf  # that fix's time [s]
        self._reframed = {"pose": -math.inf, "signal": -math.inf}  # rows up to here handed in another frame

    def _parse(self) -> int:
        if self._conn is None:
            if not os.path.exists(self.path) or os.path.getsize(self.path) == 0:
                return 0
            with library_quiet():
                self._conn = open_mavlink_log(self.path)
        rows = self.rows if self.rows is not None else TlogRows(close_as_added=True, recent=self._recent)
        copies = rows.close_copies
        f = self._conn.f
        f.seek(self._end)
        whole = self._end + whole_records(f.read())
        f.seek(self._end)
        n = 0
        with library_quiet():
            while f.tell() < whole:
                start = f.tell() - self._conn.mav.buf_len()
                try:
                    msg = self._conn.recv_msg()
                except Exception as exc:
                    raise LogFormatError(f"{self.path}: corrupt MAVLink data ({type(exc).__name__}: {exc})") from None
                if msg is None:
                    break
                n += 1
                if msg.get_type() != "BAD_DATA" and self._copy.repeats(start, f.tell() - self._conn.mav.buf_len()):
                    # the log in the file again: read once, as the offline reader does
                    self.dropped["repeated_messages"] += int(msg.get_type() in rows.rows)
                    continue
                rows.add(msg, self.path)
        self.dropped["close_copies"] += rows.close_copies - copies  # one message received twice, read once
        self._end = f.tell() - self._conn.mav.buf_len()
        if self.window is not None:
            self.window.add(rows)
        return n

    def poll(self, final: bool = False) -> tuple[pd.DataFrame, pd.DataFrame]:
        """The pose and signal rows that can be handed out (all of them with ``final``); a
        refusal names the log (as the offline reader's does)."""
        try:
            return self._poll(final)
        except InputError as exc:
            if str(exc).startswith(f"{self.path}: "):
                raise
            raise type(exc)(f"{self.path}: {exc}", param=exc.param, related=exc.related) from None

    def _poll(self, final: bool) -> tuple[pd.DataFrame, pd.DataFrame]:
        """:meth:`poll`."""
        self.parsed = self._parse()
        empty = pd.DataFrame()
        if not self.parsed and not final:
            return empty, empty
        try:
            raw = self.window.raw() if self.window is not None else tlog_raw(
                self.rows, self.path, None, {}, self._time_base)  # type: ignore[arg-type]
        except LogFormatError:  # too little received to read (no ATTITUDE yet)
            return empty, empty
        for b, (offset, n) in raw.boot_offsets.items():
            if b not in self._time_base and n >= TIME_BASE_MESSAGES:
                self._time_base[b] = offset
        newest = float(max(raw.vehicle_t[-1] if len(raw.vehicle_t) else -math.inf,
                           raw.radio[-1, 0] if len(raw.radio) else -math.inf))
        if self._station is None and raw.home is not None:
            self._station = raw.home
        elif self._station_from_fix:
            self._recheck_station(raw)
        flown = float(raw.att[-1, 0] - raw.att[0, 0]) if len(raw.att) else 0.0
        options = MavlinkOptions(station_geodetic=self._station, origin_geodetic=self.reader.origin_geodetic,
                                 station_heading_deg=self.reader.station_heading_deg)
        try:
            logs, meta = logs_from_raw(raw, self.path, (self.reader.tx_power_dbm, self.reader.frequency_hz),  # type: ignore[arg-type]
                                   (self.reader.nodes or {}).get(self.path), self.reader.station, options)
        except LogFormatError:  # fewer than 2 valid fixes, no radio report yet
            return empty, empty
        if self._station is None and (final or flown >= HOME_WAIT_S):
            self._station = tuple(meta["station_geodetic"])  # the first valid fix, as sync takes it
            tp, _, valid, _ = position_fixes(raw, self.path)
            self._station_fix_t, self._station_from_fix = float(tp[valid][0]), True  # until sync's moves (_recheck_station)
        if final:
            hand_to = math.inf
        elif self._station is None:
            return empty, empty
        else:
            hand_to = newest - max(options.max_gap_s, options.stream_timeout_s) - SETTLE_MARGIN_S
            ready = self.window.boots_ready(raw, newest, HOME_WAIT_S) if self.window else self._boots_ready(raw, newest)
            hand_to = min(hand_to, ready)
        assert logs.pose is not None and logs.signal is not None
        station_rows = logs.pose[logs.pose["node"] == meta["station"]]
        vehicle_rows = logs.pose[logs.pose["node"] != meta["station"]]
        poses = self._hand("pose", vehicle_rows, hand_to)
        if len(poses) and self._total["pose"] == len(poses):  # the first rows: the station with them
            poses = pd.concat([station_rows, poses], ignore_index=True)
        signals = self._hand("signal", logs.signal, hand_to)
        if len(poses) or len(signals):
            self._covered = max(self._covered, hand_to)
        if self.window is None and self.rows is not None and (len(poses) or len(signals)):
            self._lock(raw)
        elif self.window is not None:
            self._move_anchor(raw, final, options.stream_timeout_s, options.max_gap_s)
        return poses, signals

    def _recheck_station(self, raw: Any) -> None:
        """The station taken from the first valid fix, against what ``sync`` would take now: a
        ``HOME_POSITION`` arrived, or that fix found invalid (a step after it) and so the first
        valid fix another; then the station moves there (:meth:`_move_station`)."""
        if raw.home is not None:
            self._station_from_fix = False
            self._move_station(tuple(raw.home))
            return
        try:
            tp, pos, valid, _ = position_fixes(raw, self.path)
        except LogFormatError:
            return
        at = np.flatnonzero(tp == self._station_fix_t)
        if len(at) and not valid[at[0]] and valid.any():  # (a fix forgotten behind the window is not revisited)
            first = int(np.flatnonzero(valid)[0])
            self._station_fix_t = float(tp[first])
            lat, lon, alt = (float(v) for v in pos[first, 1:4])
            self._move_station((lat, lon, alt))

    def _move_station(self, station: tuple[float, float, float]) -> None:
        """``sync`` places the whole log about another station than the tail took: from now on
        the tail does too, and every row handed out so far (in the other frame) is counted
        withdrawn, once: the counts of their pieces and of the rows behind the last handed out
        are no longer revisited."""
        if tuple(map(float, station)) == tuple(map(float, self._station or ())):
            return
        self._station = station
        for what in ("pose", "signal"):
            # rows of the old frame counted withdrawn already (a piece found invalid) are not counted twice
            out = max(self._total[what] - self.dropped[f"withdrawn_{what}_rows"], 0)
            self.dropped[f"withdrawn_{what}_rows"] += out
            self._reframed[what] = self._last[what]
            self._handed[what] = np.zeros(0)
        if self.window is not None:
            for piece in self.window.pieces:
                piece.handed = {"pose": 0, "signal": 0}

    def _lock(self, raw: Any) -> None:
        """Fix the vehicle and the use of its boot clock, and from now on read a window."""
        assert self.rows is not None
        att = self.rows.array("ATTITUDE", 6)
        chosen = int(raw.notes["system_id"]) * 256 + int(raw.notes["component_id"])
        mine = att[att[:, 0] == chosen]
        boot_clock = len(np.unique(mine[:, 2])) >= 0.9 * len(mine)
        window = TlogWindow(chosen, boot_clock, raw, self._time_base)
        window.add(self.rows)
        window.fix_step_origin()
        self.rows, self.window = None, window

    def _move_anchor(self, raw: Any, final: bool, stream_timeout_s: float, max_gap_s: float) -> None:
        """Count what changed behind the anchor, the vehicle changing, then move the anchor on."""
        assert self.window is not None
        w = self.window
        srcs = np.array(sorted(w.senders))
        counts = np.array([w.senders[s] for s in srcs.tolist()])
        if not self._vehicle_changed and (int(srcs[np.argmax(counts)]) != w.chosen or w.clock_lost()):
            # sync would read another vehicle, or place it by its receive times: every row handed out withdrawn
            self._vehicle_changed = True
            for what in ("pose", "signal"):
                self.dropped[f"withdrawn_{what}_rows"] += self._total[what]
        fixes = position_fixes(raw, self.path)
        for k, n in w.revisit(fixes[2][:len(w.prefix)]).items():
            self.dropped[k] += n
        to = math.inf if final else self._covered - KEEP_S
        anchor = w.anchor
        self.dropped["uncertain_copy_reports"] += w.trim(raw, to, stream_timeout_s, (fixes[0], fixes[2]), self._handed,
                                                             max_gap_s)
        self.dropped["changed_copy_reports"] += w.copies.reversed_behind(w.copies.rule())
        for what in ("pose", "signal"):
            self._handed[what] = self._handed[what][self._handed[what] >= w.anchor]
            self._seen[what] = self._seen[what][self._seen[what] >= w.anchor]
            if w.anchor > anchor:  # those that vanished behind it are their pieces' (TlogWindow.revisit)
                missing = len(self._handed[what]) - int(np.count_nonzero(self._seen[what] <= self._last[what]))
                self._vanished[what] = min(self._vanished[what], max(missing, 0))
        if final:  # reports never judged
            self.dropped["uncertain_copy_reports"] += int(np.count_nonzero(w.radio[:, 8]))

    def _boots_ready(self, raw: Any, newest: float) -> float:
        """The first time of the first boot whose rows must wait: its time base not fixed, or,
        in a log with origin messages, no origin message of that boot yet (the position may be
        invalid until then: the reader finds where only from the first valid fix) for up to
        :data:`HOME_WAIT_S`."""
        for b in sorted(raw.boot_offsets):
            times = raw.att[raw.att[:, 4] == b, 0]
            if not len(times):
                continue
            first = float(times.min())
            no_origin = len(raw.origin_t) and not np.any(raw.origin_t >= first) and newest - first < HOME_WAIT_S
            if b not in self._time_base or no_origin:  # from the previous boot's last message on
                before = raw.att[raw.att[:, 4] < b, 0]
                return float(before.max()) if len(before) else first
        # readings while the vehicle is silent wait for it: a reboot would exclude them
        return float(raw.vehicle_t[-1]) if len(raw.vehicle_t) else math.inf

    def _hand(self, what: str, rows: pd.DataFrame, hand_to: float) -> pd.DataFrame:
        """The rows in (last handed out, ``hand_to``]; rows appearing or vanishing from the
        anchor up to the last handed out (against the last conversion) counted (those before the
        anchor by their piece: :meth:`TlogWindow.revisit`)."""
        t = rows["t"].to_numpy(np.float64)
        last = self._last[what]
        anchor = self.window.anchor if self.window is not None else -math.inf
        prev = self._seen[what]
        lo = self._reframed[what]  # rows up to here were counted withdrawn when the station moved
        delta = (int(np.count_nonzero((t >= anchor) & (t > lo) & (t <= last)))
                 - int(np.count_nonzero((prev >= anchor) & (prev > lo) & (prev <= last))))
        back = min(max(delta, 0), self._vanished[what])  # rows that vanished and came back: no longer withdrawn
        self._vanished[what] += max(-delta, 0) - back
        self.dropped[f"withdrawn_{what}_rows"] += max(-delta, 0) - back
        self.dropped[f"late_{what}_rows"] += max(delta, 0) - back
        self._seen[what] = t[t >= anchor]
        out = rows[(t > last) & (t <= hand_to)].reset_index(drop=True)
        if len(out) and self._vehicle_changed:  # not what sync reads either
            self.dropped[f"withdrawn_{what}_rows"] += len(out)
        if len(out):
            self._last[what] = float(out["t"].max())
            self._total[what] += len(out)
            self._handed[what] = np.concatenate([self._handed[what], out["t"].to_numpy(np.float64)])
        return out

    def sizes(self) -> dict[str, int]:
        """The length of every structure the tail keeps between polls (bounded: it does not
        grow with the log once rows are handed out)."""
        out = {f"{k}.{w}": len(v[w]) for k, v in (("seen", self._seen), ("handed", self._handed)) for w in v}
        out["time_base"] = len(self._time_base)
        if self.rows is not None:
            out["rows"] = sum(len(v) for v in self.rows.rows.values())
        if self.window is not None:
            out.update({f"window.{k}": n for k, n in self.window.sizes().items()})
        return out

    def close(self) -> None:
        """Close the file."""
        if self._conn is not None:
            self._conn.close()
            self._conn = None
        self._copy.close()


__all__ = ["DROPS", "HOME_WAIT_S", "FileCopy", "SETTLE_MARGIN_S", "TIME_BASE_MESSAGES", "TlogTail", "whole_records"]
