"""Logs that are still being written, read as they grow (``rplearn live``), and a replay.

Two sources give canonical pose and signal rows a poll at a time:

- :class:`CsvTail`: a canonical pose CSV and signal CSV that a robot appends to; every poll
  parses the complete lines added since the last (a half-written last line waits), with the
  reader of ``sync`` (:func:`rplearn.io.tables.canonical_pose`, ``canonical_signal``; a node's
  start at the zero position held back, bounded, until it is known whether ``sync`` keeps it);
- :class:`MavlinkSource`: a MAVLink connection as pymavlink names them
  (``udpin:0.0.0.0:14550``, ``tcp:host:5760``, a serial device ``/dev/ttyUSB0``, what
  MAVProxy, QGroundControl and mavlink-router forward). Every message is appended to a
  telemetry log (``.tlog``: the receive time then the frame, as a ground station writes it), and
  every ``read_every_s`` the records appended to that log are read by :class:`rplearn.io.tlog_tail.TlogTail`
  (only the new messages parsed, with the per-message functions and conversion of ``sync``'s
  reader; the time base and station fixed before any row is handed out; a row the reader changes
  its verdict on after it was handed out counted in ``Poll.dropped``).

:func:`replay_tlog` sends a ``.tlog``'s messages over UDP at a multiple of their pace, their
boot times and speeds scaled alike, so that the stream is a consistent (faster) flight.
"""

from __future__ import annotations

import hashlib
import io
import math
import os
import socket
import struct
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.data.live_sync import HOLD_ROWS, HOLD_S
from rplearn.data.tables import CSV_DTYPES, normalise_times
from rplearn.errors import BadValueError, InputError, LogFormatError
from rplearn.io._columns import EULER_ENU_FLU_COLUMNS, EULER_NED_FRD_COLUMNS, csv_missing_values
from rplearn.io._csv_headers import REPEATED_HEADER, HeaderDrops, HeaderRule, file_line, in_file_lines, without_repeated_headers
from rplearn.io._pose_checks import TrackEnds, top_speeds, track_pieces
from rplearn.io._time_order import LinkTimes, check_link_time_order
from rplearn.io.geodetic import geodetic_to_enu
from rplearn.io.mavlink_phases import MAX_HORIZONTAL_SPEED_M_S, MAX_VERTICAL_SPEED_M_S, unexplained_steps
from rplearn.io.options import ReaderOptions
from rplearn.io.tables import canonical_pose, canonical_signal


@check_types
@dataclass
class Poll:
    """What one poll of a source gave.

    Attributes
    ----------
    poses, signals : DataFrame
        New canonical pose and signal rows (empty when none).
    received : int
        Lines or messages received by this poll.
    dropped : dict of str to int
        Rows not handed out, per reason, so far (a MAVLink source: :class:`rplearn.io.tlog_tail.TlogTail`).
    held_nodes : frozenset of str
        Nodes whose first pose rows the source holds back after this poll (:class:`CsvTail`).
    where : dict of str to str
        Where the rows of a reason were so far, as said (``repeated_header``: ``pose.csv lines 604, 1210``, the first).
    """

    poses: pd.DataFrame
    signals: pd.DataFrame
    received: int
    dropped: dict[str, int] = field(default_factory=dict)
    held_nodes: frozenset[str] = frozenset()
    where: dict[str, str] = field(default_factory=dict)


#: Bytes from a tailed file's start that :class:`_Tail` keeps and compares at every poll: a file replaced
#: under its name (logrotate, a logger restarting with a new file) begins otherwise, even on the same inode.
FIRST_BYTES = 4096


