"""Link budget of a whole swarm: every ordered pair of drones, over time, and its connectivity.

For planners that must keep a swarm connected: given learned patterns and the poses of any
number of drones (a planned trajectory or a flight log), predict the received power of every
ordered pair at common times (paper eq. 1 with the learned joint gain), its spread, and per
time whether the swarm is connected when a link needs a given RSSI in both directions.

Drones need not be the ones the patterns were learned on: ``pattern_of`` maps a drone to the
learned node whose antenna it carries (several drones may share one pattern).

The *bottleneck* RSSI of a time is the largest threshold at which the swarm is still
connected: the weakest link of the maximum spanning tree of the pair weights
``min(RSSI a->b, RSSI b->a)``. A swarm is connected at threshold ``x`` exactly when
``x <= bottleneck``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree

from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.core.geometry import distance_m, link_directions
from rplearn.core.link import FAR_FIELD_WAVELENGTHS, free_space_path_loss_db, wavelength_m
from rplearn.models.patterns import PatternSet
from rplearn.data.sync import pose_tracks

#: Default spacing of the prediction times [s].
DEFAULT_STEP_S = 1.0
#: Default RSSI a link needs in each direction to count as up [dBm] (a typical Wi-Fi floor
#: for low-rate frames; set it to your radio's sensitivity plus a margin).
DEFAULT_MIN_RSSI_DBM = -85.0
#: Most yaw combinations :func:`best_swarm_headings` tries exhaustively (about 30 MB of work).
EXHAUSTIVE_MAX_COMBINATIONS = 400_000
#: Poses are interpolated only across log gaps shorter than this [s].
DEFAULT_MAX_GAP_S = 2.0


@dataclass(frozen=True)
class SwarmPrediction:
    """Predicted links of a swarm and its connectivity over time.

    Attributes
    ----------
    links : DataFrame
        One row per time and ordered pair with both poses known: ``t, tx, rx, tx_pattern,
        rx_pattern, distance_m, gain_pred_db, rssi_pred_dbm`` and, for models with a
        covariance, ``gain_pred_std_db, rssi_pred_std_db`` [dB]; ``up`` is
        ``rssi_pred_dbm >= min_rssi_dbm``. Pairs closer than the far field have NaN RSSI.
    connectivity : DataFrame
        One row per time: ``t, n_drones`` (with a pose), ``n_missing, missing``,
        ``n_pairs_up`` (unordered pairs up both ways), ``n_components``, ``connected``,
        ``bottleneck_rssi_dbm`` (see module docstring) and ``bottleneck_pair``
        (see :func:`connectivity_over_time`).
    """

    links: pd.DataFrame
    connectivity: pd.DataFrame
    pattern_of: dict[str, str]
    min_rssi_dbm: float
    tx_power_dbm: float
    frequency_hz: float
    notes: list[str] = field(default_factory=list)

    def summary(self) -> str:
        """A few lines for people: who, when, how often connected, the weakest moment."""
        c = self.connectivity
        drones = ", ".join(f"{d} ({p})" if d != p else d for d, p in self.pattern_of.items())
        lines = [
            f"drones (pattern): {drones}",
            f"{len(c):,} time(s) from {c['t'].min():.1f} s to {c['t'].max():.1f} s; "
            f"tx power {self.tx_power_dbm:g} dBm, {self.frequency_hz / 1e9:.3f} GHz; a link is up at "
            f">= {self.min_rssi_dbm:g} dBm both ways",
            f"connected at {int(c['connected'].sum()):,} of {len(c):,} time(s) ({100.0 * c['connected'].mean():.1f} %)",
        ]
        finite = np.isfinite(c["bottleneck_rssi_dbm"].to_numpy(np.float64))
        if finite.any():
            worst = c.loc[c.loc[finite, "bottleneck_rssi_dbm"].idxmin()]
            lines.append(
                f"weakest moment: t = {worst['t']:.1f} s, bottleneck {worst['bottleneck_rssi_dbm']:.1f} dBm "
                f"on {worst['bottleneck_pair']}"
            )
        per_pair = self.links.groupby(["tx", "rx"])["rssi_pred_dbm"].median().dropna()
        if len(per_pair):
            weakest = per_pair.idxmin()
            lines.append(f"weakest direction (median): {weakest[0]} -> {weakest[1]} at {per_pair.min():.1f} dBm")
        incomplete = int((c["n_missing"] > 0).sum())
        if incomplete:
            lines.append(f"at {incomplete:,} time(s) a drone has no pose: connectivity unknown there (counted as not connected)")
        lines.extend(self.notes)
        return "\n".join(lines)


def _model_frequency_hz(model: Any, frequency_hz: float | None, command: str) -> float:
    """Refuse a model without patterns; the carrier frequency given, else the model's [Hz]."""
    if not isinstance(model, PatternSet):
        raise InputError(f"{command} needs a pattern model (sh, bg or poly), not {getattr(model, 'label', model)!r}")
    if frequency_hz is None:
        frequency_hz = model.training.get("frequency_hz")
        if frequency_hz is None:
            raise InputError(
                f"the model does not state its frequency; give it (rplearn {command} --frequency HZ, or frequency_hz=)"
            )
    wavelength_m(float(frequency_hz))  # refuses a non-positive frequency
    return float(frequency_hz)


