"""A node's clock offset, found from the data (``rplearn sync --estimate-offset NODE``).

Two drones' clocks agree only as well as their time synchronisation (the paper needed chrony to
sub-millisecond). A pose log that runs late or early by ``delta`` puts every packet of that node
at the wrong attitude and position, and the joint gains then fit a smooth pattern worse. The
offset is found by shifting the node's pose times over a window, matching again, fitting a
low-order spherical-harmonic model and keeping the shift with the smallest residual:

1. a coarse grid over ``[-window, +window]``, then a fine grid around its best point;
2. the minimum by a parabola through the fine points nearest it;
3. the uncertainty, the larger of the parabola's (the shift that raises the squared error by one
   noise variance) and the spread of the minima of ten contiguous stretches of the flight
   (neighbouring packets share their errors, so the curvature alone is optimistic).

Only the signal rows that stay inside the node's pose span for every shift are used (at most
:data:`MAX_SAMPLES` of them, evenly spread), so each point of the curve sees the same packets.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn._budget import Cost, check_work
from rplearn.core.geometry import distance_m, link_directions
from rplearn.core.link import far_field_limit_m, observed_joint_gain_db
from rplearn.core.threads import one_blas_thread
from rplearn.data.poses import PoseTrack, tracks_of_checked_log
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.data.tables import link_samples, outage_mask, validate_pose_log, validate_signal_log
from rplearn.errors import InputError

#: Signal rows used at most (evenly spread over the flight).
MAX_SAMPLES = 40_000
#: Largest order of the spherical-harmonic model whose residual the offset minimises.
MAX_OFFSET_FIT_ORDER = 10
#: Packets per coefficient of that model at least (its order is the largest allowed, up to
#: :data:`MAX_OFFSET_FIT_ORDER`): a model too coarse for the patterns biases the offset.
OFFSET_SAMPLES_PER_COEF = 40
#: Largest default step of the coarse search [s].
COARSE_STEP_S = 0.1
#: Contiguous stretches of the flight whose own minima give the spread of the estimate.
OFFSET_BLOCKS = 10

#: Measured cost of one shift tried (``estimate_clock_offset`` on the smoke flight on a loaded
#: 2-core machine: 46-60 ms a shift for 2,500 packets at SH-4): fixed seconds, and seconds and
#: bytes per packet and model column.
SHIFT_S, SHIFT_S_PER_VALUE, SHIFT_BYTES_PER_VALUE = 0.03, 2e-8, 40.0

Progress = Callable[[str], None]


def offset_search_cost(window_s: float, step_s: float | None, packets: int) -> Cost:
    """What :func:`estimate_clock_offset` takes over ``+-window_s`` [s] with ``packets`` packets:
    every coarse shift and about 21 fine ones, each a fit of the largest order those packets allow
    (two nodes)."""
    step = float(step_s) if step_s is not None else min(window_s / 5.0, COARSE_STEP_S)
    shifts = 2.0 * window_s / step + 22.0
    order = max(2, min(MAX_OFFSET_FIT_ORDER, int(np.sqrt(max(packets, 1) / (2 * OFFSET_SAMPLES_PER_COEF))) - 1))
    values = float(packets) * 2 * (order + 1) ** 2
    return Cost(memory_bytes=SHIFT_BYTES_PER_VALUE * values + 2e8,
                seconds=shifts * (SHIFT_S + SHIFT_S_PER_VALUE * values))


@check_types
@dataclass(frozen=True)
class ClockOffsetEstimate:
    """The clock offset of one node's pose log that best explains the signal.

    Attributes
    ----------
    node : str
    offset_s : float
        Offset to add to the node's pose times [s] (``sync --offset NODE=offset_s``).
    std_s : float
        Its standard uncertainty [s].
    offsets_s, rmse_db : ndarray
        The curve: every shift tried [s] (sorted) and the fit's residual RMSE there [dB].
    n_samples : int
        Signal rows matched at every shift.
    at_edge : bool
        True when the minimum lies at the window's edge (the true offset may lie beyond).
    given_s : float
        The node's offset the search started from (0, or the one given to sync) [s].
    """

    node: str
    offset_s: float
    std_s: float
    offsets_s: np.ndarray
    rmse_db: np.ndarray
    n_samples: int
    at_edge: bool
    given_s: float = 0.0

    def curve_text(self, max_points: int = 25) -> str:
        """The curve as a small table (at most ``max_points`` shifts, evenly picked, and the
        minimum, marked)."""
        best = int(np.argmin(self.rmse_db))
        picked = np.linspace(0, len(self.offsets_s) - 1, min(max_points, len(self.offsets_s))).round().astype(int)
        lines = [f"residual RMSE over clock shifts of {self.node}:"]
        for i in sorted(set(picked.tolist()) | {best}):
            mark = "  <- minimum" if i == best else ""
            lines.append(f"  {self.offsets_s[i]:+7.3f} s  {self.rmse_db[i]:6.3f} dB{mark}")
        return "\n".join(lines)

    def summary(self) -> str:
        """The estimate, its uncertainty and the curve's depth, for people."""
        lo, hi = float(self.offsets_s[0]), float(self.offsets_s[-1])
        text = (f"clock offset of {self.node}: {self.offset_s:+.3f} s +- {self.std_s:.3f} s "
                f"(residual {self.rmse_db.min():.2f} dB there, {self.rmse_db[np.argmin(np.abs(self.offsets_s - self.given_s))]:.2f} dB "
                f"at {self.given_s:+.3f} s; {len(self.offsets_s)} shifts in {lo:+.2f}..{hi:+.2f} s, {self.n_samples:,} packets)")
        if self.at_edge:
            text += "\n  the minimum is at the edge of the window: widen it (--offset-window) before trusting it"
        return text


