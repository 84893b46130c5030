"""Headings that maximise links: one yaw-grid search for a link and for a hovering swarm.

A level drone sees another at azimuth ``bearing - yaw`` and at a fixed elevation, so its share
of a link's joint gain is a function of its own yaw only. :func:`heading_gain_tables`
tabulates, for every ordered pair of drones ``(a, b)``, the gain of ``a``'s pattern toward ``b``
over a list of yaws of ``a`` (directions from :mod:`rplearn.core.geometry`). Both searches read
these tables:

- :func:`best_yaw` (``rplearn orient``): one link between two drones. Its joint gain is the sum
  of the two ends' shares, so each end that may turn takes its best grid yaw, ranked by a
  lower bound (the share less ``caution_z`` standard errors, :data:`CAUTION_Z` by default).
- :func:`best_swarm_headings` (``rplearn headings``): any number of drones, maximising the
  bottleneck RSSI of the swarm (:func:`rplearn.analysis.swarm.spanning_bottleneck`) as
  predicted. With two drones the bottleneck is the one link, and the result is
  :func:`best_yaw`'s with both drones turning and ``caution_z=0``.

Yaws are ENU, counter-clockwise from east [deg].
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from rplearn._argtypes import check_types
from rplearn._budget import Budget, Cost, budget, check_work
from rplearn.analysis.heading_options import CAUTION_Z, SwarmHeadingOptions, YawOptions, check_turn  # noqa: F401 (CAUTION_Z: documented here)
from rplearn.analysis.heading_search import EXHAUSTIVE_MAX_COMBINATIONS, search  # noqa: F401 (the constant is documented here)
from rplearn.analysis.swarm import maximum_spanning_edges, resolve_patterns
from rplearn.core.geometry import direction_in_body, distance_m, quat_wxyz_from_yaw
from rplearn.core.link import free_space_path_loss_db, received_power_dbm
from rplearn.core.plausible import check_plausible
from rplearn.data.tables import check_tx_power_dbm
from rplearn.errors import InputError
from rplearn.models.base import model_frequency_hz, relative_levels, require_calibrated, require_patterns
from rplearn.models.patterns import PatternSet
from rplearn.models.predict import UNCOVERED_DEG

Pair = tuple[str, str]
Score = tuple[float, float]


# The yaw grid and the gain tables both searches read -------------------------------------


#: Finest yaw step [deg] and the memory the swarm search's yaw-pair tables may take [bytes].
MIN_YAW_STEP_DEG = 0.01
MAX_HEADING_TABLE_BYTES = 1 << 30


def yaw_grid_deg(step_deg: float) -> np.ndarray:
    """Yaws ``-180, -180 + step, ...`` below 180 [deg].

    Raises
    ------
    InputError
        (``param="step_deg"``) unless ``0 < step_deg <= 90``.
    """
    if not (MIN_YAW_STEP_DEG <= step_deg <= 90):
        raise InputError(f"step_deg: expected a yaw step in [{MIN_YAW_STEP_DEG}, 90] deg, got {step_deg}", param="step_deg")
    return np.arange(-180.0, 180.0, step_deg)


def heading_tables_cost(n_drones: int, step_deg: float) -> Cost:
    """What the swarm search's yaw-pair tables take: 8 bytes a value, and a few passes over them
    (about 5 ns a value each)."""
    n_pairs = n_drones * (n_drones - 1) // 2
    values = n_pairs * (360.0 / step_deg + n_drones) ** 2
    return Cost(memory_bytes=8.0 * values, seconds=20 * 5e-9 * values)


def check_heading_tables(n_drones: int, step_deg: float) -> None:
    """Refuse a swarm heading search whose yaw-pair tables would not fit in the work budget
    (:mod:`rplearn._budget`; at most :data:`MAX_HEADING_TABLE_BYTES`), naming the finest yaw step that does."""
    limits = budget()
    limits = Budget(min(limits.memory_bytes, MAX_HEADING_TABLE_BYTES), limits.seconds)
    check_work("step_deg", float(step_deg), lambda s: heading_tables_cost(n_drones, s), "deg", integer=False,
               bounds=(MIN_YAW_STEP_DEG, 90.0), falling=True, limits=limits)


@check_types
def heading_gain_tables(
    model: PatternSet, positions: Mapping[str, ArrayLike], patterns: Mapping[str, str], yaw_grid_deg: np.ndarray
) -> dict[Pair, np.ndarray]:
    """Gain of drone ``a``'s pattern toward drone ``b`` for every yaw of a level ``a`` [dBi].

    Parameters
    ----------
    model : PatternSet
        Learned patterns.
    positions : mapping
        Drone -> position ``(x, y, z)``, ENU [m].
    patterns : mapping
        Drone -> the model's node whose pattern it carries.
    yaw_grid_deg : ndarray
        Yaws of ``a`` to tabulate [deg].

    Returns
    -------
    dict
        ``(a, b)`` -> gains over ``yaw_grid_deg``, for every ordered pair of distinct drones.
    """
    return {(a, b): model.evaluate(patterns[a], az, el) for (a, b), (az, el) in _pair_directions(positions, yaw_grid_deg).items()}


def _pair_directions(positions: Mapping[str, ArrayLike], yaw_grid_deg: np.ndarray) -> dict[Pair, tuple[np.ndarray, np.ndarray]]:
    """``(a, b)`` -> body-frame azimuth and elevation [rad] of ``b`` seen from a level ``a`` at
    every yaw of the grid, for every ordered pair of distinct drones."""
    yaws = np.asarray(yaw_grid_deg, np.float64)
    q = quat_wxyz_from_yaw(np.radians(yaws))
    out = {}
    for a in positions:
        pa = np.broadcast_to(np.asarray(positions[a], np.float64), (yaws.size, 3))
        for b in positions:
            if a != b:
                pb = np.broadcast_to(np.asarray(positions[b], np.float64), (yaws.size, 3))
                out[(a, b)] = direction_in_body(pa, q, pb)
    return out


@check_types
def heading_std_tables(
    model: PatternSet, positions: Mapping[str, ArrayLike], patterns: Mapping[str, str], yaw_grid_deg: np.ndarray
) -> dict[Pair, np.ndarray] | None:
    """Standard error [dB] of every entry of :func:`heading_gain_tables` (None for a model
    without a covariance): larger where a drone would face the other in a direction the
    flight never looked in."""
    if getattr(model, "covariance", None) is None:
        return None
    return {(a, b): model.standard_error(patterns[a], az, el)
            for (a, b), (az, el) in _pair_directions(positions, yaw_grid_deg).items()}




# -------------------------------------------------------------------------------------------
# One link


@check_types
@dataclass(frozen=True)
class OrientationResult:
    """Headings that maximise a link, the predicted joint gain there and, given the transmit
    power, the received power before and after.

    Attributes
    ----------
    tx_yaw_deg, rx_yaw_deg : float
        Best yaws (the given yaw for an end that may not turn) [deg].
    gain_db, baseline_gain_db : float
        Joint gain at the best and at the given yaws [dB].
    distance_m : float or None
        Distance between the drones [m].
    rssi_dbm, baseline_rssi_dbm : float or None
        Received power at the best and at the given yaws [dBm] (None without a transmit power).
    frequency_hz : float or None
        Carrier used for the received power [Hz].
    coverage_deg : (float, float) or None
        At the best yaws, the angle from the direction each end looks at the other to the
        nearest direction its antenna was learned from [deg] (models that store coverage).
    gain_std_db : float or None
        Standard error of ``gain_db`` (both ends) [dB] (None for a model without covariance).
    boldest : (float, float, float) or None
        When ranking by the lower bound changed the choice: the tx yaw, rx yaw [deg] and joint
        gain [dB] that the prediction alone would have chosen.
    availability, baseline_availability : float or None
        ``P(RSSI >= sensitivity)`` at the best and at the given yaws (ranked by availability,
        ``YawOptions.sensitivity_dbm``).
    sensitivity_dbm, min_availability : float or None
        What they were ranked against.
    """

    tx_yaw_deg: float
    rx_yaw_deg: float
    gain_db: float
    baseline_gain_db: float
    distance_m: float | None = None
    rssi_dbm: float | None = None
    baseline_rssi_dbm: float | None = None
    frequency_hz: float | None = None
    coverage_deg: tuple[float, float] | None = None
    gain_std_db: float | None = None
    boldest: tuple[float, float, float] | None = None
    availability: float | None = None
    baseline_availability: float | None = None
    sensitivity_dbm: float | None = None
    min_availability: float | None = None

    def summary(self) -> str:
        """The best yaws and the gain in received power (or joint gain) they bring, for people."""
        lines = [f"best yaw: tx {self.tx_yaw_deg:.0f} deg, rx {self.rx_yaw_deg:.0f} deg (ENU, ccw from east)"]
        if self.rssi_dbm is not None and self.baseline_rssi_dbm is not None:
            before, after = self.baseline_rssi_dbm, self.rssi_dbm
            lines.append(f"predicted received power: {before:.1f} dBm now -> {after:.1f} dBm ({after - before:+.1f} dB)")
        else:
            before, after = self.baseline_gain_db, self.gain_db
            lines.append(f"predicted joint gain: {before:.1f} dB now -> {after:.1f} dB ({after - before:+.1f} dB)")
        if self.gain_std_db is not None:
            lines[-1] += f", +- {self.gain_std_db:.1f} dB (1 sigma, the model's error: patterns and any learned path-loss exponent or offset)"
        if self.availability is not None and self.baseline_availability is not None:
            lines.append(f"availability at {self.sensitivity_dbm:g} dBm: {self.baseline_availability:.3f} now -> "
                         f"{self.availability:.3f}" + ("" if self.min_availability is None else (
                             f" (the strongest heading with at least {self.min_availability:g})"
                             if self.availability >= self.min_availability else
                             f" (none reaches {self.min_availability:g}: the most available heading)")))
        if self.boldest is not None:
            lines.append(
                f"the prediction alone would turn to tx {self.boldest[0]:.0f} deg, rx {self.boldest[1]:.0f} deg "
                f"({self.boldest[2] - self.gain_db:+.1f} dB more) where it is less sure; chosen by its lower bound")
        if self.coverage_deg is not None and max(self.coverage_deg) > UNCOVERED_DEG:
            lines.append(
                f"caution: at these headings the link looks {self.coverage_deg[0]:.0f} deg (tx) and "
                f"{self.coverage_deg[1]:.0f} deg (rx) from any direction the antennas were learned from; beyond "
                f"{UNCOVERED_DEG:g} deg the gain is an extrapolation (or the prior's): fly those directions before relying on it")
        return "\n".join(lines)


@check_types
def best_yaw(
    model: PatternSet,
    tx_node: str,
    rx_node: str,
    tx_position_xyz: Sequence[float],
    rx_position_xyz: Sequence[float],
    turn: str = "tx",
    options: YawOptions | None = None,
) -> OrientationResult:
    """Heading(s) of level drones at given ENU positions that maximise the predicted joint gain.

    Headings are ranked by a lower bound of the gain, the prediction minus ``caution_z``
    standard errors of each end: where the flight never looked the pattern's spread is large,
    so of two headings predicted alike the one the flight saw wins, and an extrapolated peak
    must promise more than its uncertainty to be chosen.

    Parameters
    ----------
    model : PatternSet
        Learned patterns; ``tx_node`` and ``rx_node`` are its nodes.
    tx_position_xyz, rx_position_xyz : sequence of float
        Positions, ENU [m].
    turn : {"tx", "rx", "both"}
        Which drone may turn; the other keeps its given yaw (``options.tx_yaw_deg``,
        ``options.rx_yaw_deg``: ENU, ccw from east [deg]).
    options : YawOptions, optional
        Current yaws, yaw grid, transmit power, carrier and caution (default ``YawOptions()``).

    Examples
    --------
    >>> best_yaw(model, "A", "B", [0, 0, 10], [0, 20, 10], "both", YawOptions(tx_power_dbm=20))  # doctest: +SKIP
    """
    options = YawOptions() if options is None else options
    tx_yaw_deg, rx_yaw_deg, step_deg = options.tx_yaw_deg, options.rx_yaw_deg, options.step_deg
    tx_power_dbm, frequency_hz, caution_z = options.tx_power_dbm, options.frequency_hz, options.caution_z
    require_patterns(model, "choosing a heading")
    if not (np.isfinite(caution_z) and caution_z >= 0):
        raise InputError(f"caution_z: expected a finite number >= 0, got {caution_z!r}", param="caution_z")
    check_turn(turn)
    grid = yaw_grid_deg(step_deg)
    if tx_power_dbm is not None:
        check_tx_power_dbm(tx_power_dbm, "transmit power")
        if relative_levels(model):  # levels not in dBm: the joint gain [dB] alone is ranked and printed
            tx_power_dbm = None
    if tx_power_dbm is not None or frequency_hz is not None:  # a stated carrier of the model's band
        frequency_hz = model_frequency_hz(model, frequency_hz)
    n = grid.size
    yaws = np.concatenate([grid, [float(tx_yaw_deg), float(rx_yaw_deg)]])  # the given yaws follow the grid
    positions = {"tx": tx_position_xyz, "rx": rx_position_xyz}
    _check_places(model, positions)
    tables = heading_gain_tables(model, positions, {"tx": tx_node, "rx": rx_node}, yaws)
    g_tx, g_rx = tables[("tx", "rx")], tables[("rx", "tx")]
    spread = heading_std_tables(model, positions, {"tx": tx_node, "rx": rx_node}, yaws)
    s_tx, s_rx = (spread[("tx", "rx")], spread[("rx", "tx")]) if spread else (np.zeros_like(g_tx), np.zeros_like(g_rx))
    z = float(caution_z) if spread else 0.0

    def pick(gain_tx: np.ndarray, gain_rx: np.ndarray) -> tuple[int, int]:
        return (int(np.argmax(gain_tx[:n])) if turn in ("tx", "both") else n,
                int(np.argmax(gain_rx[:n])) if turn in ("rx", "both") else n + 1)

    i_tx, i_rx = pick(g_tx - z * s_tx, g_rx - z * s_rx)
    b_tx, b_rx = pick(g_tx, g_rx)
    env_std = float(model.link_environment_std_db(tx_node, rx_node, positions["tx"], positions["rx"])[0])
    risk: dict[str, float | None] = {}
    if options.sensitivity_dbm is not None:  # rank by availability
        from rplearn.analysis.risk_headings import risk_link_choice

        i_tx, i_rx, risk = risk_link_choice(model, (tx_node, rx_node), positions, ((g_tx, g_rx), (s_tx, s_rx), env_std),
                                      n, turn, options)
    gain = float(g_tx[i_tx] + g_rx[i_rx])
    bold = float(g_tx[b_tx] + g_rx[b_rx])
    result = OrientationResult(
        float(yaws[i_tx]), float(yaws[i_rx]), gain, float(g_tx[n] + g_rx[n + 1]),
        coverage_deg=_link_coverage(model, tx_node, rx_node, positions, float(yaws[i_tx]), float(yaws[i_rx])),
        gain_std_db=float(np.sqrt(s_tx[i_tx] ** 2 + s_rx[i_rx] ** 2 + env_std**2)) if spread else None,
        boldest=(float(yaws[b_tx]), float(yaws[b_rx]), bold) if bold > gain + 0.5 else None, **risk,
    )
    if tx_power_dbm is None:
        return result
    env = float(model.link_environment_db(tx_node, rx_node, positions["tx"], positions["rx"], frequency_hz)[0])
    return _with_received_power(result, positions, float(tx_power_dbm), model_frequency_hz(model, frequency_hz), env)


def _check_places(model: PatternSet, positions: Mapping[str, ArrayLike]) -> None:
    """Plausible places: every drone above a two-ray model's ground, every pair within a radio
    link's reach (:data:`rplearn.core.plausible.PLAUSIBLE`)."""
    xyz = {k: np.asarray(v, np.float64).ravel() for k, v in positions.items()}
    for name, p in xyz.items():
        if p.size == 3:
            model.path_loss.check_heights(p[2], f"{name} position", "z [m]")
    names = [k for k, p in xyz.items() if p.size == 3]
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            check_plausible("link_distance_m", float(np.linalg.norm(xyz[a] - xyz[b])), f"{a} to {b}", field="distance [m]")