def prediction_times(tracks: Mapping[str, Any], step_s: float, times_s: ArrayLike | None) -> np.ndarray:
    """The given times, or a grid of ``step_s`` over the span all drones' logs cover [s]."""
    if times_s is not None:
        t = np.asarray(times_s, np.float64).ravel()
        if t.size == 0 or not np.all(np.isfinite(t)):
            raise InputError("times: expected finite times in seconds (rplearn links --at)")
        return np.unique(t)
    if not (np.isfinite(step_s) and step_s > 0):
        raise InputError(f"step: expected a positive number of seconds (rplearn links --step), got {step_s!r}")
    moving = [tr for tr in tracks.values() if not tr.static]
    if not moving:
        return np.array([0.0])
    start = max(float(tr.t_s[0]) for tr in moving)
    stop = min(float(tr.t_s[-1]) for tr in moving)
    if stop < start:
        spans = ", ".join(f"{tr.node} {tr.t_s[0]:.1f}..{tr.t_s[-1]:.1f} s" for tr in moving)
        raise InputError(f"pose logs share no time span ({spans}); give times with --at")
    return np.arange(start, stop + 1e-9 * max(1.0, abs(stop)), step_s)


def resolve_patterns(drones: Sequence[str], model_nodes: Sequence[str], pattern_of: Mapping[str, str] | None) -> dict[str, str]:
    """Which learned pattern every drone carries: ``pattern_of``, else its own node id."""
    mapping = {str(k): str(v) for k, v in (pattern_of or {}).items()}
    unknown_keys = sorted(set(mapping) - set(drones))
    if unknown_keys:
        raise InputError(f"--as names drone(s) {', '.join(unknown_keys)} that are in no pose log; drones: {', '.join(drones)}")
    out = {}
    for d in drones:
        p = mapping.get(d, d)
        if d in mapping and p not in model_nodes:
            raise InputError(f"--as {d}={p}: {p} is not a learned node; the model has {', '.join(model_nodes)}")
        if p not in model_nodes:
            raise InputError(
                f"drone {d} has no learned pattern (the model has {', '.join(model_nodes)}); "
                f"say which antenna it carries with --as {d}=NODE"
            )
        out[d] = p
    return out


