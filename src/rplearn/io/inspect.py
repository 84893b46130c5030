"""Look at logs before learning from them: nodes, spans, rates, RSSI range, gaps, oddities.

:func:`inspect_logs` is the library function behind ``rplearn inspect``. It reads every file
with the readers of :mod:`rplearn.io` in a forgiving mode (NaN pose rows dropped and counted,
unsorted times accepted and reported) and returns an :class:`InspectReport` whose
:meth:`~InspectReport.to_text` and :meth:`~InspectReport.to_markdown` the CLI prints.

Flagged as suspicious: unreadable files, NaN pose rows, quaternions whose norm is off 1 by
more than :data:`~rplearn.data.tables.QUATERNION_NORM_TOLERANCE`, times going backwards, forward
clock jumps, pose gaps longer than ``max_gap_s``, sentinel or non-finite RSSI values, exact
duplicate signal rows, signals naming a node without a pose log, signal samples outside every
pose span, and rates far from the expected ones.

Pauses, gaps and clock jumps. A forward pose step longer than ``max_gap_s`` is a **pause**
when the signal log of that node stops too: it has samples before and after the step, none
inside (ignoring ``max_gap_s`` at either end, clock jitter), and that inside lasts more than :data:`PAUSE_MIN_SIGNAL_STEPS` median signal intervals
(so that a sparse signal log cannot fake one). Planned breaks between flight units (battery
swaps) are pauses; they lose no sample and are reported, not flagged. Any other such step is
a **gap** (poses missing while signals continue, or no signal log to tell): the samples inside
are dropped by :mod:`rplearn.data.sync`. A gap longer than ``clock_jump_s`` is also reported as a
possible **clock jump**: a logger's clock stepping forward looks exactly like that.

Times are printed in seconds from the **log start** (the first pose of a moving node, printed
once on the log's own clock): the same origin as ``sync``'s time window. Each reader finding is
listed under its file: periods the reader excluded (before a valid position solution, across a
reboot; ``excluded_periods`` in the reader metadata) with their reasons and row counts, and the
rows it dropped by reason. Link rates are report rates: copies of one reading
(:mod:`rplearn.data.readings`, merged by ``sync``) are counted once. A log that holds **no
calibration flight** (no node ever airborne, or two linked nodes never farther apart than a
few wavelengths: :func:`rplearn.data.phases.calibration_problems`) is a problem.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.data.phases import advised_max_gap_s, calibration_problems, flight_phases
from rplearn.data.poses import PoseTrack, pose_tracks, tracks_of_checked_log
from rplearn.data.readings import REPEAT_FRACTION, duplicate_rows, repeated_readings, report_period_s, report_rate_hz
from rplearn.data.sync import DEFAULT_SENTINEL_RSSI_DBM, PLAUSIBLE_RSSI_DBM
from rplearn.data.sync_notes import fixed_nodes
from rplearn.data.tables import QUATERNION_NORM_TOLERANCE, outage_mask, validate_pose_log
from rplearn.errors import InputError, RplearnError
from rplearn.io._csv_headers import REPEATED_HEADER, REPEATED_HEADER_AT, repeated_header_text
from rplearn.io.damage import across_files, file_damage
from rplearn.io.inspect_files import read_for_inspection
from rplearn.io.options import ReaderOptions

#: A pose step is a pause only if it spans more than this many median signal intervals.
PAUSE_MIN_SIGNAL_STEPS: float = 3.0


@check_types
@dataclass
class NodeSummary:
    """One node's pose log.

    Attributes: ``rows``; ``t_start_s``, ``t_end_s`` [s]; ``rate_hz`` (1 / median step);
    ``gaps`` (steps longer than ``max_gap_s`` that are not pauses) and ``longest_gap_s`` (the
    longest step that is not a pause); ``pauses`` (steps where the signal log stops too, see
    the module docstring) and ``longest_pause_s``; ``backward_steps`` (times going backwards);
    ``clock_jumps`` (gaps longer than ``clock_jump_s``); ``nan_rows`` (dropped on reading);
    ``static`` (a single row); ``fixed`` (taken as holding still, as ``sync`` takes it: a single
    row or only identical rows, :func:`rplearn.data.sync_notes.fixed_nodes`).
    """

    node: str
    rows: int
    t_start_s: float
    t_end_s: float
    rate_hz: float
    gaps: int
    longest_gap_s: float
    backward_steps: int = 0
    clock_jumps: int = 0
    nan_rows: int = 0
    static: bool = False
    pauses: int = 0
    longest_pause_s: float = 0.0
    fixed: bool = False


@check_types
@dataclass
class LinkSummary:
    """One direction tx -> rx of the signal log: counts, span, report rate [Hz] (copies of one
    reading counted once), RSSI range [dBm], exact duplicate rows and repeated readings."""

    tx: str
    rx: str
    samples: int
    t_start_s: float
    t_end_s: float
    rate_hz: float
    rssi_min_dbm: float
    rssi_median_dbm: float
    rssi_max_dbm: float
    sentinel_rssi: int
    backward_steps: int = 0
    duplicates: int = 0
    repeated_readings: int = 0
    period_s: float = float("nan")
    #: Readings whose RSSI no radio reports in dBm (outside the plausible range, or above the
    #: transmit power): ``sync`` drops them as ``implausible_rssi``.
    implausible_rssi: int = 0


@check_types
@dataclass
class InspectReport:
    """What :func:`inspect_logs` found; ``problems`` lists everything suspicious, one line each;
    ``start_s`` is the log start [s, log clock] that printed times count from; ``calibration``
    lists why the logs hold no calibration flight (also in ``problems``); ``fixed_nodes`` names
    the nodes ``sync`` holds at their pose (a pose log of one row, or of identical rows: a ground
    station, a parked drone), and ``fixed_note`` says so (None without any)."""

    files: list[dict[str, Any]] = field(default_factory=list)
    nodes: list[NodeSummary] = field(default_factory=list)
    links: list[LinkSummary] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    start_s: float = 0.0
    calibration: list[str] = field(default_factory=list)
    fixed_nodes: list[str] = field(default_factory=list)
    fixed_note: str | None = None

    @property
    def ok(self) -> bool:
        return not self.problems

    def _rel(self, t_s: float) -> str:
        return f"{t_s - self.start_s:.3f}"

    def findings(self, f: dict[str, Any]) -> list[str]:
        """A file's reader findings: excluded periods (times from the log start) and drops."""
        out = [f"excluded ({p.get('reason', '?')}): {self._rel(float(p['from_t']))} .. {self._rel(float(p['to_t']))} s, "
               f"{int(p.get('pose_rows', 0))} pose row(s), {int(p.get('signal_rows', 0))} signal row(s)"
               + (f": {p['detail']}" if p.get("detail") else "") for p in f.get("excluded_periods") or ()]
        for what, counts in (("pose", f.get("dropped")), ("signal", f.get("signal_dropped"))):
            out += ["dropped on reading: " + (repeated_header_text(n, f.get(REPEATED_HEADER_AT, ())) if why == REPEATED_HEADER
                                              else f"{n:,} {what} row(s) ({why})") for why, n in (counts or {}).items() if n]
        return out

    def to_text(self) -> str:
        out = [f"log start: t = {self.start_s:.3f} s on the log's clock; times below are seconds from it", "files:"]
        for f in self.files:
            out.append(f"  {f['path']}: {f['format']}" + (f" ({f['kind']} log)" if f.get("kind") else "")
                       + ("" if f.get("error") is None else f"  UNREADABLE: {f['error']}"))
            out.extend(f"    {note}" for note in [*f.get("notes", ()), *self.findings(f)])
        out.append("pose logs:")
        for n in self.nodes:
            span = "static" if n.static else (
                f"{self._rel(n.t_start_s)} .. {self._rel(n.t_end_s)} s ({n.t_end_s - n.t_start_s:.1f} s), "
                f"{n.rate_hz:.1f} Hz, gaps > threshold: {n.gaps} (longest {n.longest_gap_s:.3f} s)"
                + (f", pauses (signals stop too): {n.pauses} (longest {n.longest_pause_s:.1f} s)" if n.pauses else ""))
            out.append(f"  {n.node}: {n.rows} rows, {span}" + (", fixed" if n.fixed else ""))
        out += [f"  {self.fixed_note}"] if self.fixed_note else []
        out.append("signal links:")
        for lk in self.links:
            out.append(
                f"  {lk.tx} -> {lk.rx}: {lk.samples} samples, {self._rel(lk.t_start_s)} .. {self._rel(lk.t_end_s)} s, "
                f"{lk.rate_hz:.1f} Hz, RSSI {lk.rssi_min_dbm:.1f} / {lk.rssi_median_dbm:.1f} / "
                f"{lk.rssi_max_dbm:.1f} dBm (min/median/max), sentinel values: {lk.sentinel_rssi}"
                + (f", exact duplicate rows: {lk.duplicates}" if lk.duplicates else "")
                + (f", repeated readings: {lk.repeated_readings}" if lk.repeated_readings else ""))
        out.append("problems:" if self.problems else "problems: none found")
        out.extend(f"  - {p}" for p in self.problems)
        return "\n".join(out)

    def to_markdown(self) -> str:
        out = [f"Times in seconds from the log start, t = {self.start_s:.3f} s on the log's clock.", "",
               "## Files", "", "| path | format | kind | status |", "| --- | --- | --- | --- |"]
        for f in self.files:
            out.append(f"| {f['path']} | {f['format']} | {f.get('kind', '?')} | "
                       f"{'ok' if f.get('error') is None else 'unreadable: ' + f['error']} |")
        found = [f"- {f['path']}: {line}" for f in self.files for line in self.findings(f)]
        out += ["", "## Reader findings", "", *found] if found else []
        out += ["", "## Pose logs", "",
                "| node | rows | start [s] | end [s] | rate [Hz] | gaps | longest gap [s] | pauses | "
                "longest pause [s] | NaN rows | fixed |",
                "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
        for n in self.nodes:
            out.append(f"| {n.node} | {n.rows} | {self._rel(n.t_start_s)} | {self._rel(n.t_end_s)} | {n.rate_hz:.1f} | "
                       f"{n.gaps} | {n.longest_gap_s:.3f} | {n.pauses} | {n.longest_pause_s:.1f} | {n.nan_rows} | "
                       f"{'yes' if n.fixed else 'no'} |")
        out += ["", self.fixed_note] if self.fixed_note else []
        out += ["", "## Signal links", "",
                "| tx | rx | samples | start [s] | end [s] | rate [Hz] | RSSI min [dBm] | median | max | sentinels "
                "| duplicates | repeated readings |",
                "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
        for lk in self.links:
            out.append(f"| {lk.tx} | {lk.rx} | {lk.samples} | {self._rel(lk.t_start_s)} | {self._rel(lk.t_end_s)} | "
                       f"{lk.rate_hz:.1f} | {lk.rssi_min_dbm:.1f} | {lk.rssi_median_dbm:.1f} | "
                       f"{lk.rssi_max_dbm:.1f} | {lk.sentinel_rssi} | {lk.duplicates} | {lk.repeated_readings} |")
        out += ["", "## Problems", ""]
        out += [f"- {p}" for p in self.problems] or ["none found"]
        return "\n".join(out)


def _steps(t: np.ndarray) -> np.ndarray:
    return np.diff(t) if t.size > 1 else np.zeros(0)


def _rate_hz(t: np.ndarray) -> float:
    d = _steps(np.sort(t))
    d = d[d > 0]
    return float(1.0 / np.median(d)) if d.size else float("nan")


def _signal_times_by_node(signal: pd.DataFrame | None) -> dict[str, np.ndarray]:
    """Sorted finite times [s] of the signal samples each node sends or receives."""
    if signal is None or signal.empty:
        return {}
    t = pd.to_numeric(signal["t"], errors="coerce").to_numpy(np.float64)
    tx = signal["tx"].astype(str).to_numpy()
    rx = signal["rx"].astype(str).to_numpy()
    out = {}
    for node in set(tx) | set(rx):
        tn = t[((tx == node) | (rx == node)) & np.isfinite(t)]
        out[str(node)] = np.sort(tn)
    return out


def pause_mask(t0_s: np.ndarray, t1_s: np.ndarray, signal_t_s: np.ndarray | None,
               edge_s: float = 0.0) -> np.ndarray:
    """Which pose steps ``t0 -> t1`` are pauses: the node's signals stop over them too.

    A step is a pause when the sorted signal times ``signal_t_s`` have samples before ``t0``
    and after ``t1``, none inside ``(t0 + edge_s, t1 - edge_s)`` (a packet logged just after
    the last pose is clock jitter, not a dropout), and that interval is longer than
    :data:`PAUSE_MIN_SIGNAL_STEPS` median signal intervals. Without signals nothing is a pause.
    """
    if signal_t_s is None or signal_t_s.size < 2 or t0_s.size == 0:
        return np.zeros(t0_s.size, bool)
    a_s, b_s = t0_s + edge_s, t1_s - edge_s
    lo = np.searchsorted(signal_t_s, a_s, side="right")
    hi = np.searchsorted(signal_t_s, b_s, side="left")
    before = np.searchsorted(signal_t_s, t0_s, side="right") > 0
    after = np.searchsorted(signal_t_s, t1_s, side="left") < signal_t_s.size
    step = _steps(signal_t_s)
    step = step[step > 0]
    min_len_s = PAUSE_MIN_SIGNAL_STEPS * float(np.median(step)) if step.size else np.inf
    return before & after & (hi <= lo) & (b_s - a_s > min_len_s)


def summarise_pose(pose: pd.DataFrame, max_gap_s: float = 0.2, clock_jump_s: float = 5.0,
                   nan_rows: dict[str, int] | None = None,
                   signal: pd.DataFrame | None = None) -> list[NodeSummary]:
    """Per-node summaries of a pose log in file order (unsorted times are counted, not fixed).

    With ``signal`` (a signal log), steps where the node's signals stop too are pauses, not
    gaps or clock jumps (see the module docstring).
    """
    sig_t = _signal_times_by_node(signal)
    out = []
    for node, g in pose.groupby("node", sort=True):
        t = g["t"].to_numpy(np.float64)
        d = _steps(t)
        back = int((d < 0).sum())
        ts = np.sort(t)
        ds = _steps(ts)
        long = ds > max_gap_s
        pause = np.zeros(ds.size, bool)
        pause[long] = pause_mask(ts[:-1][long], ts[1:][long], sig_t.get(str(node)), edge_s=max_gap_s)
        gaps = long & ~pause
        other = ds[~pause]
        out.append(NodeSummary(
            node=str(node), rows=int(t.size), t_start_s=float(ts[0]), t_end_s=float(ts[-1]),
            rate_hz=_rate_hz(t), gaps=int(gaps.sum()),
            longest_gap_s=float(other.max()) if other.size else 0.0, backward_steps=back,
            clock_jumps=int((gaps & (ds > clock_jump_s)).sum()),
            nan_rows=int((nan_rows or {}).get(str(node), 0)), static=t.size == 1,
            pauses=int(pause.sum()), longest_pause_s=float(ds[pause].max()) if pause.any() else 0.0,
        ))
    return out


def summarise_signal(signal: pd.DataFrame,
                     sentinel_rssi_dbm: Sequence[float] = DEFAULT_SENTINEL_RSSI_DBM) -> list[LinkSummary]:
    """Per-direction summaries of a signal log's received packets (sentinel and non-finite RSSI
    counted apart; the rate counts repeated readings once; outage events, which the reader's
    notes count, left out)."""
    signal = signal[~outage_mask(signal)] if "outage" in signal.columns else signal
    out = []
    dup = pd.Series(duplicate_rows(signal), index=signal.index)
    repeated = pd.Series(repeated_readings(signal), index=signal.index)
    for (tx, rx), g in signal.groupby(["tx", "rx"], sort=True):
        t = pd.to_numeric(g["t"], errors="coerce").to_numpy(np.float64)
        r = pd.to_numeric(g["rssi_dbm"], errors="coerce").to_numpy(np.float64)
        bad = ~np.isfinite(r) | np.isin(r, np.asarray(sentinel_rssi_dbm, float))
        good = r[~bad]
        ptx = pd.to_numeric(g["tx_power_dbm"], errors="coerce").to_numpy(np.float64)[~bad] \
            if "tx_power_dbm" in g.columns else np.full(good.size, np.inf)
        implausible = (good < PLAUSIBLE_RSSI_DBM[0]) | (good > PLAUSIBLE_RSSI_DBM[1]) | (good > ptx)
        tf = t[np.isfinite(t)]
        copies = repeated.loc[g.index].to_numpy(bool)
        out.append(LinkSummary(
            tx=str(tx), rx=str(rx), samples=int(len(g)),
            t_start_s=float(tf.min()) if tf.size else np.nan, t_end_s=float(tf.max()) if tf.size else np.nan,
            rate_hz=report_rate_hz(t, copies), rssi_min_dbm=float(good.min()) if good.size else np.nan,
            rssi_median_dbm=float(np.median(good)) if good.size else np.nan,
            rssi_max_dbm=float(good.max()) if good.size else np.nan,
            sentinel_rssi=int(bad.sum()), backward_steps=int((_steps(tf) < 0).sum()),
            duplicates=int(dup.loc[g.index].sum()), repeated_readings=int(copies.sum()),
            period_s=report_period_s(t), implausible_rssi=int(implausible.sum()),
        ))
    return out


@check_types
def inspect_logs(
    paths: str | os.PathLike | Iterable[str | os.PathLike],
    options: ReaderOptions | None = None,
    max_gap_s: float = 0.2,
    clock_jump_s: float = 5.0,
    sentinel_rssi_dbm: Sequence[float] = DEFAULT_SENTINEL_RSSI_DBM,
) -> InspectReport:
    """Summarise logs and flag anything suspicious; never raises on a bad file (it is reported).

    Parameters
    ----------
    paths : path or iterable of paths
        Logs of any format :func:`rplearn.io.read_logs` reads.
    options : ReaderOptions, optional
        How to read them (pose topics, receivers, address map, ...), as for
        :func:`rplearn.io.read_logs`. Inspection reads forgivingly whatever
        ``nan_policy`` and ``allow_unsorted`` say, and puts placeholders where ``tx_power_dbm``
        [dBm], ``frequency_hz`` [Hz], a ULog's node id (its file name) or a pcap's receiver
        (``capture``) are missing: it does not need them.
    max_gap_s : float
        Pose steps longer than this are gaps [s] (the matching threshold of :mod:`rplearn.data.sync`).
    clock_jump_s : float
        A gap (not a pause) longer than this is reported as a possible clock jump [s].
    sentinel_rssi_dbm : sequence of float
        RSSI values meaning "no measurement" [dBm].

    Returns
    -------
    InspectReport
    """
    if options is None:
        options = ReaderOptions()
    if isinstance(paths, str) or hasattr(paths, "__fspath__"):
        paths = [paths]  # type: ignore[list-item]
    report = InspectReport()
    poses, signals, canonical = [], [], []
    owners: dict[str, list[int]] = {"pose": [], "signal": []}
    nan_rows: dict[str, int] = {}
    for p in paths:
        path = str(p)
        try:
            pose, sig, info, nans, full = read_for_inspection(path, options)
        except RplearnError as exc:
            report.files.append({"path": path, "format": "?", "kind": None, "error": str(exc)})
            report.problems.append(f"{path}: unreadable: {exc}")
            continue
        report.files.append({"path": path, **info, "error": None})
        _flag_file(report, path, info)
        for k, v in nans.items():
            nan_rows[k] = nan_rows.get(k, 0) + int(v)
        if pose is not None:
            poses.append(pose)
            owners["pose"].append(len(report.files) - 1)
        if sig is not None:
            signals.append(sig)
            owners["signal"].append(len(report.files) - 1)
        if full is not None:
            canonical.append(full)
    poses, signals = across_files(report, poses, canonical, signals, owners)
    signal = pd.concat(signals, ignore_index=True) if signals else None
    if poses:
        report.nodes = summarise_pose(pd.concat(poses, ignore_index=True), max_gap_s, clock_jump_s, nan_rows,
                                      signal)
    if signal is not None:
        report.links = summarise_signal(signal, sentinel_rssi_dbm)
    starts = [n.t_start_s for n in report.nodes if not n.static] or [n.t_start_s for n in report.nodes] or [
        lk.t_start_s for lk in report.links if np.isfinite(lk.t_start_s)]
    report.start_s = float(min(starts)) if starts else 0.0
    frequencies = [f["frequency_hz"] for f in report.files if f.get("frequency_hz")]
    if not frequencies and isinstance(options.frequency_hz, (int, float)):
        frequencies = [float(options.frequency_hz)]  # the user's, for logs that do not say it
    pose, tracks = _tracks(canonical)
    if pose is not None and tracks is not None:
        _flag_moved_station(report, pose, max_gap_s, [report.files[i]["path"] for i in owners["pose"]])
        pairs = [(lk.tx, lk.rx) for lk in report.links] or None
        report.calibration = calibration_problems(flight_phases(pose, tracks), tracks, pairs,
                                                  min(frequencies) if frequencies else None)
        _name_fixed(report, tracks)
    _flag(report, max_gap_s)
    return report


def _tracks(poses: list[pd.DataFrame]) -> tuple[pd.DataFrame | None, dict[str, PoseTrack] | None]:
    """The canonical pose logs as one, and its nodes' tracks as ``sync`` makes them; None for both when the poses
    cannot be checked (no pose log, or logs that disagree: said by the reading)."""
    if not poses:
        return None, None
    try:
        pose = pd.concat(poses, ignore_index=True)
        return pose, pose_tracks(pose)
    except RplearnError:
        return None, None


def _flag_moved_station(report: InspectReport, pose: pd.DataFrame, max_gap_s: float, files: list[str]) -> None:
    """A node that holds still at one pose and later at another with no pose between (a station moved between
    flights), which ``sync`` refuses with the same ``max_gap_s``: said as a problem (was: not a word, neither
    fixed nor flagged, when the move fell in a pause of the signals)."""
    source = ", ".join(files) or "pose log"
    try:
        tracks_of_checked_log(validate_pose_log(pose, source), None, source, max_gap_s)
    except InputError as exc:
        report.problems.append(f"{exc} (sync refuses these poses)")
    except RplearnError:
        pass  # said by the reading


def _name_fixed(report: InspectReport, tracks: dict[str, PoseTrack]) -> None:
    """The nodes ``sync`` holds at their pose (:func:`~rplearn.data.sync_notes.fixed_nodes`, its own test), named
    in the report and flagged per node."""
    report.fixed_nodes = fixed_nodes(tracks)
    for n in report.nodes:
        n.fixed = n.node in report.fixed_nodes
    if report.fixed_nodes:
        said = [f"{node} ({'one pose row' if tracks[node].static else 'identical pose rows'})"
                for node in report.fixed_nodes]
        report.fixed_note = (f"fixed node(s), held at their one pose by sync (a pose log of one row, or of identical "
                             f"rows: a ground station, a parked drone; if one moved, its motion was not logged): "
                             f"{', '.join(said)}")


def _flag_file(report: InspectReport, path: str, info: dict[str, Any]) -> None:
    """Problems of one file: a cut-off or corrupt file, rows flagged invalid by the autopilot,
    non-unit quaternions."""
    for line in file_damage(path, info):
        report.problems.append(line)
    if info.get("invalid_flag_rows"):
        report.problems.append(
            f"{path}: {info['invalid_flag_rows']} pose row(s) flagged invalid by the autopilot "
            "(xy_valid or z_valid = 0); they are kept unless dropped on reading "
            "(ReaderOptions.require_valid=True)"
        )
    if info.get("non_unit_quaternion_rows"):
        report.problems.append(
            f"{path}: {info['non_unit_quaternion_rows']} pose row(s) with a quaternion norm off 1 by "
            f"more than {QUATERNION_NORM_TOLERANCE:g} (normalised on reading; a scaling or unit mistake?)"
        )


def _flag(report: InspectReport, max_gap_s: float) -> None:
    known = {n.node: n for n in report.nodes}
    report.problems.extend(report.calibration)
    for n in report.nodes:
        if n.nan_rows:
            report.problems.append(f"node {n.node}: {n.nan_rows} pose row(s) with NaN or non-numeric values")
        if n.backward_steps:
            report.problems.append(f"node {n.node}: time goes backwards {n.backward_steps} time(s)")
        if n.fixed:  # held at its one pose across any step (sync_notes.fixed_nodes): no gap drops a sample
            continue
        if n.clock_jumps:
            report.problems.append(
                f"node {n.node}: {n.clock_jumps} clock jump(s) or long dropout(s) (forward step longer than "
                "the clock-jump threshold while signals continue, or no signal log to tell it from a pause)")
        if n.gaps:
            report.problems.append(
                f"node {n.node}: {n.gaps} pose gap(s) longer than {max_gap_s} s "
                f"(longest {n.longest_gap_s:.3f} s); samples inside are dropped")
        if not n.static and np.isfinite(n.rate_hz) and n.rate_hz < 1.0 / max_gap_s:
            report.problems.append(
                f"node {n.node}: pose rate {n.rate_hz:.2f} Hz is below 1 / max_gap_s; most samples would drop "
                f"(sync with max_gap_s={advised_max_gap_s(1.0 / n.rate_hz):g}: 1.5 x its median pose interval)")
    for lk in report.links:
        if lk.sentinel_rssi:
            report.problems.append(
                f"link {lk.tx} -> {lk.rx}: {lk.sentinel_rssi} sentinel or non-finite RSSI value(s)")
        if lk.duplicates:
            report.problems.append(
                f"link {lk.tx} -> {lk.rx}: {lk.duplicates} exact duplicate row(s); sync drops them (duplicate)")
        if lk.repeated_readings:
            report.problems.append(
                f"link {lk.tx} -> {lk.rx}: {lk.repeated_readings} reading(s) logged twice (equal values within "
                f"{REPEAT_FRACTION:g} of the {lk.period_s:.3g} s report period); sync merges them (duplicate_reading)")
        if lk.backward_steps:
            report.problems.append(f"link {lk.tx} -> {lk.rx}: time goes backwards {lk.backward_steps} time(s)")
        if lk.implausible_rssi:
            report.problems.append(
                f"link {lk.tx} -> {lk.rx}: {lk.implausible_rssi} RSSI value(s) outside {PLAUSIBLE_RSSI_DBM[0]:g} to "
                f"{PLAUSIBLE_RSSI_DBM[1]:g} dBm or above the transmit power (median {lk.rssi_median_dbm:.1f}); sync drops "
                "them (implausible_rssi); a radio reporting its own units or with a constant offset? "
                "SyncOptions.rssi_scale='relative' reads them as relative power")
        for end in (lk.tx, lk.rx):
            if report.nodes and end not in known:
                msg = f"node {end}: named by signals but has no pose log"
                if msg not in report.problems:
                    report.problems.append(msg)
        if report.nodes and lk.tx in known and lk.rx in known:
            moving = [known[n] for n in (lk.tx, lk.rx) if not known[n].static]  # a static node holds at all times
            lo = max((n.t_start_s for n in moving), default=-np.inf)
            hi = min((n.t_end_s for n in moving), default=np.inf)
            if moving and (lk.t_end_s < lo or lk.t_start_s > hi):
                rel = report._rel
                report.problems.append(
                    f"link {lk.tx} -> {lk.rx}: signal times {rel(lk.t_start_s)} .. {rel(lk.t_end_s)} s "
                    f"do not overlap the poses ({rel(lo)} .. {rel(hi)} s from the log start): a clock offset?")


__all__ = [
    "InspectReport", "LinkSummary", "NodeSummary", "inspect_logs", "pause_mask", "summarise_pose",
    "summarise_signal",
]
