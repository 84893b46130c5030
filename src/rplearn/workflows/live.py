"""``rplearn live``: learn the patterns while the vehicles fly.

The loop polls a source (:mod:`rplearn.io.live_sources`: a MAVLink connection, or a pose and a
signal CSV being appended to), matches the rows with ``sync``'s rules as their times settle
(:class:`rplearn.data.live_sync.LiveMatcher`), predicts every new batch with the current model
*before* learning from it (the prequential error: a running test score on samples no model
had seen), adds the batch to the statistics (:class:`rplearn.models.live_stats.LiveStatistics`)
and every ``refit_s`` refits from them and writes the model file atomically, so that a session
stopped at any moment (Ctrl-C, SIGTERM, a killed process) leaves the last good model. It ends
at the end of the stream (no row for ``idle_s`` after the first; before the first it waits),
after ``duration_s``, or when every node's pattern spread is below ``until_spread_db`` (over the
sphere, the directions never seen at the spread the fit gives them; or, ``spread_over="covered"``,
over the directions seen, with a coverage target: that spread is small from the first seconds,
while they are a few percent of the sphere) and/or every node's covered share of the sphere
reaches ``until_coverage_pct``; a last exact refit then follows. The next-best manoeuvres are ranked
beside the loop (:mod:`rplearn.workflows.live_ranking`), so that a ranking of seconds does not
stop the refits; what the loop keeps does not grow with the session's length (the prequential
record in a bounded number of bins, the notes one per kind, the matched rows of the budget
check a window).

Its final model is the offline fit of the same rows with every stretch learned from
(:mod:`rplearn.models.live_stats`): ``rplearn sync`` of the recorded logs, then ``rplearn fit
DATA --units 'flight[1/5],flight[2/5],flight[3/5],flight[4/5],test[5/5]'`` (and ``--order N``
for a fixed order). From a CSV source the last refit comes from the statistics alone (the
stretches' cuts exact, :mod:`rplearn.models.live_stats`). A MAVLink stream is recorded as a
``.tlog`` whose reader looks at the whole log (the boot clock's median offset, the periods
before a valid position fix are found after the fact), so rows matched from a shorter read can
differ from ``sync`` of the whole recording: the last refit of a MAVLink session learns the
recording matched whole, once, and says so in the notes.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_path, check_output
from rplearn.analysis.budget import check_fit_budget
from rplearn.analysis.decoupling import decoupling_certificate
from rplearn.core.lsq.selection import at_smoothing_cap
from rplearn.data.live_sync import LiveMatcher
from rplearn.data.sync import SyncOptions, SyncSummary
from rplearn.data.sync_notes import FIXED_NOTE_START
from rplearn.errors import InputError, RplearnError
from rplearn.io.live_sources import CsvTail, MavlinkSource
from rplearn.io.options import ReaderOptions
from rplearn.models.live_stats import MAX_SEGMENTS, LiveStatistics
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.workflows.live_checks import check_live_options, check_live_outputs, check_live_source, fixed_nodes_note, is_csv_source, no_model_message
from rplearn.workflows.live_ranking import Ranking, RankingWorker
from rplearn.workflows.live_status import LiveStatus, Prequential, page_rows

#: The manoeuvre hook: ``(statistics, fitted, latest pose per node) -> rows (name, duration [s],
#: predicted spread after [dB])``, best first; the statistics are the fixed-order
#: ``NormalEquations`` of every sample so far (at the accumulation order), ``fitted`` the current
#: ``FittedModel`` (its spec and model). :class:`rplearn.workflows.live_advice.ManoeuvreAdvisor`
#: is the one ``rplearn live`` uses.
ManoeuvreRanker = Callable[[Any, Any, pd.DataFrame], Sequence[tuple[str, float, float]]]
#: Matched rows kept for the link budget's plausibility check (a window of the latest).
BUDGET_WINDOW_ROWS = 2000
#: Seconds a stop waits for a running manoeuvre ranking before the last refit: the ranking holds
#: the process's BLAS limit (one thread) until it ends, and the last refit and a MAVLink
#: recording's whole re-match would otherwise run under it. One still running then is dropped
#: (a note says the last work ran under its limit).
STOP_RANKING_WAIT_S = 5.0


@check_types
@dataclass(frozen=True)
class LiveOptions:
    """How a live session learns and when it stops.

    Attributes
    ----------
    spec : ModelSpec
        Pattern model: its kind and ridge with ``fit.auto``, else its fixed order.
    fit : FitOptions
        As ``fit`` (gauge, path loss, link offsets, ``auto``).
    reader : ReaderOptions
        How a MAVLink stream is read (transmit power, frequency, station).
    sync : SyncOptions
        How rows are matched (as ``sync``; no time window, no airborne filter).
    refit_s : float
        Seconds between refits.
    duration_s, until_spread_db, until_coverage_pct : float or None
        Stop criteria (module docstring).
    spread_over : {"sphere", "covered"}
        What ``until_spread_db`` is read over: each node's whole sphere (default; the directions
        the flight never saw count with the spread the fit gives them there), or only the
        directions it saw, which needs ``until_coverage_pct`` too (a ground flight replayed:
        0.65 dB over the 1.2 % of the sphere seen after 2 s; a ``paper`` flight: below 2 dB at
        84 s while B had seen 27 %).
    idle_s : float
        The stream has ended when nothing arrived for this long [s] after its first message
        (before the first, the session waits: the drones may not be up yet).
    nodes : tuple of str or None
        The node ids (default: those of the first matched batch), each named once.
    manoeuvres : ManoeuvreRanker or None
        Ranks the next manoeuvres after a refit, best first (the top three are shown).
    rank_beside : bool
        Rank on a thread beside the loop (:mod:`rplearn.workflows.live_ranking`), so that refits
        go on meanwhile; False: in the loop, after the refit, which waits for it.
    ranking_every_s : float
        Seconds of wall time at least between the starts of two rankings (0: after any refit
        once the last ranking has finished).
    max_segments : int
        Segments of statistics kept (:class:`rplearn.models.live_stats.LiveStatistics`).
    fixed_nodes : tuple of str
        The nodes the caller named as unable to move (``manoeuvres`` holds them still): one not
        among ``nodes`` is refused, one no matched row names gets a note.
    """

    spec: ModelSpec = field(default_factory=lambda: ModelSpec.parse("sh"))
    fit: FitOptions = field(default_factory=lambda: FitOptions(auto=True))
    reader: ReaderOptions = field(default_factory=ReaderOptions)
    sync: SyncOptions = field(default_factory=SyncOptions)
    refit_s: float = 2.0
    duration_s: float | None = None
    until_spread_db: float | None = None
    until_coverage_pct: float | None = None
    spread_over: str = "sphere"
    idle_s: float = 10.0
    nodes: tuple[str, ...] | None = None
    manoeuvres: ManoeuvreRanker | None = None
    max_segments: int = MAX_SEGMENTS
    rank_beside: bool = True
    ranking_every_s: float = 0.0
    fixed_nodes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        check_live_options(self)


@check_types
@dataclass
class LiveOutcome:
    """A finished session: the last status, the last fitted model, the prequential record."""

    status: LiveStatus
    fitted: Any
    prequential: Prequential
    output: str


@check_types
def open_source(source: str, work_dir: str, reader: ReaderOptions) -> CsvTail | MavlinkSource:
    """``POSE.csv,SIGNAL.csv`` (two canonical CSVs being appended to) or a MAVLink connection."""
    if is_csv_source(source):
        pose, signal = source.split(",")
        return CsvTail(pose, signal, reader)
    if reader.tx_power_dbm is None or reader.frequency_hz is None:
        raise InputError(f"{source}: give the telemetry radios' transmit power [dBm] and carrier frequency [Hz], a "
                         "MAVLink stream carries neither", param="tx_power_dbm")
    return MavlinkSource(source, os.path.join(work_dir, "session.tlog"), reader)


def _capped_note(ranker: Any) -> str:
    """The view's note while the fit is at the search's largest smoothing (``ranker``: the
    session's manoeuvre hook; the project's advisor then ranks under the nominal prior)."""
    text = "not known yet: the fit took the largest smoothing the search tries (the data do not yet tell the patterns' shape from flat)"
    from rplearn.workflows.live_advice import ManoeuvreAdvisor  # the ranking's module: only once a fit is capped

    return text + (ranker.capped_note() if isinstance(ranker, ManoeuvreAdvisor) else "")


def _capped(model: Any) -> bool:
    """Whether a fit took the search's largest smoothing (its spread is the cap's, not the data's)."""
    return model.training.smoothing is not None and at_smoothing_cap(model.training.smoothing)