def predict_swarm(
    model: PatternSet,
    pose_log: pd.DataFrame,
    tx_power_dbm: float,
    frequency_hz: float | None = None,
    pattern_of: Mapping[str, str] | None = None,
    step_s: float = DEFAULT_STEP_S,
    times_s: ArrayLike | None = None,
    min_rssi_dbm: float = DEFAULT_MIN_RSSI_DBM,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
    source: str = "pose log",
) -> SwarmPrediction:
    """Predict every ordered link of a swarm over time, and whether the swarm is connected.

    Parameters
    ----------
    model : PatternSet
        Learned patterns (SH, BG or P).
    pose_log : DataFrame
        Canonical pose log (``t, node, x, y, z, qw, qx, qy, qz``; ENU [m], FLU->ENU quaternions).
    tx_power_dbm : float
        Transmit power of every drone [dBm].
    frequency_hz : float, optional
        Carrier [Hz]; by default the one the model was learned at.
    pattern_of : mapping, optional
        Drone -> learned node whose pattern it carries; drones not named use their own id.
    step_s, times_s
        Prediction times: a grid of ``step_s`` [s] over the common span, or these times [s].
    min_rssi_dbm : float
        RSSI a link needs in each direction to be up [dBm].
    max_gap_s : float
        Longest log gap a pose is interpolated across [s]; a drone is absent inside longer ones.
    """
    frequency_hz = _model_frequency_hz(model, frequency_hz, "links")
    if not np.isfinite(tx_power_dbm):
        raise InputError("tx power: expected a finite number of dBm (rplearn links --tx-power)")
    if not (np.isfinite(max_gap_s) and max_gap_s > 0):
        raise InputError(f"max gap: expected a positive number of seconds (rplearn links --max-gap), got {max_gap_s!r}")
    tracks = pose_tracks(pose_log, source=source)
    drones = sorted(tracks)
    if len(drones) < 2:
        raise InputError(f"{source}: a swarm needs at least 2 drones, the pose log has {', '.join(drones) or 'none'}")
    patterns = resolve_patterns(drones, model.nodes, pattern_of)
    t = prediction_times(tracks, step_s, times_s)
    poses = {d: tracks[d].interpolate(t, max_gap_s) for d in drones}
    residual_db = float(model.training.get("rmse_db", np.nan))
    limit_m = FAR_FIELD_WAVELENGTHS * float(wavelength_m(frequency_hz))
    # Every (time, ordered pair) with both poses known, gathered into one batch: the geometry,
    # the gains and their spreads are then computed by a few vectorised calls, not per pair.
    rows_t, rows_a, rows_b = [], [], []
    for i, a in enumerate(drones):
        for j, b in enumerate(drones):
            if a != b:
                ok = np.flatnonzero((poses[a][2] == 0) & (poses[b][2] == 0))
                rows_t.append(ok)
                rows_a.append(np.full(ok.size, i, np.intp))
                rows_b.append(np.full(ok.size, j, np.intp))
    ti, ia, ib = (np.concatenate(r) for r in (rows_t, rows_a, rows_b))
    if ti.size == 0:
        raise InputError(
            f"{source}: no time at which two drones both have a pose; check the logs' spans, or allow longer "
            f"gaps between pose rows (rplearn links --max-gap, now {max_gap_s:g} s)"
        )
    position = np.stack([poses[d][0] for d in drones])  # (drones, times, 3)
    quat = np.stack([poses[d][1] for d in drones])
    pa, pb = position[ia, ti], position[ib, ti]
    d = distance_m(pa, pb)
    dirs = link_directions(pa, quat[ia, ti], pb, quat[ib, ti])
    pattern_index = np.array([model.node_index(patterns[x]) for x in drones], np.intp)
    samples = LinkSamples(dirs, pattern_index[ia], pattern_index[ib], model.nodes, np.full(d.size, np.nan), d, np.full(d.size, frequency_hz))
    gain = model.predict_samples(samples)
    far = d > limit_m
    too_close = int((~far).sum())
    rssi = np.full(d.size, np.nan)
    rssi[far] = tx_power_dbm + gain[far] - free_space_path_loss_db(d[far], frequency_hz)
    names = np.array(drones, dtype=object)
    pattern_names = np.array([patterns[x] for x in drones], dtype=object)
    columns = {
        "t": t[ti], "tx": names[ia], "rx": names[ib], "tx_pattern": pattern_names[ia], "rx_pattern": pattern_names[ib],
        "distance_m": d, "gain_pred_db": gain, "rssi_pred_dbm": rssi,
    }
    if model.covariance is not None:
        std = model.predict_samples_std(samples)
        columns["gain_pred_std_db"] = std
        columns["rssi_pred_std_db"] = np.sqrt(std**2 + residual_db**2)
    links = pd.DataFrame(columns).sort_values(["t", "tx", "rx"], kind="stable", ignore_index=True)
    links["near_field"] = links["distance_m"] <= limit_m
    links["up"] = (links["rssi_pred_dbm"] >= min_rssi_dbm) | links["near_field"]
    notes = []
    if too_close:
        notes.append(
            f"note: {too_close:,} pair-time(s) closer than the far field ({limit_m:.3f} m): no RSSI predicted, "
            "counted as up (near_field)"
        )
    absent = {d: int(np.sum(poses[d][2] != 0)) for d in drones}
    if any(absent.values()):
        notes.append("note: drone(s) without a pose at some times (outside their log or in a gap): "
                     + ", ".join(f"{d} {n}" for d, n in absent.items() if n))
    connectivity = connectivity_over_time(links, t, drones, min_rssi_dbm)
    return SwarmPrediction(links, connectivity, patterns, float(min_rssi_dbm), float(tx_power_dbm), frequency_hz, notes)


