"""Commands before and instead of a flight: ``trajectory`` (plan and check a campaign) and
``simulate`` (a calibration flight with known patterns)."""

from __future__ import annotations

import typer
from rich.table import Table

from rplearn.cli._app import app, flag_values, floats, out, parts_step, progress_bar, say, user_errors
from rplearn.errors import BadValueError, InputError

#: The plan's library parameters whose flags have other names.
TRAJECTORY_FLAGS = {
    "check_model": "--check-model", "distance_m": "--distance", "height_m": "--height", "n_loops": "--loops", "speed_m_s": "--speed",
    "learning_psi0_deg": "--psi0", "testing_psi0_deg": "--test-psi0", "rate_hz": "--rate",
    "max_speed_m_s": "--max-speed", "max_accel_m_s2": "--max-accel", "max_flight_time_s": "--max-flight-time",
    "target_spread_db": "--target-spread", "budget_s": "--budget-s", "noise_std_db": "--noise", "prior_std_db": "--prior-std",
    "prior_pattern": "--prior-pattern", "model": "--check-model", "drift_std_db": "--drift",
    "packet_rate_hz": "--packet-rate", "from_model": "--from-model",
}


@app.command()
@user_errors(flags=TRAJECTORY_FLAGS)
def trajectory(
    out_dir: str = typer.Option("trajectory", "-o", "--out", help="Directory for the per-drone reference CSVs."),
    distance_m: float = typer.Option(10.0, "--distance", help="Distance between the drones = circle diameter [m]."),
    height_m: float = typer.Option(20.0, "--height", help="Height of the circle centre [m]."),
    loops: int = typer.Option(5, "--loops", help="Headings per drone n; heading step 360/n deg."),
    speed_m_s: float = typer.Option(2.0, "--speed", help="Cruise speed along the circle [m/s]."),
    psi0_deg: list[str] | None = typer.Option(None, "--psi0", help="Initial headings of learning units [deg] (default 0,24,48)."),
    test_psi0_deg: list[str] | None = typer.Option(None, "--test-psi0", help="Initial headings of testing units [deg] (default 36)."),
    max_speed: float | None = typer.Option(None, help="Refuse plans faster than this [m/s]."),
    max_accel: float | None = typer.Option(None, help="Refuse plans with larger accelerations [m/s^2]."),
    max_flight_time: float | None = typer.Option(None, help="Flight time per battery; each unit must fit [s]."),
    rate_hz: float = typer.Option(10.0, "--rate", help="Sample rate of the reference files [Hz]."),
    check_model: str | None = typer.Option("sh-10", "--check-model", help="Model whose rank and condition number the plan check reports (e.g. sh-10, bg-7; "
                                                                          "'none' to skip)."),
    wind_m_s: float = typer.Option(0.0, "--wind", help="Steady wind for the plan check [m/s] (tilts the drones)."),
    optimize: bool = typer.Option(False, "--optimize", help="Choose and order manoeuvres of the library for the information "
                                                           "they gather (greedy by expected spread reduction per second) "
                                                           "instead of the paper's campaign."),
    target_spread: float | None = typer.Option(None, "--target-spread", help="--optimize: stop at this per-node pattern spread "
                                                                            "[dB] (default 2)."),
    budget_s: float | None = typer.Option(None, "--budget-s", help="--optimize: flight-time budget [s] (default 900)."),
    noise_db: float | None = typer.Option(None, "--noise", help="--optimize: RSSI noise about the model [dB] (default 4.2; "
                                                                "with --from-model the model's)."),
    packet_rate_hz: float | None = typer.Option(None, "--packet-rate", help="--optimize: packets per second the radio reports in "
                                                                            "each link direction [Hz] (fewer: each second teaches "
                                                                            "less; default 80, with --from-model the earlier flight's)."),
    prior_std: float | None = typer.Option(None, "--prior-std", help="--optimize: the prior's pattern spread over the sphere "
                                                                     "[dB] (default 6; with --from-model the model's smoothing)."),
    drift: float | None = typer.Option(None, "--drift", help="--optimize: an error drifting over seconds (a heading "
                                                            "estimate's), one offset per 5-s block [dB]; 0: white noise only "
                                                            "(default 0; with --from-model the model's)."),
    from_model: str | None = typer.Option(None, "--from-model", help="--optimize: an earlier flight's model file (rplearn fit "
                                                                      "--order auto): its noise, smoothing and drift as the "
                                                                      "prior; --noise, --prior-std, --drift override them."),
    prior_pattern: str | None = typer.Option(None, "--prior-pattern", help="--optimize: a reference pattern model file "
                                                                           "(rplearn reference) as the prior instead of smoothness."),
    station: bool | None = typer.Option(None, "--station/--two-drones", help="--optimize: a static ground station G and one "
                                                                            "drone D (--distance horizontal from the station), or "
                                                                            "two drones A, B (default; with --from-model the "
                                                                            "earlier flight's layout and node names)."),
) -> None:
    """Plan a calibration campaign and check it before flying.

    Plans the paper's campaign (Sec. IV-A), writes references t,x,y,z,yaw_deg per drone, and
    checks before flying whether the plan will decouple the patterns (coverage, rank,
    condition number).

    Example: rplearn trajectory --distance 10 --height 20 --loops 5 --max-flight-time 600 -o plan
    """
    from rplearn.io.files import check_output_folder

    check_output_folder(out_dir)
    if optimize:
        _optimized(out_dir, check_model, (target_spread, budget_s, noise_db, prior_std, drift, packet_rate_hz),
                   (prior_pattern, from_model), station, (distance_m, height_m, speed_m_s), rate_hz)
        return
    given = [flag for flag, value in (("--from-model", from_model), ("--target-spread", target_spread), ("--budget-s", budget_s),
                                      ("--noise", noise_db), ("--packet-rate", packet_rate_hz), ("--prior-std", prior_std),
                                      ("--drift", drift), ("--prior-pattern", prior_pattern),
                                      ("--station" if station else "--two-drones", station)) if value is not None]
    if given:  # they were ignored without a word: the paper's campaign has no prior, noise or station
        raise InputError(f"{given[0]}: it is an option of --optimize's plan, not of the paper's campaign; add --optimize")
    from rplearn.plan.trajectory import PlanLimits
    from rplearn.workflows.planning import PAPER_LEARNING_PSI0_DEG, PAPER_TESTING_PSI0_DEG, CampaignOptions, plan_campaign, plan_check_spec

    with flag_values():
        campaign = CampaignOptions(
            floats(psi0_deg, "--psi0", "headings in degrees") or PAPER_LEARNING_PSI0_DEG,
            floats(test_psi0_deg, "--test-psi0", "headings in degrees") or PAPER_TESTING_PSI0_DEG,
            distance_m, height_m, loops, speed_m_s,
        )
        limits = PlanLimits(max_speed, max_accel, max_flight_time)
        checked = None if not check_model or check_model.lower() == "none" else check_model
        plan_check_spec(checked)
    plan = plan_campaign(out_dir, campaign, limits, rate_hz, checked, wind_m_s)
    table = Table(title="calibration campaign")
    for col in ("unit", "duration/s", "path/m", "max speed/(m/s)", "max accel/(m/s^2)", "max yaw rate/(deg/s)"):
        table.add_column(col)
    for s in plan.units:
        table.add_row(s.label, f"{s.duration_s:.0f}", f"{s.path_length_m:.0f}", f"{s.max_speed_m_s:.2f}", f"{s.max_accel_m_s2:.2f}",
                      f"{s.max_yaw_rate_deg_s:.1f}")
    out.print(table)
    say(f"wrote {len(plan.paths)} reference files to {out_dir}")
    if plan.check is not None:
        say("plan check (learning units):\n" + plan.check.summary())