def _link_coverage(
    model: PatternSet, tx_node: str, rx_node: str, positions: Mapping[str, Sequence[float]], tx_yaw_deg: float,
    rx_yaw_deg: float,
) -> tuple[float, float] | None:
    """Coverage [deg] of the directions each end (level, at its yaw) looks at the other."""
    d = np.asarray(positions["rx"], np.float64) - np.asarray(positions["tx"], np.float64)
    el = float(np.arctan2(d[2], np.hypot(d[0], d[1])))
    az_tx = float(np.arctan2(d[1], d[0])) - np.radians(tx_yaw_deg)
    az_rx = float(np.arctan2(-d[1], -d[0])) - np.radians(rx_yaw_deg)
    cov_tx = model.coverage_deg(tx_node, [az_tx], [el])
    cov_rx = model.coverage_deg(rx_node, [az_rx], [-el])
    if cov_tx is None or cov_rx is None:
        return None
    return float(cov_tx[0]), float(cov_rx[0])


def _with_received_power(
    result: OrientationResult, positions: Mapping[str, Sequence[float]], tx_power_dbm: float, frequency_hz: float,
    environment_db: float = 0.0,
) -> OrientationResult:
    """``result`` with the distance [m] and the received power before and after [dBm] (Friis,
    plus the model's environment term and link offset, which no heading changes)."""
    d = float(distance_m(np.asarray(positions["tx"], np.float64), np.asarray(positions["rx"], np.float64)))
    return dataclasses.replace(
        result,
        distance_m=d,
        rssi_dbm=float(received_power_dbm(tx_power_dbm, result.gain_db + environment_db, d, frequency_hz)),
        baseline_rssi_dbm=float(received_power_dbm(tx_power_dbm, result.baseline_gain_db + environment_db, d,
                                                   frequency_hz)),
        frequency_hz=frequency_hz,
    )


