"""Look at logs before learning from them: nodes, spans, rates, RSSI range, gaps, oddities.

:func:`inspect_logs` is the library function behind ``rplearn inspect``. It reads every file
with the readers of :mod:`rplearn.io` in a forgiving mode (NaN pose rows dropped and counted,
unsorted times accepted and reported) and returns an :class:`InspectReport` whose
:meth:`~InspectReport.to_text` and :meth:`~InspectReport.to_markdown` the CLI prints.

Flagged as suspicious: unreadable files, NaN pose rows, times going backwards, forward clock
jumps (a forward step longer than ``clock_jump_s``),
pose gaps longer than ``max_gap_s``, sentinel or non-finite RSSI values, signals naming a
node without a pose log, signal samples outside every pose span, and rates far from the
expected ones.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable, Sequence

import numpy as np
import pandas as pd

from rplearn.errors import RplearnError
from rplearn.sync import DEFAULT_SENTINEL_RSSI_DBM


_POSE_VALUE_COLUMNS = ("t", "x", "y", "z", "lat", "lon", "alt", "qw", "qx", "qy", "qz", "roll_deg",
                       "pitch_deg", "yaw_deg", "roll_ned_deg", "pitch_ned_deg", "yaw_ned_deg")


@dataclass
class NodeSummary:
    """One node's pose log.

    Attributes: ``rows``; ``t_start_s``, ``t_end_s`` [s]; ``rate_hz`` (1 / median step);
    ``gaps`` (steps longer than ``max_gap_s``) and ``longest_gap_s``; ``backward_steps``
    (times going backwards); ``clock_jumps`` (forward steps longer than ``clock_jump_s``);
    ``nan_rows`` (dropped on reading); ``static`` (a single row).
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


@dataclass
class LinkSummary:
    """One direction tx -> rx of the signal log: counts, span, rate and RSSI range [dBm]."""

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


