"""The recent stretch of a growing ``.tlog`` with what its past fixed, for :class:`rplearn.io.tlog_tail.TlogTail`.

A poll of ``rplearn live``'s MAVLink source converts only a window of the log: the messages
since the *anchor*, a position fix at least :data:`KEEP_S` before the rows last handed out, plus
a bounded summary of the past, built so that every row after the anchor is converted as the
offline reader (:func:`rplearn.io.mavlink.logs_from_raw` over the whole log so far) converts it.
The offline reader's rules that look at the whole log, and their causal forms here:

- the vehicle (the system sending most ATTITUDE), the boot clock's use and the station: fixed
  when the first rows are handed out (:class:`rplearn.io.tlog_tail.TlogTail`); ATTITUDE counts
  per sender and repeated boot times are kept, and a later change of the vehicle, or a boot
  clock the reader would stop using, is counted (every row handed out withdrawn);
- boots: a message's boot is found on arrival from the message before it (the boot clock
  stepping back); each boot's time offset is fixed from its first messages
  (``TIME_BASE_MESSAGES``); each boot's first and last times are kept;
- the validity of position fixes (:func:`rplearn.io.mavlink_phases.invalid_fixes`: a piece of a
  boot is valid when it joins the valid fixes after it, so a verdict depends only on later
  fixes): the fixes of the anchor's boot before the anchor are kept as the first and last fix of
  each of its pieces (at most :data:`MAX_PIECES`), so verdicts and excluded periods are the offline
  reader's; a piece behind the anchor whose verdict changes counts the rows handed out in it
  (``withdrawn_*``) or the messages it holds (``late_*``);
- the GPS fix type and the armed state: the last report before the anchor is kept;
- origin messages: their last time; the vehicle's stream (a link lost): its messages within
  ``stream_timeout_s`` of the window;
- copies of radio reports: judged on arrival (:mod:`rplearn.io.tlog_copies`).

Every array holds only the window: the state does not grow with the flight. In a gap of
position fixes longer than the reader's ``max_gap_s`` the anchor moves into the gap (every
attitude instant there is dropped whatever fix comes later; the rows handed out there are
counted in the last fix's piece), the last fix kept standing in for the fixes behind it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rplearn.io import mavlink_phases as phases
from rplearn.io._mavlink_records import MAV_TYPE_GCS, ORIGIN_TYPES, Raw, TlogRows, rows_array
from rplearn.io.geodetic import geodetic_to_enu
from rplearn.io.tlog_copies import ReportCopies

#: The anchor lies at least this long before the rows last handed out [s]: rows after it are
#: converted again at every poll, so that a verdict changed by later messages is counted.
KEEP_S = 10.0
#: Pieces of the anchor's boot kept behind it (older ones are forgotten: their verdicts are no
#: longer revisited).
MAX_PIECES = 32

_ATT, _GPI, _RADIO = 6, 8, 9  # columns of the window's arrays (below)


@dataclass
class _Piece:
    """A piece of fixes behind the anchor: its first fix's time, the verdict it last had, and
    the rows handed out and messages received from its first fix to the next piece's."""

    first_t: float
    valid: bool = True
    handed: dict[str, int] = field(default_factory=lambda: {"pose": 0, "signal": 0})
    received: dict[str, int] = field(default_factory=lambda: {"pose": 0, "signal": 0})
    late: dict[str, int] = field(default_factory=lambda: {"pose": 0, "signal": 0})  # counted late, not yet taken back