class _Session:
    """The state of one live session (see :func:`run_live`)."""

    def __init__(self, options: LiveOptions, output: str, work_dir: str) -> None:
        self.options, self.output, self.work_dir = options, output, work_dir
        self.matcher = LiveMatcher(options.sync)
        self.stats: LiveStatistics | None = None
        self.fitted: Any = None
        self.status = LiveStatus()
        self.preq = Prequential()
        self.recent: deque[pd.DataFrame] = deque()
        self.deferred: list[pd.DataFrame] = []  # matched before the node list is fixed (see learn)
        self.held_nodes: frozenset[str] = frozenset()
        self.late_rows = 0  # matched rows naming a node outside the fixed node list (dropped: late_node)
        self.last_pose: dict[str, pd.Series] = {}
        self.new_samples = 0
        self.ranking = None if options.manoeuvres is None else RankingWorker(
            options.manoeuvres, options.rank_beside, options.ranking_every_s)
        self.shown: Ranking | None = None  # the ranking on view
        self.source_dropped: dict[str, int] = {}  # rows the source's reader dropped, per reason (a CSV's pose rows)
        self.source_where: dict[str, str] = {}  # where some of them were (Poll.where)
        self.fixed_said: list[str] = []  # the notes on the fixed nodes (say_fixed_nodes)

    def note(self, prefix: str, text: str | None = None) -> None:
        """Set (or, with no text, remove) the one note that starts with ``prefix``: a note
        repeated at every refit replaces the last, so the notes do not grow with the session."""
        kept = [n for n in self.status.notes if not n.startswith(prefix)]
        self.status.notes = kept + ([] if text is None else [prefix + text])

    def feed(self, poses: pd.DataFrame, signals: pd.DataFrame, held_nodes: frozenset[str] = frozenset()) -> None:
        self.held_nodes = held_nodes  # the source's: its nodes' first poses held back (Poll.held_nodes)
        if len(poses):
            self.matcher.add_poses(poses)
            if self.ranking is not None:  # only a ranking reads the latest poses
                self.last_pose.update((str(n), g.sort_values("t").iloc[-1]) for n, g in poses.groupby("node", sort=False))
        self.matcher.add_signals(signals)
        self.status.received += len(signals)

    def learn(self, final: bool = False) -> None:
        try:
            rows = self.matcher.match(final).dataset
        except InputError as exc:  # too few matched over the whole stream: the matched rows are learned
            if not final:  # refused in flight (as sync refuses the whole log): the rows taken for it are not matched
                raise
            rows = self.matcher.last_matched
            self.status.notes.append(str(exc))
        held = self.held_nodes
        if self.stats is None and not self.options.nodes and not final and (self.deferred or len(rows)) and held:
            # the source holds a node's first poses back (bounded by its hold): the node list, fixed by the first rows
            # learned, must name it too, so the rows matched meanwhile wait (a radio that logs no poses fixes nothing)
            self.deferred.append(rows)
            rows = rows.iloc[:0]
            self.note("nodes: ", f"learning waits for the first poses of {', '.join(sorted(held))} "
                                 "(the source holds its start back)")
        elif self.deferred:
            rows = pd.concat([*self.deferred, rows], ignore_index=True)
            self.deferred = []
            self.note("nodes: ")
        if len(rows):
            if self.stats is None:
                nodes = self.options.nodes or LiveStatistics.nodes_of(rows)
                self.stats = LiveStatistics(self.options.spec, nodes, self.options.fit,
                                            spool_dir=self.work_dir, max_segments=self.options.max_segments,
                                            keep_blocks=self.options.manoeuvres is not None)
            n, (rows, late) = len(rows), self.stats.known_rows(rows)
            if late:  # a node first matched after the node list was fixed: its rows are counted, the session goes on
                self.late_rows += n - len(rows)
                self.note("late: ", f"node(s) {', '.join(late)} appeared after the session fixed its nodes ({', '.join(self.stats.nodes)}): "
                                    "their rows are dropped (late_node); name every node with --nodes")
            samples = self.stats.samples(rows)
            if self.fitted is not None:  # predicted before it is learned from
                self.preq.add(samples.joint_gain_db - self.fitted.model.predict_gain(samples))
            self.stats.add(rows, samples)
            self.new_samples += len(samples)
            self.recent.append(rows)
            while sum(len(r) for r in self.recent) - len(self.recent[0]) >= BUDGET_WINDOW_ROWS:
                self.recent.popleft()
        s = self.status
        s.matched, s.pending = self.matcher.summary.n_out, self.matcher.pending_rows
        s.dropped = {**self.matcher.summary.dropped, **self.source_dropped, **({"late_node": self.late_rows} if self.late_rows else {})}
        s.dropped_where = dict(self.source_where)
        s.learned = 0 if self.stats is None else self.stats.n_samples
        s.prequential_rmse_db, s.prequential_n = self.preq.rmse_db(), self.preq.n_samples

    def say_fixed_nodes(self, summary: SyncSummary, metadata: Mapping[str, Any]) -> None:
        """The nodes the matching took as fixed, as ``sync`` says them: the summary's note and what each node is by
        where its poses came from (:func:`rplearn.workflows.logs.fixed_node_advice`; ``metadata``: the pose logs'
        :func:`rplearn.io.read_logs` metadata, the stream's name as their source). Said again, they replace the
        last."""
        from rplearn.workflows.logs import fixed_node_advice  # sync's pipeline: imported by a session that ends

        self.status.notes = [n for n in self.status.notes if n not in self.fixed_said]
        self.fixed_said = [n for n in summary.notes if n.startswith(FIXED_NOTE_START)]
        self.fixed_said += fixed_node_advice(summary.fixed_nodes, metadata, self.options.reader)
        self.status.notes += self.fixed_said

    def rematch_whole(self, src: MavlinkSource) -> None:
        """Learn the recorded MAVLink log afresh, matched whole, as ``sync`` (its reader's rules look at the whole log:
        the boot clock's median offset, the periods before a valid position), every node it names (unless ``--nodes``)."""
        from rplearn.data.sync import synchronise
        from rplearn.io.read import read_logs

        if self.stats is None:  # nothing learned (a silent stream: an empty recording)
            return
        try:
            logs, meta = read_logs([src.record_path], self.options.reader)
            if logs.pose is None or logs.signal is None:
                return
            result = synchronise(logs.pose, logs.signal, self.options.sync, src.record_path)
            meta = {**meta, "files": [{**f, "source": src.name} for f in meta.get("files", [])]}  # the stream's name
            self.say_fixed_nodes(result.summary, meta)
        except InputError as exc:  # the rows learned in flight stay; the working recording is named as the stream
            self.status.notes.append("last refit: the recorded stream matched whole was refused, the rows learned in flight "
                                     f"kept: {str(exc).replace(src.record_path, f'the recording of {src.name}')}")
            return
        rows = result.dataset.sort_values("t", kind="stable").reset_index(drop=True)
        before = self.stats.n_samples
        named = LiveStatistics.nodes_of(rows) if len(rows) else self.stats.nodes
        self.stats = LiveStatistics(self.options.spec, self.options.nodes or named, self.options.fit, spool_dir=self.work_dir,
                                    max_segments=self.options.max_segments, keep_blocks=self.options.manoeuvres is not None)
        rows = self.stats.known_rows(rows)[0] if len(rows) else rows  # --nodes: the others' rows are not learned
        if len(rows):
            self.stats.add(rows, self.stats.samples(rows, src.record_path))
        self.new_samples = len(rows)
        s = self.status
        s.received, s.matched, s.pending, s.dropped = result.summary.n_in, result.summary.n_out, 0, dict(result.summary.dropped)
        s.learned = self.stats.n_samples
        s.notes.append(f"last refit: the recorded log matched whole, as sync does ({len(rows)} samples; "
                       f"{before} were learned in flight)")

    def refit(self, final: bool = False) -> bool:
        if self.stats is None or (not self.new_samples and not final):
            return False
        t0 = time.perf_counter()
        try:
            fitted = self.stats.refit(final=final, provenance={"source": "rplearn live"})
        except RplearnError as exc:  # too few samples yet
            self.note("waiting: ", str(exc))
            return False
        self.status.refit_ms = 1e3 * (time.perf_counter() - t0)
        fitted.model.save(self.output)  # atomic: an interrupted session keeps the last good model
        self.fitted, self.new_samples = fitted, 0
        self.status.refits += 1
        self.note("waiting: ")
        self.note("--fixed ", fixed_nodes_note(self.options.fixed_nodes, self.fitted.model.nodes))
        mismatch = getattr(self.options.manoeuvres, "mismatch", None)  # ManoeuvreAdvisor's: --from-model not of this session
        why = mismatch(fitted) if callable(mismatch) else None
        self.note("--from-model ", None if why is None else f"{why}; the manoeuvres are ranked with the session's own instead")
        late = 0 if self.stats.drift is None else self.stats.drift.late_rows  # the drift's blocks: rows that came late
        self.note("drift: ", f"{late} samples came after later 5-s blocks were folded: their blocks are counted in parts" if late else None)
        self._describe()
        if self.ranking is not None and self.stats is not None:
            self.ranking.submit(self._snapshot, self.status.refits)
            self.show_ranking()
        return True

    def _snapshot(self) -> tuple[Any, Any, pd.DataFrame]:
        """What a ranking reads, none of it touched by the loop after: the sum of the statistics
        (a new object) with a closed copy of the time-block sums, this refit's model (never
        changed after it is made), the latest pose of every node."""
        assert self.stats is not None
        total = self.stats.total()
        if total.blocks is not None:
            total.blocks = total.blocks.closed()
        return total, self.fitted, pd.DataFrame(list(self.last_pose.values())).reset_index(drop=True)

    def show_ranking(self) -> bool:
        """Take a ranking finished since the last call into the status; its age. Whether one was taken."""
        if self.ranking is None:
            return False
        done, s = self.ranking.collect(), self.status
        if done is not None:
            if done.error:
                self.note("manoeuvres: ", done.error)
            else:
                self.note("manoeuvres: ")
                self.shown = done
                s.manoeuvres = list(done.rows[:3])
                s.manoeuvres_refit, s.ranking_s = done.refit, done.took_s
        if self.shown is not None:
            s.manoeuvres_age_s = self.ranking.clock() - self.shown.finished_s
        s.ranking_running = self.ranking.running
        return done is not None

    def stop_ranking(self, timeout_s: float) -> None:
        """At a stop: wait at most ``timeout_s`` for a running ranking (:data:`STOP_RANKING_WAIT_S`),
        then no more rankings; its result is dropped."""
        if self.ranking is not None and not self.ranking.wait(timeout_s):
            self.note("stop: ", f"a manoeuvre ranking still running {timeout_s:g} s after the stop was dropped; "
                                "the last refit ran under its BLAS limit of one thread")
        self.close_ranking(wait=False)

    def close_ranking(self, wait: bool) -> None:
        """No more rankings: with ``wait``, the running one is waited for and shown; else dropped."""
        if self.ranking is None:
            return
        if wait:
            self.ranking.wait()
            self.show_ranking()
        self.ranking.close()
        self.status.ranking_running = False

    def _describe(self) -> None:
        s, model = self.status, self.fitted.model
        s.model = model.label
        noise = model.training.noise_std_db if model.training.noise_std_db is not None else model.training.rmse_db
        s.noise_db = math.nan if noise is None else float(noise)
        # at the search's largest smoothing the data do not identify the shape: its spread (about
        # none) is the cap's, not a measurement, and can end no session (shown as inf)
        capped = _capped(model)
        try:
            cert = decoupling_certificate(model, posterior=self.fitted.own_posterior)
            for node, spread in cert.nodes.items():
                s.coverage_pct[node] = 100.0 * spread.covered_fraction
                s.spread_db[node] = math.inf if capped else spread.covered_std_db
                s.sphere_spread_db[node] = math.inf if capped else spread.sphere_std_db
            self.note("spread: ", _capped_note(self.options.manoeuvres) if capped else None)
        except InputError as exc:
            self.note("spread: ", str(exc))
        if self.recent and self.stats is not None:
            window = pd.concat(list(self.recent), ignore_index=True)
            s.budget = [f.text for f in check_fit_budget(model, self.stats.samples(window))]

    def write_page(self, path: str | None) -> None:
        if path is None:
            return
        from rplearn.viz.live_page import write_live_page

        rows, node_rows = page_rows(self.status)
        model = None if self.fitted is None else self.fitted.model
        write_live_page(path, "rplearn live", rows, node_rows, model, refresh_s=max(self.options.refit_s, 1.0),
                        spread_known=model is None or not _capped(model))

    def stop_reason(self, elapsed_s: float) -> str:
        o, s = self.options, self.status
        if o.duration_s is not None and elapsed_s >= o.duration_s:
            return f"duration {o.duration_s:g} s reached"
        if not s.spread_db or (o.until_spread_db is None and o.until_coverage_pct is None):
            return ""
        spread = s.sphere_spread_db if o.spread_over == "sphere" else s.spread_db
        spread_ok = o.until_spread_db is None or max(spread.values()) < o.until_spread_db
        cover_ok = o.until_coverage_pct is None or min(s.coverage_pct.values()) >= o.until_coverage_pct
        if spread_ok and cover_ok:
            over = "over the sphere" if o.spread_over == "sphere" else "over the covered directions"
            what = [f"every node's spread {over} below {o.until_spread_db:g} dB" if o.until_spread_db is not None else "",
                    f"every node's coverage at least {o.until_coverage_pct:g}%" if o.until_coverage_pct is not None else ""]
            return " and ".join(w for w in what if w)
        return ""


