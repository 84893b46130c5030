"""Pose-signal matching while the logs are still being written (``rplearn live``).

:class:`LiveMatcher` takes pose and signal rows as they arrive and matches a signal row once
its time is *settled*: on the common clock (``SyncOptions.clock_offsets_s`` added to each node's pose times,
``signal_clock_offset_s`` to the signal times, as ``sync`` matches them), at or before the latest pose of every
moving node (a node whose poses
are not all one identical row, :mod:`rplearn.data.poses`), so that both neighbours of its
interpolation are known. The rows of one instant are matched together. Matching is
:func:`rplearn.data.sync.match_chunk`, with the duplicate hashes across chunks and the carry
of repeated readings of :func:`rplearn.data.streaming.synchronise_stream`: the same rules and
the same drop reasons as ``sync``, so that at the end of a stream the matched rows and the
counts are those of ``sync`` on the whole logs (:meth:`LiveMatcher.match` with
``final=True`` matches what is still pending; rows after a node's last pose are then
``out_of_span``).

Memory: the pose rows a later match can need (per moving node, those after the matched
horizon and the one before it, and never fewer than two: one row is a static track; a still
node's first and last row), the pending signal rows,
and for duplicates across chunks the hashes of the signal rows at most
:data:`DUPLICATE_MEMORY_S` older than the oldest pose a moving node keeps (16 bytes a row): it
does not grow with the stream's length. The hashes of older rows are forgotten, so a row whose
time is before that threshold (more than :data:`DUPLICATE_MEMORY_S` late) is dropped as
``late`` before any other test, whatever its link (a link of two still nodes keeps their
poses for the whole flight, and a copy matched then would be learned twice): where ``sync``
of the whole log says ``duplicate`` for a copy, live matching says ``late`` (and a row
without a valid time is forgotten at once: ``invalid_value`` for ``duplicate``).

A node with a single pose row is a node logged once, holding still (as ``sync`` holds a one-row
log), or a node whose log has just started: until its second row, or :data:`ONE_ROW_S` of the pose
rows' time (``max_gap_s`` if longer) without one, the rows after its pose are not settled and the
rows naming it wait as for a node without poses (below); a node first logged once and again, at
another pose, more than that later has the rows matched between taken at its first pose (``sync``:
``pose_gap``).

A node logged with identical rows (a station logging its surveyed pose at a steady rate, or when something
changes) holds still over its log's span, as in ``sync``; a row after its last row so far is in that span once
its next row comes, so such rows wait for it, as for a moving node's next pose, for :data:`NEXT_ROW_S` of the
pose rows' time; past that, no row having come, the node is held at its pose (as a station logged once is) and
the rows are matched there: where its next row comes later still (a station logged at the start and again at
the end) as ``sync`` matches them, where it never comes again as ``sync`` does not (``out_of_span``). At the
end of the stream the rows after its last row are ``out_of_span``, as in ``sync``.

A signal row naming a node that has no pose yet (a node whose first poses the source holds back, as
:class:`rplearn.io.live_sources.CsvTail` holds a logger's start at the zero position, or a ground
station at the ENU origin that logs its attitude) waits, settled or not, for that node's poses:
bounded as the source's hold is, for :data:`HOLD_S` of the pose rows' time after it, and
:data:`WAIT_ROWS` signal rows waiting in all (the oldest go first), then matched as it stands
(``unknown_node``, as ``sync`` drops a link to a node that has no poses). The pose rows and row hashes
those rows need are kept while they wait.

Limits against ``sync`` on the whole logs: the nodes' flight phases (``airborne``, the
window's log start) are those of the poses kept, so :class:`LiveMatcher` refuses the
``airborne`` filter and a time window; a node first logged more than :data:`HOLD_S` after rows that
name it has those rows dropped as ``unknown_node`` (a whole-log sync would place them).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.data.phases import flight_phases
from rplearn.data.poses import PoseTrack, TrackSet, tracks_of_checked_log
from rplearn.data.streaming import row_hashes
from rplearn.data.sync import SyncOptions, SyncResult, SyncSummary, check_receiver_offsets, finish_summary, match_chunk, sync_options_or_default
from rplearn.data.tables import MATCHED_COLUMNS, POSE_COLUMNS, non_unit_quaternion_rows, validate_pose_log
from rplearn.errors import InputError


class _RecentRows:
    """Hashes of the signal rows of earlier chunks, with their times, sorted for look-up; those
    of rows before a time are forgotten (:meth:`forget`)."""

    def __init__(self) -> None:
        self.sorted = np.empty(0, np.uint64)
        self.t_s = np.empty(0, np.float64)

    def repeats(self, hashes: np.ndarray, t_s: np.ndarray) -> np.ndarray:
        """Mask of hashes seen in an earlier chunk; then remember these with their times."""
        if self.sorted.size:
            pos = np.searchsorted(self.sorted, hashes).clip(max=self.sorted.size - 1)
            seen = self.sorted[pos] == hashes
        else:
            seen = np.zeros(hashes.size, bool)
        both = np.concatenate([self.sorted, hashes])
        order = np.argsort(both, kind="stable")
        self.sorted, self.t_s = both[order], np.concatenate([self.t_s, t_s])[order]
        return seen

    def forget(self, before_s: float) -> None:
        """Forget the rows before ``before_s`` [s] (and those without a valid time)."""
        keep = self.t_s >= before_s
        if not keep.all():
            self.sorted, self.t_s = self.sorted[keep], self.t_s[keep]

    def __len__(self) -> int:
        return int(self.sorted.size)


#: Seconds of signal time before the oldest pose a moving node keeps for which row hashes are
#: remembered; a row older than that is dropped as ``late``.
DUPLICATE_MEMORY_S = 30.0
#: How long and how many pose rows a node's first poses may be held back by a live source (its start at the
#: zero position: :class:`rplearn.io.live_sources.CsvTail`), and so how long a signal row naming a node without
#: poses waits for them (:class:`LiveMatcher`): seconds of the pose rows' time after the row, and pose rows in all.
HOLD_S = 60.0
HOLD_ROWS = 16384
#: Signal rows that may wait for a held node's poses in all (the oldest then go, as ``unknown_node``): the
#: rows of :data:`HOLD_S` at about 1,000 readings a second over every link (some 100 bytes a row).
WAIT_ROWS = 65536
#: Seconds of the pose rows' time (or ``max_gap_s`` when longer) after a node's only pose row past which, no second
#: row having come, the node is taken to hold still at it (a station logged once, as ``sync`` holds a one-row log);
#: before then it may be a node whose log has just started (:class:`LiveMatcher`: the rows naming it wait).
ONE_ROW_S = 1.0
#: Seconds of the pose rows' time the rows after the last row of a node logged with identical rows wait for its
#: next row (:class:`LiveMatcher`: within the node's span once it comes, as ``sync`` holds it still over its log's
#: span); past that the node is held at its pose, as a station logged once is.
NEXT_ROW_S = HOLD_S


def _offset_slack_s(options: SyncOptions) -> float:
    """The largest shift [s] the clock offsets make between a signal time and a pose time."""
    pose = max((abs(float(v)) for v in (options.clock_offsets_s or {}).values()), default=0.0)
    sig = options.signal_clock_offset_s
    signal = max((abs(float(v)) for v in sig.values()), default=0.0) if isinstance(sig, Mapping) else abs(float(sig))
    return pose + signal


def _common_signal_t(rows: pd.DataFrame, options: SyncOptions) -> np.ndarray:
    """Signal rows' times on the common clock [s] (NaN where not a number): plus the signal clock offset, one for
    the log or one per receiver (as :func:`rplearn.data.sync.match_chunk` puts them)."""
    t = pd.to_numeric(rows["t"], errors="coerce").to_numpy(np.float64) if "t" in rows.columns else np.full(len(rows), np.nan)
    offset = options.signal_clock_offset_s
    if isinstance(offset, Mapping):
        rx = rows["rx"].astype(str) if "rx" in rows.columns else pd.Series("", index=rows.index)
        return t + rx.map(lambda r: float(offset.get(r, 0.0))).to_numpy(np.float64)
    return t + float(offset)


def _still(group: pd.DataFrame) -> bool:
    """Whether a node's (sorted) pose rows are all one pose (as :mod:`rplearn.data.poses` decides)."""
    if len(group) < 2:
        return True
    tracks = tracks_of_checked_log(group, None, "pose log")
    return bool(next(iter(tracks.values())).still)