def connectivity_over_time(
    links: pd.DataFrame, times_s: np.ndarray, drones: Sequence[str], min_rssi_dbm: float
) -> pd.DataFrame:
    """Per time: drones with a pose, pairs up both ways, groups, bottleneck (module docstring).

    A row for every time. The swarm is ``connected`` only when every drone has a pose and the
    pairs up both ways join them all; ``bottleneck_rssi_dbm`` is NaN when a drone is missing
    (connectivity unknown) and +inf when every needed link is closer than the far field.
    """
    n = len(drones)
    iu, ju = np.triu_indices(n, 1)
    t_links = links["t"].to_numpy()
    tx = pd.Categorical(links["tx"], categories=list(drones)).codes.astype(np.intp)
    rx = pd.Categorical(links["rx"], categories=list(drones)).codes.astype(np.intp)
    rssi_all = links["rssi_pred_dbm"].to_numpy(np.float64)
    near_all = links["near_field"].to_numpy(bool)
    starts = np.searchsorted(t_links, times_s, side="left")
    stops = np.searchsorted(t_links, times_s, side="right")
    rows = []
    for t_val, lo, hi in zip(times_s, starts, stops):
        rssi = np.full((n, n), np.nan)
        rssi[tx[lo:hi], rx[lo:hi]] = np.where(near_all[lo:hi], np.inf, rssi_all[lo:hi])
        present = np.zeros(n, bool)
        present[tx[lo:hi]] = True
        present[rx[lo:hi]] = True
        w = np.fmin(rssi, rssi.T)[iu, ju]  # a pair's weight: its weaker direction
        up = w >= min_rssi_dbm
        n_groups = connected_components(csr_matrix((np.ones(int(up.sum())), (iu[up], ju[up])), shape=(n, n)), directed=False)[0]
        missing = [d for d, p in zip(drones, present) if not p]
        bottleneck, pair = (float("nan"), "") if missing else _bottleneck(w, iu, ju, n, drones)
        rows.append({
            "t": float(t_val), "n_drones": int(present.sum()), "n_missing": len(missing), "missing": ",".join(missing),
            "n_pairs_up": int(up.sum()), "n_components": int(n_groups - len(missing)),
            "connected": bool(not missing and n_groups == 1), "bottleneck_rssi_dbm": bottleneck, "bottleneck_pair": pair,
        })
    return pd.DataFrame(rows)