@dataclass
class InspectReport:
    """What :func:`inspect_logs` found; ``problems`` lists everything suspicious, one line each."""

    files: list[dict[str, Any]] = field(default_factory=list)
    nodes: list[NodeSummary] = field(default_factory=list)
    links: list[LinkSummary] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems

    def to_text(self) -> str:
        out = ["files:"]
        for f in self.files:
            out.append(f"  {f['path']}: {f['format']} ({f.get('kind', '?')})"
                       + ("" if f.get("error") is None else f"  UNREADABLE: {f['error']}"))
        out.append("pose logs:")
        for n in self.nodes:
            span = "static" if n.static else (
                f"{n.t_start_s:.3f} .. {n.t_end_s:.3f} s ({n.t_end_s - n.t_start_s:.1f} s), "
                f"{n.rate_hz:.1f} Hz, gaps > threshold: {n.gaps} (longest {n.longest_gap_s:.3f} s)")
            out.append(f"  {n.node}: {n.rows} rows, {span}")
        out.append("signal links:")
        for lk in self.links:
            out.append(
                f"  {lk.tx} -> {lk.rx}: {lk.samples} samples, {lk.t_start_s:.3f} .. {lk.t_end_s:.3f} s, "
                f"{lk.rate_hz:.1f} Hz, RSSI {lk.rssi_min_dbm:.1f} / {lk.rssi_median_dbm:.1f} / "
                f"{lk.rssi_max_dbm:.1f} dBm (min/median/max), sentinel values: {lk.sentinel_rssi}")
        out.append("problems:" if self.problems else "problems: none found")
        out.extend(f"  - {p}" for p in self.problems)
        return "\n".join(out)

    def to_markdown(self) -> str:
        out = ["## Files", "", "| path | format | kind | status |", "| --- | --- | --- | --- |"]
        for f in self.files:
            out.append(f"| {f['path']} | {f['format']} | {f.get('kind', '?')} | "
                       f"{'ok' if f.get('error') is None else 'unreadable: ' + f['error']} |")
        out += ["", "## Pose logs", "",
                "| node | rows | start [s] | end [s] | rate [Hz] | gaps | longest gap [s] | NaN rows |",
                "| --- | --- | --- | --- | --- | --- | --- | --- |"]
        for n in self.nodes:
            out.append(f"| {n.node} | {n.rows} | {n.t_start_s:.3f} | {n.t_end_s:.3f} | {n.rate_hz:.1f} | "
                       f"{n.gaps} | {n.longest_gap_s:.3f} | {n.nan_rows} |")
        out += ["", "## Signal links", "",
                "| tx | rx | samples | start [s] | end [s] | rate [Hz] | RSSI min [dBm] | median | max | sentinels |",
                "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
        for lk in self.links:
            out.append(f"| {lk.tx} | {lk.rx} | {lk.samples} | {lk.t_start_s:.3f} | {lk.t_end_s:.3f} | "
                       f"{lk.rate_hz:.1f} | {lk.rssi_min_dbm:.1f} | {lk.rssi_median_dbm:.1f} | "
                       f"{lk.rssi_max_dbm:.1f} | {lk.sentinel_rssi} |")
        out += ["", "## Problems", ""]
        out += [f"- {p}" for p in self.problems] or ["none found"]
        return "\n".join(out)


def _steps(t: np.ndarray) -> np.ndarray:
    return np.diff(t) if t.size > 1 else np.zeros(0)


def _rate_hz(t: np.ndarray) -> float:
    d = _steps(np.sort(t))
    d = d[d > 0]
    return float(1.0 / np.median(d)) if d.size else float("nan")


def summarise_pose(pose: pd.DataFrame, max_gap_s: float = 0.2, clock_jump_s: float = 5.0,
                   nan_rows: dict[str, int] | None = None) -> list[NodeSummary]:
    """Per-node summaries of a pose log in file order (unsorted times are counted, not fixed)."""
    out = []
    for node, g in pose.groupby("node", sort=True):
        t = g["t"].to_numpy(np.float64)
        d = _steps(t)
        back = int((d < 0).sum())
        ts = np.sort(t)
        ds = _steps(ts)
        gaps = ds > max_gap_s
        jumps = int((ds > clock_jump_s).sum())
        out.append(NodeSummary(
            node=str(node), rows=int(t.size), t_start_s=float(ts[0]), t_end_s=float(ts[-1]),
            rate_hz=_rate_hz(t), gaps=int(gaps.sum()),
            longest_gap_s=float(ds.max()) if ds.size else 0.0, backward_steps=back,
            clock_jumps=jumps, nan_rows=int((nan_rows or {}).get(str(node), 0)), static=t.size == 1,
        ))
    return out


def summarise_signal(signal: pd.DataFrame,
                     sentinel_rssi_dbm: Sequence[float] = DEFAULT_SENTINEL_RSSI_DBM) -> list[LinkSummary]:
    """Per-direction summaries of a signal log (sentinel and non-finite RSSI counted apart)."""
    out = []
    for (tx, rx), g in signal.groupby(["tx", "rx"], sort=True):
        t = pd.to_numeric(g["t"], errors="coerce").to_numpy(np.float64)
        r = pd.to_numeric(g["rssi_dbm"], errors="coerce").to_numpy(np.float64)
        bad = ~np.isfinite(r) | np.isin(r, np.asarray(sentinel_rssi_dbm, float))
        good = r[~bad]
        tf = t[np.isfinite(t)]
        out.append(LinkSummary(
            tx=str(tx), rx=str(rx), samples=int(len(g)),
            t_start_s=float(tf.min()) if tf.size else np.nan, t_end_s=float(tf.max()) if tf.size else np.nan,
            rate_hz=_rate_hz(tf), rssi_min_dbm=float(good.min()) if good.size else np.nan,
            rssi_median_dbm=float(np.median(good)) if good.size else np.nan,
            rssi_max_dbm=float(good.max()) if good.size else np.nan,
            sentinel_rssi=int(bad.sum()), backward_steps=int((_steps(tf) < 0).sum()),
        ))
    return out


def _read_one(path: str, options: dict[str, Any]) -> tuple[pd.DataFrame | None, pd.DataFrame | None,
                                                          dict[str, Any], dict[str, int]]:
    from rplearn.io import detect_format, read_logs
    from rplearn.io import tables as _tables

    kind = detect_format(path)
    nan_rows: dict[str, int] = {}
    if kind == "table":
        what = _tables.table_kind(path, options.get("columns"))
        if what == "pose":
            raw = _tables._read(path, path)
            pose, meta = _tables.canonical_pose(
                raw, source=path, columns=options.get("columns"),
                node=(options.get("nodes") or {}).get(path), nan_policy="drop", allow_unsorted=True,
                origin_geodetic=options.get("origin_geodetic"),
            )
            del pose  # validated and sorted; inspection wants the file order
            df = _tables.rename_columns(raw, options.get("columns"))
            node = (df["node"].astype(str) if "node" in df.columns
                    else pd.Series([(options.get("nodes") or {}).get(path, "?")] * len(df)))
            cols = [c for c in _POSE_VALUE_COLUMNS if c in df.columns]
            values = df[cols].apply(pd.to_numeric, errors="coerce").to_numpy(np.float64)
            bad = ~np.isfinite(values).all(axis=1)
            nan_rows = {str(k): int(v) for k, v in node[bad].value_counts().items()}
            file_order = pd.DataFrame({"t": values[~bad, cols.index("t")], "node": node[~bad].to_numpy()})
            return file_order, None, {"format": meta.get("format", "table"), "kind": "pose"}, nan_rows
        sig, meta = _tables.read_signal_table(
            path, columns=options.get("columns"), rx=(options.get("receivers") or {}).get(path),
            tx_power_dbm=0.0, frequency_hz=1.0)
        return None, sig, {"format": meta["format"], "kind": "signal"}, nan_rows
    opts = dict(options)
    if kind == "ulog":
        import os

        opts["nodes"] = {path: os.path.splitext(os.path.basename(path))[0], **(opts.get("nodes") or {})}
    if kind == "pcap":
        opts.setdefault("tx_power_dbm", 0.0)
        opts.setdefault("receivers", {path: "capture"})
    if kind in ("ros1", "ros2") and opts.get("rssi_topics"):
        opts.setdefault("tx_power_dbm", 0.0)
        opts.setdefault("frequency_hz", 1.0)
    logs, meta = read_logs(path, **opts)
    f = meta["files"][0]
    info = {"format": f.get("format", kind), "kind": f.get("kind")}
    if f.get("invalid_flag_rows"):
        info["invalid_flag_rows"] = int(f["invalid_flag_rows"])
    return logs.pose, logs.signal, info, nan_rows


def inspect_logs(
    paths: str | Iterable[str],
    max_gap_s: float = 0.2,
    clock_jump_s: float = 5.0,
    sentinel_rssi_dbm: Sequence[float] = DEFAULT_SENTINEL_RSSI_DBM,
    **read_options: Any,
) -> InspectReport:
    """Summarise logs and flag anything suspicious; never raises on a bad file (it is reported).

    Parameters
    ----------
    paths : path or iterable of paths
        Logs of any format :func:`rplearn.io.read_logs` reads.
    max_gap_s : float
        Pose steps longer than this are gaps [s] (the matching threshold of :mod:`rplearn.sync`).
    clock_jump_s : float
        A forward step longer than this is reported as a clock jump [s], not a dropout.
    sentinel_rssi_dbm : sequence of float
        RSSI values meaning "no measurement".
    **read_options
        Passed to :func:`rplearn.io.read_logs` (pose topics, receivers, address map, ...).
        ``tx_power_dbm`` and ``frequency_hz`` default to placeholders here: inspection does
        not need them.

    Returns
    -------
    InspectReport
    """
    if isinstance(paths, str) or hasattr(paths, "__fspath__"):
        paths = [paths]  # type: ignore[list-item]
    report = InspectReport()
    poses, signals = [], []
    nan_rows: dict[str, int] = {}
    for p in paths:
        path = str(p)
        try:
            pose, sig, info, nans = _read_one(path, dict(read_options))
        except RplearnError as exc:
            report.files.append({"path": path, "format": "?", "kind": None, "error": str(exc)})
            report.problems.append(f"{path}: unreadable: {exc}")
            continue
        report.files.append({"path": path, **info, "error": None})
        if info.get("invalid_flag_rows"):
            report.problems.append(
                f"{path}: {info['invalid_flag_rows']} pose row(s) flagged invalid by the autopilot "
                "(xy_valid or z_valid = 0); they are kept unless read with require_valid=True"
            )
        for k, v in nans.items():
            nan_rows[k] = nan_rows.get(k, 0) + int(v)
        if pose is not None:
            poses.append(pose)
        if sig is not None:
            signals.append(sig)
    if poses:
        report.nodes = summarise_pose(pd.concat(poses, ignore_index=True), max_gap_s, clock_jump_s, nan_rows)
    if signals:
        report.links = summarise_signal(pd.concat(signals, ignore_index=True), sentinel_rssi_dbm)
    _flag(report, max_gap_s)
    return report


def _flag(report: InspectReport, max_gap_s: float) -> None:
    known = {n.node: n for n in report.nodes}
    for n in report.nodes:
        if n.nan_rows:
            report.problems.append(f"node {n.node}: {n.nan_rows} pose row(s) with NaN or non-numeric values")
        if n.backward_steps:
            report.problems.append(f"node {n.node}: time goes backwards {n.backward_steps} time(s)")
        if n.clock_jumps:
            report.problems.append(f"node {n.node}: {n.clock_jumps} clock jump(s) (forward step longer than the clock-jump threshold)")
        if n.gaps:
            report.problems.append(
                f"node {n.node}: {n.gaps} pose gap(s) longer than {max_gap_s} s "
                f"(longest {n.longest_gap_s:.3f} s); samples inside are dropped")
        if not n.static and np.isfinite(n.rate_hz) and n.rate_hz < 1.0 / max_gap_s:
            report.problems.append(
                f"node {n.node}: pose rate {n.rate_hz:.2f} Hz is below 1 / max_gap_s; most samples would drop")
    for lk in report.links:
        if lk.sentinel_rssi:
            report.problems.append(
                f"link {lk.tx} -> {lk.rx}: {lk.sentinel_rssi} sentinel or non-finite RSSI value(s)")
        if lk.backward_steps:
            report.problems.append(f"link {lk.tx} -> {lk.rx}: time goes backwards {lk.backward_steps} time(s)")
        for end in (lk.tx, lk.rx):
            if report.nodes and end not in known:
                msg = f"node {end}: named by signals but has no pose log"
                if msg not in report.problems:
                    report.problems.append(msg)
        if report.nodes and lk.tx in known and lk.rx in known:
            lo = max(known[lk.tx].t_start_s, known[lk.rx].t_start_s)
            hi = min(known[lk.tx].t_end_s, known[lk.rx].t_end_s)
            if not (known[lk.tx].static and known[lk.rx].static) and (lk.t_end_s < lo or lk.t_start_s > hi):
                report.problems.append(
                    f"link {lk.tx} -> {lk.rx}: signal times {lk.t_start_s:.3f} .. {lk.t_end_s:.3f} s "
                    f"do not overlap the poses ({lo:.3f} .. {hi:.3f} s): a clock offset?")


__all__ = ["InspectReport", "LinkSummary", "NodeSummary", "inspect_logs", "summarise_pose", "summarise_signal"]
