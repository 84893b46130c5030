"""Availability: the probability that a link, and a whole swarm, is up.

A link is *up* when its RSSI reaches the receiver's sensitivity ``s`` [dBm]. Its RSSI is
predicted with a full predictive distribution: the learned patterns' posterior (the coefficient
covariance, inflated by cross-validation where the fit estimated it), the environment term and
link offsets with their covariance, a new flight's own level (``new_flight_level_std_db``: the
between-flight spread of an automatic fit) and one packet's fading and noise
(``noise_std_db``, else the training residual).

- One link (:func:`link_availability_column`): the marginal of that distribution is normal in
  dB, so ``P(up) = Phi((mean - s) / std)`` (:func:`rplearn.core.availability.link_availability`).
- A swarm (:func:`swarm_availability`): its links are *not* independent, since every link that
  uses a pattern shares its coefficients' error and all share the flight's level. Monte Carlo
  draws the coefficients (and shared terms) from their posterior once per draw, for every link
  and time at once, the level once per draw, and the fading independently per link, time and
  draw; each draw's link graph (a pair is up when both directions are) is connected or not
  (batched maximum spanning trees, :func:`rplearn.analysis.swarm.maximum_spanning_edges`).
  Where a draw is not connected, the weakest edge of its maximum spanning tree is the link
  that failed it: its *share of the failures* names the swarm's weakest link.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types, is_finite_real
from rplearn._budget import Cost, check_work
from rplearn.analysis.swarm import SwarmOptions, maximum_spanning_edges, prediction_times, resolve_patterns
from rplearn.core.availability import link_availability
from rplearn.core.geometry import distance_m, link_directions
from rplearn.core.link import far_field_limit_m, free_space_path_loss_db
from rplearn.data.poses import pose_tracks
from rplearn.data.tables import LinkSamples, check_tx_power_dbm
from rplearn.errors import InputError
from rplearn.models.base import Model, model_frequency_hz, require_patterns
from rplearn.models.patterns import PatternSet

#: Default Monte Carlo draws of :func:`swarm_availability`.
DEFAULT_DRAWS = 1000
#: Values (rows x draws) one block of the Monte Carlo holds at once.
DRAW_BLOCK_VALUES = 4_000_000
#: Measured cost of the Monte Carlo (``links --sensitivity -90`` on the smoke flight, 142 times of
#: 2 drones, 1e4 to 4e5 draws, RPLEARN_THREADS=1, load 6 on 2 cores: 4.4 s to 19.8 s): seconds per
#: draw of one directed link at one time, and a fixed part [s].
DRAW_S_PER_LINK_TIME, DRAW_S_FIXED = 1.5e-7, 4.0


def draws_cost(n_draws: float, n_coef: int, n_times: int, n_drones: int, n_pairs: int) -> Cost:
    """What :func:`swarm_availability` takes for ``n_draws`` draws: the draws of the
    coefficients and level (float64), the connected and path flags of every draw and time, one
    block of rows, and the time of every directed link at every time per draw."""
    per_draw = 8.0 * (n_coef + 1) + n_times * (1.0 + n_pairs)
    links = n_times * n_drones * max(n_drones - 1, 1)
    return Cost(memory_bytes=2e8 + n_draws * per_draw + 16.0 * DRAW_BLOCK_VALUES,
                seconds=DRAW_S_FIXED + DRAW_S_PER_LINK_TIME * n_draws * links)


@check_types
def residual_std_db(model: Model) -> float:
    """Spread of one packet's RSSI about its flight's predicted level [dB]: the noise an
    automatic fit estimated about each flight's level (``noise_std_db``), else the training
    residual; NaN when the model states neither."""
    training = model.training
    value = training.noise_std_db if training.noise_std_db is not None else training.rmse_db
    return float(value) if value is not None else float("nan")


@check_types
def link_availability_column(table: pd.DataFrame, model: Model, sensitivity_dbm: float) -> np.ndarray:
    """Availability of every predicted link of a table (``predict``'s or ``links``'s).

    The spread is ``sqrt(gain_pred_std_db^2 + residual^2)`` (:func:`residual_std_db`; the
    gain's spread holds the patterns' posterior, the shared terms and a new flight's level);
    a table without ``gain_pred_std_db`` (a baseline model) uses the residual alone. Links
    closer than the far field (``near_field``) are up.

    Returns
    -------
    ndarray
        ``P(RSSI >= sensitivity_dbm)`` per row.
    """
    if "rssi_pred_dbm" not in table.columns:
        raise InputError("table: no rssi_pred_dbm column (predict first)", param="table")
    mean = table["rssi_pred_dbm"].to_numpy(np.float64)
    residual = residual_std_db(model)
    gain_std = table["gain_pred_std_db"].to_numpy(np.float64) if "gain_pred_std_db" in table.columns else 0.0
    p = link_availability(mean, np.sqrt(np.square(gain_std) + residual**2), sensitivity_dbm)
    if "near_field" in table.columns:
        p = np.where(table["near_field"].to_numpy(bool), 1.0, p)
    return np.asarray(p, np.float64)


@check_types
@dataclass(frozen=True)
class AvailabilityOptions:
    """How :func:`swarm_availability` draws a swarm's links.

    Attributes
    ----------
    sensitivity_dbm : float
        RSSI a link needs in each direction [dBm].
    n_draws : int
        Monte Carlo draws of the whole predictive distribution.
    seed : int
        Seed of the draws.
    pairs : sequence of (str, str)
        Pairs of drones whose probability of a path (over any relays) is reported.
    fading : bool
        Draw one packet's fading and noise per link (else only the patterns and the level: the
        availability of the links' *mean* power).
    """

    sensitivity_dbm: float
    n_draws: int = DEFAULT_DRAWS
    seed: int = 0
    pairs: Sequence[tuple[str, str]] = ()
    fading: bool = True

    def __post_init__(self) -> None:
        if not is_finite_real(self.sensitivity_dbm):
            raise InputError(f"sensitivity_dbm: expected a finite level in dBm, got {self.sensitivity_dbm!r}",
                             param="sensitivity_dbm")
        if isinstance(self.n_draws, bool) or not isinstance(self.n_draws, (int, np.integer)) or self.n_draws < 1:
            raise InputError(f"n_draws: expected a positive integer, got {self.n_draws!r}", param="n_draws")
        pairs = tuple((str(a), str(b)) for a, b in self.pairs)
        if any(a == b for a, b in pairs):
            raise InputError("pairs: a pair names one drone twice", param="pairs")
        object.__setattr__(self, "pairs", pairs)


@check_types
@dataclass(frozen=True)
class SwarmAvailability:
    """A swarm's connectivity probability over time, from Monte Carlo draws.

    Attributes
    ----------
    connectivity : DataFrame
        One row per time: ``t``, ``n_missing`` (drones without a pose: NaN probabilities),
        ``p_connected`` (share of draws whose link graph is connected), ``p_connected_se`` (its
        Monte Carlo standard error) and ``p_path_A-B`` for every named pair.
    weakest : DataFrame
        ``pair``, ``failures`` (failed draw-times it was the weakest tree edge of) and ``share``
        of all failures, strongest culprit first.
    n_draws : int
    sensitivity_dbm : float
    """

    connectivity: pd.DataFrame
    weakest: pd.DataFrame
    n_draws: int
    sensitivity_dbm: float
    notes: list[str] = field(default_factory=list)

    def summary(self) -> str:
        """A few lines for people: the mean probability, the worst time, the weakest link."""
        c = self.connectivity
        p = c["p_connected"].to_numpy(np.float64)
        known = np.isfinite(p)
        lines = [f"swarm availability at {self.sensitivity_dbm:g} dBm ({self.n_draws:,} draws of the patterns' "
                 "posterior, the flight level and the fading)"]
        if known.any():
            worst = int(np.flatnonzero(known)[np.argmin(p[known])])
            lines.append(f"P(connected): mean {np.mean(p[known]):.3f} over {int(known.sum()):,} time(s); lowest "
                         f"{p[worst]:.3f} at t = {c['t'].iloc[worst]:.1f} s")
        for col in (k for k in c.columns if k.startswith("p_path_")):
            lines.append(f"P(path {col[len('p_path_'):]}): mean {np.nanmean(c[col].to_numpy(np.float64)):.3f}")
        if len(self.weakest):
            top = self.weakest.iloc[0]
            lines.append(f"weakest link: {top['pair']}, {top['share']:.0%} of the failures")
        lines.extend(self.notes)
        return "\n".join(lines)


@dataclass(frozen=True)
class _Posterior:
    """Draws of the coefficients' errors: ``delta = factor @ z`` over the columns ``columns``
    (the used nodes' pattern blocks, then the shared terms), the level's and the noise's spread."""

    node_rows: dict[int, np.ndarray]  # node index -> rows of ``factor`` holding its coefficients
    shared_rows: np.ndarray
    factor: np.ndarray
    level_std_db: float
    noise_std_db: float


def _posterior_factor(model: PatternSet, node_indices: Sequence[int]) -> _Posterior:
    """A square root of the posterior covariance of the nodes ``node_indices`` and the shared
    terms (eigenvalues clipped at 0: the gauge leaves some directions exactly free)."""
    if model.covariance is None:
        raise InputError("model: a swarm's availability needs the patterns' covariance; this model carries none",
                         param="model")
    p = model.basis.n_coef
    m = len(model.shared_names)
    if m and model.covariance.shape[0] != model.n_pattern_columns + m:
        m = 0
    blocks = [np.arange(k * p, (k + 1) * p) for k in node_indices]
    shared = model.n_pattern_columns + np.arange(m)
    columns = np.concatenate(blocks + [shared]).astype(np.intp)
    cov = model.covariance[np.ix_(columns, columns)]
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    keep = w > max(float(w.max()), 0.0) * 1e-12
    factor = v[:, keep] * np.sqrt(w[keep])
    rows = {int(k): np.arange(i * p, (i + 1) * p) for i, k in enumerate(node_indices)}
    return _Posterior(rows, len(blocks) * p + np.arange(m), factor, model.new_flight_level_std_db,
                      residual_std_db(model))


def _draw_link_rssi(
    model: PatternSet, samples: LinkSamples, mean_dbm: np.ndarray, deltas: np.ndarray, posterior: _Posterior,
    rng: np.random.Generator, fading: bool = True,
) -> np.ndarray:
    """RSSI [dBm] of every sample in every draw, shape ``(samples, draws)`` (float32).

    ``deltas`` are the draws of the coefficients' errors ``(columns, draws)`` (the same for
    every block of samples: the links share them); the level's draws are its last row.
    """
    n_draws = deltas.shape[1]
    out = np.repeat(np.asarray(mean_dbm, np.float32)[:, None], n_draws, axis=1)
    tx, rx = model.end_indices(samples)
    d = samples.directions
    for node, az, el in ((tx, d.az_tx, d.el_tx), (rx, d.az_rx, d.el_rx)):
        for k in np.unique(node):
            sel = np.flatnonzero(node == k)
            f = model.basis.design(np.asarray(az)[sel], np.asarray(el)[sel])
            out[sel] += (f @ deltas[posterior.node_rows[int(k)]]).astype(np.float32)
    if posterior.shared_rows.size:
        shared = model.shared_regressors(samples)[: posterior.shared_rows.size]
        out += (shared.T @ deltas[posterior.shared_rows]).astype(np.float32)
    out += deltas[-1].astype(np.float32)[None, :]  # the flight's level, shared by every link
    if fading and np.isfinite(posterior.noise_std_db) and posterior.noise_std_db > 0:
        out += np.float32(posterior.noise_std_db) * rng.standard_normal(out.shape, dtype=np.float32)
    return out


@check_types
def connected_draws(
    margin: np.ndarray, k: np.ndarray, a: np.ndarray, b: np.ndarray, shape: tuple[int, int, int],
    pairs: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Connectivity of every draw and time of a block.

    Parameters
    ----------
    margin : ndarray (rows, draws)
        RSSI less the sensitivity of every ordered link row [dB] (+inf: near field).
    k, a, b : ndarray of int (rows,)
        Time index within the block, transmitter and receiver of every row.
    shape : (draws, times, drones)
    pairs : ndarray of int (n_pairs, 2)
        Drone pairs whose path is asked for.

    Returns
    -------
    connected : ndarray of bool (draws, times)
    weakest_a, weakest_b : ndarray of int (draws, times)
        The weakest tree edge of every draw-time (meaningful where it is not connected).
    path : ndarray of bool (n_pairs, draws, times)
    """
    n_draws, n_times, n = shape
    directed = np.full((n_draws, n_times, n, n), -np.inf, np.float32)
    directed[:, k, a, b] = margin.T
    w = np.fmin(directed, directed.transpose(0, 1, 3, 2)).reshape(n_draws * n_times, n, n)  # a pair: its weaker way
    edge_w, edge_a, edge_b = maximum_spanning_edges(w)
    rows = np.arange(edge_w.shape[0])
    weakest = np.argmin(edge_w, axis=1)
    connected = edge_w[rows, weakest] >= 0
    # the groups at the threshold: Prim adds b next to a node a already in the tree, so one pass
    # in that order labels every node with its group's first node
    label = np.tile(np.arange(n), (edge_w.shape[0], 1))
    for step in range(n - 1):
        up = edge_w[:, step] >= 0
        nb = edge_b[:, step]
        label[rows, nb] = np.where(up, label[rows, edge_a[:, step]], nb)
    path = np.stack([label[:, i] == label[:, j] for i, j in pairs]) if len(pairs) else np.zeros((0, rows.size), bool)
    return (connected.reshape(n_draws, n_times), edge_a[rows, weakest].reshape(n_draws, n_times),
            edge_b[rows, weakest].reshape(n_draws, n_times), path.reshape(len(pairs), n_draws, n_times))


@dataclass(frozen=True)
class _Swarm:
    """Poses of the drones at the prediction times: (drones, times, 3) positions and (…, 4)
    quaternions, which drones are present, and the drones' pattern indices."""

    drones: list[str]
    t: np.ndarray
    position: np.ndarray
    quat: np.ndarray
    present: np.ndarray  # (times, drones)
    pattern_index: np.ndarray


def _swarm_poses(model: PatternSet, pose_log: pd.DataFrame, options: SwarmOptions, source: str) -> _Swarm:
    tracks = pose_tracks(pose_log, source=source)
    drones = sorted(tracks)
    if len(drones) < 2:
        raise InputError(f"{source}: a swarm needs at least 2 drones, the pose log has {', '.join(drones) or 'none'}")
    patterns = resolve_patterns(drones, model.nodes, options.pattern_of)
    t = prediction_times(tracks, options.step_s, options.times_s)
    poses = [tracks[d].interpolate(t, options.max_gap_s) for d in drones]
    return _Swarm(drones, t, np.stack([p[0] for p in poses]), np.stack([p[1] for p in poses]),
                  np.stack([p[2] == 0 for p in poses], axis=1),
                  np.array([model.node_index(patterns[d]) for d in drones], np.intp))


@check_types
def swarm_availability(
    model: PatternSet,
    pose_log: pd.DataFrame,
    tx_power_dbm: float,
    availability: AvailabilityOptions,
    options: SwarmOptions | None = None,
    source: str = "pose log",
) -> SwarmAvailability:
    """Probability over time that a swarm's link graph is connected, by Monte Carlo.

    Parameters
    ----------
    model : PatternSet
        Learned patterns with their covariance.
    pose_log : DataFrame
        Canonical pose log of the drones (as for :func:`rplearn.analysis.swarm.predict_swarm`).
    tx_power_dbm : float
        Transmit power of every drone [dBm].
    availability : AvailabilityOptions
        Sensitivity, draws, seed and the pairs whose path is asked for.
    options : SwarmOptions, optional
        Carrier, which antenna each drone carries, the times and the longest pose gap (its
        ``min_rssi_dbm`` is not used: the sensitivity is).
    source : str
        What the pose log is, for messages.

    Examples
    --------
    >>> swarm_availability(model, poses, 20, AvailabilityOptions(-90, pairs=[("A", "C")]))  # doctest: +SKIP
    """
    options = SwarmOptions() if options is None else options
    require_patterns(model, "a swarm's availability")
    check_tx_power_dbm(tx_power_dbm, "transmit power")
    frequency_hz = model_frequency_hz(model, options.frequency_hz)
    swarm = _swarm_poses(model, pose_log, options, source)
    n = len(swarm.drones)
    unknown = sorted({d for pair in availability.pairs for d in pair} - set(swarm.drones))
    if unknown:
        raise InputError(f"pairs: drone(s) {', '.join(unknown)} not in the swarm ({', '.join(swarm.drones)})",
                         param="pairs")
    pairs = np.array([[swarm.drones.index(a), swarm.drones.index(b)] for a, b in availability.pairs], np.intp)
    posterior = _posterior_factor(model, sorted(set(swarm.pattern_index.tolist())))
    n_draws = availability.n_draws
    check_work("n_draws", n_draws, lambda k: draws_cost(k, posterior.factor.shape[0], swarm.t.size, n, len(pairs)), "draws")
    rng = np.random.default_rng(availability.seed)
    deltas = posterior.factor @ rng.standard_normal((posterior.factor.shape[1], n_draws))
    deltas = np.vstack([deltas, posterior.level_std_db * rng.standard_normal((1, n_draws))])
    m = swarm.t.size
    connected = np.zeros((n_draws, m), bool)
    paths = np.zeros((len(pairs), n_draws, m), bool)
    culprits = np.zeros((n, n), np.int64)
    step = max(1, DRAW_BLOCK_VALUES // max(n_draws * n * n, 1))
    limit_m = float(far_field_limit_m(frequency_hz))
    for s0 in range(0, m, step):
        s1 = min(m, s0 + step)
        both = swarm.present[s0:s1, :, None] & swarm.present[s0:s1, None, :] & ~np.eye(n, dtype=bool)
        k, a, b = np.nonzero(both)
        ti = k + s0
        pa, pb = swarm.position[a, ti], swarm.position[b, ti]
        d = distance_m(pa, pb)
        samples = LinkSamples(link_directions(pa, swarm.quat[a, ti], pb, swarm.quat[b, ti]), swarm.pattern_index[a],
                              swarm.pattern_index[b], model.nodes, np.full(d.size, np.nan), d,
                              np.full(d.size, frequency_hz), tx_z_m=pa[:, 2], rx_z_m=pb[:, 2])
        near = d <= limit_m
        mean = tx_power_dbm + model.predict_gain(samples) - free_space_path_loss_db(np.where(near, 1.0, d), frequency_hz)
        rssi = _draw_link_rssi(model, samples, mean, deltas, posterior, rng, availability.fading)
        margin = np.where(near[:, None], np.inf, rssi - np.float32(availability.sensitivity_dbm))
        ok, wa, wb, path = connected_draws(margin, k, a, b, (n_draws, s1 - s0, n), pairs)
        connected[:, s0:s1] = ok
        paths[:, :, s0:s1] = path
        complete = np.asarray(np.all(swarm.present[s0:s1], axis=1), bool)
        failed = ~ok & complete[None, :]  # a missing drone is unknown, not a failure  # a missing drone is unknown, not a failure
        np.add.at(culprits, (np.minimum(wa, wb)[failed], np.maximum(wa, wb)[failed]), 1)
    return _result(swarm, connected, paths, culprits, availability)


def _result(
    swarm: _Swarm, connected: np.ndarray, paths: np.ndarray, culprits: np.ndarray, availability: AvailabilityOptions,
) -> SwarmAvailability:
    """The tables of :class:`SwarmAvailability` from the draws' outcomes."""
    n_missing = (~swarm.present).sum(axis=1)
    p = connected.mean(axis=0)
    unknown = n_missing > 0
    table = {"t": swarm.t, "n_missing": n_missing.astype(int),
             "p_connected": np.where(unknown, np.nan, p),
             "p_connected_se": np.where(unknown, np.nan, np.sqrt(p * (1 - p) / connected.shape[0]))}
    for (a, b), path in zip(availability.pairs, paths):
        table[f"p_path_{a}-{b}"] = path.mean(axis=0)  # a missing drone has no path
    total = int(culprits.sum())
    i, j = np.nonzero(culprits)
    weakest = pd.DataFrame({"pair": [f"{swarm.drones[x]}-{swarm.drones[y]}" for x, y in zip(i, j)],
                            "failures": culprits[i, j].astype(int)})
    weakest["share"] = weakest["failures"] / max(total, 1)
    weakest = weakest.sort_values("failures", ascending=False, kind="stable").reset_index(drop=True)
    notes = []
    if unknown.any():
        notes.append(f"note: at {int(unknown.sum()):,} time(s) a drone has no pose: P(connected) unknown there (NaN)")
    return SwarmAvailability(pd.DataFrame(table), weakest, int(availability.n_draws),
                             float(availability.sensitivity_dbm), notes)


__all__ = [
    "DEFAULT_DRAWS",
    "AvailabilityOptions",
    "SwarmAvailability",
    "connected_draws",
    "link_availability_column",
    "residual_std_db",
    "swarm_availability",
]