def _bottleneck(w: np.ndarray, iu: np.ndarray, ju: np.ndarray, n: int, names: Sequence[str]) -> tuple[float, str]:
    """Weakest link of the maximum spanning tree of pair weights ``w`` (NaN: not spannable)."""
    known = ~np.isnan(w)
    if n < 2 or not known.any():
        return float("nan"), ""
    finite = np.isfinite(w) & known
    top = float(np.max(w[finite])) if finite.any() else 0.0
    w_eff = np.where(np.isinf(w), top + 1e6, w)[known]  # near-field pairs: stronger than any
    # scipy finds minimum trees of positive weights: map the largest RSSI to the smallest cost
    cost = (top + 1e6 + 1.0) - w_eff
    graph = csr_matrix((cost, (iu[known], ju[known])), shape=(n, n))
    if connected_components(graph, directed=False)[0] != 1:
        return float("nan"), ""
    tree = minimum_spanning_tree(graph).tocoo()
    weights = (top + 1e6 + 1.0) - tree.data
    k = int(np.argmin(weights))
    value = float("inf") if weights[k] >= top + 1e6 - 0.5 else float(weights[k])
    return value, f"{names[tree.row[k]]}-{names[tree.col[k]]}"


# -------------------------------------------------------------------------------------------
# Headings for a hovering swarm


@dataclass(frozen=True)
class SwarmHeadings:
    """Yaws chosen for level, hovering drones, and the link budget before and after.

    Attributes
    ----------
    yaw_deg, start_yaw_deg : dict
        Chosen and starting yaw of every drone (ENU, counter-clockwise from east) [deg].
    pair_rssi_dbm, start_pair_rssi_dbm : DataFrame
        Predicted RSSI of every unordered pair (equal both ways for level drones of equal
        power: the joint gain is the same sum of the two patterns) [dBm].
    bottleneck_dbm, start_bottleneck_dbm : float
        Weakest link of the maximum spanning tree: the swarm is connected at any threshold
        below it [dBm].
    """

    yaw_deg: dict[str, float]
    start_yaw_deg: dict[str, float]
    pair_rssi_dbm: pd.DataFrame
    start_pair_rssi_dbm: pd.DataFrame
    bottleneck_dbm: float
    start_bottleneck_dbm: float
    sweeps: int

    def summary(self) -> str:
        lines = [
            "drone  yaw now -> best [deg] (ENU, ccw from east)",
            *(f"  {d}: {self.start_yaw_deg[d]:7.1f} -> {self.yaw_deg[d]:7.1f}" for d in self.yaw_deg),
            f"bottleneck RSSI: {self.start_bottleneck_dbm:.1f} dBm now -> {self.bottleneck_dbm:.1f} dBm "
            f"({self.bottleneck_dbm - self.start_bottleneck_dbm:+.1f} dB); the swarm stays connected for any "
            "threshold below it",
            "pair RSSI now -> best [dBm]:",
        ]
        before = self.start_pair_rssi_dbm.set_index("pair")["rssi_dbm"]
        for _, row in self.pair_rssi_dbm.iterrows():
            lines.append(f"  {row['pair']}: {before[row['pair']]:6.1f} -> {row['rssi_dbm']:6.1f}")
        return "\n".join(lines)


def heading_gain_tables(
    model: PatternSet, positions: Mapping[str, ArrayLike], patterns: Mapping[str, str], yaw_grid_deg: np.ndarray
) -> dict[tuple[str, str], np.ndarray]:
    """Gain of drone ``a``'s pattern toward drone ``b`` for every yaw of ``a`` [dBi].

    A level drone sees another at azimuth ``bearing - yaw`` and at a fixed elevation, so its
    share of the link is a function of its own yaw only.
    """
    drones = list(positions)
    table = {}
    for a in drones:
        pa = np.asarray(positions[a], np.float64)
        for b in drones:
            if a == b:
                continue
            v = np.asarray(positions[b], np.float64) - pa
            bearing = np.arctan2(v[1], v[0])
            el = np.arctan2(v[2], np.hypot(v[0], v[1]))
            az = np.angle(np.exp(1j * (bearing - np.radians(yaw_grid_deg))))
            table[(a, b)] = model.evaluate(patterns[a], az, np.full(az.size, el))
    return table