# -------------------------------------------------------------------------------------------
# A hovering swarm


@check_types
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
    sweeps : int
        Sweeps of the coordinate ascent (0 for an exhaustive search).
    availability, start_availability, sensitivity_dbm, min_availability : float or None
        Ranked by availability: the weakest link's of the most available spanning tree at the
        chosen and the starting yaws, at ``sensitivity_dbm`` (:mod:`rplearn.analysis.risk_headings`).
    """

    yaw_deg: dict[str, float]
    start_yaw_deg: dict[str, float]
    pair_rssi_dbm: pd.DataFrame
    start_pair_rssi_dbm: pd.DataFrame
    bottleneck_dbm: float
    start_bottleneck_dbm: float
    sweeps: int
    availability: float | None = None
    start_availability: float | None = None
    sensitivity_dbm: float | None = None
    min_availability: float | None = None

    def to_frame(self) -> pd.DataFrame:
        """One row per drone: ``drone, start_yaw_deg, yaw_deg``."""
        return pd.DataFrame(
            {
                "drone": list(self.yaw_deg),
                "start_yaw_deg": [self.start_yaw_deg[d] for d in self.yaw_deg],
                "yaw_deg": list(self.yaw_deg.values()),
            }
        )

    def to_dict(self) -> dict[str, object]:
        """The chosen yaws and bottleneck RSSI before and after, as plain values for JSON."""
        return {
            "yaw_deg": dict(self.yaw_deg),
            "bottleneck_dbm": self.bottleneck_dbm,
            "start_bottleneck_dbm": self.start_bottleneck_dbm,
            **({} if self.availability is None else {"availability": self.availability,
                                                     "start_availability": self.start_availability,
                                                     "sensitivity_dbm": self.sensitivity_dbm})}

    def summary(self) -> str:
        lines = [
            "drone  yaw now -> best [deg] (ENU, ccw from east)",
            *(f"  {d}: {self.start_yaw_deg[d]:7.1f} -> {self.yaw_deg[d]:7.1f}" for d in self.yaw_deg),
            f"bottleneck RSSI: {self.start_bottleneck_dbm:.1f} dBm now -> {self.bottleneck_dbm:.1f} dBm "
            f"({self.bottleneck_dbm - self.start_bottleneck_dbm:+.1f} dB); the swarm stays connected for any "
            "threshold below it",
            "pair RSSI now -> best [dBm]:",
        ]
        if self.availability is not None and self.start_availability is not None:
            lines.insert(-1, f"availability of the weakest link at {self.sensitivity_dbm:g} dBm: "
                             f"{self.start_availability:.3f} now -> {self.availability:.3f}"
                             + ("" if self.min_availability is None else f" (required {self.min_availability:g})"))
        before = self.start_pair_rssi_dbm.set_index("pair")["rssi_dbm"]
        for _, row in self.pair_rssi_dbm.iterrows():
            lines.append(f"  {row['pair']}: {before[row['pair']]:6.1f} -> {row['rssi_dbm']:6.1f}")
        return "\n".join(lines)


@dataclass(frozen=True)
class _HeadingProblem:
    """Every pair's RSSI as a function of the drones' yaws, indexed into ``yaw_deg``.

    ``yaw_deg`` is the yaw grid (its first ``n_grid`` values) followed by the drones' start
    yaws; a *choice* maps every drone to an index into it.
    """

    drones: list[str]
    pairs: list[Pair]
    yaw_deg: np.ndarray
    n_grid: int
    tables: dict[Pair, np.ndarray]
    base_dbm: dict[Pair, float]  # transmit power minus free-space path loss
    iu: np.ndarray  # drone index of each pair's first and second drone
    ju: np.ndarray

    @property
    def start_index(self) -> dict[str, int]:
        return {d: self.n_grid + i for i, d in enumerate(self.drones)}

    def pair_rssi(self, choice: Mapping[str, int]) -> np.ndarray:
        """RSSI of every pair [dBm] at the chosen yaws."""
        t = self.tables
        return np.array([self.base_dbm[(a, b)] + t[(a, b)][choice[a]] + t[(b, a)][choice[b]] for a, b in self.pairs])

    def score(self, choice: Mapping[str, int]) -> Score:
        """Bottleneck RSSI, then mean pair RSSI [dBm]: larger is better."""
        b, m = self.scores(self.pair_rssi(choice)[None, :])
        return float(b[0]), float(m[0])

    def scores(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bottleneck and mean pair RSSI [dBm] of many choices at once: ``w`` (choices, pairs)."""
        n = len(self.drones)
        full = np.full((w.shape[0], n, n), -np.inf)
        full[:, self.iu, self.ju] = w
        full[:, self.ju, self.iu] = w
        edge_w = maximum_spanning_edges(full)[0]
        bottleneck = edge_w.min(axis=1) if n > 1 else np.full(w.shape[0], np.inf)
        return np.where(np.isneginf(bottleneck), np.nan, bottleneck), w.mean(axis=1)

    def yaw_scores(self, choice: Mapping[str, int], drone: str) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`scores` of ``choice`` with ``drone`` at every grid yaw (one sweep step, array
        operations on the gain tables, no model call)."""
        k = np.arange(self.n_grid)
        t = self.tables
        w = np.empty((self.n_grid, len(self.pairs)))
        for j, (a, b) in enumerate(self.pairs):
            ia = k if a == drone else choice[a]
            ib = k if b == drone else choice[b]
            w[:, j] = self.base_dbm[(a, b)] + t[(a, b)][ia] + t[(b, a)][ib]
        return self.scores(w)

    def pair_table(self, choice: Mapping[str, int]) -> pd.DataFrame:
        return pd.DataFrame({"pair": [f"{a}-{b}" for a, b in self.pairs], "rssi_dbm": self.pair_rssi(choice)})


@check_types
def best_swarm_headings(
    model: PatternSet,
    positions: Mapping[str, ArrayLike],
    tx_power_dbm: float,
    options: SwarmHeadingOptions | None = None,
) -> SwarmHeadings:
    """Yaws of hovering, level drones that maximise the swarm's bottleneck RSSI.

    On a yaw grid of ``options.step_deg``, maximising the bottleneck and, among equal
    bottlenecks, the mean pair RSSI. Up to three drones the search is exhaustive (the global
    optimum on the grid) when the grid has at most :data:`EXHAUSTIVE_MAX_COMBINATIONS`
    combinations (72^3 at the default 5 deg). Otherwise coordinate ascent (each drone in turn
    takes its best yaw with the others held, until a sweep changes nothing) from the current
    yaws and from ``options.restarts`` seeded random ones: a local optimum. Either way the
    result is never worse than the current yaws.

    Parameters
    ----------
    model : PatternSet
        Learned patterns.
    positions : mapping
        Drone -> hover position ``(x, y, z)``, ENU [m].
    tx_power_dbm : float
        Transmit power of every drone [dBm].
    options : SwarmHeadingOptions, optional
        Carrier, which antenna each drone carries, current and fixed yaws, yaw grid and search
        limits (default ``SwarmHeadingOptions()``).

    Examples
    --------
    >>> best_swarm_headings(model, positions, 20, SwarmHeadingOptions(pattern_of={"C": "A"}))  # doctest: +SKIP
    """
    options = SwarmHeadingOptions() if options is None else options
    frequency_hz, pattern_of, start_yaw_deg = options.frequency_hz, options.pattern_of, options.start_yaw_deg
    fixed, step_deg, max_sweeps, restarts = options.fixed, options.step_deg, options.max_sweeps, options.restarts
    require_patterns(model, "choosing headings")
    frequency_hz = model_frequency_hz(model, frequency_hz)
    grid = yaw_grid_deg(step_deg)
    drones = sorted(positions)
    _check_swarm(drones, positions, tx_power_dbm, start_yaw_deg or {}, fixed)
    _check_places(model, {d: positions[d] for d in drones})
    require_calibrated(model, "choosing headings by RSSI")
    check_heading_tables(len(drones), step_deg)
    patterns = resolve_patterns(drones, model.nodes, pattern_of)
    start = {d: float((start_yaw_deg or {}).get(d, 0.0)) for d in drones}
    problem = _heading_problem(model, {d: positions[d] for d in drones}, patterns, grid, start, tx_power_dbm, frequency_hz)
    free = [d for d in drones if d not in fixed]
    risk: dict[str, float | None] = {}
    if options.sensitivity_dbm is not None:  # rank by availability (never less available than now)
        from rplearn.analysis.risk_headings import risk_swarm_choice

        stds = heading_std_tables(model, {d: positions[d] for d in drones}, patterns, problem.yaw_deg)
        choice, risk, sweeps = risk_swarm_choice(model, problem, stds, free, options)
        best = problem.score(choice)
    else:
        choice, best, sweeps = search(problem, free, max_sweeps, restarts)
    start_score = problem.score(problem.start_index)
    if start_score > best and not risk:  # never worse than the current yaws (which may lie off the grid)
        best, choice = start_score, problem.start_index
    return SwarmHeadings(
        yaw_deg={d: float(problem.yaw_deg[choice[d]]) for d in drones},
        start_yaw_deg=start,
        pair_rssi_dbm=problem.pair_table(choice),
        start_pair_rssi_dbm=problem.pair_table(problem.start_index),
        bottleneck_dbm=best[0],
        start_bottleneck_dbm=start_score[0],
        sweeps=sweeps, **risk,
    )


def _check_swarm(
    drones: Sequence[str], positions: Mapping[str, ArrayLike], tx_power_dbm: float, start_yaw_deg: Mapping[str, float],
    fixed: Sequence[str],
) -> None:
    """Refuse fewer than two drones, a non-finite power, position or yaw, a start yaw or a fixed
    drone that names no drone."""
    if len(drones) < 2:
        raise InputError(f"positions: a swarm needs at least 2 drones, got {', '.join(drones) or 'none'}", param="positions")
    check_tx_power_dbm(tx_power_dbm, "transmit power")
    for d in drones:
        p = np.asarray(positions[d], np.float64)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InputError(f"positions: drone {d}: expected three finite numbers x,y,z in metres", param="positions")
        if not np.isfinite(float(start_yaw_deg.get(d, 0.0))):
            raise InputError(f"start_yaw_deg: drone {d}: expected a finite number of degrees", param="start_yaw_deg")
    strays = sorted(set(start_yaw_deg) - set(drones))
    if strays:
        raise InputError(f"start_yaw_deg names drone(s) {', '.join(strays)} without a position", param="start_yaw_deg")
    unknown = sorted(set(fixed) - set(drones))
    if unknown:
        raise InputError(f"fixed names unknown drone(s) {', '.join(unknown)}; drones: {', '.join(drones)}", param="fixed")


def _heading_problem(
    model: PatternSet, positions: Mapping[str, ArrayLike], patterns: Mapping[str, str], grid: np.ndarray,
    start: Mapping[str, float], tx_power_dbm: float, frequency_hz: float,
) -> _HeadingProblem:
    """Gain tables over the grid and the start yaws, and every pair's free-space budget."""
    drones = list(positions)
    yaws = np.concatenate([grid, [start[d] for d in drones]])  # the start yaws follow the grid
    pairs = [(a, b) for i, a in enumerate(drones) for b in drones[i + 1 :]]
    base = {}
    for a, b in pairs:
        dist = float(distance_m(np.asarray(positions[a], np.float64), np.asarray(positions[b], np.float64)))
        # the environment term and the offsets change with no heading: the weaker direction's
        env = min(float(model.link_environment_db(patterns[a], patterns[b], positions[a], positions[b], frequency_hz)[0]),
                  float(model.link_environment_db(patterns[b], patterns[a], positions[b], positions[a], frequency_hz)[0]))
        base[(a, b)] = tx_power_dbm - float(free_space_path_loss_db(dist, frequency_hz)) + env
    tables = heading_gain_tables(model, positions, patterns, yaws)
    iu = np.array([drones.index(a) for a, _ in pairs])
    ju = np.array([drones.index(b) for _, b in pairs])
    return _HeadingProblem(drones, pairs, yaws, grid.size, tables, base, iu, ju)