class TlogWindow:
    """The window of a growing ``.tlog`` and the summary of what came before (module docstring).

    Parameters
    ----------
    chosen : int
        ``system * 256 + component`` of the vehicle's ATTITUDE sender.
    boot_clock : bool
        Whether the vehicle's ``time_boot_ms`` is its clock.
    raw : Raw
        The offline conversion of the log so far (notes, home, station-independent fields).
    time_base : dict
        Boot number -> its fixed receive-minus-boot offset [s] (shared with the tail, which fixes them).
    """

    def __init__(self, chosen: int, boot_clock: bool, raw: Raw, time_base: dict[int, float]) -> None:
        self.chosen, self.vehicle, self.boot_clock = chosen, chosen // 256, boot_clock
        self.home, self.notes = raw.home, dict(raw.notes)
        self.counts: dict[str, int] = {}
        self.senders: dict[int, int] = {}  # ATTITUDE messages per (system, component)
        self.radio_senders: dict[str, int] = {}
        self.att = np.zeros((0, _ATT))  # t_recv, t_boot, roll, pitch, yaw, boot
        self.gpi = np.zeros((0, _GPI))  # t_recv, t_boot, lat, lon, alt, speed h, speed v, boot
        self.radio = np.zeros((0, _RADIO))  # t, rssi, remrssi, noise, remnoise, rxerrors, fixed, gap, uncertain
        self.vehicle_t = np.zeros(0)
        self.origin_t = np.zeros(0)
        self.fix = np.zeros((0, 2))
        self.armed = np.zeros((0, 2))
        self.copies = ReportCopies()
        self.time_base = time_base  # the tail's: boot -> receive minus boot time [s], fixed
        self.boot_first: dict[int, float] = {}  # first ATTITUDE per boot [s, log clock]
        self.boot_last_att: dict[int, float] = {}
        self.boot_last: dict[int, float] = {}  # last ATTITUDE or position per boot
        self.last_origin = -np.inf
        self.has_origin = False
        self._boot_at: tuple[float, float, int] | None = None  # the last vehicle message's receive, boot time, boot
        self.anchor = -np.inf
        self.last_fix: tuple[float, int] = (-np.inf, 0)  # the last fix at or before the anchor (time [s], boot)
        self.in_gap = False  # the anchor lies in a gap of fixes, after last_fix (trim)
        self.prefix = np.zeros((0, 7))
        self.prefix_joined = np.zeros(0, bool)
        self.pieces: list[_Piece] = []
        self.step_origin: tuple[float, float, float] | None = None
        self.att_total, self.att_repeats, self._last_boot_ms = 0, 0, np.nan

    def clock_lost(self) -> bool:
        """Whether the offline reader would no longer use the boot clock: its ATTITUDE messages
        with distinct ``time_boot_ms`` (at most those differing from the one before) fell below
        90 % of them."""
        return self.boot_clock and self.att_total - self.att_repeats < 0.9 * self.att_total

    def fix_step_origin(self) -> None:
        """The geodetic origin of the step test: the first fix of the log (``position_fixes``'s)."""
        from rplearn.io.mavlink import increasing_times

        pos = self.raw().pos
        pos = pos[np.all(np.isfinite(pos[:, :4]), axis=1)]
        if len(pos):
            self.step_origin = tuple(increasing_times(pos[:, 0], pos)[1][0, 1:4])

    # --- messages in ---------------------------------------------------------------------------
    def add(self, rows: TlogRows) -> None:
        """Add the messages of ``rows`` (those parsed since the last call)."""
        for k, m in rows.counts.items():
            self.counts[k] = self.counts.get(k, 0) + m
        for key, m in rows.radio_senders.items():
            self.radio_senders[key] = self.radio_senders.get(key, 0) + m
        att = rows.array("ATTITUDE", 6)
        srcs, per_src = np.unique(att[:, 0].astype(int), return_counts=True)
        for s, k in zip(srcs.tolist(), per_src.tolist(), strict=True):
            self.senders[s] = self.senders.get(s, 0) + k
        att = att[att[:, 0] == self.chosen]
        tb = att[:, 2]
        self.att_total += len(tb)  # a clock repeating its value (a sender leaving time_boot_ms at 0)
        self.att_repeats += int(np.count_nonzero(np.diff(np.concatenate([[self._last_boot_ms], tb])) == 0))
        if len(tb):
            self._last_boot_ms = float(tb[-1])
        gpi = rows.array("GLOBAL_POSITION_INT", 8)
        gpi = gpi[(gpi[:, 0] == self.chosen) & ((gpi[:, 3] != 0) | (gpi[:, 4] != 0))]
        boot = self._boots(np.concatenate([att[:, 1:3], gpi[:, 1:3]]))
        self.att = np.concatenate([self.att, np.column_stack([att[:, 1:6], boot[:len(att)]])])
        self.gpi = np.concatenate([self.gpi, np.column_stack([gpi[:, 1:8], boot[len(att):]])])
        radio = np.concatenate([rows.array("RADIO_STATUS", 7), rows.array("RADIO", 7)])
        radio = radio[np.lexsort(radio.T[::-1])]
        gaps = self.copies.add(radio)
        self.radio = np.concatenate([self.radio, np.column_stack([radio, gaps, np.zeros(len(radio))])])
        self.vehicle_t = np.concatenate([self.vehicle_t, np.sort(rows.times(self.vehicle))])
        origin = [h[1] for k in ORIGIN_TYPES for h in rows.rows[k] if h[0] // 256 == self.vehicle and (h[2] != 0 or h[3] != 0)]
        if origin:
            self.has_origin, self.last_origin = True, max(self.last_origin, max(origin))
            self.origin_t = np.sort(np.concatenate([self.origin_t, origin]))
        if self.home is None:
            home = [h for h in rows.rows["HOME_POSITION"] if h[0] // 256 == self.vehicle and (h[2] != 0 or h[3] != 0)]
            self.home = (float(home[0][2]), float(home[0][3]), float(home[0][4])) if home else None
        fix = [r[1:3] for r in rows.rows["GPS_RAW_INT"] if r[0] // 256 == self.vehicle]
        beats = [r[1:3] for r in rows.rows["HEARTBEAT"] if r[0] // 256 == self.vehicle and r[3] != MAV_TYPE_GCS]
        if fix:
            self.fix = rows_array(sorted([tuple(r) for r in self.fix.tolist()] + fix), 2)
        if beats:
            self.armed = rows_array(sorted([tuple(r) for r in self.armed.tolist()] + beats), 2)

    def _boots(self, both: np.ndarray) -> np.ndarray:
        """Each message's boot, as :func:`rplearn.io._mavlink_records.boot_offsets` numbers them
        over the whole log (receive order; a new boot where the boot clock steps back)."""
        if not self.boot_clock:
            return np.zeros(len(both), np.int64)
        order = np.argsort(both[:, 0], kind="stable")
        tb = both[order, 1]
        prev = self._boot_at
        start = np.concatenate([[prev[1]], tb]) if prev is not None else tb
        steps = np.cumsum(np.diff(start) < -phases.REBOOT_STEP_S)
        base = prev[2] if prev is not None else 0
        seg_sorted = base + (steps if prev is not None else np.concatenate([[0], steps]))
        out = np.empty(len(both), np.int64)
        out[order] = seg_sorted
        if len(both):
            self._boot_at = (float(both[order[-1], 0]), float(tb[-1]), int(seg_sorted[-1]))
        return out

    # --- the window's Raw ----------------------------------------------------------------------
    def _t_log(self, rows: np.ndarray) -> tuple[np.ndarray, dict[int, tuple[float, int]]]:
        """Log-clock times of ``att``/``gpi`` rows and each boot's (offset, messages) of the window."""
        boot = rows[:, -1].astype(np.int64)
        if not self.boot_clock:
            return rows[:, 1] + (rows[:, 0] - rows[:, 1]), {}
        offset = np.empty(len(rows))
        per_boot: dict[int, tuple[float, int]] = {}
        for b in np.unique(boot).tolist():
            m = boot == b
            off = self.time_base.get(b)
            if off is None:
                off = float(np.median(rows[m, 0] - rows[m, 1]))
            offset[m] = off
            per_boot[b] = (off, int(m.sum()))
        return rows[:, 1] + offset, per_boot

    def raw(self) -> Raw:
        """The window as the offline reader's :class:`Raw` (with the summary of the past)."""
        both = np.concatenate([self.att[:, [0, 1, 5]], self.gpi[:, [0, 1, 7]]])
        t_log, per_boot = self._t_log(both)
        n_att = len(self.att)
        boot = both[:, -1]
        last = dict(self.boot_last)
        for b in np.unique(boot).astype(int).tolist():
            last[b] = max(last.get(b, -np.inf), float(t_log[boot == b].max()))
        boot_last_t = np.array([last.get(b, -np.inf) for b in range(max(last) + 1)]) if last else np.zeros(0)
        rule = self.copies.rule()
        copy, uncertain = ReportCopies.verdicts(self.radio[:, 7], rule)
        self.radio[:, 8] = uncertain
        band = self.copies.period_band()
        others: dict[int, int] = {}
        for s, k in self.senders.items():
            if s // 256 != self.vehicle:
                others[s // 256] = others.get(s // 256, 0) + k
        notes = {**self.notes, "other_vehicles": others, "radio_senders": dict(self.radio_senders)}
        pos = np.column_stack([t_log[n_att:], self.gpi[:, 2:7], boot[n_att:]])
        fix = self.fix
        if self.in_gap and len(self.prefix):
            # the anchor in a gap of fixes (trim): the last fix kept (valid by its fix type) again in
            # front, twice (the reader wants two fixes; the same time: one fix, joining itself)
            last = self.prefix[-1]
            pos = np.concatenate([np.stack([last, last]), pos])
            fix = np.concatenate([[[last[0], 1.0]], fix]) if len(fix) else fix
        return Raw(
            fmt="tlog", att=np.column_stack([t_log[:n_att], self.att[:, 2:5], boot[:n_att]]),
            pos=pos,
            radio=self.radio[~uncertain, :7], vehicle_t=self.vehicle_t, home=self.home, counts=dict(self.counts),
            boot_last_t=boot_last_t, origin_t=self.origin_t, fix=fix, armed=self.armed, boot_offsets=per_boot,
            notes=notes, prefix=self.prefix, prefix_joined=self.prefix_joined, step_origin=self.step_origin,
            radio_copy=copy[~uncertain], radio_period=None if band is None else 0.5 * (band[0] + band[1]),
        )

    def boots_ready(self, raw: Raw, newest: float, home_wait_s: float) -> float:
        """``TlogTail``'s wait for boots (its ``_boots_ready``) from the kept first and last times."""
        if not self.boot_clock:
            return float(raw.vehicle_t[-1]) if len(raw.vehicle_t) else np.inf
        first = dict(self.boot_first)
        last_att = dict(self.boot_last_att)
        for b in np.unique(raw.att[:, 4]).astype(int).tolist():
            t = raw.att[raw.att[:, 4] == b, 0]
            first.setdefault(b, float(t.min()))
            last_att[b] = max(last_att.get(b, -np.inf), float(t.max()))
        for b in sorted(set(first) | set(raw.boot_offsets)):
            if b not in first:
                continue
            no_origin = self.has_origin and not self.last_origin >= first[b] and newest - first[b] < home_wait_s
            if b not in self.time_base or no_origin:
                before = [v for k, v in last_att.items() if k < b]
                return max(before) if before else first[b]
        return float(raw.vehicle_t[-1]) if len(raw.vehicle_t) else np.inf

    # --- trimming ------------------------------------------------------------------------------
    def trim(self, raw: Raw, to: float, stream_timeout_s: float, verdict: tuple[np.ndarray, np.ndarray],
             handed: dict[str, np.ndarray], max_gap_s: float = np.inf) -> int:
        """Move the anchor to the last position fix at or before ``to`` (if later than the
        present one), or, in a gap of fixes longer than ``max_gap_s`` [s] (the reader's longest
        bridged gap), into the gap (:meth:`_gap_anchor`), folding what lies before it into the
        summary. ``raw`` is :meth:`raw`'s output, ``verdict`` the times of its fixes and which
        are valid (``position_fixes``), ``handed`` the times of the rows handed out after the present
        anchor (those before the new one are counted in their piece). Returns the reports left
        behind that could not be judged."""
        fixes_t = raw.pos[:, 0]
        finite = np.all(np.isfinite(raw.pos[:, :4]), axis=1)
        cand = fixes_t[finite & (fixes_t <= to)]
        if len(cand):
            last_fix = (float(cand.max()), int(raw.pos[finite & (fixes_t == cand.max()), 6][0]))
        else:
            last_fix = self.last_fix
        gap = self._gap_anchor(raw, last_fix, to, max_gap_s)
        anchor = max(gap, last_fix[0])
        if not np.isfinite(anchor) or anchor <= self.anchor:
            return 0
        anchor_boot = last_fix[1]
        self.last_fix, self.in_gap = last_fix, gap > last_fix[0]
        self._fold_pieces(raw, anchor, anchor_boot, verdict, handed)
        both = np.concatenate([self.att[:, [0, 1, 5]], self.gpi[:, [0, 1, 7]]])
        t_log = raw.att[:, 0], raw.pos[len(raw.pos) - len(self.gpi):, 0]  # (without the fix repeated in a gap: raw)
        for b in np.unique(both[:, -1]).astype(int).tolist():
            gone_att = t_log[0][(raw.att[:, 4] == b) & (t_log[0] < anchor)]
            gone_pos = t_log[1][(raw.pos[len(raw.pos) - len(self.gpi):, 6] == b) & (t_log[1] < anchor)]
            if len(gone_att):
                self.boot_first.setdefault(b, float(gone_att.min()))
                self.boot_last_att[b] = max(self.boot_last_att.get(b, -np.inf), float(gone_att.max()))
            gone = np.concatenate([gone_att, gone_pos])
            if len(gone):
                self.boot_last[b] = max(self.boot_last.get(b, -np.inf), float(gone.max()))
        self.att = self.att[t_log[0] >= anchor]
        self.gpi = self.gpi[t_log[1] >= anchor]
        keep = self.radio[:, 0] >= anchor
        gone = self.radio[~keep & (self.radio[:, 8] == 0)]
        uncertain = int(np.count_nonzero(~keep & (self.radio[:, 8] != 0)))
        self.copies.behind(gone[:, 7], self.copies.rule())
        self.radio = self.radio[keep]
        self.vehicle_t = self.vehicle_t[self.vehicle_t >= anchor - stream_timeout_s - 1.0]
        self.origin_t = self.origin_t[self.origin_t >= anchor]
        self.fix, self.armed = _events_from(self.fix, anchor), _events_from(self.armed, anchor)
        self.anchor = anchor
        return uncertain

    def _gap_anchor(self, raw: Raw, last_fix: tuple[float, int], to: float, max_gap_s: float) -> float:
        """Where the anchor may lie in a gap of position fixes (-inf: nowhere): ``to``, if the
        last fix at or before it lies more than ``max_gap_s`` before it, and no message of a
        later boot than that fix's comes before it (else up to the first such message, if still
        more than ``max_gap_s`` after the fix). Whatever fix comes later, the reader drops every
        attitude instant of the gap (a gap longer than ``max_gap_s``, or after the last valid
        fix), and the only verdict a later fix can change on the rows of the gap is that of the
        last fix's piece (its rows counted in the piece: :meth:`revisit`); the rows of a boot
        without a fix yet stay in the window (its first fix excludes them)."""
        t_fix, boot = last_fix
        if not np.isfinite(t_fix):
            return -np.inf
        later = raw.att[(raw.att[:, 4] != boot) & (raw.att[:, 0] > t_fix), 0]
        gap_to = min(to, float(later.min())) if len(later) else to
        return gap_to if gap_to - t_fix > max_gap_s else -np.inf

    def _fold_pieces(self, raw: Raw, anchor: float, boot: int, verdict: tuple[np.ndarray, np.ndarray],
                     handed: dict[str, np.ndarray]) -> None:
        """The anchor's boot's fixes before the anchor as the ends of their pieces."""
        from rplearn.io.mavlink import increasing_times, step_state

        pos = raw.pos[np.all(np.isfinite(raw.pos[:, :4]), axis=1)]
        tp, pos = increasing_times(pos[:, 0], pos)
        ok = (step_state(tp, raw.fix, 1.0) > 0.5) & (pos[:, 6] == boot) & (tp < anchor)
        gone = pos[ok]
        same_boot = len(self.prefix) and int(self.prefix[0, 6]) == boot
        prefix = self.prefix if same_boot else np.zeros((0, 7))
        joined = self.prefix_joined if same_boot else np.zeros(0, bool)
        pieces = self.pieces if same_boot else []
        seq = np.concatenate([prefix, gone])
        if not len(seq):
            self.prefix, self.prefix_joined, self.pieces = prefix, joined, pieces
            return
        assert self.step_origin is not None  # fixed when the window was made
        xyz = geodetic_to_enu(seq[:, 1], seq[:, 2], seq[:, 3], self.step_origin)
        h = phases.logged_speeds(seq[:, 4], phases.MAX_HORIZONTAL_SPEED_M_S)
        v = phases.logged_speeds(seq[:, 5], phases.MAX_VERTICAL_SPEED_M_S)
        a, c = slice(0, -1), slice(1, None)
        bad, _, _ = phases.unexplained_steps(seq[a, 0], xyz[a], h[a], v[a], seq[c, 0], xyz[c], h[c], v[c])
        cut = np.concatenate([[True], bad & ~np.concatenate([joined, np.zeros(len(gone), bool)])[1:]])
        starts = np.flatnonzero(cut)
        ends = np.concatenate([starts[1:], [len(seq)]]) - 1
        rows, flags = [], []
        old = {p.first_t: p for p in pieces}
        new_pieces = []
        for s, e in zip(starts.tolist(), ends.tolist(), strict=True):
            rows.append(seq[s])
            flags.append(False)
            if e > s:
                rows.append(seq[e])
                flags.append(True)
            t0 = float(seq[s, 0])
            i0 = min(int(np.searchsorted(verdict[0], t0)), len(verdict[0]) - 1)
            new_pieces.append(old.get(t0, _Piece(t0, valid=bool(verdict[1][i0]) if len(verdict[0]) else True)))
        firsts = np.array([p.first_t for p in new_pieces])
        for what, times in handed.items():
            t = times[times < anchor]
            where = np.searchsorted(firsts, t, side="right") - 1
            for i in where[where >= 0].tolist():
                new_pieces[i].handed[what] += 1
        for what, t in (("pose", raw.att[:, 0]), ("signal", raw.radio[:, 0])):
            t = t[(t >= self.anchor) & (t < anchor)]
            where = np.searchsorted(firsts, t, side="right") - 1
            for i in where[where >= 0].tolist():
                new_pieces[i].received[what] += 1
        if len(new_pieces) > MAX_PIECES:  # the oldest forgotten
            drop = len(new_pieces) - MAX_PIECES
            first_kept = new_pieces[drop].first_t
            keep = np.array([r[0] >= first_kept for r in rows])
            rows, flags = [r for r, k in zip(rows, keep, strict=True) if k], [f for f, k in zip(flags, keep, strict=True) if k]
            new_pieces = new_pieces[drop:]
        self.prefix, self.prefix_joined, self.pieces = np.asarray(rows).reshape(-1, 7), np.asarray(flags, bool), new_pieces

    def revisit(self, valid: np.ndarray) -> dict[str, int]:
        """Changes of the counts of rows whose verdict changed behind the anchor, given which
        fixes of the conversion (``position_fixes``: the prefix's rows first) are valid: a piece turned
        invalid withdraws the rows handed out in it (or, if none were, takes back the messages
        it was counted late by); one turned valid again gives them back (the withdrawn count
        falls by them), or, if none were handed out, counts the messages it holds late. So a
        verdict that flips and flips back (a short position glitch under way at a poll, the
        last piece of the boot, so the pieces before it invalid for that poll) leaves the counts
        where they were. Values may be negative."""
        out = {f"{k}_{w}_rows": 0 for k in ("late", "withdrawn") for w in ("pose", "signal")}
        for p, v in zip(self.pieces, np.asarray(valid, bool)[np.flatnonzero(~self.prefix_joined)].tolist(), strict=True):
            handed = any(p.handed.values())
            for w in ("pose", "signal"):
                if p.valid and not v:
                    out[f"withdrawn_{w}_rows"] += p.handed[w]
                    out[f"late_{w}_rows"] -= p.late[w]
                    p.late[w] = 0
                elif v and not p.valid and handed:
                    out[f"withdrawn_{w}_rows"] -= p.handed[w]
                elif v and not p.valid:
                    out[f"late_{w}_rows"] += p.received[w]
                    p.late[w] = p.received[w]
            p.valid = v
        return out

    def sizes(self) -> dict[str, int]:
        """The length of every structure kept (for tests of bounded state)."""
        out = {name: len(getattr(self, name)) for name in ("att", "gpi", "radio", "vehicle_t", "origin_t", "fix",
                                                            "armed", "prefix", "pieces", "time_base", "boot_first",
                                                            "boot_last", "senders", "counts")}
        return {**out, **self.copies.sizes()}


def _events_from(events: np.ndarray, t: float) -> np.ndarray:
    """The events at or after ``t`` and the last one before it."""
    before = np.flatnonzero(events[:, 0] < t) if len(events) else np.zeros(0, np.int64)
    keep = events[:, 0] >= t if len(events) else np.zeros(0, bool)
    if len(before):
        keep[before[-1]] = True
    return events[keep]


__all__ = ["KEEP_S", "MAX_PIECES", "TlogWindow"]