def best_swarm_headings(
    model: PatternSet,
    positions: Mapping[str, ArrayLike],
    tx_power_dbm: float,
    frequency_hz: float | None = None,
    pattern_of: Mapping[str, str] | None = None,
    start_yaw_deg: Mapping[str, float] | None = None,
    fixed: Sequence[str] = (),
    step_deg: float = 5.0,
    max_sweeps: int = 20,
    restarts: int = 8,
) -> SwarmHeadings:
    """Yaws of hovering, level drones that maximise the swarm's bottleneck RSSI.

    On a yaw grid of ``step_deg``, maximising the bottleneck and, among equal bottlenecks, the
    mean pair RSSI. Up to three drones the search is exhaustive (the global optimum on the
    grid) when the grid has at most :data:`EXHAUSTIVE_MAX_COMBINATIONS` combinations (72^3 at
    the default 5 deg). Otherwise coordinate ascent (each drone in turn takes its best yaw with the others
    held, until a sweep changes nothing) from the current yaws and from ``restarts`` seeded
    random ones: a local optimum. Either way the result is never worse than the current yaws.

    Parameters
    ----------
    model : PatternSet
        Learned patterns.
    positions : mapping
        Drone -> hover position ``(x, y, z)``, ENU [m].
    tx_power_dbm : float
        Transmit power of every drone [dBm].
    frequency_hz : float, optional
        Carrier [Hz]; by default the one the model was learned at.
    pattern_of : mapping, optional
        Drone -> learned node whose antenna it carries (default: its own id).
    start_yaw_deg : mapping, optional
        Current yaws, ENU counter-clockwise from east [deg] (default 0).
    fixed : sequence of str
        Drones that keep their current yaw.
    step_deg : float
        Yaw grid [deg].
    max_sweeps, restarts : int
        Limits of the coordinate ascent (four drones or more).
    """
    frequency_hz = _model_frequency_hz(model, frequency_hz, "headings")
    if not (0 < step_deg <= 90):
        raise InputError(f"yaw step: expected 0 < step <= 90 deg (rplearn headings --step), got {step_deg}")
    drones = sorted(positions)
    if len(drones) < 2:
        raise InputError(f"a swarm needs at least 2 drones, got {', '.join(drones) or 'none'}")
    if not np.isfinite(tx_power_dbm):
        raise InputError("tx power: expected a finite number of dBm (rplearn headings --tx-power)")
    for d in drones:
        if np.asarray(positions[d], np.float64).shape != (3,) or not np.all(np.isfinite(np.asarray(positions[d], np.float64))):
            raise InputError(f"position of {d}: expected three finite numbers x,y,z in metres (rplearn headings --pos)")
        if not np.isfinite(float((start_yaw_deg or {}).get(d, 0.0))):
            raise InputError(f"yaw of {d}: expected a finite number of degrees (rplearn headings --yaw)")
    patterns = resolve_patterns(drones, model.nodes, pattern_of)
    unknown = sorted(set(fixed) - set(drones))
    if unknown:
        raise InputError(f"--fixed names unknown drone(s) {', '.join(unknown)}; drones: {', '.join(drones)}")
    grid = np.arange(-180.0, 180.0, step_deg)
    start = {d: float((start_yaw_deg or {}).get(d, 0.0)) for d in drones}
    tables = heading_gain_tables(model, {d: positions[d] for d in drones}, patterns, np.concatenate([grid, list(start.values())]))
    n_grid = grid.size
    start_index = {d: n_grid + i for i, d in enumerate(drones)}  # the start yaws follow the grid
    pairs = [(a, b) for i, a in enumerate(drones) for b in drones[i + 1 :]]
    base = {}
    for a, b in pairs:
        dist = float(np.linalg.norm(np.asarray(positions[a], float) - np.asarray(positions[b], float)))
        base[(a, b)] = tx_power_dbm - float(free_space_path_loss_db(dist, frequency_hz))

    def pair_rssi(choice: Mapping[str, int]) -> np.ndarray:
        return np.array([base[(a, b)] + tables[(a, b)][choice[a]] + tables[(b, a)][choice[b]] for a, b in pairs])

    iu = np.array([drones.index(a) for a, _ in pairs])
    ju = np.array([drones.index(b) for _, b in pairs])

    def score(choice: Mapping[str, int]) -> tuple[float, float]:
        w = pair_rssi(choice)
        return _bottleneck(w, iu, ju, len(drones), drones)[0], float(np.mean(w))

    free = [d for d in drones if d not in fixed]
    if len(drones) <= 3 and n_grid ** len(free) <= EXHAUSTIVE_MAX_COMBINATIONS:
        # exact: a triangle's spanning tree is its two strongest edges
        choice, best = _exhaustive_three(drones, free, start_index, n_grid, pairs, base, tables)
        sweeps = 0
    else:  # coordinate ascent from the current yaws, then from seeded random yaws
        rng = np.random.default_rng(0)
        starts = [dict(start_index)] + [
            {d: (int(rng.integers(n_grid)) if d in free else start_index[d]) for d in drones} for _ in range(restarts)
        ]
        best, choice, sweeps = (-np.inf, -np.inf), dict(start_index), 0
        for first in starts:
            found, s_found, n_sweeps = _coordinate_ascent(first, free, n_grid, score, max_sweeps)
            sweeps += n_sweeps
            if s_found > best:
                best, choice = s_found, found
    if score(start_index) > best:  # never worse than the current yaws (which may lie off the grid)
        best, choice = score(start_index), dict(start_index)

    def table_of(ch: Mapping[str, int]) -> pd.DataFrame:
        return pd.DataFrame({"pair": [f"{a}-{b}" for a, b in pairs], "rssi_dbm": pair_rssi(ch)})

    yaw_values = np.concatenate([grid, list(start.values())])  # index as in the gain tables
    return SwarmHeadings(
        yaw_deg={d: float(yaw_values[choice[d]]) for d in drones},
        start_yaw_deg=start,
        pair_rssi_dbm=table_of(choice),
        start_pair_rssi_dbm=table_of(start_index),
        bottleneck_dbm=best[0],
        start_bottleneck_dbm=score(start_index)[0],
        sweeps=sweeps,
    )