@check_types
def run_live(
    source: str,
    output: str,
    options: LiveOptions | None = None,
    on_update: Callable[[LiveStatus], None] | None = None,
    record: str | None = None,
    html: str | None = None,
) -> LiveOutcome:
    """Learn from a live source until it ends or a stop criterion holds (module docstring).

    Parameters
    ----------
    source : str
        A MAVLink connection string (``udpin:0.0.0.0:14550``, ``tcp:host:port``, a serial
        device) or ``POSE.csv,SIGNAL.csv``.
    output : str
        Model file (JSON), rewritten atomically at every refit.
    options : LiveOptions, optional
    on_update : callable, optional
        Called with the :class:`LiveStatus` after every poll that matched rows and every refit.
    record : str, optional
        Where to keep the received MAVLink stream as a ``.tlog`` (written at the end).
    html : str, optional
        A page with the same numbers and the coverage and spread maps, rewritten atomically at
        every refit and when a ranking of the manoeuvres finishes (the browser reloads it).

    Returns
    -------
    LiveOutcome
    """
    options = options or LiveOptions()
    check_live_source(source)
    earlier = getattr(getattr(options.manoeuvres, "earlier", None), "path", None)  # ManoeuvreAdvisor's --from-model
    check_live_outputs(source, output, record, html, earlier if isinstance(earlier, str) else None)
    work_dir = tempfile.mkdtemp(prefix="rplearn-live-")
    src = open_source(source, work_dir, options.reader)
    session = _Session(options, output, work_dir)
    start = last_refit = time.monotonic()
    # the silence that ends the stream counts from its first message; a file (a .tlog read as a connection) from the start
    last_rx: float | None = start if os.path.isfile(source) else None
    try:
        while True:
            got = src.poll()
            now = time.monotonic()
            session.source_dropped, session.source_where = dict(got.dropped), dict(got.where)
            session.feed(got.poses, got.signals, got.held_nodes)
            if got.received:
                last_rx = now
            if len(got.signals) or len(got.poses):
                session.learn()
                if on_update is not None:
                    session.status.elapsed_s = now - start
                    on_update(session.status)
            if now - last_refit >= options.refit_s and session.refit():
                last_refit = now
                session.status.elapsed_s = now - start
                session.write_page(html)
                if on_update is not None:
                    on_update(session.status)
            elif session.show_ranking():  # a ranking beside the loop finished: shown now, not at the next refit
                session.status.elapsed_s = now - start
                session.write_page(html)
                if on_update is not None:
                    on_update(session.status)
            reason = session.stop_reason(now - start)
            if not reason and last_rx is not None and now - last_rx >= options.idle_s:
                reason = f"end of stream (nothing received for {options.idle_s:g} s)"
            if reason:
                session.status.stopped = reason
                break
            if not got.received:
                time.sleep(0.05)
        session.stop_ranking(STOP_RANKING_WAIT_S)  # briefly waited for (its BLAS limit), then dropped
        last = src.poll(final=True)
        mavlink = isinstance(src, MavlinkSource)  # its recording is rematched whole below
        session.source_dropped, session.source_where = ({}, {}) if mavlink else (dict(last.dropped), dict(last.where))
        session.feed(last.poses, last.signals, last.held_nodes)
        session.learn(final=True)
        from rplearn.workflows.live_checks import source_pose_metadata

        session.say_fixed_nodes(session.matcher.summary, source_pose_metadata(source, options.reader.station))
        if isinstance(src, MavlinkSource):
            src.close()
            session.rematch_whole(src)  # the whole recording's fixed nodes said instead
        session.refit(final=True)
        session.status.elapsed_s = time.monotonic() - start
        session.write_page(html)
        if on_update is not None:
            on_update(session.status)
    finally:
        session.close_ranking(wait=False)
        src.close()
        if record is not None and isinstance(src, MavlinkSource) and os.path.getsize(src.record_path):  # not when silent
            with atomic_path(record) as tmp:
                shutil.copyfile(src.record_path, tmp)
        shutil.rmtree(work_dir, ignore_errors=True)
    if session.fitted is None:
        messages = src.messages if isinstance(src, MavlinkSource) else None
        raise InputError(no_model_message(source, session.status, messages, time.monotonic() - start), param="source")
    return LiveOutcome(session.status, session.fitted, session.preq, output)


