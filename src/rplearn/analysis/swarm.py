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

Headings that keep a hovering swarm best connected are chosen in :mod:`rplearn.analysis.headings`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree

from rplearn._argtypes import check_types, is_finite_real
from rplearn._budget import Cost, check_work
from rplearn.analysis.heading_options import check_optional_frequency
from rplearn.analysis.swarm_connectivity import connectivity_of_weights, connectivity_table
from rplearn.analysis.swarm_connectivity import maximum_spanning_edges as maximum_spanning_edges  # re-exported
from rplearn.analysis.swarm_links import Radio, SwarmPoses, predict_links
from rplearn.core.link import far_field_limit_m
from rplearn.core.threads import blas_threads, prediction_flops
from rplearn.data.poses import pose_tracks
from rplearn.data.tables import check_tx_power_dbm
from rplearn.errors import InputError
from rplearn.models.base import model_frequency_hz, require_calibrated, require_patterns
from rplearn.models.patterns import PatternSet
from rplearn.models.predict import UNCOVERED_DEG

#: Default spacing of the prediction times [s].
DEFAULT_STEP_S = 1.0
#: Default RSSI a link needs in each direction to count as up [dBm] (a typical Wi-Fi floor
#: for low-rate frames; set it to your radio's sensitivity plus a margin).
DEFAULT_MIN_RSSI_DBM = -85.0
#: Poses are interpolated only across log gaps shorter than this [s].
DEFAULT_MAX_GAP_S = 2.0


@check_types
@dataclass(frozen=True)
class SwarmOptions:
    """How :func:`predict_swarm` predicts a swarm's links (everything but the model, the poses
    and the transmit power).

    Attributes
    ----------
    frequency_hz : float, optional
        Carrier [Hz]; by default the one the model was learned at.
    pattern_of : mapping, optional
        Drone -> learned node whose pattern it carries; drones not named use their own id.
    min_rssi_dbm : float
        RSSI a link needs in each direction to be up [dBm].
    step_s, times_s
        Prediction times: a grid of ``step_s`` [s] over the common span, or these times [s].
    max_gap_s : float
        Longest log gap a pose is interpolated across [s]; a drone is absent inside longer ones.

    Raises
    ------
    InputError
        On the first invalid option, naming it (``param``).
    """

    frequency_hz: float | None = None
    pattern_of: Mapping[str, str] | None = None
    min_rssi_dbm: float = DEFAULT_MIN_RSSI_DBM
    step_s: float = DEFAULT_STEP_S
    times_s: ArrayLike | None = None
    max_gap_s: float = DEFAULT_MAX_GAP_S

    def __post_init__(self) -> None:
        check_optional_frequency(self.frequency_hz)
        if self.pattern_of is not None:
            if not isinstance(self.pattern_of, Mapping):
                raise InputError(f"pattern_of: expected a mapping drone -> node, got {self.pattern_of!r}",
                                 param="pattern_of")
            object.__setattr__(self, "pattern_of", {str(d): str(n) for d, n in self.pattern_of.items()})
        if not is_finite_real(self.min_rssi_dbm):
            raise InputError(f"min_rssi_dbm: expected a finite number of dBm, got {self.min_rssi_dbm!r}",
                             param="min_rssi_dbm")
        if self.times_s is None and not (is_finite_real(self.step_s) and self.step_s > 0):
            raise InputError(f"step_s: expected a positive number of seconds, got {self.step_s!r}", param="step_s")
        if not (is_finite_real(self.max_gap_s) and self.max_gap_s > 0):
            raise InputError(f"max_gap_s: expected a positive number of seconds, got {self.max_gap_s!r}",
                             param="max_gap_s")


@check_types
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
            weakest = cast(tuple[str, str], per_pair.idxmin())  # (tx, rx): the index's two levels
            lines.append(f"weakest direction (median): {weakest[0]} -> {weakest[1]} at {per_pair.min():.1f} dBm")
        incomplete = int((c["n_missing"] > 0).sum())
        if incomplete:
            lines.append(f"at {incomplete:,} time(s) a drone has no pose: connectivity unknown there (counted as not connected)")
        lines.extend(self.notes)
        return "\n".join(lines)