def _optimized(out_dir: str, model: str | None, figures: tuple[float | None, ...],
               priors: tuple[str | None, str | None], station: bool | None, geometry: tuple[float, float, float], rate_hz: float) -> None:
    """``trajectory --optimize``: the greedy plan, its expected spread over time, the references."""
    from rplearn.models.spec import ModelSpec
    from rplearn.workflows.calibration_plan import OptimizeOptions, optimize_plan

    target_given, budget_given, noise, prior_std, drift, packet_rate = figures
    defaults = OptimizeOptions()
    target = defaults.target_spread_db if target_given is None else target_given
    budget = defaults.budget_s if budget_given is None else budget_given
    with flag_values():
        ModelSpec.parse(model or "sh-10")
        options = OptimizeOptions(target_spread_db=target, budget_s=budget, model=model or "sh-10", noise_std_db=noise,
                                  packet_rate_hz=packet_rate, prior_std_db=prior_std, prior_pattern=priors[0], station=station,
                                  distance_m=geometry[0], height_m=geometry[1], speed_m_s=geometry[2], drift_std_db=drift,
                                  from_model=priors[1])
    plan = optimize_plan(out_dir, options, rate_hz)
    if plan.prior is not None:
        say(f"prior from {priors[1]}: {plan.prior}")
    for note in plan.notes:
        say(f"note: {note}")
    say("expected per-node pattern spread over time (greedy: the largest expected reduction per second at each step):")
    say(plan.summary())
    if not plan.steps:
        if max(plan.start_spread_db.values()) <= target:
            say(f"the prior's spread is already at most the target {target:g} dB: nothing to fly (check the prior: "
                "--noise, --prior-std, or the --from-model file's); nothing written")
        else:
            say(f"no manoeuvre lowers the spread within {budget:g} s; nothing written")
        return
    worst = max(plan.steps[-1].spread_db.values())
    reached = "reached" if worst <= target else f"not reached within the budget (worst node {worst:.2f} dB)"
    say(f"target {target:g} dB {reached} after {plan.duration_s:.0f} s; wrote {len(plan.paths)} reference files to {out_dir}")