def track_at(track: PoseTrack, t_s: np.ndarray, shift_s: float, max_gap_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`PoseTrack.interpolate` of ``track`` with ``shift_s`` added to its times."""
    return dataclasses.replace(track, t_s=track.t_s + shift_s).interpolate(t_s, max_gap_s)


def usable_at_every_shift(track: PoseTrack, t_s: np.ndarray, shifts_s: np.ndarray, far_end_xyz: np.ndarray,
                          near_m: np.ndarray, max_gap_s: float) -> np.ndarray:
    """The packets at times ``t_s`` [s] whose node pose is known (status 0 of
    :meth:`PoseTrack.interpolate`) and whose link is in the far field at every shift of ``track``'s
    times in ``shifts_s`` [s].

    Parameters
    ----------
    track : PoseTrack
        The node's poses (two rows or more).
    t_s : ndarray (n,)
        Packet times [s].
    shifts_s : ndarray (k,)
        Shifts added to the track's times [s].
    far_end_xyz : ndarray (n, 3)
        ENU position of each packet's other end [m] (which does not move with the shift).
    near_m : ndarray (n,)
        Far-field limit of each packet [m]: the link must be longer.
    max_gap_s : float
        As :meth:`PoseTrack.interpolate`'s.

    Returns
    -------
    ndarray (n,) of bool
        The same rows :func:`track_at`'s positions and statuses keep, shift by shift: only the
        positions are interpolated (no attitude), each shift's track times computed as there.
    """
    usable = np.ones(t_s.shape[0], bool)
    xyz = track.position_xyz
    for shift in shifts_s:
        i, frac, status = dataclasses.replace(track, t_s=track.t_s + shift).brackets(t_s, max_gap_s)
        pos = xyz[i + 1] - xyz[i]
        pos *= frac[:, None]
        pos += xyz[i]
        pos -= far_end_xyz
        usable &= (status == 0) & (np.sqrt(np.add.reduce(pos * pos, axis=1)) > near_m)
    return usable


def _shift_grid(center_s: float, half_width_s: float, step_s: float) -> np.ndarray:
    n = int(round(half_width_s / step_s))
    return center_s + step_s * np.arange(-n, n + 1)


def _parabola_minimum(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Vertex and curvature ``a`` of the least-squares parabola ``a (x - x0)^2 + c``."""
    a, b, _ = np.polyfit(x, y, 2)
    if not a > 0:
        return float(x[np.argmin(y)]), 0.0
    return float(-b / (2.0 * a)), float(a)


@check_types
def estimate_clock_offset(
    pose_log: pd.DataFrame,
    signal_log: pd.DataFrame,
    node: str,
    window_s: float = 1.0,
    options: SyncOptions | None = None,
    step_s: float | None = None,
    progress: Progress | None = None,
) -> ClockOffsetEstimate:
    """Find the offset of ``node``'s pose times that best explains the signal (module docstring).

    Parameters
    ----------
    pose_log, signal_log : DataFrame
        Canonical logs (:mod:`rplearn.data.tables`).
    node : str
        The node whose pose clock is searched.
    window_s : float
        Shifts from ``-window_s`` to ``+window_s`` [s] are tried (on top of any offset of
        ``node`` already in ``options``).
    options : SyncOptions, optional
        How to match (its link filter, gaps and other offsets are kept).
    step_s : float, optional
        Coarse step [s]; default ``window_s / 5``, at most :data:`COARSE_STEP_S` (a wider
        step can step over the minimum, a few tenths of a second wide). The fine step is a tenth of it, over one
        coarse step either side of the coarse minimum.

    Raises
    ------
    InputError
        For an unknown node, a bad window, or too few packets of the node.
    """
    from rplearn.models import ModelSpec
    from rplearn.models.fit import solve_patterns

    if not (np.isfinite(window_s) and 0 < window_s <= 600):
        raise InputError(f"offset window: expected more than 0 and at most 600 s, got {window_s!r}", param="offset_window")
    step = float(step_s) if step_s is not None else min(window_s / 5.0, COARSE_STEP_S)
    if not (np.isfinite(step) and 0 < step <= window_s):
        raise InputError(f"offset step: expected a positive number up to the window, got {step_s!r}", param="step_s")
    options = options or SyncOptions()
    pose = validate_pose_log(pose_log, "pose log")
    sig = validate_signal_log(signal_log, "signal log")
    node = str(node)
    mine = pose[pose["node"].astype(str) == node]
    if mine.empty:
        known = ", ".join(sorted(set(pose["node"].astype(str))))
        raise InputError(f"estimate-offset: node {node} has no pose log (nodes: {known})", param="estimate_offset")
    base = dict(options.clock_offsets_s or {})
    start = float(mine["t"].min()) + base.get(node, 0.0) + window_s
    stop = float(mine["t"].max()) + base.get(node, 0.0) - window_s
    involved = ((sig["tx"].astype(str) == node) | (sig["rx"].astype(str) == node)).to_numpy()
    t = sig["t"].to_numpy(np.float64)
    rows = np.flatnonzero(involved & (t >= start) & (t <= stop))
    if rows.size == 0:
        span = float(mine["t"].max() - mine["t"].min())
        raise InputError(f"offset_window: shifts of +-{window_s:g} s leave no packet of node {node} inside its pose "
                         f"span ({span:.1f} s): use a window well under half of it", param="offset_window")
    packets = min(int(np.count_nonzero(involved)), MAX_SAMPLES)
    check_work("offset_window", float(window_s), lambda w: offset_search_cost(w, step_s, packets), "s", integer=False,
               bounds=(1e-3, 600.0))
    if rows.size > MAX_SAMPLES:
        rows = rows[np.linspace(0, rows.size - 1, MAX_SAMPLES).astype(int)]
    sig = sig.iloc[rows].reset_index(drop=True)
    opts = dataclasses.replace(options, min_samples=0)
    matched = synchronise(pose, sig, opts, source="signal log").dataset  # the other ends' poses, once
    matched = matched[~outage_mask(matched)].reset_index(drop=True)  # outage events: no RSSI to fit
    track = tracks_of_checked_log(mine, {node: base.get(node, 0.0)}, "pose log")[node]
    t_sig = matched["t"].to_numpy(np.float64)
    grid = np.unique(np.concatenate([_shift_grid(0.0, window_s, step), _shift_grid(0.0, window_s, step / 10.0)]))
    if track.static or track.still:
        raise InputError(f"estimate-offset: node {node} holds still in its pose log; shifting its clock changes "
                         "nothing, so its offset cannot be told from the data", param="estimate_offset")
    node_end = {end: matched[end].astype(str).to_numpy() == node for end in ("tx", "rx")}
    far_end = np.where(node_end["tx"][:, None], matched[["rx_x", "rx_y", "rx_z"]].to_numpy(np.float64),
                       matched[["tx_x", "tx_y", "tx_z"]].to_numpy(np.float64))
    usable = usable_at_every_shift(track, t_sig, grid, far_end, far_field_limit_m(matched["frequency_hz"].to_numpy(np.float64)),
                                   options.max_gap_s)
    matched = matched[usable].reset_index(drop=True)
    t_sig = t_sig[usable]
    n_nodes = len(set(matched["tx"].astype(str).unique()) | set(matched["rx"].astype(str).unique()))
    if n_nodes == 0:
        raise InputError(f"offset_window: no packet of node {node} matches inside its pose span at every shift of "
                         f"+-{window_s:g} s: use a narrower window", param="offset_window")
    order = min(MAX_OFFSET_FIT_ORDER, int(np.sqrt(len(matched) / (n_nodes * OFFSET_SAMPLES_PER_COEF))) - 1)
    if order < 2:
        raise InputError(f"estimate-offset: {len(matched)} packets of node {node} match inside its pose span; "
                         "too few to tell its clock offset", param="estimate_offset")
    spec = ModelSpec("sh", order)
    base_samples = link_samples(matched, "signal log")
    pose_of = {end: (matched[[f"{end}_x", f"{end}_y", f"{end}_z"]].to_numpy(np.float64),
                     matched[[f"{end}_qw", f"{end}_qx", f"{end}_qy", f"{end}_qz"]].to_numpy(np.float64))
               for end in ("tx", "rx")}
    is_node = {end: node_end[end][usable] for end in ("tx", "rx")}
    rssi, ptx, freq = (matched[c].to_numpy(np.float64) for c in ("rssi_dbm", "tx_power_dbm", "frequency_hz"))
    residuals: dict[float, np.ndarray] = {}

    def rmse(shift: float) -> float:
        key = round(float(shift), 9)
        if key not in residuals:
            pos, quat, _ = track_at(track, t_sig, key, options.max_gap_s)
            ends = {}
            for end in ("tx", "rx"):
                p, q = (a.copy() for a in pose_of[end])
                p[is_node[end]], q[is_node[end]] = pos[is_node[end]], quat[is_node[end]]
                ends[end] = (p, q)
            dist = distance_m(ends["tx"][0], ends["rx"][0])
            samples = dataclasses.replace(
                base_samples, directions=link_directions(ends["tx"][0], ends["tx"][1], ends["rx"][0], ends["rx"][1]),
                distance_m=dist, joint_gain_db=observed_joint_gain_db(rssi, ptx, dist, freq))
            model, _ = solve_patterns(samples, spec)
            residuals[key] = samples.joint_gain_db - model.predict_gain(samples)
        return float(np.sqrt(np.mean(residuals[key] ** 2)))

    coarse = _shift_grid(0.0, window_s, step)
    # each fit's solve is small (a few hundred columns) and its statistics are accumulated on the
    # runtime's workers, one BLAS thread each: a second thread only waits (on a busy 2-core
    # machine it doubled the search's CPU time: 18 s against 9 s on the paper's campaign)
    with one_blas_thread():
        coarse_rmse = np.array([rmse(s) for s in coarse])
        if progress:
            progress(f"coarse search over {coarse.size} shifts done")
        best = float(coarse[int(np.argmin(coarse_rmse))])
        fine = _shift_grid(best, step, step / 10.0)
        fine = fine[(fine >= -window_s - 1e-12) & (fine <= window_s + 1e-12)]
        for s in fine:
            rmse(s)
    shifts = np.array(sorted(residuals))
    curve = np.array([rmse(s) for s in shifts])
    n = t_sig.size  # every shift sees the same packets
    near = shifts[np.argsort(np.abs(shifts - shifts[np.argmin(curve)]))[:7]]
    sse = {s: float(np.sum(residuals[round(float(s), 9)] ** 2)) for s in near}
    offset, curvature = _parabola_minimum(near, np.array([sse[s] for s in near]))
    noise_var = min(sse.values()) / n
    at_edge = bool(abs(shifts[np.argmin(curve)]) >= window_s - 1e-9)
    if not curvature > 0 and not at_edge:
        raise InputError(f"estimate-offset: the residual does not grow away from its minimum: node {node}'s clock "
                         "offset cannot be told from the data (its poses barely change over the window)",
                         param="estimate_offset")
    std = float(np.sqrt(noise_var / curvature)) if curvature > 0 else float(window_s)
    # the spread of the minima of contiguous stretches (packets share errors within one)
    block_minima = []
    edges = np.quantile(t_sig, np.linspace(0, 1, OFFSET_BLOCKS + 1))
    for k in range(OFFSET_BLOCKS):
        stretch = (t_sig >= edges[k]) & (t_sig <= edges[k + 1])
        part = {s: residuals[round(float(s), 9)][stretch] for s in near}
        if min(p.size for p in part.values()) > 10:
            block_minima.append(_parabola_minimum(near, np.array([np.sum(part[s] ** 2) for s in near]))[0])
    if len(block_minima) >= 3:
        spread = float(np.std(np.clip(block_minima, -window_s, window_s), ddof=1) / np.sqrt(len(block_minima)))
        std = max(std, spread)
    offset = float(np.clip(offset, shifts[0], shifts[-1]))
    given = base.get(node, 0.0)
    return ClockOffsetEstimate(node, offset + given, std, shifts + given, curve, int(n), at_edge, given)


__all__ = ["COARSE_STEP_S", "MAX_OFFSET_FIT_ORDER", "MAX_SAMPLES", "OFFSET_BLOCKS", "OFFSET_SAMPLES_PER_COEF", "ClockOffsetEstimate", "estimate_clock_offset"]