class _Tail:
    """The complete lines appended to one text file since the last call; a file that shrank, was replaced
    (another file under its name whose bytes differ from those read: its first :data:`FIRST_BYTES` compared at
    every poll, all of them when its device and inode changed) or went away once read is refused naming it (its
    rows, their numbers and times are those read before: no new start)."""

    def __init__(self, path: str) -> None:
        self.path, self.offset, self.header = path, 0, b""
        self.line = 0  # lines read (the header the first)
        self.repeated = HeaderDrops()  # the header line again later in the file (a logger restarted appending): dropped
        self.read_from = 1  # the file line of the first line the last call returned
        self.read_dropped: tuple[int, ...] = ()  # the file lines of the header lines dropped from it
        self.rule: HeaderRule | None = None  # how its header lines are told from rows, once the header is read
        self.identity: tuple[int, int] | None = None  # (device, inode) of the file read
        self.first = b""  # its first bytes read (at most FIRST_BYTES)
        self.digest = hashlib.sha256()  # of every byte read

    def _same_start(self, fh: Any) -> bool:
        """Whether the file open as ``fh`` begins with the bytes read so far (a log rewritten whole under its name,
        as a writer replacing it atomically does, is the same log grown)."""
        fh.seek(0)
        again, left = hashlib.sha256(), self.offset
        while left > 0 and (chunk := fh.read(min(left, 1 << 20))):
            again.update(chunk)
            left -= len(chunk)
        return left == 0 and again.digest() == self.digest.digest()

    def _refuse(self, what: str, why: str) -> LogFormatError:
        return LogFormatError(f"{self.path}: {what} while it was read ({why}): give the new file as a session of its own")

    def lines(self) -> bytes:
        if not os.path.exists(self.path):
            if self.identity is not None:
                raise self._refuse("the file went away", f"moved or deleted after {self.offset:,} bytes were read: rotated?")
            return b""
        with open(self.path, "rb") as fh:
            st = os.fstat(fh.fileno())
            size = st.st_size
            if size < self.offset:
                raise self._refuse(f"the file shrank from {self.offset:,} to {size:,} bytes",
                                   "truncated, or rewritten shorter")
            moved = self.identity is not None and (st.st_dev, st.st_ino) != self.identity
            if moved and not self._same_start(fh):
                raise self._refuse("the file was replaced by another under its name", "another device and inode whose "
                                   "bytes differ from those read: rotated, or a logger that restarted with a new file")
            if not moved and self.first and fh.read(len(self.first)) != self.first:
                raise self._refuse("the file's first bytes changed", "rewritten in place: rotated by copy and "
                                   "truncate, or a logger that restarted")
            self.identity = (st.st_dev, st.st_ino)
            fh.seek(self.offset)
            data = fh.read()
        end = data.rfind(b"\n") + 1  # a line still being written waits for its newline
        if end == 0:
            return b""
        if len(self.first) < FIRST_BYTES:
            self.first = (self.first + data[:end])[:FIRST_BYTES] if self.offset == len(self.first) else self.first
        self.offset += end
        data = data[:end]
        self.digest.update(data)
        first_line, self.line = self.line + 1, self.line + data.count(b"\n")
        if not self.header:
            self.header, _, data = data.partition(b"\n")
            self.header += b"\n"
            first_line += 1
        return self._without_headers(data, first_line)

    def _without_headers(self, data: bytes, first_line: int) -> bytes:
        """``data`` (lines from line ``first_line`` on) without the header lines repeated in it, counted; another
        header is refused, naming the line (:mod:`rplearn.io._csv_headers`)."""
        self.rule = self.rule or HeaderRule.of(self.header)
        data, repeated = without_repeated_headers(data, self.rule, first_line, self.path, _SESSION_ADVICE)
        self.repeated.add(repeated)
        self.read_from, self.read_dropped = first_line, repeated
        return data

    def file_line(self, line: int) -> int:
        """The file line of line ``line`` (from 1) of the header and the lines the last call returned, as the parser
        read them."""
        return 1 if line <= 1 else file_line(line - 1, self.read_dropped, self.read_from)


#: What to do with a CSV being appended to that holds another header (:func:`rplearn.io._csv_headers.HeaderRule.refusal`).
_SESSION_ADVICE = "give each part as a session of its own"


def _table(tail: _Tail, data: bytes) -> pd.DataFrame | None:
    if not data.strip():
        return None
    try:
        header = pd.read_csv(io.BytesIO(tail.header), nrows=0, skipinitialspace=True).columns
        df = pd.read_csv(io.BytesIO(tail.header + data), skipinitialspace=True, dtype=CSV_DTYPES,
                         **csv_missing_values(header))  # RSSI text: unparsable_rssi, as sync counts it
    except Exception as exc:  # parsers raise many classes on corrupt bytes; their lines said as the file's
        text = (str(exc).strip().splitlines() or [""])[0]  # one line (pandas ends its complaint with a newline)
        text = in_file_lines(text, tail.file_line) if isinstance(exc, pd.errors.ParserError) else text
        raise LogFormatError(f"{tail.path}: cannot parse the rows appended ({type(exc).__name__}: {text})") from None
    return normalise_times(df, tail.path)