def _coordinate_ascent(
    choice: dict[str, int], free: Sequence[str], n_grid: int, score: Any, max_sweeps: int
) -> tuple[dict[str, int], tuple[float, float], int]:
    """Each free drone in turn takes its best grid yaw, until a sweep changes nothing."""
    best = score(choice)
    sweeps = 0
    for sweeps in range(1, max_sweeps + 1):
        changed = False
        for d in free:
            for k in range(n_grid):
                trial = {**choice, d: k}
                s = score(trial)
                if s > best:
                    best, choice, changed = s, trial, True
        if not changed:
            break
    return choice, best, sweeps


def _exhaustive_three(
    drones: Sequence[str],
    free: Sequence[str],
    start_index: Mapping[str, int],
    n_grid: int,
    pairs: Sequence[tuple[str, str]],
    base: Mapping[tuple[str, str], float],
    tables: Mapping[tuple[str, str], np.ndarray],
) -> tuple[dict[str, int], tuple[float, float]]:
    """Best grid yaws of two or three drones by trying every combination (vectorised).

    The bottleneck of two drones is their one pair; of three, the second strongest pair.
    """
    axes = [np.arange(n_grid) if d in free else np.array([start_index[d]]) for d in drones]
    grids = np.meshgrid(*axes, indexing="ij")
    idx = {d: g for d, g in zip(drones, grids)}
    w = np.stack([base[(a, b)] + tables[(a, b)][idx[a]] + tables[(b, a)][idx[b]] for a, b in pairs])
    bottleneck = w[0] if len(pairs) == 1 else np.sort(w, axis=0)[-2]
    mean = w.mean(axis=0)
    top = bottleneck.max()
    candidates = bottleneck >= top  # exact ties, then the best mean among them
    flat = int(np.argmax(np.where(candidates, mean, -np.inf)))
    pos = np.unravel_index(flat, bottleneck.shape)
    choice = {d: int(idx[d][pos]) for d in drones}
    return choice, (float(top), float(mean[pos]))