@check_types
def replay_session(
    pose_log: pd.DataFrame,
    signal_log: pd.DataFrame,
    output: str,
    options: LiveOptions | None = None,
    batch_s: float = 1.0,
    on_update: Callable[[LiveStatus], None] | None = None,
) -> LiveOutcome:
    """A live session on logs already written, fed ``batch_s`` of log time at a time with no
    waiting: the same matching, prequential prediction, statistics and refits (every
    ``options.refit_s`` of log time) as :func:`run_live`, deterministic (tests, benchmarks,
    a flight log learned as it would have been in flight). Stops at ``until_*`` criteria and
    ``duration_s`` (log time) as :func:`run_live` does; the model file is written at every refit;
    ``on_update(status)`` after every batch. A manoeuvre ranking beside the loop
    (``options.rank_beside``) is not deterministic in which refits it ranks (a refit while one
    runs starts none); at the end the running one is waited for, then the last model is ranked
    (when ``ranking_every_s`` allows) and waited for, as the loop would show it.
    """
    options = options or LiveOptions()
    if not batch_s > 0:
        raise InputError(f"batch_s: expected a positive number of seconds, got {batch_s}", param="batch_s")
    check_output(output, [])
    work_dir = tempfile.mkdtemp(prefix="rplearn-live-")
    session = _Session(options, output, work_dir)
    try:
        pt = pose_log["t"].to_numpy(np.float64)
        st = signal_log["t"].to_numpy(np.float64)
        t0 = float(min(pt.min(), st.min()))
        end = float(max(pt.max(), st.max()))
        last_refit = t0
        edge = t0
        while edge <= end:
            nxt = edge + batch_s
            session.feed(pose_log[(pt >= edge) & (pt < nxt)], signal_log[(st >= edge) & (st < nxt)])
            session.learn()
            if nxt - last_refit >= options.refit_s and session.refit():
                last_refit = nxt
            else:
                session.show_ranking()
            session.status.elapsed_s = nxt - t0
            if on_update is not None:
                on_update(session.status)
            reason = session.stop_reason(nxt - t0)
            edge = nxt
            if reason:
                session.status.stopped = reason
                break
        session.learn(final=True)
        if session.ranking is not None:  # deterministic: the last model is ranked as in the loop
            session.ranking.wait()
        session.refit(final=True)
        session.close_ranking(wait=True)
        if not session.status.stopped:
            session.status.stopped = "end of the logs"
    finally:
        session.close_ranking(wait=False)
        shutil.rmtree(work_dir, ignore_errors=True)
    if session.fitted is None:
        raise InputError(f"the logs ended before a model could be learned ({session.status.learned} samples learned)",
                         param="signal_log")
    return LiveOutcome(session.status, session.fitted, session.preq, output)


__all__ = ["BUDGET_WINDOW_ROWS", "STOP_RANKING_WAIT_S", "LiveOptions", "LiveOutcome", "ManoeuvreRanker", "open_source", "replay_session", "run_live"]