#: How long and how many rows :class:`CsvTail` holds back a node's leading rows at the zero position (a logger
#: writing before the fix) while which side of its first jump is valid cannot be told yet: seconds of the pose
#: table's time from the node's first row, and rows held in all (:data:`rplearn.data.live_sync.HOLD_S`,
#: ``HOLD_ROWS``; the matcher keeps the signal rows of its links waiting for its poses as long, at most
#: :data:`rplearn.data.live_sync.WAIT_ROWS` of them).
#: Seconds of the table's time a node's rows must stand as one pose at the ENU origin before it is taken
#: for a station there (a logger before its fix that logs its attitude has changed it by then; a poll of a
#: row or two is no evidence either way).
STATION_SPAN_S = 1.0
#: The attitude columns a pose table may give (a quaternion, or Euler angles in either frame): with the
#: position, what one pose is (a sequence number or another column that varies does not move a node).
_ATTITUDE = ("qw", "qx", "qy", "qz", *EULER_ENU_FLU_COLUMNS, *EULER_NED_FRD_COLUMNS)
#: The column of a pose row's row in the file, while it is held.
_FILE_ROW = "__file_row__"


def _track(rows: pd.DataFrame, columns: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A node's rows with a time and a position, in time order: times [s], positions (``columns``), and which
    stand at the zero position (x = y = z = 0, or lat = lon = 0)."""
    t = pd.to_numeric(rows["t"], errors="coerce").to_numpy(np.float64, na_value=np.nan)
    pos = np.column_stack([pd.to_numeric(rows[c], errors="coerce").to_numpy(np.float64, na_value=np.nan)
                           for c in columns])
    ok = np.isfinite(t) & np.all(np.isfinite(pos), axis=1)
    order = np.argsort(t[ok], kind="stable")
    t, pos = t[ok][order], pos[ok][order]
    zero = np.all(pos[:, :2] == 0.0, axis=1) & ((pos[:, 2] == 0.0) if columns[0] == "x" else True)
    return t, pos, zero


def _start_known(t: np.ndarray, pos: np.ndarray, zero: np.ndarray, enu: bool) -> bool:
    """Whether a node's rows read so far (:func:`_track`) tell which of them are valid as ``sync`` tells them from
    the whole file (:func:`rplearn.io._pose_checks.position_jumps`: the largest piece of track between two steps
    the node's top speeds do not explain is valid, ties to the earlier). Unknown while they begin at the zero
    position (a logger writing before the fix, or a node standing at the origin) and that piece, still at zero,
    is the largest."""
    if not len(t) or not zero[0]:
        return True
    if zero.all():
        return False
    if not enu:  # geodetic: the steps in metres around the first fix off zero
        try:
            pos = geodetic_to_enu(pos[:, 0], pos[:, 1], pos[:, 2], tuple(pos[int(np.argmin(zero))]))
        except InputError:  # an implausible position: the reader refuses it, naming it
            return True
    starts, ends = track_pieces(t, pos, *top_speeds(t, pos, np.zeros(len(t), np.int64)))
    sizes = ends - starts
    # the first piece left zero by steps the speeds explain (odometry from the origin), or another piece larger
    return not zero[:sizes[0]].all() or int(np.argmax(sizes)) != 0


@dataclass
class _StartHold:
    """The rows of a pose table being appended to that :class:`CsvTail` holds back at its nodes' starts
    (:func:`_start_known`), with their rows in the file; ``at_zero``: the nodes handed out at the zero position
    when the hold ran out (:data:`HOLD_S`, :data:`HOLD_ROWS`), with their last time there; ``stations``: those
    of them handed out at once, standing still at the ENU origin (one pose: a station at the natural origin of
    a frame measured from it, whose links' rows would otherwise wait in the matcher while it is held,
    :class:`~rplearn.data.live_sync.LiveMatcher`; a logger before its fix writes its attitude, or a lat = lon = 0
    that no station has)."""

    source: str
    held: pd.DataFrame | None = None
    known: set[str] = field(default_factory=set)
    at_zero: dict[str, float] = field(default_factory=dict)
    stations: set[str] = field(default_factory=set)
    rows_seen: int = 0

    def take(self, table: pd.DataFrame | None, final: bool) -> pd.DataFrame | None:
        """The rows to read now (held ones first, in file order; a column :data:`_FILE_ROW`); the others held."""
        if table is not None:
            table = table.assign(**{_FILE_ROW: self.rows_seen + np.arange(len(table))})
            self.rows_seen += len(table)
        parts = [p for p in (self.held, table) if p is not None and len(p)]
        self.held = None
        if not parts:
            return None
        block = pd.concat(parts, ignore_index=True) if len(parts) > 1 else parts[0]
        columns = next((c for c in (("x", "y", "z"), ("lat", "lon", "alt")) if set(c) <= set(block.columns)), None)
        if columns is None or "node" not in block.columns or "t" not in block.columns:
            return block  # the reader names what is missing
        nodes = block["node"].astype(str).to_numpy()
        newest = float(pd.to_numeric(block["t"], errors="coerce").max())
        hold = np.zeros(len(block), bool)
        for node in dict.fromkeys(nodes):
            if node in self.known and node not in self.at_zero:
                continue
            at = nodes == node
            t, pos, zero = _track(block.loc[at], columns)
            if node in self.at_zero:
                self._left_zero(node, t, pos, zero, columns[0] == "x")
            elif final or _start_known(t, pos, zero, columns[0] == "x"):
                self.known.add(node)
            elif (columns[0] == "x" and zero.all() and t[-1] - t[0] >= STATION_SPAN_S
                  and len(block.loc[at, [c for c in (*columns, *_ATTITUDE) if c in block.columns]].drop_duplicates()) == 1):
                self.known.add(node)  # one pose at the ENU origin: a station there, watched for a jump
                self.stations.add(node)
                self.at_zero[node] = float(t[-1])
            elif newest - t[0] >= HOLD_S:  # bounded: handed out as it stands, watched
                self.known.add(node)
                self.at_zero[node] = float(t[zero][-1])
            else:
                hold |= at
        if hold.sum() > HOLD_ROWS:  # bounded: handed out as they stand, watched from their last row at zero
            for node in dict.fromkeys(nodes[hold]):
                self.known.add(node)
                t, _, zero = _track(block.loc[nodes == node], columns)
                self.at_zero[node] = float(t[zero][-1] if zero.any() else t[-1])
            hold[:] = False
        if hold.any():
            self.held = block.loc[hold]
        return block.loc[~hold] if not hold.all() else None

    def _left_zero(self, node: str, t: np.ndarray, pos: np.ndarray, zero: np.ndarray, enu: bool) -> None:
        """A node handed out at the zero position: its first row off zero is refused when the step to it is one no
        plausible speed explains (its zero start was a logger's before the fix, which ``sync`` drops: the rows
        handed out cannot be taken back), and it is watched no longer when the step is explained."""
        if zero.all():
            if len(t):
                self.at_zero[node] = float(t[-1])
            return
        m = int(np.argmin(zero))
        t0 = float(t[m - 1]) if m else self.at_zero.pop(node)
        self.at_zero.pop(node, None)
        h, v = np.array([MAX_HORIZONTAL_SPEED_M_S]), np.array([MAX_VERTICAL_SPEED_M_S])
        if enu and not unexplained_steps(np.array([t0]), np.zeros((1, 3)), h, v, t[m:m + 1], pos[m:m + 1], h, v)[0][0]:
            return
        how = ("as one pose, taken for a station at the origin" if node in self.stations else
               f"longer than it is held back ({HOLD_S:g} s of the table's time or {HOLD_ROWS:,} rows)")
        raise InputError(f"{self.source}: fields x, y, z of node {node}: it stood at the zero position from its first "
                         f"row {how} (rows handed out as valid) and now jumps off it at t = "
                         f"{float(t[m]):.3f} s: a logger writing before its fix, whose zero rows sync drops; read the "
                         "file with sync, or start the live session after the fix", param="nan_policy")


#: Polls of a signal CSV whose rows' hashes :class:`CsvTail` keeps: a row repeating one of them
#: is a copy, not a step back in time (the matcher drops it); older rows are forgotten.
LINK_MEMORY_POLLS = 16


@check_types
class CsvTail:
    """A canonical pose CSV and signal CSV being appended to (module docstring).

    A node whose rows begin at the zero position (a logger writing before the fix) is held back until its
    rows tell which side of its first jump ``sync`` keeps (:func:`_start_known`), at most :data:`HOLD_S` of
    the table's time or :data:`HOLD_ROWS` rows, then handed out as they stand and refused if they jump off
    zero later (the rows handed out cannot be taken back); a node standing still at the ENU origin (one
    pose for :data:`STATION_SPAN_S`) is a station there, handed out then and watched alike; ``poll(final=True)`` hands out what is
    held. The rows kept and the drops counted are then those of ``sync`` on the whole file, however it is
    written in pieces.

    Parameters
    ----------
    pose_path, signal_path : str
        The files (they may not exist yet).
    reader : ReaderOptions, optional
        As ``sync`` reads the same tables: ``origin_geodetic`` (a geodetic table's ENU origin; by default
        its first fix, kept for every later poll), ``nan_policy`` (pose rows with a NaN, a coordinate
        beyond any place or on the wrong side of a position jump refused or dropped and counted
        in :attr:`Poll.dropped`), ``receivers[signal_path]``, a constant ``tx_power_dbm`` and
        ``frequency_hz`` for a signal table without those columns.
    """

    def __init__(self, pose_path: str, signal_path: str, reader: ReaderOptions | None = None) -> None:
        self.pose, self.signal = _Tail(pose_path), _Tail(signal_path)
        self.name = f"{pose_path} + {signal_path}"
        self.reader = reader if reader is not None else ReaderOptions()
        self.dropped: dict[str, int] = {}
        self._ends = TrackEnds()  # each node's last pose kept: a poll's rows are checked against it
        self._signal_rows = 0
        self._links = LinkTimes()  # each link's last time: a logger that rebooted is refused, as by sync
        self._origin = self.reader.origin_geodetic  # as sync: given, else the first part's first fix
        self._hold = _StartHold(pose_path)  # pose rows at a node's start whose validity is not known yet

    def poll(self, final: bool = False) -> Poll:
        """Rows appended since the last poll; with ``final`` (the session's end) the rows held back too."""
        p, s = self.pose.lines(), self.signal.lines()
        poses = signals = pd.DataFrame()
        new = _table(self.pose, p)
        pt = self._hold.take(new, final)
        if pt is not None:
            self._ends.file_rows = pt[_FILE_ROW].to_numpy()
            poses, meta = canonical_pose(pt.drop(columns=_FILE_ROW), source=self.pose.path,
                                         origin_geodetic=self._origin, nan_policy=self.reader.nan_policy,
                                         allow_unsorted=self.reader.allow_unsorted, ends=self._ends)
            self._origin = self._origin or meta["origin_geodetic"]  # a geodetic table: one frame for every part
            for reason, n in meta["dropped"].items():
                self.dropped[reason] = self.dropped.get(reason, 0) + int(n)
        st = _table(self.signal, s)
        if st is not None:
            ptx = self.reader.tx_power_dbm if not isinstance(self.reader.tx_power_dbm, Mapping) else None
            signals = canonical_signal(st, source=self.signal.path, rx=(self.reader.receivers or {}).get(self.signal.path),
                                       tx_power_dbm=ptx, frequency_hz=self.reader.frequency_hz,
                                       first_row=self._signal_rows)
            if not self.reader.allow_unsorted:
                check_link_time_order(signals, self.signal.path, self._signal_rows, self._links)
                del self._links.seen[:-LINK_MEMORY_POLLS]  # copies of rows of older polls: a step back
            self._signal_rows += len(signals)
        received = (0 if new is None else len(new)) + len(signals)  # held rows too: the stream is not idle
        self.dropped[REPEATED_HEADER] = self.pose.repeated.count + self.signal.repeated.count
        where = "; ".join(w for w in (self.pose.repeated.where(self.pose.path), self.signal.repeated.where(self.signal.path)) if w)
        held = self._hold.held
        held_nodes = frozenset() if held is None or "node" not in held.columns else frozenset(held["node"].astype(str))
        return Poll(poses, signals, received, {k: n for k, n in self.dropped.items() if n}, held_nodes, {REPEATED_HEADER: where} if where else {})

    def close(self) -> None:
        """Nothing to release."""


@check_types
class MavlinkSource:
    """A MAVLink connection recorded to a ``.tlog`` and read back where it grew by ``sync``'s reader.

    Parameters
    ----------
    connection : str
        pymavlink connection string.
    record_path : str
        The telemetry log written as messages arrive (a working file of the session).
    reader : ReaderOptions
        As ``sync`` reads a ``.tlog`` (transmit power and frequency at least).
    read_every_s : float
        Seconds between readings of the log.

    Attributes
    ----------
    tail : TlogTail
        The reader of the recording (``tail.parsed``: messages parsed by the last reading).
    messages : int
        Messages received in all.
    """

    def __init__(self, connection: str, record_path: str, reader: ReaderOptions, read_every_s: float = 1.0) -> None:
        from rplearn.io._log_schema import library_quiet
        from rplearn.io._mavlink_records import mavutil_module, open_mavlink_log
        from rplearn.io.tlog_tail import TlogTail

        try:
            # a file: the streaming reader (pymavlink's connection would index it whole, and fail inside on a cut record)
            with library_quiet():  # pymavlink prints its retries ("Connection refused sleeping")
                self.conn = open_mavlink_log(connection) if os.path.isfile(connection) else \
                    mavutil_module().mavlink_connection(connection, dialect="ardupilotmega")
        except LogFormatError:
            raise
        except Exception as exc:
            raise InputError(f"{connection}: cannot open the MAVLink connection ({type(exc).__name__}: {exc})",
                             param="source") from None
        self.name, self.record_path, self.reader, self.read_every_s = connection, record_path, reader, read_every_s
        self._fh = open(record_path, "wb")  # noqa: SIM115 (a working log, closed by close())
        self._lock = threading.Lock()
        self._received = 0
        self.messages = 0  # received in all
        self._unread = 0
        self._last_read = -math.inf
        self.tail = TlogTail(record_path, reader)
        self._stop = threading.Event()
        self._error: BaseException | None = None
        # messages are received and stamped on their own thread, so that a refit does not delay
        # their receive times (the clock of the radio readings) nor overflow the socket's buffer
        self._thread = threading.Thread(target=self._receive, name="rplearn-live-mavlink", daemon=True)
        self._thread.start()

    def _receive(self) -> None:
        try:
            while not self._stop.is_set():
                msg = self.conn.recv_match(blocking=True, timeout=0.2)
                if msg is None or msg.get_type() == "BAD_DATA":
                    continue
                usec = int(msg._timestamp * 1.0e6) & ~3
                with self._lock:
                    self._fh.write(struct.pack(">Q", usec) + msg.get_msgbuf())
                    self._received += 1
                    self.messages += 1
        except BaseException as exc:  # pragma: no cover - a dead link: reported by poll
            self._error = exc

    def poll(self, final: bool = False) -> Poll:
        """What has arrived: every ``read_every_s`` (and with ``final``) the new rows."""
        if self._error is not None:
            raise InputError(f"{self.name}: the MAVLink connection failed ({type(self._error).__name__}: "
                             f"{self._error})", param="source")
        with self._lock:
            n, self._received = self._received, 0
            self._unread += n
            now = time.monotonic()
            empty = pd.DataFrame()
            # rows held back by the reader (time base, station, settling) are released by the final poll
            if not final and (not self._unread or now - self._last_read < self.read_every_s):
                return Poll(empty, empty, n, dict(self.tail.dropped))
            self._fh.flush()
            self._last_read, self._unread = now, 0
        poses, signals = self.tail.poll(final=final)
        return Poll(poses, signals, n, dict(self.tail.dropped))

    def close(self) -> None:
        """Stop receiving; close the connection and the recording."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        with self._lock:
            if self._fh.closed:
                return
            self._fh.close()
        self.tail.close()
        try:
            self.conn.close()
        except Exception:  # pragma: no cover - closing a dead socket
            pass


#: Messages whose boot time and speeds :func:`replay_tlog` scales.
_SPEED_FIELDS = ("vx", "vy", "vz")


def _scaled(msg: Any, speed: float, boot0_ms: int) -> Any:
    if hasattr(msg, "time_boot_ms"):
        msg.time_boot_ms = int(boot0_ms + (msg.time_boot_ms - boot0_ms) / speed)
    if msg.get_type() == "GLOBAL_POSITION_INT":
        for f in _SPEED_FIELDS:
            setattr(msg, f, int(np.clip(getattr(msg, f) * speed, -32768, 32767)))
    return msg


#: Receive-time steps between two messages that :func:`replay_tlog` waits for at most [s of the log]: a step
#: back or a longer one (a corrupt record's time, a log of two sessions) starts the pace afresh at that message.
MAX_REPLAY_STEP_S = 60.0


def udp_target(address: str) -> tuple[int, tuple[Any, ...]]:
    """The socket family and address of ``HOST:PORT`` (``[IPv6]:PORT`` too), refused in one line naming it."""
    host, _, port = address.rpartition(":")
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    try:
        number = int(port)
    except ValueError:
        raise BadValueError(f"address: expected HOST:PORT, got {address!r}", param="address") from None
    if not 0 < number < 65536:
        raise InputError(f"address: port {number} of {address!r} is not a UDP port (1 to 65535)", param="address")
    try:
        family, _, _, _, target = socket.getaddrinfo(host or "127.0.0.1", number, type=socket.SOCK_DGRAM)[0]
    except (socket.gaierror, UnicodeError) as exc:
        raise InputError(f"address: cannot resolve the host of {address!r} ({exc})", param="address") from None
    return int(family), tuple(target)


def _next_message(log: Any, path: str) -> Any:
    """The log's next message (None at its end); pymavlink failing on corrupt bytes refused naming the file."""
    try:
        return log.recv_msg()
    except Exception as exc:  # pymavlink raises many classes on corrupt records
        raise LogFormatError(f"{path}: cannot read a MAVLink message at byte {log.f.tell() if hasattr(log, 'f') else '?'} "
                             f"({type(exc).__name__}: {exc}): a corrupt .tlog") from None


@check_types
def replay_tlog(path: str, address: str, speed: float = 1.0, start_delay_s: float = 0.0) -> int:
    """Send a ``.tlog``'s messages to ``host:port`` over UDP at ``speed`` times their pace.

    Each message is re-encoded by pymavlink with its own system and component ids; its
    ``time_boot_ms`` is scaled by ``1/speed`` from the log's first one, and the velocities of
    ``GLOBAL_POSITION_INT`` by ``speed``, so that the stream is the same flight, faster. A message
    pymavlink reads but cannot encode (an id its dialect does not know) is not sent.

    Returns
    -------
    int
        Messages sent.

    Raises
    ------
    InputError
        When the file holds no message to send (not a MAVLink log).
    """
    from rplearn.io._mavlink_records import mavutil_module, open_mavlink_log

    if not (math.isfinite(speed) and speed > 0):
        raise InputError(f"speed: expected a positive, finite factor, got {speed}", param="speed")
    family, target = udp_target(address)
    mavutil = mavutil_module()
    log = open_mavlink_log(str(path))  # a file, never a connection string
    enc = mavutil.mavlink.MAVLink(None)
    sock = socket.socket(family, socket.SOCK_DGRAM)
    sent, t0, wall0, boot0, last = 0, None, 0.0, None, None
    try:
        while True:
            msg = _next_message(log, path)
            if msg is None:
                break
            if msg.get_type() == "BAD_DATA":
                continue
            stamp = float(msg._timestamp)
            if t0 is None or last is None or not 0.0 <= stamp - last <= MAX_REPLAY_STEP_S:  # a receive time gone wrong
                t0, wall0 = stamp, (time.monotonic() + start_delay_s if t0 is None else time.monotonic())
            last = stamp
            if boot0 is None and hasattr(msg, "time_boot_ms"):
                boot0 = int(msg.time_boot_ms)
            wait = wall0 + (stamp - t0) / speed - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            enc.srcSystem, enc.srcComponent = msg.get_srcSystem(), msg.get_srcComponent()
            try:
                packed = _scaled(msg, speed, boot0 or 0).pack(enc)
            except NotImplementedError:  # a message pymavlink read but cannot encode (an unknown id): not sent
                continue
            try:
                sock.sendto(packed, target)
            except OSError as exc:
                raise InputError(f"address: cannot send to {address} ({exc.strerror or exc})", param="address") from None
            sent += 1
    finally:
        sock.close()
    if not sent:
        raise InputError(f"{path}: no MAVLink message in it to send (a .tlog, as MAVProxy or QGroundControl record it?)",
                         param="path")
    return sent


__all__ = ["CsvTail", "MavlinkSource", "Poll", "replay_tlog", "udp_target"]