def prediction_times(tracks: Mapping[str, Any], step_s: float, times_s: ArrayLike | None,
                     spreads: bool = True) -> np.ndarray:
    """The given times, or a grid of ``step_s`` over the span all drones' logs cover [s]
    (refused before it is built when the links at those times, with their ``spreads`` or
    without, would not fit the work budget)."""
    if times_s is not None:
        t = np.asarray(times_s, np.float64).ravel()
        if t.size == 0 or not np.all(np.isfinite(t)):
            raise InputError("times_s: expected finite times in seconds", param="times_s")
        t = np.unique(t)
        check_link_rows(t.size, len(tracks), spreads=spreads)
        return t
    if not (np.isfinite(step_s) and step_s > 0):
        raise InputError(f"step_s: expected a positive number of seconds, got {step_s!r}", param="step_s")
    moving = [tr for tr in tracks.values() if not tr.static]
    if not moving:
        return np.array([0.0])
    start = max(float(tr.t_s[0]) for tr in moving)
    stop = min(float(tr.t_s[-1]) for tr in moving)
    if stop < start:
        spans = ", ".join(f"{tr.node} {tr.t_s[0]:.1f}..{tr.t_s[-1]:.1f} s" for tr in moving)
        raise InputError(f"pose logs share no time span ({spans}); give the times (times_s)", param="times_s")
    check_link_rows(int((stop - start) / step_s) + 1, len(tracks), step_s, spreads)
    return np.arange(start, stop + 1e-9 * max(1.0, abs(stop)), step_s)


#: Measured cost of one predicted link (a time and an ordered pair) with its spread (``links`` on
#: the smoke flight at --step 0.01 and 0.001, 14,048 and 140,480 rows, on a loaded 2-core machine:
#: about 60 us and 700 bytes a row, 160 bytes of CSV) and without (``predict_swarm`` of 30 drones x
#: 1,000 and 3,000 times, no covariance, at a load of 16 on 2 cores: 5.4-7.1 us a row).
LINK_ROW_S, LINK_ROW_BARE_S, LINK_ROW_BYTES = 60e-6, 8e-6, 700.0


def link_rows_cost(n_times: float, n_drones: int, spreads: bool = True) -> Cost:
    """What predicting ``n_times`` times of ``n_drones`` drones' ordered pairs takes (``spreads``:
    each with its standard error, ``f^T C f``)."""
    rows = float(n_times) * n_drones * (n_drones - 1)
    per_row_s = LINK_ROW_S if spreads else LINK_ROW_BARE_S
    return Cost(memory_bytes=2e8 + LINK_ROW_BYTES * rows, seconds=2.0 + per_row_s * rows)


def check_link_rows(n_times: int, n_drones: int, step_s: float | None = None, spreads: bool = True) -> None:
    """Refuse a prediction of more links (times x ordered pairs) than the work budget
    (:mod:`rplearn._budget`) allows, before any work: the largest step or number of times that fits named."""
    if step_s:
        span = (n_times - 1) * step_s
        check_work("step_s", float(step_s), lambda s: link_rows_cost(span / s + 1, n_drones, spreads), "s",
                   integer=False, bounds=(0.0, max(span, step_s)), falling=True)
    else:
        check_work("times_s", n_times, lambda n: link_rows_cost(n, n_drones, spreads), "times")


def resolve_patterns(drones: Sequence[str], model_nodes: Sequence[str], pattern_of: Mapping[str, str] | None) -> dict[str, str]:
    """Which learned pattern every drone carries: ``pattern_of``, else its own node id.

    Raises
    ------
    InputError
        (``param="pattern_of"``) when ``pattern_of`` names a drone not in the swarm or a node
        the model does not know, or a drone without a pattern of its own is not mapped.
    """
    mapping = {str(k): str(v) for k, v in (pattern_of or {}).items()}
    unknown_keys = sorted(set(mapping) - set(drones))
    if unknown_keys:
        raise InputError(
            f"pattern_of names drone(s) {', '.join(unknown_keys)} that are not in the swarm; drones: {', '.join(drones)}",
            param="pattern_of",
        )
    out = {}
    for d in drones:
        p = mapping.get(d, d)
        if d in mapping and p not in model_nodes:
            raise InputError(
                f"pattern_of {d}={p}: {p} is not a learned node; the model has {', '.join(model_nodes)}", param="pattern_of"
            )
        if p not in model_nodes:
            raise InputError(
                f"drone {d} has no learned pattern (the model has {', '.join(model_nodes)}); "
                f"say which antenna it carries (pattern_of {d}=NODE)",
                param="pattern_of",
            )
        out[d] = p
    return out


