"""``rplearn trajectory --optimize``: a calibration plan chosen for the information it gathers.

Before the flight there is no data, only the antennas' prior (a smoothness prior, or a
reference pattern file: a ridge on the deviation from it) with its spread, the radio's noise
level and packet rate, and a flight-time budget. :func:`optimize_plan` chooses and orders
manoeuvres of the library (:func:`rplearn.plan.manoeuvres.candidate_manoeuvres`) greedily, each
the one with the largest expected reduction of the per-node pattern spread per second from
where the previous one ended (:func:`rplearn.analysis.manoeuvres.greedy_plan`), until every
node's expected spread is at most the target or the budget is spent, and writes the chosen
units' references in the format ``rplearn trajectory`` writes (``<label>_<node>.csv``:
``t, x, y, z, yaw_deg``, ``t`` from 0 in each unit), their labels numbered in flying order.

With an earlier flight's model file (``--from-model``, :func:`options_from_model`) the plan takes
its prior from what that flight taught: the noise (the fit's noise times the square root of its
variance inflation, as ``rplearn live`` reads the posterior), the smoothness prior (its
cross-validated smoothing as an absolute penalty weight, ``training.planning_penalty_weight``)
and the error drifting over seconds (``training.drift_std_db``), all written by
``rplearn fit --order auto``. A value stated explicitly (``--noise``, ``--prior-std``,
``--drift``) overrides the model's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from rplearn._argtypes import check_types
from rplearn._budget import Cost, budget, check_work
from rplearn.analysis.manoeuvre_prior import NOMINAL_PRIOR_STD_DB
from rplearn.analysis.manoeuvres import ManoeuvreOptions, PlanStep, greedy_plan, pattern_spreads, prior_penalty_weight
from rplearn.core.lsq.block_sums import DEFAULT_BLOCK_S, MIN_BLOCKS
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection import MAX_SMOOTHING, at_smoothing_cap
from rplearn.errors import InputError, RplearnError
from rplearn.models.auto_spread import PLANNING_ORDER
from rplearn.models.base import require_patterns
from rplearn.models.load import load_model
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec
from rplearn.plan.campaign import Campaign, write_references
from rplearn.plan.manoeuvres import CandidateOptions
from rplearn.workflows.plan_layout import PlanLayout, plan_layout
from rplearn.workflows.planning import MIN_REFERENCE_RATE_HZ, REFERENCE_ROW_BYTES, REFERENCE_ROW_DISK, REFERENCE_ROW_S

#: The RSSI noise about the model a plan assumes without a fit or ``--noise`` [dB].
DEFAULT_NOISE_STD_DB = 4.2
#: The spreads a plan reads as a radio's (its noise, the drifting error) [dB]: RSSI values lie
#: within the 180-dB plausible window (-150 to 30 dBm), so no scatter of them exceeds 90 dB,
#: and radios report them in steps of 0.5 or 1 dB, so none is below 0.01 dB (a smaller noise
#: underflows the plan's arithmetic: its spreads came out NaN, a larger one overflowed).
SPREAD_RANGE_DB = (0.01, 90.0)
#: Packets per second in one link direction a plan counts at most [Hz] (no radio reports RSSI
#: more often; 1e300 made the posterior's matrix singular).
MAX_PACKET_RATE_HZ = 1e5
#: Packets per second a plan accepts at least [Hz]: one reading in about 17 minutes.
MIN_PACKET_RATE_HZ = 1e-3
#: Cruise speeds a plan's drones fly [m/s] (a slower one makes each manoeuvre hours long: 1e-3
#: m/s planned for over 10 minutes, 1e-300 failed on an array too large; a faster one no drone flies).
SPEED_RANGE_M_S = (0.5, 50.0)
#: Starting distance and height a plan accepts at most [m] (the plausible link distance and
#: drone altitude of :data:`rplearn.core.plausible.PLAUSIBLE`).
MAX_DISTANCE_M, MAX_HEIGHT_M = 100_000.0, 50_000.0


@check_types
@dataclass(frozen=True)
class OptimizeOptions:
    """What :func:`optimize_plan` plans for.

    Attributes
    ----------
    target_spread_db : float
        Stop when every node's expected pattern spread over the target directions is at most this [dB].
    budget_s : float
        Flight-time budget [s].
    model : str
        The fixed-order model the spread is read at (e.g. ``sh-10``).
    noise_std_db : float or None
        Standard deviation of one RSSI reading about the model [dB]; None: ``from_model``'s, or
        :data:`DEFAULT_NOISE_STD_DB`.
    prior_std_db : float or None
        The prior's spread of each node's pattern over the sphere [dB]; None: ``from_model``'s
        smoothness prior, or :data:`~rplearn.analysis.manoeuvre_prior.NOMINAL_PRIOR_STD_DB`.
    prior_pattern : str or None
        A reference pattern model file (``rplearn reference``): the prior is a ridge on the
        deviation from it instead of a smoothness prior.
    station : bool or None
        One static ground station ``G`` and one drone ``D`` (True) instead of two drones ``A``,
        ``B`` (False); None: ``from_model``'s layout, its nodes' names and its station when one
        node held still in every learning row (:mod:`rplearn.workflows.plan_layout`), else two drones.
    distance_m, height_m : float
        Starting distance between the nodes (horizontal from a station) and drone height [m].
    speed_m_s : float
        The drones' cruise speed [m/s].
    packet_rate_hz : float or None
        Packets per second in each link direction; None: ``from_model``'s radio's
        (``training.packet_rate_hz``), else :data:`~rplearn.workflows.plan_layout.DEFAULT_PACKET_RATE_HZ`.
    target_el_deg : (float, float)
        Band of body-frame elevations the spread is taken over [deg].
    drift_std_db : float or None
        An error drifting over seconds (a heading estimate's wander), as one offset per link and
        5-s block [dB] (:attr:`rplearn.analysis.manoeuvres.ManoeuvreOptions.correlated_std_db`;
        what :func:`rplearn.analysis.manoeuvres.correlated_error_std_db` finds in an earlier
        flight): the plan then counts a direction seen once as less learned than white noise
        says; 0: white noise only; None: ``from_model``'s, or 0.
    from_model : str or None
        An earlier flight's model file (``rplearn fit --order auto``) whose noise, smoothness
        prior and drift the plan takes where the fields above are None (:func:`options_from_model`).
    """

    target_spread_db: float = 2.0
    budget_s: float = 900.0
    model: str = f"sh-{PLANNING_ORDER}"
    noise_std_db: float | None = None
    prior_std_db: float | None = None
    prior_pattern: str | None = None
    station: bool | None = None
    distance_m: float = 10.0
    height_m: float = 20.0
    speed_m_s: float = 1.5
    packet_rate_hz: float | None = None
    target_el_deg: tuple[float, float] = (-90.0, 90.0)
    drift_std_db: float | None = None
    from_model: str | None = None

    def __post_init__(self) -> None:
        if self.drift_std_db is not None and not (np.isfinite(self.drift_std_db) and self.drift_std_db >= 0):
            raise InputError(f"drift_std_db: expected a non-negative spread [dB], got {self.drift_std_db!r}", param="drift_std_db")
        for name in ("target_spread_db", "budget_s", "noise_std_db", "prior_std_db", "distance_m", "height_m", "speed_m_s",
                     "packet_rate_hz"):
            if getattr(self, name) is None:
                continue
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"{name}: expected a positive finite number, got {v!r}", param=name)
        lo, hi = SPREAD_RANGE_DB
        ranges = {"noise_std_db": (lo, hi, "dB", "a radio's RSSI scatter"),
                  "drift_std_db": (0.0, hi, "dB", "a radio's RSSI scatter"),
                  "packet_rate_hz": (MIN_PACKET_RATE_HZ, MAX_PACKET_RATE_HZ, "Hz", "packets a radio reports per second"),
                  "speed_m_s": (*SPEED_RANGE_M_S, "m/s", "a drone's cruise speed"),
                  "distance_m": (0.0, MAX_DISTANCE_M, "m", "a drone radio link"),
                  "height_m": (0.0, MAX_HEIGHT_M, "m", "a drone's height")}
        for name, (low, high, unit, what) in ranges.items():
            v = getattr(self, name)
            if v is not None and not low <= float(v) <= high:
                raise InputError(f"{name}: {float(v):g} {unit} is not {what}: expected {low:g} to {high:g} {unit}",
                                 param=name)


@check_types
@dataclass(frozen=True)
class OptimizedPlan:
    """The chosen manoeuvres, the expected spread after each, and the files written.

    Attributes
    ----------
    steps : tuple of PlanStep
    start_spread_db : dict of str to float
        The prior's spread per node [dB].
    campaign : Campaign or None
        The chosen units in flying order (None when no manoeuvre helps within the budget).
    paths : list of str
    prior : str or None
        With a model file (:attr:`OptimizeOptions.from_model`): the nodes it was a fit of, the
        noise, penalty and drift the plan took, and which of them were stated.
    notes : tuple of str
        What the plan took otherwise than stated, one line each (a stated prior spread above
        what the model's ridge allows at the noise: the ridge's spread instead).
    """

    steps: tuple[PlanStep, ...]
    start_spread_db: dict[str, float]
    campaign: Campaign | None
    paths: list[str]
    prior: str | None = None
    notes: tuple[str, ...] = ()

    @property
    def duration_s(self) -> float:
        return self.steps[-1].end_s if self.steps else 0.0

    def summary(self) -> str:
        """The expected spread over time, one line per manoeuvre."""
        lines = [f"{'time/s':>7}  {'spread/dB':<18} manoeuvre",
                 f"{0:7.0f}  {', '.join(f'{n} {v:.2f}' for n, v in self.start_spread_db.items()):<18} (prior)"]
        for s in self.steps:
            lines.append(f"{s.end_s:7.0f}  {', '.join(f'{n} {v:.2f}' for n, v in s.spread_db.items()):<18} "
                         f"{s.manoeuvre.name} ({s.manoeuvre.duration_s:.0f} s)")
        return "\n".join(lines)


def _layout(opts: OptimizeOptions, earlier: PatternSet | None) -> PlanLayout:
    """The plan's nodes, start poses, station and packet rate: the flags', else the earlier
    flight's (:func:`~rplearn.workflows.plan_layout.plan_layout`), its packet rate checked as the flag's."""
    layout = plan_layout(opts.station, opts.packet_rate_hz, float(opts.distance_m), float(opts.height_m),
                         None if earlier is None else earlier.training, () if earlier is None else tuple(map(str, earlier.nodes)))
    if opts.packet_rate_hz is None and earlier is not None and not MIN_PACKET_RATE_HZ <= layout.packet_rate_hz <= MAX_PACKET_RATE_HZ:
        raise InputError(f"from_model: {opts.from_model}: training.packet_rate_hz is {layout.packet_rate_hz:g}, not the packets a "
                         f"radio reports per second: expected {MIN_PACKET_RATE_HZ:g} to {MAX_PACKET_RATE_HZ:g} Hz; give --packet-rate",
                         param="from_model")
    return layout


@check_types
def optimize_plan(out_dir: str, options: OptimizeOptions | None = None, rate_hz: float = 10.0) -> OptimizedPlan:
    """Choose and order manoeuvres before the flight (module docstring) and write their references.

    Parameters
    ----------
    out_dir : str
        Folder for the per-drone reference CSVs (created).
    options : OptimizeOptions, optional
    rate_hz : float
        Sample rate of the reference files [Hz].
    """
    opts = options or OptimizeOptions()
    if not (np.isfinite(rate_hz) and rate_hz >= MIN_REFERENCE_RATE_HZ):
        raise InputError(f"rate_hz: expected a sample rate of at least {MIN_REFERENCE_RATE_HZ:g} Hz, got {rate_hz!r}",
                         param="rate_hz")
    # before any work: the references of a plan as long as the budget (no plan is longer: each
    # manoeuvre is taken only while it ends within it), two drones' files
    rows = 2.0 * float(opts.budget_s)
    try:
        check_work("rate_hz", rate_hz, lambda r: Cost(memory_bytes=REFERENCE_ROW_BYTES * rows * r, seconds=REFERENCE_ROW_S * rows * r,
                                                      disk_bytes=REFERENCE_ROW_DISK * rows * r),
                   "Hz", integer=False, bounds=(MIN_REFERENCE_RATE_HZ, math.inf), limits=budget(out_dir))
    except InputError as exc:  # the budget sets the size as much as the rate: say so
        raise InputError(f"{exc} (reference files of a plan as long as budget_s {float(opts.budget_s):g} s; a smaller "
                         "budget_s fits a larger rate)", param="rate_hz", related=("budget_s",)) from None
    spec = ModelSpec.parse(opts.model)
    if not spec.decouples:
        raise InputError(f"model: {spec.label} has no per-node pattern to plan for; use sh, bg or poly", param="model")
    earlier = None if opts.from_model is None else _planning_model(opts.from_model)
    layout = _layout(opts, earlier)
    nodes, poses, fixed = layout.nodes, layout.poses, layout.fixed
    shape = "smoothness"
    if opts.prior_pattern is not None:
        # its shape sets the prior's mean, which does not change the spread: read to refuse a bad file early
        require_patterns(load_model(opts.prior_pattern), "prior_pattern")
        shape = "reference"
    noise = DEFAULT_NOISE_STD_DB if opts.noise_std_db is None else float(opts.noise_std_db)
    prior_std = NOMINAL_PRIOR_STD_DB if opts.prior_std_db is None else float(opts.prior_std_db)
    mopts = ManoeuvreOptions(noise_std_db=noise, packet_rate_hz=layout.packet_rate_hz, target_el_deg=opts.target_el_deg,
                             candidates=CandidateOptions(fixed_nodes=fixed, speed_m_s=opts.speed_m_s),
                             correlated_std_db=float(opts.drift_std_db or 0.0))
    if earlier is not None and opts.from_model is not None:
        # a reference pattern's prior replaces the model's smoothness prior: stated, or the nominal spread
        stated = prior_std if shape == "reference" else opts.prior_std_db
        mopts = _options_of(earlier, opts.from_model, mopts, spec, (opts.noise_std_db, stated, opts.drift_std_db), True)
    else:
        mopts = replace(mopts, penalty_weight=prior_penalty_weight(spec.basis(), prior_std, noise, spec.ridge_weight))
    if shape == "reference":
        weight = prior_penalty_weight(spec.basis(), prior_std, mopts.noise_std_db, spec.ridge_weight, shape=shape)
        mopts = replace(mopts, penalty_weight=weight, power=0.0)
    empty = NormalEquations(spec.basis(), len(nodes))
    start_spread = pattern_spreads(empty, spec, nodes, mopts)
    if not all(np.isfinite(v) for v in start_spread.values()):
        raise InputError(f"the prior's spread is not finite (noise {mopts.noise_std_db:g} dB, penalty weight "
                         f"{mopts.penalty_weight!r}, power {mopts.power:g}): "
                         + ("the model's training values are out of range" if opts.from_model else "give other values"),
                         param="from_model" if opts.from_model else "noise_std_db")
    notes = _capped_note(opts, spec, mopts, start_spread)
    steps = greedy_plan(empty, spec, nodes, poses, opts.budget_s, opts.target_spread_db, mopts)
    prior = None if earlier is None else _prior_text(mopts, opts, shape, (tuple(map(str, earlier.nodes)), nodes))
    if prior is not None and layout.text:
        prior = f"{prior}; planned for {layout.text}"
    if not steps:
        return OptimizedPlan(steps, start_spread, None, [], prior, notes)
    units = tuple(replace(s.manoeuvre.candidate.unit, label=f"{k + 1:02d}_{s.manoeuvre.candidate.unit.label}")
                  for k, s in enumerate(steps))
    campaign = Campaign(units, gap_s=0.0)
    paths = write_references(campaign, out_dir, rate_hz)
    return OptimizedPlan(steps, start_spread, campaign, paths, prior, notes)


def _capped_note(opts: OptimizeOptions, spec: ModelSpec, mopts: ManoeuvreOptions, start: dict[str, float]) -> tuple[str, ...]:
    """One line when a stated prior spread is more than the model's ridge allows at the plan's
    noise (:func:`~rplearn.analysis.manoeuvre_prior.prior_penalty_weight` then gives no penalty:
    the prior is the ridge's alone, the largest any fit of ``spec`` has at that noise)."""
    stated = opts.prior_std_db
    if stated is None or mopts.penalty_weight != 0.0:
        return ()
    largest = max(start.values())
    if largest >= float(stated) * (1.0 - 1e-3):
        return ()
    return (f"the stated prior spread {float(stated):g} dB is more than {spec.label}'s ridge ({spec.ridge_weight:g}) allows "
            f"with a {mopts.noise_std_db:.3g}-dB noise (a coefficient's prior variance is the noise's over ridge plus "
            f"penalty): planned with the ridge's alone, {largest:.2f} dB, no smoothness penalty",)


def _prior_text(mopts: ManoeuvreOptions, opts: OptimizeOptions, shape: str, nodes: tuple[tuple[str, ...], tuple[str, ...]]) -> str:
    """What a plan from a model file took, each value marked when it was stated instead; first
    the nodes the model was a fit of (``nodes``: the model's, the plan's), and when the plan's
    are others, that its figures stand for them."""
    def source(value: float | None) -> str:
        return " (stated)" if value is not None else ""
    theirs, ours = nodes
    of = f"a fit of nodes {', '.join(theirs)}" + ("" if set(ours) <= set(theirs) else f", taken for the plan's {', '.join(ours)}")

    penalty = (f"a reference pattern's ridge for a {opts.prior_std_db or NOMINAL_PRIOR_STD_DB:g}-dB spread" if shape == "reference"
               else f"smoothness penalty weight {mopts.penalty_weight:.3g} (power {mopts.power:g})"
               + (f" for a {opts.prior_std_db:g}-dB spread (stated)" if opts.prior_std_db is not None else ""))
    return (f"{of}: noise {mopts.noise_std_db:.2f} dB{source(opts.noise_std_db)}, {penalty}, drift "
            f"{mopts.correlated_std_db:.2f} dB per {mopts.correlation_s:g}-s block{source(opts.drift_std_db)}")


@check_types
def options_from_model(model: str, options: ManoeuvreOptions, spec: ModelSpec, *, noise_std_db: float | None = None,
                       prior_std_db: float | None = None, drift_std_db: float | None = None,
                       overridable: bool = True) -> ManoeuvreOptions:
    """``options`` with the prior an earlier flight's model file gives a plan (module docstring).

    Parameters
    ----------
    model : str
        The model file of ``rplearn fit --order auto`` (spherical harmonics, no ``--prior``).
    options : ManoeuvreOptions
        What the plan is for (candidates, packet rate, target directions...); its noise,
        penalty weight and power, drift, misfit and prior-variance factor are replaced.
    spec : ModelSpec
        The model the plan reads its spread at (its basis and ridge convert ``prior_std_db``).
    noise_std_db, prior_std_db, drift_std_db : float, optional
        Values stated explicitly, which override the model's: the noise [dB]; the prior's
        spread over the sphere [dB] (the smoothness prior of that spread instead of the
        model's penalty weight); the drift per block [dB].
    overridable : bool
        Whether the caller has flags that replace the model's figures (``trajectory``'s
        ``--noise``, ``--prior-std``, ``--drift``): a refusal names them only then (``rplearn
        live --from-model`` has none).

    Returns
    -------
    ManoeuvreOptions
        The noise (stated, or the model's ``noise_std_db`` times the square root of its
        ``variance_inflation``), the penalty (the model's ``planning_penalty_weight``, an
        absolute weight in the units of ``X^T X``, and its ``penalty_power``), the drift per
        :data:`~rplearn.core.lsq.block_sums.DEFAULT_BLOCK_S` block (``drift_std_db``), no
        misfit term and the prior's variance as the penalty implies (the inflated posterior
        ``trajectory --optimize`` and ``rplearn live`` plan with).

    Raises
    ------
    InputError
        ``param="from_model"``, one line: the file is missing, not a model file, not a pattern
        model, a fixed-order fit, of another kind than ``spec``, fitted with priors, lacks a
        field that no explicit value replaces (naming it and how to get it), holds a figure out
        of its range (naming it: the noise, inflation, power and drift in :data:`SPREAD_RANGE_DB`,
        :data:`INFLATION_RANGE`, :data:`PENALTY_POWER_RANGE`; the penalty weight within
        :func:`penalty_weight_bound`), or was fitted at the search's largest smoothing
        (:func:`~rplearn.core.lsq.selection.at_smoothing_cap`: its flight did not tell the
        patterns' shape from flat, so its penalty weight is no prior) while no prior spread is
        stated.
    """
    return _options_of(_planning_model(model), model, options, spec, (noise_std_db, prior_std_db, drift_std_db), overridable)


def _options_of(fitted: PatternSet, model: str, options: ManoeuvreOptions, spec: ModelSpec,
                stated: tuple[float | None, float | None, float | None], overridable: bool) -> ManoeuvreOptions:
    """:func:`options_from_model` of the model ``fitted`` read from the file ``model``; ``stated``: the
    noise, prior spread and drift stated explicitly."""
    noise_std_db, prior_std_db, drift_std_db = stated
    training = fitted.training
    refit = "fit the earlier flight with rplearn fit DATASET --order auto -o MODEL.json"

    def flag(name: str) -> str | None:
        return name if overridable else None

    def or_give(name: str) -> str:
        return f", or give {name}" if overridable else ""
    if fitted.basis.kind != spec.kind:
        raise InputError(f"from_model: {model} is a {fitted.basis.label} fit; the plan reads its spread at {spec.label}: "
                         f"give a {spec.kind} model's file, or --check-model {fitted.basis.kind}-...", param="from_model")
    if training.prior:
        raise InputError(f"from_model: {model} was fitted with priors (--prior): its penalty is a ridge toward them, not a "
                         "smoothness prior; plan with --prior-pattern and --noise, --drift instead", param="from_model")
    if noise_std_db is None:
        if training.noise_std_db is None or training.variance_inflation is None:
            field = "noise_std_db" if training.noise_std_db is None else "variance_inflation"
            raise InputError(f"from_model: {model} has no training.{field}; {refit}{or_give('--noise')}", param="from_model")
        _in_range(model, "noise_std_db", training.noise_std_db, SPREAD_RANGE_DB, flag("--noise"))
        _in_range(model, "variance_inflation", training.variance_inflation, INFLATION_RANGE, flag("--noise"))
        # each factor in its range keeps the product finite; the product itself is no RSSI scatter (the inflation
        # carries the errors correlated over a fast radio's packets) and is not bounded as one
        noise_std_db = float(training.noise_std_db) * float(np.sqrt(training.variance_inflation))
    if training.penalty_power is not None:
        _in_range(model, "penalty_power", training.penalty_power, PENALTY_POWER_RANGE, None)
    power = float(training.penalty_power if training.penalty_power is not None else options.power)
    if prior_std_db is not None:
        weight = prior_penalty_weight(spec.basis(), prior_std_db, noise_std_db, spec.ridge_weight, power)
    elif training.planning_penalty_weight is None:
        raise InputError(f"from_model: {model} has no training.planning_penalty_weight (written by rplearn fit --order auto "
                         f"since this version); {refit}{or_give('--prior-std')}", param="from_model")
    else:
        if training.smoothing is not None and at_smoothing_cap(float(training.smoothing)):
            raise InputError(f"from_model: {model}: training.smoothing is {float(training.smoothing):g}, the largest the "
                             "search tries: its flight did not tell the patterns' shape from flat (too short), so its "
                             "planning_penalty_weight is no prior; fit a longer flight with rplearn fit DATASET --order auto"
                             f"{or_give('--prior-std')}",
                             param="from_model")
        _in_range(model, "planning_penalty_weight", training.planning_penalty_weight, (0.0, penalty_weight_bound(fitted)),
                  flag("--prior-std"))
        weight = float(training.planning_penalty_weight)
    if drift_std_db is None:
        if training.drift_std_db is None:
            raise InputError(f"from_model: {model} has no training.drift_std_db (written by rplearn fit --order auto of a "
                             f"dataset whose rows of one link have times in at least {MIN_BLOCKS} blocks of {DEFAULT_BLOCK_S:g} s, "
                             f"short of the search's largest smoothing; by this version also when streamed and by an automatic "
                             f"rplearn live session); {refit}{or_give('--drift')}",
                             param="from_model")
        _in_range(model, "drift_std_db", training.drift_std_db, (0.0, SPREAD_RANGE_DB[1]), flag("--drift"))
        drift_std_db = float(training.drift_std_db)
    return replace(options, noise_std_db=float(noise_std_db), penalty_weight=float(weight), power=power,
                   correlated_std_db=float(drift_std_db), misfit_std_db=0.0, prior_variance_factor=1.0)


#: Variance inflations a plan reads from a model file (a fit's held-out error variance over its white noise's:
#: at least 1; hundreds for a fast radio whose errors are correlated over many packets).
INFLATION_RANGE = (1.0, 1e4)
#: Roughness powers of a smoothness penalty a plan reads from a model file: rplearn's fits write
#: 2 (the squared Laplacian; 0 a plain ridge); beyond these the weights of high degrees overflow.
PENALTY_POWER_RANGE = (0.0, 4.0)
#: What a figure a model file gives the plan is, by field.
_WHAT = {"noise_std_db": "a radio's RSSI scatter [dB]", "drift_std_db": "a radio's drifting error [dB]",
         "variance_inflation": "a fit's variance inflation (at least 1)",
         "penalty_power": "a smoothness penalty's roughness power",
         "planning_penalty_weight": "a fit's smoothness penalty weight for its samples (units of X^T X)"}


def penalty_weight_bound(fitted: PatternSet) -> float:
    """The largest ``training.planning_penalty_weight`` an automatic fit of ``fitted``'s basis,
    nodes and sample count writes (``math.inf`` without a sample count): the weight is the chosen
    relative smoothing, at most the search's :data:`~rplearn.core.lsq.selection.MAX_SMOOTHING`,
    times the mean diagonal of ``X^T X`` over the pattern columns, which each sample adds to at
    most ``2 max_d sum_j x_j(d)^2 / (nodes x coefficients)`` (its two ends' features; for
    spherical harmonics ``1 / (2 pi nodes)`` at every direction). Measured: the smoke flight's
    fits 0.0338 (1,345 samples; bound 1.07e8), its first 7 s 2.16e7 at the search's largest
    smoothing (271 samples; bound 2.16e7)."""
    from rplearn.core.bases import fibonacci_grid_nodes

    n = fitted.training.n_samples
    if n is None:
        return math.inf
    basis = fitted.basis
    az, el = fibonacci_grid_nodes(2048)
    per_sample = 2.0 * float(np.max(np.sum(basis.design(az, el) ** 2, axis=1))) / (len(fitted.nodes) * basis.n_coef)
    # 1e-9 relative: the bound is the largest value itself (a fit at the cap with every direction alike)
    return MAX_SMOOTHING * float(n) * per_sample * (1.0 + 1e-9)


def _in_range(model: str, field: str, value: float, bounds: tuple[float, float], flag: str | None) -> None:
    """Refuse a model file's ``training.<field>`` outside ``bounds`` in one line naming the file and the
    field, and the flag that replaces it (the figure would otherwise overflow the plan's arithmetic,
    or be blamed on that flag)."""
    if not bounds[0] <= float(value) <= bounds[1]:
        instead = f"; give {flag} instead" if flag else ""
        raise InputError(f"from_model: {model}: training.{field} is {float(value):g}, not {_WHAT[field]}: expected "
                         f"{bounds[0]:g} to {bounds[1]:g}{instead}", param="from_model")


def _planning_model(model: str) -> PatternSet:
    """The automatic pattern fit of a model file, or a one-line refusal naming it."""
    try:
        fitted = load_model(model)
    except FileNotFoundError:
        raise InputError(f"from_model: {model}: no such file", param="from_model") from None
    except IsADirectoryError:
        raise InputError(f"from_model: {model}: a folder, not a model file", param="from_model") from None
    except RplearnError as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"from_model: {first}", param="from_model") from None
    if not isinstance(fitted, PatternSet):
        raise InputError(f"from_model: {model} is a {fitted.kind} baseline ({fitted.label}), not a pattern fit; {model} must come from "
                         "rplearn fit --order auto", param="from_model")
    if fitted.training.reference is not None:
        raise InputError(f"from_model: {model} is a reference pattern model (rplearn reference), not a fit of a flight: it "
                         f"has no noise, smoothing or drift; give it as --prior-pattern {model}, with --noise and --drift",
                         param="from_model")
    if fitted.training.selection is None:
        raise InputError(f"from_model: {model} is a fixed-order fit ({fitted.basis.label}): it learned no smoothing, noise "
                         f"inflation or drift; fit the earlier flight with rplearn fit DATASET --order auto", param="from_model")
    return fitted


__all__ = ["DEFAULT_NOISE_STD_DB", "OptimizeOptions", "OptimizedPlan", "optimize_plan", "options_from_model"]
