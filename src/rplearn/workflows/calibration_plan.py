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
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.analysis.manoeuvre_prior import NOMINAL_PRIOR_STD_DB
from rplearn.analysis.manoeuvres import ManoeuvreOptions, PlanStep, greedy_plan, pattern_spreads, prior_penalty_weight
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.errors import InputError
from rplearn.models.base import require_patterns
from rplearn.models.load import load_model
from rplearn.models.spec import ModelSpec
from rplearn.plan.campaign import Campaign, write_references
from rplearn.plan.manoeuvres import CandidateOptions
from rplearn.plan.references import read_plan


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
    noise_std_db : float
        Standard deviation of one RSSI reading about the model [dB].
    prior_std_db : float
        The prior's spread of each node's pattern over the sphere [dB].
    prior_pattern : str or None
        A reference pattern model file (``rplearn reference``): the prior is a ridge on the
        deviation from it instead of a smoothness prior.
    station : bool
        One static ground station ``G`` and one drone ``D`` instead of two drones ``A``, ``B``.
    distance_m, height_m : float
        Starting distance between the nodes (horizontal from a station) and drone height [m].
    speed_m_s : float
        The drones' cruise speed [m/s].
    packet_rate_hz : float
        Packets per second in each link direction.
    target_el_deg : (float, float)
        Band of body-frame elevations the spread is taken over [deg].
    drift_std_db : float
        An error drifting over seconds (a heading estimate's wander), as one offset per link and
        5-s block [dB] (:attr:`rplearn.analysis.manoeuvres.ManoeuvreOptions.correlated_std_db`;
        what :func:`rplearn.analysis.manoeuvres.correlated_error_std_db` finds in an earlier
        flight): the plan then counts a direction seen once as less learned than white noise
        says; 0: white noise only.
    """

    target_spread_db: float = 2.0
    budget_s: float = 900.0
    model: str = "sh-10"
    noise_std_db: float = 4.2
    prior_std_db: float = NOMINAL_PRIOR_STD_DB
    prior_pattern: str | None = None
    station: bool = False
    distance_m: float = 10.0
    height_m: float = 20.0
    speed_m_s: float = 1.5
    packet_rate_hz: float = 80.0
    target_el_deg: tuple[float, float] = (-90.0, 90.0)
    drift_std_db: float = 0.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.drift_std_db) and self.drift_std_db >= 0):
            raise InputError(f"drift_std_db: expected a non-negative spread [dB], got {self.drift_std_db!r}", param="drift_std_db")
        for name in ("target_spread_db", "budget_s", "noise_std_db", "prior_std_db", "distance_m", "height_m", "speed_m_s",
                     "packet_rate_hz"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"{name}: expected a positive finite number, got {v!r}", param=name)


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
    """

    steps: tuple[PlanStep, ...]
    start_spread_db: dict[str, float]
    campaign: Campaign | None
    paths: list[str]

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


def _start(opts: OptimizeOptions) -> tuple[tuple[str, str], dict[str, tuple[tuple[float, float, float], float]], tuple[str, ...]]:
    d, h = float(opts.distance_m), float(opts.height_m)
    if opts.station:
        return ("D", "G"), {"G": ((0.0, 0.0, 1.5), 0.0), "D": ((d, 0.0, h), 180.0)}, ("G",)
    return ("A", "B"), {"A": ((-d / 2.0, 0.0, h), 0.0), "B": ((d / 2.0, 0.0, h), 0.0)}, ()


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
    spec = ModelSpec.parse(opts.model)
    if not spec.decouples:
        raise InputError(f"model: {spec.label} has no per-node pattern to plan for; use sh, bg or poly", param="model")
    nodes, poses, fixed = _start(opts)
    shape = "smoothness"
    if opts.prior_pattern is not None:
        # its shape sets the prior's mean, which does not change the spread: read to refuse a bad file early
        require_patterns(load_model(opts.prior_pattern), "prior_pattern")
        shape = "reference"
    weight = prior_penalty_weight(spec.basis(), opts.prior_std_db, opts.noise_std_db, spec.ridge_weight, shape=shape)
    mopts = ManoeuvreOptions(noise_std_db=opts.noise_std_db, packet_rate_hz=opts.packet_rate_hz, penalty_weight=weight,
                             target_el_deg=opts.target_el_deg, candidates=CandidateOptions(fixed_nodes=fixed, speed_m_s=opts.speed_m_s),
                             correlated_std_db=float(opts.drift_std_db))
    if shape == "reference":
        mopts = replace(mopts, power=0.0)
    empty = NormalEquations(spec.basis(), len(nodes))
    start_spread = pattern_spreads(empty, spec, nodes, mopts)
    steps = greedy_plan(empty, spec, nodes, poses, opts.budget_s, opts.target_spread_db, mopts)
    if not steps:
        return OptimizedPlan(steps, start_spread, None, [])
    units = tuple(replace(s.manoeuvre.candidate.unit, label=f"{k + 1:02d}_{s.manoeuvre.candidate.unit.label}")
                  for k, s in enumerate(steps))
    campaign = Campaign(units, gap_s=0.0)
    paths = write_references(campaign, out_dir, rate_hz)
    return OptimizedPlan(steps, start_spread, campaign, paths)


@check_types
def plan_config(preset: str, plan_dir: str) -> Any:
    """A simulator preset flying a folder of reference files instead of its own campaign
    (``rplearn simulate --plan``): its antennas, vehicles and radio; the plan's units
    (:func:`rplearn.plan.references.read_plan`). Its electronics offsets and dropouts, drawn for
    its own campaign, are kept."""
    from rplearn.sim.presets import make_preset

    config = make_preset(preset)
    campaign = read_plan(plan_dir)
    unknown = sorted(set(campaign.nodes) - set(config.node_antennas))
    if unknown:
        raise InputError(f"{plan_dir}: node(s) {', '.join(unknown)} have no antenna in preset {preset} "
                         f"({', '.join(sorted(config.node_antennas))})", param="plan")
    return replace(config, campaign=campaign)


__all__ = ["OptimizeOptions", "OptimizedPlan", "optimize_plan", "plan_config"]
