"""Pipelines before and after learning that write or answer one thing: plan a calibration
campaign (``rplearn trajectory``), export a model file (``rplearn export``), draw its patterns
(``rplearn plot``) and orient one link (``rplearn orient``)."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import cast

from rplearn._argtypes import check_types
from rplearn._budget import Cost, budget, check_work
from rplearn.analysis.heading_options import YawOptions
from rplearn.analysis.headings import OrientationResult, best_yaw
from rplearn.data.phases import CALIBRATION_MIN_DISTANCE_M
from rplearn.errors import BadValueError, InputError
from rplearn.io.export import export_grid
from rplearn.io.files import check_output_kind, check_output_path, provenance
from rplearn.io.msi import export_msi_files
from rplearn.models.base import require_patterns
from rplearn.models.load import load_model
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec
from rplearn.plan.campaign import Campaign, paper_campaign, write_references
from rplearn.plan.check import NominalAttitude, PlanCheck, check_plan
from rplearn.plan.trajectory import PlanLimits, TrajectoryUnit, UnitSummary, summarize_unit

#: Headings [deg] of the paper's learning and testing units (Sec. V-C).
PAPER_LEARNING_PSI0_DEG: tuple[float, ...] = (0.0, 24.0, 48.0)
PAPER_TESTING_PSI0_DEG: tuple[float, ...] = (36.0,)


@check_types
@dataclass
class CampaignPlan:
    """A planned campaign, what each unit asks of the drones, the references written and the
    plan check (None when not asked for)."""

    campaign: Campaign
    units: list[UnitSummary]
    paths: list[str]
    check: PlanCheck | None = None


@check_types
@dataclass(frozen=True)
class CampaignOptions:
    """The units of a campaign :func:`plan_campaign` plans (the paper's, Sec. IV-A, by default).

    Attributes
    ----------
    learning_psi0_deg, testing_psi0_deg : sequence of float
        Initial headings of the learning and the testing units [deg].
    distance_m, height_m : float
        Distance between the drones and flight height [m].
    n_loops : int
        Loops per unit.
    speed_m_s : float
        Flight speed [m/s].

    Raises
    ------
    InputError
        On the first invalid option, naming it (``param``).
    """

    learning_psi0_deg: Sequence[float] = PAPER_LEARNING_PSI0_DEG
    testing_psi0_deg: Sequence[float] = PAPER_TESTING_PSI0_DEG
    distance_m: float = 10.0
    height_m: float = 20.0
    n_loops: int = 5
    speed_m_s: float = 2.0

    def __post_init__(self) -> None:
        for name in ("learning_psi0_deg", "testing_psi0_deg"):
            try:
                headings = tuple(float(v) for v in getattr(self, name))
            except (TypeError, ValueError):
                headings = (float("nan"),)
            if not all(math.isfinite(v) for v in headings):
                raise InputError(f"{name}: expected finite headings in degrees, got {getattr(self, name)!r}",
                                 param=name)
            object.__setattr__(self, name, headings)
        if not self.learning_psi0_deg:
            raise InputError("learning_psi0_deg: expected at least one learning heading", param="learning_psi0_deg")
        # the unit fields, checked as every unit will be (InputError naming the field)
        TrajectoryUnit(distance_m=self.distance_m, height_m=self.height_m, n_loops=self.n_loops,
                       speed_m_s=self.speed_m_s)
        if not self.distance_m >= CALIBRATION_MIN_DISTANCE_M:  # the least distance of a calibration flight
            raise InputError(f"distance_m: expected at least {CALIBRATION_MIN_DISTANCE_M:g} m between the drones, got "
                             f"{self.distance_m:g} m (closer, a GNSS position's 1-2 m error turns the directions between "
                             "them by more than 10-20 deg, and the drones may touch)", param="distance_m")


#: The least rate of a reference file [Hz]: a row at least every second (a unit turns between its
#: loops in a few seconds; sparser rows cut the turns, and a loop to a polygon of a few sides).
MIN_REFERENCE_RATE_HZ = 1.0

#: Measured costs of planning (``trajectory`` at --loops 5 and 50, --rate 10 and 1000 on a loaded
#: 2-core machine): the plan check's seconds and bytes per loop of the learning units, and per
#: reference row (one drone at one instant) its seconds, bytes in memory and on disk.
PLAN_CHECK_S_PER_LOOP, PLAN_CHECK_BYTES_PER_LOOP = 0.4, 1e6
REFERENCE_ROW_S, REFERENCE_ROW_BYTES, REFERENCE_ROW_DISK = 15e-6, 320.0, 40.0


def campaign_cost(options: CampaignOptions, n_loops: float, rate_hz: float) -> Cost:
    """What :func:`plan_campaign` takes for ``n_loops`` loops per unit at ``rate_hz`` [Hz]
    (each unit's flight time from one loop's: ``2 n`` loops and turns of at least 1 s)."""
    one = TrajectoryUnit(distance_m=options.distance_m, height_m=options.height_m, n_loops=1,
                         speed_m_s=options.speed_m_s)
    duration_s = 2.0 * n_loops * (one.duration_s / 2.0 + 1.0)
    n_units = len(options.learning_psi0_deg) + len(options.testing_psi0_deg)
    rows = n_units * 2.0 * duration_s * rate_hz
    learning_loops = len(options.learning_psi0_deg) * n_loops
    return Cost(memory_bytes=3e8 + PLAN_CHECK_BYTES_PER_LOOP * learning_loops + REFERENCE_ROW_BYTES * 2 * duration_s * rate_hz,
                seconds=3.0 + PLAN_CHECK_S_PER_LOOP * learning_loops + REFERENCE_ROW_S * rows,
                disk_bytes=REFERENCE_ROW_DISK * rows)


def plan_check_spec(check_model: str | None) -> ModelSpec | None:
    """The model whose patterns :func:`plan_campaign`'s check reads (None: no check); a name that
    is no model, or a baseline without per-node patterns, refused (``check_model``)."""
    if not check_model:
        return None
    spec = ModelSpec.parse(check_model)
    if not spec.decouples:
        raise BadValueError(f"check_model: {spec.label} has no per-node pattern to check; use sh, bg or poly", param="check_model")
    return spec


def check_export_format(fmt: str) -> None:
    """Refuse an export format other than ``grid``, ``msi`` or ``images`` (``fmt``)."""
    if fmt not in ("grid", "msi", "images"):
        raise BadValueError(f"fmt: expected grid, msi or images, got {fmt!r}", param="fmt")


@check_types
def plan_campaign(
    out_dir: str,
    campaign: CampaignOptions | None = None,
    limits: PlanLimits | None = None,
    rate_hz: float = 10.0,
    check_model: str | None = "sh-10",
    wind_speed_m_s: float = 0.0,
) -> CampaignPlan:
    """Plan the paper's campaign (Sec. IV-A), refuse units beyond ``limits``, write one
    reference file per unit and drone, and check whether the learning units will decouple the
    patterns of ``check_model`` (rank, condition number, coverage) before anyone flies.

    ``campaign`` gives the units' headings and geometry (default ``CampaignOptions()``, the
    paper's); ``rate_hz`` is the rate of the reference files [Hz] and ``wind_speed_m_s`` the
    wind the plan check assumes [m/s].
    """
    options = CampaignOptions() if campaign is None else campaign
    if not (isinstance(rate_hz, (int, float)) and math.isfinite(rate_hz) and rate_hz > 0):
        raise InputError(f"rate_hz: expected a positive sample rate, got {rate_hz!r}", param="rate_hz")
    if rate_hz < MIN_REFERENCE_RATE_HZ:
        raise InputError(f"rate_hz: expected at least {MIN_REFERENCE_RATE_HZ:g} Hz, got {rate_hz:g} Hz: the units turn "
                         "between loops in a few seconds, and sparser rows cut the turns and the loops short",
                         param="rate_hz")
    work = budget(out_dir)
    # each alone (the other at most its default), then both: the rate is named for what they need together
    n_loops, usual_rate = options.n_loops, min(rate_hz, 10.0)
    over = work.refusal(campaign_cost(options, 1, usual_rate))
    if over is not None:  # not the loops: one loop alone is too long, at this speed
        raise InputError(f"speed_m_s: at {options.speed_m_s:g} m/s even one loop per unit would take {over}; fly faster",
                         param="speed_m_s")
    check_work("n_loops", n_loops, lambda n: campaign_cost(options, n, usual_rate), "loops", limits=work)
    for loops in (min(n_loops, 5), n_loops):
        check_work("rate_hz", rate_hz, lambda r: campaign_cost(options, loops, r), "Hz",  # noqa: B023 (used at once)
                   integer=False, bounds=(1e-3, math.inf), limits=work)
    spec = plan_check_spec(check_model)  # refuse a bad model before writing files
    planned = paper_campaign(
        learning_psi0_deg=list(options.learning_psi0_deg), testing_psi0_deg=list(options.testing_psi0_deg),
        distance_m=options.distance_m, height_m=options.height_m, n_loops=options.n_loops, speed_m_s=options.speed_m_s,
    )
    units = [summarize_unit(unit, limits) for unit in planned.units]
    paths = write_references(planned, out_dir, rate_hz)
    attitude = NominalAttitude(wind_speed_m_s=wind_speed_m_s)
    check = check_plan(planned, spec.basis(), attitude=attitude) if spec is not None else None
    return CampaignPlan(planned, units, paths, check)


@check_types
def export_model_file(
    model_path: str, fmt: str, output: str, step_deg: float = 5.0, frequency_hz: float | None = None
) -> list[str]:
    """Export a learned model: ``grid`` (one CSV: node, az_deg, el_deg, gain_db), ``msi`` (one
    MSI Planet file per node) or ``images`` (one 3-D PNG per node). Returns the paths written.
    """
    check_export_format(fmt)
    if fmt == "grid":
        check_output_path(output, [model_path])
        check_output_kind(output, "grid")
    elif os.path.exists(output) and not os.path.isdir(output):
        raise InputError(f"{output}: is a file; give a folder for the {fmt} files", param="output")
    model = load_model(model_path)
    if model.kind != "patterns":
        raise InputError(f"{model_path}: a {model.kind} baseline has no per-node pattern to export")
    if fmt == "grid":
        export_grid(model, step_deg, output)
        return [output]
    if fmt == "msi":
        return export_msi_files(model, output, frequency_hz)
    from rplearn.viz.images import export_pattern_images

    return export_pattern_images(model, output)


@check_types
def orient_link(
    model_path: str,
    tx_node: str,
    rx_node: str,
    tx_position_xyz: Sequence[float],
    rx_position_xyz: Sequence[float],
    turn: str = "tx",
    options: YawOptions | None = None,
) -> OrientationResult:
    """Heading(s) that maximise one link of a model file (``rplearn orient``): the model's
    :func:`rplearn.analysis.headings.best_yaw`."""
    model = load_model(model_path)
    require_patterns(model, f"{model_path}: telling which heading is better")
    return best_yaw(cast(PatternSet, model), tx_node, rx_node, tx_position_xyz, rx_position_xyz, turn, options)


def _data_lines(path: str) -> int:
    """Lines of a text file after its header, counted in 1 MiB blocks (no parsing)."""
    lines = 0
    with open(path, "rb") as f:
        while block := f.read(1 << 20):
            lines += block.count(b"\n")
    return max(lines - 1, 0)


def _precheck_reference_rows(patterns: Mapping[str, str]) -> None:
    """Refuse a CSV pattern grid too fine to expand before reading it: its rows (shared by the
    nodes that name the same file) against the expansion's work budget
    (:func:`rplearn.models.reference.expansion_cost`; checked again, exactly, after reading)."""
    from rplearn.models.reference import expansion_cost

    users: dict[str, int] = {}
    for path in patterns.values():
        users[path] = users.get(path, 0) + 1
    for path, n_nodes in users.items():
        if path.lower().endswith(".csv") and os.path.isfile(path):
            rows = _data_lines(path) // n_nodes
            if rows > 1:
                check_work(path, rows, expansion_cost, "directions (a coarser grid fits)", bounds=(1, rows))


@check_types
def reference_model_file(
    patterns: Mapping[str, str], output: str, mounts: Mapping[str, Sequence[float]] | None = None
) -> PatternSet:
    """``rplearn reference``: read each node's reference pattern (CSV or MSI, with its mount)
    and write them as one model file (:func:`rplearn.models.reference.reference_model`)."""
    from rplearn.io.reference import read_reference_pattern
    from rplearn.models.reference import reference_model

    if not patterns:
        raise InputError("patterns: give NODE=FILE for at least one node", param="patterns")
    mounts = {str(k): tuple(float(x) for x in v) for k, v in (mounts or {}).items()}
    unknown = sorted(set(mounts) - {str(n) for n in patterns})
    if unknown:
        raise InputError(f"mounts: node(s) {', '.join(unknown)} have no pattern; patterns are given for "
                         f"{', '.join(sorted(patterns))}", param="mounts")
    check_output_path(output, list(patterns.values()))
    check_output_kind(output, "model")
    _precheck_reference_rows(patterns)
    samples = {str(n): read_reference_pattern(path, mounts.get(str(n), (0.0, 0.0, 0.0)), node=str(n))
               for n, path in patterns.items()}
    model = reference_model(samples, mounts, provenance=provenance(patterns=dict(patterns), mounts=mounts))
    model.save(output)
    return model


@check_types
def draw_pattern_files(
    model_paths: Sequence[str], output: str, truth: str | None = None, dataset: str | None = None,
    spread: str | None = None,
) -> str:
    """Draw learned patterns of model files in the azimuth-elevation domain (paper Fig. 9,
    ``rplearn plot``), beside a simulation's true patterns and over a dataset's sample
    directions when given; with ``spread``, also each node's own-pattern spread there
    (:func:`rplearn.viz.plot.plot_spread_maps`). Returns the PNG path (of the patterns)."""
    from rplearn.analysis.pattern_error import node_directions
    from rplearn.data.tables import link_samples
    from rplearn.io.files import read_dataset
    from rplearn.io.resolve import check_outputs
    from rplearn.sim.antennas import load_ground_truth
    from rplearn.viz.plot import plot_pattern_maps

    check_outputs({"output": output, "spread": spread}, [*model_paths, truth, dataset])
    for param, path in (("output", output), ("spread", spread)):
        if path is not None:
            check_output_kind(path, "png", param)
    models = {}
    for path in model_paths:
        model = load_model(path)
        if not isinstance(model, PatternSet):
            raise InputError(f"{path}: a {model.kind} baseline has no per-node pattern to draw", param="model_paths")
        models[model.label] = model
    gt = load_ground_truth(truth) if truth else None
    nodes = list(next(iter(models.values())).nodes)
    dirs = node_directions(link_samples(read_dataset(dataset), dataset)) if dataset else None
    if spread:
        from rplearn.viz.plot import plot_spread_maps

        plot_spread_maps(models, spread, nodes)
    return plot_pattern_maps(models, gt, nodes, dirs, output, center=gt is not None)