@check_types
class LiveMatcher:
    """Match pose and signal rows as they arrive (module docstring).

    Parameters
    ----------
    options : SyncOptions, optional
        As :func:`rplearn.data.sync.synchronise`; ``airborne`` and a time window are refused.
    source : str
        Name of the signal stream in messages.
    """

    def __init__(self, options: SyncOptions | None = None, source: str = "signal stream") -> None:
        self.options = sync_options_or_default(options)
        if self.options.airborne or self.options.from_s is not None or self.options.to_s is not None:
            raise InputError("live matching: the airborne filter and a time window need the whole log; "
                             "sync the recorded log instead", param="options")
        self.source = source
        self.summary = SyncSummary()
        self._poses = pd.DataFrame(columns=list(POSE_COLUMNS))
        self._pending: list[pd.DataFrame] = []
        self._seen = _RecentRows()
        self._forgotten_s = -math.inf  # the hashes of rows before this time [s] are forgotten
        self._carry: dict = {}
        self._horizon = -math.inf
        # every time the matcher compares is on the common clock, after the clock offsets (as sync matches)
        self._signal_t = -math.inf  # the latest signal time received: later rows come at or after it
        self._pose_t = -math.inf  # the latest pose time received
        self._waiting_from = math.inf  # the earliest time of a row waiting for a node's poses [s]
        self._n_waiting = 0
        self._waiting_nodes: frozenset[str] = frozenset()
        self._signal_rows = 0
        self._moving: set[str] = set()
        self._receivers: set[str] = set()  # with clock offsets per receiver: the receivers the rows name (checked at the end)
        #: The rows the last :meth:`match` gave (also when its end-of-stream check raised).
        self.last_matched = pd.DataFrame(columns=list(MATCHED_COLUMNS))

    @property
    def horizon_s(self) -> float:
        """Time [s, common clock] up to which signal rows have been matched."""
        return self._horizon

    @property
    def pending_rows(self) -> int:
        """Signal rows received and not yet matched."""
        return int(sum(len(p) for p in self._pending))

    def add_poses(self, rows: pd.DataFrame) -> None:
        """Append pose rows (canonical columns, any order); checked as ``sync`` checks a pose log."""
        if rows.empty:
            return
        new = validate_pose_log(rows, "pose log")
        self._pose_t = max(self._pose_t, float(self._common_pose_t(new).max()))
        self.summary.non_unit_quaternions += non_unit_quaternion_rows(new)
        both = pd.concat([self._poses, new], ignore_index=True) if len(self._poses) else new
        self._poses = validate_pose_log(both.drop(columns=[c for c in both.columns if c not in new.columns]), "pose log")

    def add_signals(self, rows: pd.DataFrame) -> None:
        """Append signal rows (canonical columns); they wait until their time is settled."""
        if len(rows):
            self._pending.append(rows.reset_index(drop=True))
            if isinstance(self.options.signal_clock_offset_s, Mapping) and "rx" in rows.columns:
                self._receivers.update(rows["rx"].astype(str).unique())
            t = _common_signal_t(rows, self.options)
            if np.isfinite(t).any():
                self._signal_t = max(self._signal_t, float(np.nanmax(t[np.isfinite(t)])))

    def _offset_s(self, node: str) -> float:
        """The clock offset of a node's poses [s] (``SyncOptions.clock_offsets_s``; 0 when none)."""
        return float((self.options.clock_offsets_s or {}).get(node, 0.0))

    def _common_pose_t(self, rows: pd.DataFrame) -> np.ndarray:
        """Pose rows' times on the common clock [s]: plus their node's clock offset."""
        offsets = self.options.clock_offsets_s
        t = rows["t"].to_numpy(np.float64)
        return t + rows["node"].astype(str).map(lambda n: float(offsets.get(n, 0.0))).to_numpy(np.float64) if offsets else t

    def _one_row(self) -> dict[str, float]:
        """The nodes with a single pose row whose next row may still come (:data:`ONE_ROW_S`), with its time [s]:
        moving (its log just started) or holding still is not known yet."""
        if self._poses.empty:
            return {}
        nodes = self._poses["node"].astype(str)
        counts = nodes.value_counts()
        single = self._poses[nodes.isin(counts.index[counts == 1]).to_numpy()]
        t = self._common_pose_t(single)
        young = t > self._pose_t - max(float(self.options.max_gap_s), ONE_ROW_S)
        return {str(n): float(v) for n, v in zip(single["node"][young], t[young]) if str(n) not in self._moving}

    def settled_s(self, one_row: Mapping[str, float] | None = None) -> float:
        """The latest time [s, common clock: after the clock offsets] every moving node's poses reach (-inf before
        two poses of one); a node with one pose row whose next may still come counts as moving (its time).
        ``one_row``: :meth:`_one_row`, when known (it is the same after this call: the nodes this adds to the
        moving ones are not among them)."""
        if self._poses.empty:
            return -math.inf
        last = []
        one_row = self._one_row() if one_row is None else one_row
        for node, group in self._poses.groupby("node", sort=False):
            t_last = float(group["t"].iloc[-1]) + self._offset_s(str(node))
            if str(node) in one_row:
                last.append(one_row[str(node)])
            elif str(node) in self._moving or not _still(group):
                self._moving.add(str(node))
                last.append(t_last)
            elif len(group) > 1 and t_last > self._pose_t - NEXT_ROW_S:
                last.append(t_last)  # identical rows: the next one may come (NEXT_ROW_S)
        return min(last) if last else -math.inf

    def match(self, final: bool = False) -> SyncResult:
        """Match the pending rows whose time is settled (every pending row with ``final``).

        Returns
        -------
        SyncResult
            The matched rows (sorted by time, as ``sync`` writes a log read whole) and this
            chunk's counts; :attr:`summary` holds the counts so far. With ``final``, the
            whole stream's notes are added and fewer than ``min_samples`` matched raises as
            ``sync`` does.
        """
        pending = pd.concat(self._pending, ignore_index=True) if self._pending else pd.DataFrame()
        one_row = None if final else self._one_row()  # read by settled_s and _waiting, the same for both
        horizon = math.inf if final else self.settled_s(one_row)
        self._waiting_from, self._n_waiting, self._waiting_nodes = math.inf, 0, frozenset()
        if pending.empty or self._poses.empty and not final:
            chunk, rest = pending.iloc[:0], pending
        else:
            t = _common_signal_t(pending, self.options)
            ready = ~(t > horizon)  # a time that is not a number is matched (and dropped) at once
            if not final:
                ready &= ~self._waiting(pending, t, one_row or {})
            chunk, rest = pending[ready], pending[~ready]
        self._pending = [rest.reset_index(drop=True)] if len(rest) else []
        self.last_matched = pd.DataFrame(columns=list(MATCHED_COLUMNS))  # not the last call's, should this one raise
        result = self._match(chunk.sort_values("t", kind="stable") if "t" in chunk.columns else chunk, final)
        self.last_matched = result.dataset
        if not final and len(chunk):  # poses are kept back to where the signal stream has reached (it may lag the poses)
            self._horizon = max(self._horizon, min(horizon, self._signal_t))
            self._trim()
        if final:
            tracks = self._tracks(final=True)
            phases = flight_phases(self._poses, tracks, self.options.clock_offsets_s, self.options.airborne_margin_m)
            finish_summary(self.summary, tracks, phases, self.options, self.source)
            # a receiver may start later in a stream: its offset is checked at the end (rplearn live says it in a note)
            check_receiver_offsets(self.options.signal_clock_offset_s, self._receivers, self.source)
        return result

    def _waiting(self, pending: pd.DataFrame, t: np.ndarray, one_row: Mapping[str, float]) -> np.ndarray:
        """Which pending rows wait for the poses of a node they name (module docstring; bounded by :data:`HOLD_S`
        and :data:`WAIT_ROWS`), and the earliest time among them kept (:meth:`_trim`)."""
        if not {"tx", "rx"} <= set(pending.columns):
            return np.zeros(len(pending), bool)
        # a node with one pose row whose next may still come: if it moves, rows before its first pose are out of span
        known = (set(self._poses["node"].astype(str)) if len(self._poses) else set()) - set(one_row)
        named = pending["tx"].astype(str).isin(known).to_numpy() & pending["rx"].astype(str).isin(known).to_numpy()
        wait = ~named & np.isfinite(t) & (t >= self._pose_t - HOLD_S - _offset_slack_s(self.options))
        if wait.sum() > WAIT_ROWS:  # the oldest go: matched as they stand
            wait[np.flatnonzero(wait)[np.argsort(t[wait], kind="stable")[:int(wait.sum()) - WAIT_ROWS]]] = False
        if wait.any():
            self._waiting_from = float(t[wait].min())
            ends = set(pending["tx"].astype(str)[wait]) | set(pending["rx"].astype(str)[wait])
            self._waiting_nodes = frozenset(ends - known)
        self._n_waiting = int(wait.sum())
        return wait

    @property
    def waiting_rows(self) -> int:
        """Signal rows waiting for the poses of a node they name (as of the last :meth:`match`)."""
        return self._n_waiting

    @property
    def waiting_nodes(self) -> frozenset[str]:
        """The nodes without poses that the waiting rows name (as of the last :meth:`match`)."""
        return self._waiting_nodes

    def _tracks(self, final: bool = False) -> TrackSet:
        """The tracks of the poses kept; before the stream's end, the clock offsets of the nodes with poses only (a
        node whose poses a source holds back or that starts later: its rows wait, and its offset is checked at the end)."""
        offsets = self.options.clock_offsets_s
        if offsets and not final:
            known = set(self._poses["node"].astype(str))
            offsets = {node: dt for node, dt in offsets.items() if str(node) in known}
        return tracks_of_checked_log(self._poses, offsets, "pose log", self.options.max_gap_s)

    def _held(self, tracks: Mapping[str, PoseTrack], chunk: pd.DataFrame) -> dict[str, PoseTrack]:
        """``tracks`` with the nodes of identical rows held at their pose through the chunk's latest time: the
        rows after such a node's last row are in the chunk only once they waited :data:`NEXT_ROW_S` for its next
        row (:meth:`settled_s`)."""
        t = _common_signal_t(chunk, self.options)
        through_s = float(t[np.isfinite(t)].max()) if np.isfinite(t).any() else -math.inf
        out: dict[str, PoseTrack] = dict(tracks)
        for node, track in tracks.items():
            if track.still and node not in self._moving and track.t_s[-1] < through_s:
                out[node] = PoseTrack(node, np.array([track.t_s[0], through_s]), track.position_xyz[[0, -1]],
                                      track.quat_wxyz[[0, -1]], still=True)
        return out

    def _match(self, chunk: pd.DataFrame, final: bool = False) -> SyncResult:
        if chunk.empty:
            return SyncResult(pd.DataFrame(columns=list(MATCHED_COLUMNS)), SyncSummary())
        if self._poses.empty:
            raise InputError(f"{self.source}: signal rows but no pose rows to match them with", param="poses")
        tracks: Mapping[str, PoseTrack] = self._tracks(final)
        if not final:
            tracks = self._held(tracks, chunk)
        phases = flight_phases(self._poses, tracks, self.options.clock_offsets_s, self.options.airborne_margin_m)
        t = _common_signal_t(chunk, self.options)
        late = t < self._forgotten_s  # their copies could no longer be found: never learned
        first_row = self._signal_rows
        self._signal_rows += len(chunk)
        if late.any():
            chunk, t = chunk[~late], t[~late]
        repeats = self._seen.repeats(row_hashes(chunk), t)
        result = match_chunk(tracks, chunk.reset_index(drop=True), self.options, self.source, seen_before=repeats,
                              first_row=first_row, phases=phases, carry=self._carry)
        result.summary.n_in += int(late.sum())
        result.summary.dropped["late"] += int(late.sum())
        self.summary.merge(result.summary)
        return result

    def _trim(self) -> None:
        """Forget the pose rows no later match needs (module docstring)."""
        keep = []
        oldest = math.inf  # the earliest pose a moving node keeps
        for node, group in self._poses.groupby("node", sort=False):
            if str(node) not in self._moving and _still(group):
                keep.append(group.iloc[[0, -1]] if len(group) > 1 else group)
                continue
            t = group["t"].to_numpy(np.float64) + self._offset_s(str(node))
            # the rows waiting for a node's poses need the poses from their time on too
            # at least two rows: one left would be a one-row track, static, its pose held at every time (sync
            # interpolates a moving node between two rows, and a row after its last is out_of_span)
            first = max(min(int(np.searchsorted(t, min(self._horizon, self._waiting_from), side="right")) - 1, t.size - 2), 0)
            keep.append(group.iloc[first:])
            oldest = min(oldest, float(t[first]))
        self._poses = pd.concat(keep).sort_values(["node", "t"], kind="stable").reset_index(drop=True)
        if math.isfinite(oldest):  # later rows before this are dropped as ``late`` (module docstring)
            self._forgotten_s = max(self._forgotten_s, oldest - _offset_slack_s(self.options) - DUPLICATE_MEMORY_S)
            self._seen.forget(self._forgotten_s)


__all__ = ["DUPLICATE_MEMORY_S", "HOLD_ROWS", "HOLD_S", "NEXT_ROW_S", "ONE_ROW_S", "WAIT_ROWS", "LiveMatcher"]
