"""Next-best manoeuvre: which flight from here shrinks the per-node pattern spread fastest.

The posterior of a fixed-order pattern fit is Gaussian with precision
``Lambda = (X^T X + diag(ridge + penalty)) / sigma^2`` over the pattern columns: the accumulated
normal equations (:class:`~rplearn.core.lsq.normal_equations.NormalEquations`), the project's
ridge and smoothness penalty (:func:`~rplearn.core.lsq.penalty.penalty_vector`: the relative
smoothing of the :class:`~rplearn.models.spec.ModelSpec` times the statistics' own scale, or an
absolute weight) and the noise variance. A manoeuvre adds the rows ``F`` of the features its
packets would carry (poses of the manoeuvre's references, tilted into their acceleration ->
link directions in each body frame -> basis features of both ends, both link directions at the
packet rate): ``Lambda' = Lambda + w F^T F / sigma^2``. The covariance after it comes from the
Woodbury identity (a manoeuvre with more feature rows than columns first compressed to the
triangular factor of its ``F^T F``, the same update), of which the spreads need only the
nodes' diagonal blocks.

Each node's *spread* is read as the decoupling certificate reads it
(:mod:`rplearn.analysis.decoupling`): the RMS over the target directions of the posterior std
of the node's gain, the node's mean over them removed (the constant of a two-node link is a
convention), ``sqrt(sum(M_k * Sigma_kk))`` with ``M_k`` the mean-removed design's second
moment. The target directions are the whole sphere by default, an elevation band, or given
directions per node. A manoeuvre's score is the reduction of the nodes' RMS spread (or of the
largest, ``aggregate="max"``) per second of flight, its time to reach its start included;
with ``prefixes`` above 1 a long candidate is scored by its best prefix too, which is then
what is flown (its braking counted).
Shared columns (link offsets, the environment term) are left out of the posterior.

Besides the white noise the posterior may carry (:mod:`rplearn.analysis.manoeuvre_posterior`):
an error drifting over seconds (``correlated_std_db``, from the time-block sums), a prior whose
variance exceeds what the penalty implies (``prior_variance_factor``) and the pattern structure
the fixed order cannot represent, fixed per direction cell (``misfit_std_db``,
:mod:`rplearn.analysis.manoeuvre_cells`); the last two are off by default
(``benchmarks/manoeuvres.py --posterior honest``: within the cells' scatter, 2.2x as slow).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.analysis.manoeuvre_aimed import target_directions, widest_directions
from rplearn.analysis.manoeuvre_cells import DirectionCells, cell_grid
from rplearn.analysis.manoeuvre_design import design_order
from rplearn.analysis.manoeuvre_lookahead import Scored, lookahead_order
from rplearn.analysis.manoeuvre_posterior import ManoeuvrePosterior
from rplearn.analysis.manoeuvre_prior import prior_penalty_weight
from rplearn.analysis.manoeuvre_rows import Steady, known_rows_and_ends, manoeuvre_rows, rows_and_ends
from rplearn.analysis.manoeuvre_tilt import steady_tilt_accel
from rplearn.core.basis_base import Basis
from rplearn.core.geometry import yaw_from_quat_wxyz
from rplearn.core.lsq.block_sums import DEFAULT_BLOCK_S, BlockSums, correlated_ratio
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import DEFAULT_PENALTY_POWER, penalty_scale
from rplearn.core.threads import one_blas_thread
from rplearn.errors import InputError
from rplearn.models.spec import ModelSpec
from rplearn.plan.aimed import aimed_manoeuvres
from rplearn.plan.manoeuvres import Candidate, CandidateOptions, candidate_manoeuvres
from rplearn.plan.prefix import braking_s, cut_candidate, prefix_cuts
from rplearn.plan.trajectory import G_M_S2

#: How the nodes' spreads are combined into one score.
AGGREGATES = ("rms", "max")
#: What a manoeuvre's effect per second is measured in (:attr:`ManoeuvreOptions.rate`).
RATES = ("spread", "information")
#: How the candidates are ordered (:attr:`ManoeuvreOptions.design`), and the design's steps for ``"end"``.
DESIGNS, DESIGN_STEPS = ("rate", "end", "support"), 30


@check_types
@dataclass(frozen=True)
class ManoeuvreOptions:
    """How :func:`rank_manoeuvres` scores manoeuvres.

    Attributes
    ----------
    noise_std_db : float
        Standard deviation of one RSSI reading about the model [dB] (a live fit's residual).
    packet_rate_hz : float
        Packets per second in each link direction.
    sample_rate_hz : float
        Rate at which a manoeuvre's poses are sampled for its features [Hz]; each sample stands
        for ``packet_rate_hz / sample_rate_hz`` packets.
    target_el_deg : (float, float)
        The band of body-frame elevations the spread is taken over [deg] (default the sphere).
    target_points : int
        Points of the Fibonacci grid covering the sphere, of which the band is kept.
    targets : mapping of node to (az, el) arrays, optional
        Target directions per node [rad], instead of the band.
    penalty_weight : float or None
        Absolute weight of the smoothness penalty (``smoothing * scale`` of
        :func:`~rplearn.core.lsq.penalty.penalty_vector`); None: the spec's relative smoothing
        times the statistics' scale (:func:`~rplearn.core.lsq.penalty.penalty_scale`), held
        fixed for the manoeuvres' updates.
    power : float
        Exponent of the roughness weights.
    candidates : CandidateOptions
        Which manoeuvres the vehicles can fly (fixed nodes, speeds, elevations, library).
    aggregate : str
        ``"rms"`` (the nodes' RMS spread) or ``"max"`` (the largest).
    rate : str
        What the candidates are ranked by per second: ``"spread"`` (the combined spread's
        reduction [dB/s]) or ``"information"`` (the growth of its inverse square [1/(dB^2 s)]:
        under a steady information rate the spread falls as ``1/sqrt(t)``, so its reduction per
        second favours short manoeuvres, the inverse square's growth does not; with the loop
        sweeps it met benchmarks/manoeuvres.py's checks in 7 of 12 cells against 6).
    floor_db : float or None
        Spreads below this count as this [dB] (a stop criterion's target: no reward for
        lowering a node already below it; every node below it: none, as it would leave the order arbitrary); None: none.
    correlated_std_db : float or None
        Standard deviation of an error that drifts over ``correlation_s`` (a heading estimate's
        wander), as one offset per link and time block [dB], carried into the posterior
        (:mod:`rplearn.analysis.manoeuvre_posterior`): a manoeuvre that sees a direction once
        then learns it less than white noise says, and one that sees it again later more. None:
        estimated from the block sums given to the ranking (:func:`correlated_error_std_db`),
        or 0 without them (the white-noise posterior).
    correlation_s : float
        Length of a time block of the drifting error [s] (the manoeuvres' own blocks).
    misfit_std_db : float
        Standard deviation of the pattern structure the fixed order cannot represent, per node
        and direction cell [dB] (:mod:`rplearn.analysis.manoeuvre_cells`: fixed per direction,
        so looking again at the same directions does not average it out, looking at others
        does); the held-out misfit ``fit --degree auto`` reports (``misfit_std_db`` of its
        training summary) is one estimate. 0: none (the white and drifting posterior alone).
    steady_accel_enu_m_s2 : (float, float, float)
        The acceleration the drones' thrust carries on top of their references' [m/s^2] (ENU):
        the drag of a steady wind, which they tilt against (:func:`steady_tilt_accel`
        estimates it from the latest poses). A drone leaning by ``theta`` sees a peer up to
        ``theta`` off the elevation a level hover gives (by ``theta`` toward or away from the
        lean, not at all across it; its body z axis is held by the thrust as it turns), so its
        manoeuvres cover other bands than the level references say; 0: level hover. Never
        applied to ``candidates.fixed_nodes``. Off (``benchmarks/manoeuvres.py --tilt``: 5 of 12 cells against 6).
    lookahead : int
        Rank the best ``lookahead`` candidates by rate again by their estimated flight time to
        the target spread ``floor_db`` (:mod:`rplearn.analysis.manoeuvre_lookahead`: the time of
        each, then its information deficit over the best rate from where it ends, one more
        ranking each, about 6x a ranking's time at 4); 0 (default) or no ``floor_db``: the rate alone
        (flown, ``benchmarks/manoeuvres.py --lookahead 4``: 5 of 12 tuning cells against 7).
    prefixes : int
        Also score each candidate's first ``k / prefixes`` (whole drifting-error blocks, at
        least two; :func:`rplearn.plan.prefix.prefix_cuts`) and rank it by its best prefix, which
        is then what is flown (:class:`rplearn.plan.prefix.PrefixUnit`, its braking counted:
        :attr:`~rplearn.plan.prefix.PrefixUnit.brake_s`); 1 (default): whole manoeuvres only.
        Flown (``benchmarks/manoeuvres.py --prefixes 4``): 6 of 12 tuning cells against 7.
    prior_variance_factor : float
        The prior's variance over the one ``noise_std_db`` and the penalty imply
        (:meth:`~rplearn.analysis.manoeuvre_posterior.ManoeuvrePosterior.with_prior_excess`): the fit
        keeps its penalty, so where the data are thin its error is that of the larger prior,
        while the noise part stays at ``noise_std_db``. The variance inflation of
        ``fit --degree auto`` (its held-out error over what its posterior states) is one
        estimate; 1: the prior the penalty implies.
    aimed : int
        Also offer manoeuvres that make each node look along its ``aimed`` target directions of
        largest posterior variance now (:mod:`rplearn.analysis.manoeuvre_aimed`,
        :func:`rplearn.plan.aimed.aimed_manoeuvres`; negative: ``-aimed`` directions, their
        elevations only, full rings); 0 (default): none. Flown (``--aimed 3``): 2 of 12 cells against 7.
    design : str
        ``"rate"`` (default), ``"end"`` or ``"support"``: :func:`rplearn.analysis.manoeuvre_design.design_order`
        (by the optimal remaining design: the gradient at its end, or the rate among what it flies; needs ``floor_db``).
        Flown (``benchmarks/manoeuvres.py --design``, ground seeds 0-2): ``end`` slower, ``support`` faster in 1 of 6 cells.
    """

    noise_std_db: float = 4.2
    packet_rate_hz: float = 80.0
    sample_rate_hz: float = 4.0
    target_el_deg: tuple[float, float] = (-90.0, 90.0)
    target_points: int = 1024
    targets: Mapping[str, tuple[Any, Any]] | None = None
    penalty_weight: float | None = None
    power: float = DEFAULT_PENALTY_POWER
    candidates: CandidateOptions = field(default_factory=CandidateOptions)
    aggregate: str = "rms"
    rate: str = "information"
    floor_db: float | None = None
    correlated_std_db: float | None = None
    correlation_s: float = DEFAULT_BLOCK_S
    misfit_std_db: float = 0.0
    prior_variance_factor: float = 1.0
    steady_accel_enu_m_s2: tuple[float, float, float] = (0.0, 0.0, 0.0)
    prefixes: int = 1
    lookahead: int = 0
    aimed: int = 0
    design: str = "rate"

    def __post_init__(self) -> None:
        if not (np.isfinite(self.prior_variance_factor) and self.prior_variance_factor >= 1.0):
            raise InputError(f"prior_variance_factor: expected a number of at least 1, got {self.prior_variance_factor!r}",
                             param="prior_variance_factor")
        if not (np.isfinite(self.misfit_std_db) and self.misfit_std_db >= 0):
            raise InputError(f"misfit_std_db: expected a non-negative spread [dB], got {self.misfit_std_db!r}",
                             param="misfit_std_db")
        for name in ("noise_std_db", "packet_rate_hz", "sample_rate_hz", "correlation_s"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"{name}: expected a positive finite number, got {v!r}", param=name)
        lo, hi = (float(v) for v in self.target_el_deg)
        if not -90.0 <= lo < hi <= 90.0:
            raise InputError(f"target_el_deg: expected -90 <= low < high <= 90, got {self.target_el_deg!r}",
                             param="target_el_deg")
        if self.penalty_weight is not None and not (np.isfinite(self.penalty_weight) and self.penalty_weight >= 0):
            raise InputError(f"penalty_weight: expected a non-negative number, got {self.penalty_weight!r}",
                             param="penalty_weight")
        if self.aggregate not in AGGREGATES:
            raise InputError(f"aggregate: expected one of {', '.join(AGGREGATES)}, got {self.aggregate!r}", param="aggregate")
        for name, allowed in (("rate", RATES), ("design", DESIGNS)):
            if getattr(self, name) not in allowed:
                raise InputError(f"{name}: expected one of {', '.join(allowed)}, got {getattr(self, name)!r}", param=name)
        if self.floor_db is not None and not (np.isfinite(self.floor_db) and self.floor_db >= 0):
            raise InputError(f"floor_db: expected a non-negative spread [dB], got {self.floor_db!r}", param="floor_db")
        if self.correlated_std_db is not None and not (np.isfinite(self.correlated_std_db) and self.correlated_std_db >= 0):
            raise InputError(f"correlated_std_db: expected a non-negative spread [dB], got {self.correlated_std_db!r}",
                             param="correlated_std_db")
        accel = tuple(float(v) for v in self.steady_accel_enu_m_s2)
        if len(accel) != 3 or not all(np.isfinite(accel)) or np.hypot(accel[0], accel[1]) >= G_M_S2 or accel[2] <= -G_M_S2:
            raise InputError(f"steady_accel_enu_m_s2: expected three finite numbers, less than g horizontally, got "
                             f"{self.steady_accel_enu_m_s2!r}", param="steady_accel_enu_m_s2")
        object.__setattr__(self, "steady_accel_enu_m_s2", accel)
        if int(self.lookahead) != self.lookahead or self.lookahead < 0:
            raise InputError(f"lookahead: expected a whole number of candidates, at least 0, got {self.lookahead!r}",
                             param="lookahead")
        if int(self.aimed) != self.aimed:
            raise InputError(f"aimed: expected a whole number of directions per node, got {self.aimed!r}", param="aimed")
        if int(self.prefixes) != self.prefixes or self.prefixes < 1:
            raise InputError(f"prefixes: expected a whole number of at least 1, got {self.prefixes!r}", param="prefixes")
        if int(self.target_points) < 16:
            raise InputError(f"target_points: expected at least 16, got {self.target_points!r}", param="target_points")


@check_types
@dataclass(frozen=True)
class RankedManoeuvre:
    """A candidate manoeuvre and its predicted effect.

    Attributes
    ----------
    name : str
        What to fly, in words.
    duration_s : float
        Flight time, the way to its start included [s].
    spread_before_db, spread_after_db : dict of str to float
        Each node's pattern spread over the target directions now and after it [dB].
    reduction_db_per_s : float
        Reduction of the combined spread (``ManoeuvreOptions.aggregate``) per second [dB/s].
    candidate : Candidate
        The unit to fly (``candidate.unit``: references through ``sample``), its lead time and
        the moved nodes' poses after it.
    score_per_s : float
        What the ranking orders by (:attr:`ManoeuvreOptions.rate`), per second (``"spread"``:
        ``reduction_db_per_s``).
    time_to_target_s : float or None
        The estimated flight time to the target spread with this manoeuvre first
        (:attr:`ManoeuvreOptions.lookahead`; None: not looked ahead from).
    """

    name: str
    duration_s: float
    spread_before_db: dict[str, float]
    spread_after_db: dict[str, float]
    reduction_db_per_s: float
    candidate: Candidate
    score_per_s: float
    time_to_target_s: float | None = None

    def text(self) -> str:
        """One line: the manoeuvre, its time and the spreads it leaves."""
        after = ", ".join(f"{n} {self.spread_before_db[n]:.2f} -> {v:.2f} dB" for n, v in self.spread_after_db.items())
        return f"{self.name}: {self.duration_s:.0f} s, {after} ({self.reduction_db_per_s * 60:.2f} dB/min)"


def target_metrics(basis: Basis, nodes: Sequence[str], options: ManoeuvreOptions) -> list[np.ndarray]:
    """Per node, the second moment ``M_k`` of the mean-removed design over its target directions."""
    out = []
    for az, el in _directions(nodes, options):
        x = basis.design(az, el)
        x = x - x.mean(axis=0)
        out.append(x.T @ x / x.shape[0])
    return out


def _directions(nodes: Sequence[str], options: ManoeuvreOptions) -> list[tuple[np.ndarray, np.ndarray]]:
    return target_directions(nodes, int(options.target_points), options.target_el_deg, options.targets)


def prior_weights(spec: ModelSpec, normal: NormalEquations, options: ManoeuvreOptions) -> np.ndarray:
    """The prior's precision in the units of ``X^T X`` for every pattern column (ridge + penalty)."""
    basis = normal.basis
    pat = normal.n_pattern_columns
    weight = options.penalty_weight
    if weight is None:
        weight = float(spec.smoothing) * penalty_scale(normal.gram, pat)
    rough = np.tile(basis.roughness(options.power), normal.n_nodes)
    return float(spec.ridge_weight) + float(weight) * rough


def _aggregate(spreads: np.ndarray, options: ManoeuvreOptions) -> float:
    if options.floor_db is not None:
        spreads = np.maximum(spreads, options.floor_db)
    return float(np.max(spreads)) if options.aggregate == "max" else float(np.sqrt(np.mean(spreads**2)))


def latest_poses(poses: pd.DataFrame | Mapping[str, Any], nodes: Sequence[str]) -> dict[str, tuple[tuple[float, float, float], float]]:
    """Latest pose per node as ((x, y, z), yaw_deg) from a pose table or a mapping."""
    if isinstance(poses, pd.DataFrame):
        need = ("t", "node", "x", "y", "z", "qw", "qx", "qy", "qz")
        miss = [c for c in need if c not in poses.columns]
        if miss:
            raise InputError(f"poses: missing column(s) {', '.join(miss)}", param="poses")
        last = poses.sort_values("t").groupby(poses["node"].astype(str)).tail(1)
        out: dict[str, tuple[tuple[float, float, float], float]] = {}
        xyz = last[["x", "y", "z"]].to_numpy(np.float64)
        yaw = np.degrees(yaw_from_quat_wxyz(last[["qw", "qx", "qy", "qz"]].to_numpy(np.float64)))
        for k, node in enumerate(last["node"].astype(str)):
            out[node] = ((float(xyz[k, 0]), float(xyz[k, 1]), float(xyz[k, 2])), float(yaw[k]))
    else:
        out = {}
        for n, (p, y) in poses.items():
            x0, y0, z0 = (float(v) for v in p)
            out[str(n)] = ((x0, y0, z0), float(y))
    missing = [n for n in nodes if n not in out]
    if missing:
        raise InputError(f"poses: no pose for node(s) {', '.join(missing)}", param="poses")
    return {n: out[n] for n in nodes}


def check_statistics_nodes(normal: NormalEquations, nodes: Sequence[str]) -> None:
    if len(nodes) != normal.n_nodes or len(set(nodes)) != len(nodes):
        raise InputError(f"nodes: {len(nodes)} names ({', '.join(nodes)}) for statistics of {normal.n_nodes} nodes", param="nodes")


def start_posterior(normal: NormalEquations, spec: ModelSpec, nodes: Sequence[str], options: ManoeuvreOptions,
                    blocks: BlockSums | None = None, cells: DirectionCells | None = None) -> ManoeuvrePosterior:
    check_statistics_nodes(normal, nodes)
    pat = normal.n_pattern_columns
    gram = np.asarray(normal.gram, np.float64)[:pat, :pat]
    prior = prior_weights(spec, normal, options)
    precision = (gram + np.diag(prior)) / options.noise_std_db**2
    post = ManoeuvrePosterior(precision, target_metrics(normal.basis, nodes, options), options.noise_std_db**2)
    post = post.with_prior_excess(float(options.prior_variance_factor) - 1.0, prior)
    closed = None if blocks is None else blocks.closed()
    sc = options.correlated_std_db
    if sc is None:
        sc = 0.0 if closed is None else float(np.sqrt(correlated_ratio(normal, closed, prior))) * options.noise_std_db
    rows = int(round(options.correlation_s * options.sample_rate_hz))
    post = post.with_drift(float(sc) ** 2, None if closed is None else closed.cross, rows)
    if cells is not None and (cells.basis.to_dict() != normal.basis.to_dict() or cells.n_nodes != normal.n_nodes):
        raise InputError(f"cells: direction cells of {cells.n_nodes} nodes x {cells.basis.label} for "
                         f"statistics of {normal.n_nodes} x {normal.basis.label}", param="cells")
    return post.with_misfit(float(options.misfit_std_db) ** 2, None if cells is None else cells.factor(),
                            cell_grid(normal.basis.n_coef))


@check_types
def correlated_error_std_db(normal: NormalEquations, spec: ModelSpec, blocks: BlockSums,
                            options: ManoeuvreOptions | None = None) -> float:
    """The drifting error's block-offset spread [dB] the statistics show: ``sqrt(kappa)`` times
    the options' noise, ``kappa`` of :func:`rplearn.core.lsq.block_sums.correlated_ratio` under
    the options' prior (for :attr:`ManoeuvreOptions.correlated_std_db` of a plan made before a
    flight, from an earlier flight's statistics and block sums)."""
    opts = options or ManoeuvreOptions()
    kappa = correlated_ratio(normal, blocks.closed(), prior_weights(spec, normal, opts))
    return float(np.sqrt(kappa)) * opts.noise_std_db


def _score(post: ManoeuvrePosterior, cand: Candidate, nodes: Sequence[str], basis: Basis, options: ManoeuvreOptions,
           geometry: tuple[np.ndarray, Any] | None = None, before: np.ndarray | None = None) -> tuple[RankedManoeuvre, tuple[np.ndarray, Any]]:
    """The candidate's effect (or that of its best prefix, :attr:`ManoeuvreOptions.prefixes`), and
    its feature rows (for :meth:`ManoeuvrePosterior.update` if chosen); ``geometry``: those rows and
    link ends already computed (:func:`~rplearn.analysis.manoeuvre_rows.batch_rows_and_ends`), ``before``: ``post``'s spreads."""
    before = post.spreads() if before is None else before
    rows, ends = rows_and_ends(cand.unit, nodes, basis, options.sample_rate_hz, _steady(options)) if geometry is None else geometry
    b = _aggregate(before, options)
    best: tuple[float, float, int, np.ndarray] | None = None
    for cut in prefix_cuts(rows.shape[0], options.sample_rate_hz, options.prefixes, options.correlation_s):
        part = None if cut == rows.shape[0] else tuple((k[:cut], az[:cut], el[:cut]) for k, az, el in ends)
        after = post.spreads_after(rows[:cut], packet_weight(options), ends if part is None else part)
        a = _aggregate(after, options)
        # a prefix of ``cut`` rows is the unit up to its last row's time (its own rows, resampled, the same)
        cut_s = (cut - 1) / options.sample_rate_hz  # a prefix: its rows, then braking to rest
        took_s = cand.lead_s + (float(cand.unit.duration_s) if part is None else cut_s + braking_s(cand.unit, cut_s))
        score = ((b - a) if options.rate == "spread" else 1.0 / max(a, 1e-12) ** 2 - 1.0 / max(b, 1e-12) ** 2) / max(took_s, 1e-9)
        if best is None or score > best[0]:
            best = (score, (b - a) / max(took_s, 1e-9), cut, after)
    assert best is not None
    score, reduction, cut, after = best
    if cut < rows.shape[0]:  # fly only the prefix: its unit, the poses where it ends, its rows
        cand = cut_candidate(cand, (cut - 1) / options.sample_rate_hz)
        rows, ends = rows[:cut], tuple((k[:cut], az[:cut], el[:cut]) for k, az, el in ends)
    ranked = RankedManoeuvre(cand.name, cand.duration_s, dict(zip(nodes, before.tolist())), dict(zip(nodes, after.tolist())),
                             reduction, cand, score)
    return ranked, (rows, ends)


def _steady(options: ManoeuvreOptions) -> Steady:
    """The steady extra thrust and the nodes it spares, or None for a level hover."""
    accel = options.steady_accel_enu_m_s2
    return None if not any(accel) else (accel, tuple(options.candidates.fixed_nodes))


def packet_weight(options: ManoeuvreOptions) -> float:
    """Packets per feature row: both link directions share a row's pair of directions."""
    return 2.0 * options.packet_rate_hz / options.sample_rate_hz


@check_types
def pattern_spreads(normal: NormalEquations, spec: ModelSpec, nodes: Sequence[str],
                    options: ManoeuvreOptions | None = None, blocks: BlockSums | None = None,
                    cells: DirectionCells | None = None) -> dict[str, float]:
    """Each node's pattern spread over the target directions under the current posterior [dB]
    (module docstring; arguments as :func:`rank_manoeuvres`)."""
    opts = options or ManoeuvreOptions()
    names = [str(n) for n in nodes]
    with one_blas_thread():
        return dict(zip(names, start_posterior(normal, spec, names, opts, blocks, cells).spreads().tolist()))


@check_types
def rank_manoeuvres(
    normal: NormalEquations,
    spec: ModelSpec,
    nodes: Sequence[str],
    poses: pd.DataFrame | Mapping[str, Any],
    options: ManoeuvreOptions | None = None,
    blocks: BlockSums | None = None,
    cells: DirectionCells | None = None,
) -> tuple[RankedManoeuvre, ...]:
    """Candidate manoeuvres from the current poses, best first by spread reduction per second.

    Parameters
    ----------
    normal : NormalEquations
        The statistics accumulated so far at the fit's fixed order (pattern columns first).
    spec : ModelSpec
        The fit's model (its ridge and relative smoothing).
    nodes : sequence of str
        Node names in the order of the statistics' blocks.
    poses : DataFrame or mapping
        The latest pose of every node: a pose table (``t, node, x, y, z, qw, qx, qy, qz``,
        ENU/FLU; the last row per node is used) or ``{node: ((x, y, z), yaw_deg)}``.
    options : ManoeuvreOptions, optional
    blocks : BlockSums, optional
        The statistics' sums per time block (:mod:`rplearn.core.lsq.block_sums`): the drifting
        error of the samples so far enters the posterior (and, unless
        :attr:`ManoeuvreOptions.correlated_std_db` gives it, its size is estimated from them).
    cells : DirectionCells, optional
        The statistics' features per node and direction cell
        (:mod:`rplearn.analysis.manoeuvre_cells`): with :attr:`ManoeuvreOptions.misfit_std_db`,
        the misfit of the samples so far enters the posterior (without them, only the
        manoeuvres' own).

    Returns
    -------
    tuple of RankedManoeuvre
        Every candidate (:func:`rplearn.plan.manoeuvres.candidate_manoeuvres`), largest
        ``reduction_db_per_s`` first.
    """
    opts = options or ManoeuvreOptions()
    names = [str(n) for n in nodes]
    check_statistics_nodes(normal, names)
    state = latest_poses(poses, names)
    with one_blas_thread():  # many small factorisations: threads only contend
        post = start_posterior(normal, spec, names, opts, blocks, cells)
        opts = replace(opts, floor_db=None) if opts.floor_db is not None and np.max(post.spreads()) <= opts.floor_db else opts  # see floor_db
        return tuple(r for r, _ in _ordered(post, scored_candidates(post, state, names, normal.basis, opts), state, names, normal.basis, opts))


def scored_candidates(post: ManoeuvrePosterior, state: Mapping[str, Any], names: list[str], basis: Basis,
                      opts: ManoeuvreOptions, known: dict[Any, Any] | None = None) -> list[Scored]:
    """Every candidate flyable from ``state`` scored on ``post``, best rate first (``known``: the
    rows of the previous call's units, :func:`~rplearn.analysis.manoeuvre_rows.known_rows_and_ends`)."""
    cands = candidate_manoeuvres(state, opts.candidates)
    if opts.aimed:  # and those aimed at where each node's posterior is widest now
        aims = widest_directions(post, basis, names, _directions(names, opts), abs(int(opts.aimed)))
        cands += aimed_manoeuvres(state, aims, opts.candidates, rings=opts.aimed < 0)
    before = post.spreads()  # the same for every candidate; their rows computed in batches
    units = [c.unit for c in cands]
    geometry = known_rows_and_ends(units, names, basis, opts.sample_rate_hz, _steady(opts), {} if known is None else known)
    scored = [_score(post, c, names, basis, opts, g, before) for c, g in zip(cands, geometry)]
    return sorted(scored, key=lambda s: -s[0].score_per_s)


def _ordered(post: ManoeuvrePosterior, scored: list[Scored], state: Mapping[str, Any], names: list[str], basis: Basis,
             opts: ManoeuvreOptions) -> list[Scored]:
    """``scored`` (best rate first) with :attr:`ManoeuvreOptions.lookahead`'s reordering, each
    looked-ahead candidate carrying its estimated time to the target."""
    if opts.design != "rate" and opts.floor_db is not None and scored:
        return design_order(post, scored, packet_weight(opts), float(opts.floor_db), opts.design, DESIGN_STEPS)
    if opts.lookahead == 0 or opts.floor_db is None:
        return scored
    out = lookahead_order(post, scored, opts.lookahead, float(opts.floor_db), packet_weight(opts), lambda v: _aggregate(v, opts),
                          lambda p, s: scored_candidates(p, s, names, basis, opts), dict(state))
    return [(r if t is None else replace(r, time_to_target_s=t), rows) for (r, rows), t in out]


@check_types
@dataclass(frozen=True)
class PlanStep:
    """One manoeuvre of a greedy plan and the spread expected after it.

    Attributes
    ----------
    manoeuvre : RankedManoeuvre
    end_s : float
        Flight time at its end [s].
    spread_db : dict of str to float
        Each node's expected spread after it [dB].
    """

    manoeuvre: RankedManoeuvre
    end_s: float
    spread_db: dict[str, float]


@check_types
def greedy_plan(
    normal: NormalEquations,
    spec: ModelSpec,
    nodes: Sequence[str],
    poses: pd.DataFrame | Mapping[str, Any],
    budget_s: float,
    target_spread_db: float,
    options: ManoeuvreOptions | None = None,
    blocks: BlockSums | None = None,
) -> tuple[PlanStep, ...]:
    """Manoeuvres chosen one at a time by spread reduction per second, until every node's spread
    is at most ``target_spread_db`` or the next one would exceed ``budget_s`` of flight.

    Greedy: each step takes the best manoeuvre from where the last one ended, with the
    posterior it would leave; it is not the optimal sequence (which no tractable search gives),
    but each step is the best single next step; spreads below the target count as the target
    (``ManoeuvreOptions.floor_db``, unless given). Arguments as :func:`rank_manoeuvres`.
    """
    if not (np.isfinite(budget_s) and budget_s > 0):
        raise InputError(f"budget_s: expected a positive flight time [s], got {budget_s!r}", param="budget_s")
    if not (np.isfinite(target_spread_db) and target_spread_db > 0):
        raise InputError(f"target_spread_db: expected a positive spread [dB], got {target_spread_db!r}", param="target_spread_db")
    opts = options or ManoeuvreOptions()
    if opts.floor_db is None:
        opts = replace(opts, floor_db=float(target_spread_db))
    names = [str(n) for n in nodes]
    check_statistics_nodes(normal, names)
    state = latest_poses(poses, names)
    with one_blas_thread():  # many small factorisations: threads only contend
        return _greedy(start_posterior(normal, spec, names, opts, blocks), state, names, normal.basis, (budget_s, target_spread_db), opts)


def _greedy(post: ManoeuvrePosterior, state: dict[str, Any], names: list[str], basis: Basis, limits: tuple[float, float],
            opts: ManoeuvreOptions) -> tuple[PlanStep, ...]:
    budget_s, target_spread_db = limits
    steps: list[PlanStep] = []
    t = 0.0
    known: dict[Any, Any] = {}  # the last step's units' rows: a turn in place leaves the same candidates
    while float(np.max(post.spreads())) > target_spread_db:
        scored = [s for s in scored_candidates(post, state, names, basis, opts, known) if t + s[0].duration_s <= budget_s and s[0].reduction_db_per_s > 0]
        if not scored:
            break
        best, (rows, ends) = _ordered(post, scored, state, names, basis, opts)[0]
        post.update(rows, packet_weight(opts), ends)
        t += best.duration_s
        state.update(best.candidate.ends)
        steps.append(PlanStep(best, t, dict(zip(names, post.spreads().tolist()))))
    return tuple(steps)


__all__ = ["AGGREGATES", "DESIGNS", "RATES", "ManoeuvreOptions", "PlanStep", "RankedManoeuvre", "correlated_error_std_db", "greedy_plan",
           "manoeuvre_rows", "pattern_spreads", "prior_penalty_weight", "prior_weights", "rank_manoeuvres", "steady_tilt_accel", "target_metrics"]