@check_types
def predict_swarm(
    model: PatternSet,
    pose_log: pd.DataFrame,
    tx_power_dbm: float,
    options: SwarmOptions | None = None,
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
    options : SwarmOptions, optional
        Carrier, which antenna each drone carries, the RSSI a link needs, the prediction times
        and the longest pose gap (default ``SwarmOptions()``).
    source : str
        What the pose log is (its files), for error messages.

    Examples
    --------
    >>> predict_swarm(model, poses, 20, SwarmOptions(pattern_of={"C": "A"}))  # doctest: +SKIP
    """
    options = SwarmOptions() if options is None else options
    frequency_hz, pattern_of, min_rssi_dbm = options.frequency_hz, options.pattern_of, options.min_rssi_dbm
    step_s, times_s, max_gap_s = options.step_s, options.times_s, options.max_gap_s
    require_patterns(model, "predicting a swarm's links")
    require_calibrated(model, "predicting a swarm's links")
    frequency_hz = model_frequency_hz(model, frequency_hz)
    _check_link_options(tx_power_dbm, max_gap_s, min_rssi_dbm)
    tracks = pose_tracks(pose_log, source=source)
    drones = sorted(tracks)
    if len(drones) < 2:
        raise InputError(f"{source}: a swarm needs at least 2 drones, the pose log has {', '.join(drones) or 'none'}")
    patterns = resolve_patterns(drones, model.nodes, pattern_of)
    t = prediction_times(tracks, step_s, times_s, model.covariance is not None)
    swarm = _swarm_poses(tracks, drones, t, max_gap_s)
    span = (min(float(tr.t_s[0]) for tr in tracks.values()), max(float(tr.t_s[-1]) for tr in tracks.values()))
    del tracks  # memory: the poses at the prediction times are all that is needed now
    present = swarm.present
    for k, d in enumerate(drones):  # a two-ray model predicts nothing at or below its ground
        model.path_loss.check_heights(swarm.position_m[k][present[:, k], 2], f"{source}: drone {d}", "z [m]")
    n_present = present.sum(axis=1)
    if not np.any(n_present >= 2) and times_s is not None:  # the times asked, not the logs or their gaps
        raise InputError(f"times_s: no time asked has two drones with a pose ({len(t):,} time(s), {float(np.min(t)):g} .. "
                         f"{float(np.max(t)):g} s); the pose logs of {source} span {span[0]:g} .. {span[1]:g} s",
                         param="times_s")
    if not np.any(n_present >= 2):
        raise InputError(
            f"{source}: no time at which two drones both have a pose; check the logs' spans, or allow longer "
            f"gaps between pose rows (max_gap_s, now {max_gap_s:g} s)",
            param="max_gap_s",
        )
    n_links = int(np.sum(n_present * (n_present - 1)))
    with blas_threads(prediction_flops(n_links, model.basis.n_coef, model.covariance is not None)):
        links, connectivity = predict_links(model, swarm, patterns, Radio(tx_power_dbm, frequency_hz, min_rssi_dbm))
    notes = _swarm_notes(links, swarm, frequency_hz)
    return SwarmPrediction(links, connectivity, patterns, float(min_rssi_dbm), float(tx_power_dbm), frequency_hz, notes)


def _check_link_options(tx_power_dbm: float, max_gap_s: float, min_rssi_dbm: float = DEFAULT_MIN_RSSI_DBM) -> None:
    """Refuse a non-finite transmit power or threshold [dBm], or a non-positive largest pose
    gap [s]."""
    if not np.isfinite(min_rssi_dbm):
        raise InputError(f"min_rssi_dbm: expected a finite number of dBm, got {min_rssi_dbm!r}", param="min_rssi_dbm")
    check_tx_power_dbm(tx_power_dbm, "transmit power")
    if not (np.isfinite(max_gap_s) and max_gap_s > 0):
        raise InputError(f"max_gap_s: expected a positive number of seconds, got {max_gap_s!r}", param="max_gap_s")


def _swarm_poses(tracks: Mapping[str, Any], drones: Sequence[str], t: np.ndarray, max_gap_s: float) -> SwarmPoses:
    """Every drone's pose at the times ``t`` [s], interpolated across log gaps up to ``max_gap_s``,
    straight into one array per quantity."""
    n = len(drones)
    position, quat = np.empty((n, t.size, 3)), np.empty((n, t.size, 4))
    present = np.empty((t.size, n), bool)
    for k, d in enumerate(drones):
        position[k], quat[k], status = tracks[d].interpolate(t, max_gap_s)
        present[:, k] = status == 0
    return SwarmPoses(position, quat, present, t, tuple(drones))


def _far_field_limit_m(frequency_hz: float) -> float:
    """Distance below which no received power is predicted (paper Sec. III: 2 wavelengths) [m]."""
    return float(far_field_limit_m(frequency_hz))


def _swarm_notes(links: pd.DataFrame, poses: SwarmPoses, frequency_hz: float) -> list[str]:
    """Notes for people: pairs too close for the far field, drones without a pose at some times."""
    notes = []
    too_close = int(links["near_field"].sum())
    if too_close:
        notes.append(
            f"note: {too_close:,} pair-time(s) closer than the far field ({_far_field_limit_m(frequency_hz):.3f} m): "
            "no RSSI predicted, counted as up (near_field)"
        )
    if "tx_coverage_deg" in links.columns:
        far = int((np.fmax(links["tx_coverage_deg"], links["rx_coverage_deg"]) > UNCOVERED_DEG).sum())
        if far:
            notes.append(
                f"note: {far:,} of {len(links):,} link predictions look more than {UNCOVERED_DEG:g} deg from any direction "
                "the antennas were learned from (columns tx_coverage_deg, rx_coverage_deg): there the gain is an "
                "extrapolation (or the prior's), with its spread"
            )
    absent = {d: int(np.sum(~poses.present[:, k])) for k, d in enumerate(poses.drones)}
    if any(absent.values()):
        notes.append("note: drone(s) without a pose at some times (outside their log or in a gap): "
                     + ", ".join(f"{d} {n}" for d, n in absent.items() if n))
    return notes


@check_types
def connectivity_over_time(
    links: pd.DataFrame, times_s: np.ndarray, drones: Sequence[str], min_rssi_dbm: float
) -> pd.DataFrame:
    """Per time: drones with a pose, pairs up both ways, groups, bottleneck (module docstring).

    A row for every time. The swarm is ``connected`` only when every drone has a pose and the
    pairs up both ways join them all; ``bottleneck_rssi_dbm`` is NaN when a drone is missing
    (connectivity unknown) and +inf when every needed link is closer than the far field.

    Every time at once (:func:`maximum_spanning_edges`, in blocks of times): the groups at the
    threshold are the drones less the tree's edges at or above it, and the bottleneck is the
    tree's weakest edge (what :func:`spanning_bottleneck` gives one time).
    """
    n = len(drones)
    times_s = np.asarray(times_s, np.float64)
    t_index = np.searchsorted(times_s, links["t"].to_numpy(np.float64))
    tx = pd.Categorical(links["tx"], categories=list(drones)).codes.astype(np.intp)
    rx = pd.Categorical(links["rx"], categories=list(drones)).codes.astype(np.intp)
    rssi_all = np.where(links["near_field"].to_numpy(bool), np.inf, links["rssi_pred_dbm"].to_numpy(np.float64))
    parts = []
    step = max(1, CONNECTIVITY_BLOCK_VALUES // max(n * n, 1))  # memory: a block of (times, n, n) weights
    for s0 in range(0, times_s.size, step):
        s1 = min(times_s.size, s0 + step)
        sel = (t_index >= s0) & (t_index < s1)
        parts.append(_connectivity_block(t_index[sel] - s0, tx[sel], rx[sel], rssi_all[sel], times_s[s0:s1], drones,
                                         min_rssi_dbm))
    return connectivity_table(parts)


#: Weights held at once by :func:`connectivity_over_time` (times x drones x drones).
CONNECTIVITY_BLOCK_VALUES = 4_000_000


def _connectivity_block(
    k: np.ndarray, tx: np.ndarray, rx: np.ndarray, rssi_dbm: np.ndarray, times_s: np.ndarray,
    drones: Sequence[str], min_rssi_dbm: float,
) -> dict[str, np.ndarray]:
    """Rows of :func:`connectivity_over_time` for the times ``times_s`` of one block, from its
    links: time index ``k`` within the block, drone indices, RSSI (+inf near field) [dBm]."""
    n, m = len(drones), times_s.size
    rssi = np.full((m, n, n), np.nan)
    rssi[k, tx, rx] = rssi_dbm
    present = np.zeros((m, n), bool)
    present[k, tx] = True
    present[k, rx] = True
    return connectivity_of_weights(rssi, present, times_s, drones, min_rssi_dbm)


@check_types
def spanning_bottleneck(w: np.ndarray, iu: np.ndarray, ju: np.ndarray, n: int, names: Sequence[str]) -> tuple[float, str]:
    """Weakest link of the maximum spanning tree of pair weights (see the module docstring).

    Parameters
    ----------
    w : ndarray
        Weight of every unordered pair ``(iu[k], ju[k])``: its weaker direction's RSSI [dBm];
        NaN for an unknown pair, +inf for a pair closer than the far field.
    iu, ju : ndarray of int
        Drone indices of the pairs.
    n : int
        Number of drones.
    names : sequence of str
        Drone names, for the pair.

    Returns
    -------
    bottleneck : float
        The largest threshold at which the drones are connected [dBm]; NaN when the known
        pairs do not span them, +inf when every pair of the tree is near field.
    pair : str
        ``"a-b"``, the pair of the bottleneck ("" when NaN).
    """
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