@app.command()
@user_errors
def simulate(
    preset: str = typer.Option("paper", "--preset", help="paper, trio, smoke, ground, pathloss (log-distance exponent 3), tworay (ground reflection) or fleet "
                                                         "(many flights of a fleet as a partitioned matched dataset, one Parquet file per flight)."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random effect."),
    out_dir: str = typer.Option("flight", "-o", "--out", help="Output directory."),
    log_format: str = typer.Option("parquet", "--format", help="parquet or csv."),
    flights: int = typer.Option(8, "--flights", help="fleet: number of flights (about 160,000 samples each)."),
    drones: int = typer.Option(4, "--drones", help="fleet: drones in the fleet, flying in pairs taken in turn."),
    plan: str | None = typer.Option(None, "--plan", help="Fly this folder of reference files (rplearn trajectory's output, "
                                                        "e.g. of --optimize) with the preset's antennas, vehicles and radio, under the "
                                                        "plan's node names: a station it holds still flown as the preset's station, a "
                                                        "drone as its drone."),
    node_map: str | None = typer.Option(None, "--node-map", help="PLAN=PRESET,...: with --plan, fly each plan node as this "
                                                                 "preset node (e.g. gcs=G,sys1=D) instead of by role."),
) -> None:
    """Simulate a calibration flight: raw pose and signal logs plus the true patterns.

    Example: rplearn simulate --preset smoke --seed 1 -o flight
    """
    from rplearn.sim.flight import simulate as run
    from rplearn.sim.presets import make_preset

    with flag_values():
        if log_format not in ("parquet", "csv"):
            raise BadValueError(f"--format: expected parquet or csv, got {log_format!r}")
        if preset != "fleet":
            make_preset(preset)  # a name of no preset refused before the output folder is made
    mapping = _node_map(node_map) if node_map is not None else None
    if mapping is not None and plan is None:
        raise typer.BadParameter("needs --plan, the folder of reference files to fly", param_hint="--node-map")
    from rplearn.io.files import check_output_folder

    check_output_folder(out_dir)
    if preset == "fleet":
        from rplearn.sim.fleet import simulate_fleet

        if log_format != "parquet":
            raise InputError("--format: the fleet preset writes Parquet")
        if plan is not None:
            raise InputError("--plan: the fleet preset flies its own flights, not a plan; fly a plan with another --preset")
        with progress_bar() as p:
            task = p.add_task("simulating a fleet", total=None)
            fleet = simulate_fleet(out_dir, flights=flights, drones=drones, seed=seed,
                                   progress=parts_step(p, task, "simulated", "flight"))
        say(f"{len(fleet.files):,} flights of {drones} drones, {fleet.samples:,} matched samples, {fleet.elapsed_s:.1f} s "
            f"-> {out_dir} (give the folder to fit and evaluate)")
        return
    config = None
    if plan is not None:
        from rplearn.workflows.plan_flight import plan_flight

        flight = plan_flight(preset, plan, mapping)
        config = flight.config
        if flight.text:
            say(flight.text)
    with progress_bar() as p:
        p.add_task(f"simulating preset '{preset}'" + (f" flying {plan}" if plan else ""), total=None)
        result = run(config or preset, seed=seed, out_dir=out_dir, log_format=log_format)
    say(
        f"{len(result.pose_log):,} pose rows, {len(result.signal_log):,} packets, noise {result.noise_std_db:.2f} dB, "
        f"{result.elapsed_s:.1f} s"
    )
    for k, v in result.paths.items():
        say(f"  {k}: {v}")


def _node_map(text: str) -> dict[str, str]:
    """``--node-map PLAN=PRESET,...`` as plan node -> preset node; bad syntax, a node given twice or
    two plan nodes on one preset node: a usage error (one line, exit 2)."""
    found: dict[str, str] = {}
    for item in text.split(","):
        plan, sep, ours = (part.strip() for part in item.partition("="))
        if not (sep and plan and ours):
            raise typer.BadParameter(f"expected PLAN=PRESET,... (e.g. gcs=G,sys1=D), got {text!r}", param_hint="--node-map")
        if plan in found:
            raise typer.BadParameter(f"{plan} is mapped twice in {text!r}", param_hint="--node-map")
        if ours in found.values():
            raise typer.BadParameter(f"two plan nodes are flown as {ours} in {text!r} (expected one to one)",
                                     param_hint="--node-map")
        found[plan] = ours
    return found
