"""The ``rplearn`` command line: thin wrappers that parse, call one library function, print.

Every user error (a subclass of :class:`rplearn.errors.RplearnError`, a missing file) prints one
line ``error: ...`` on standard error and exits with code 1, without a traceback.
"""

from __future__ import annotations

import functools
import json
import logging
import os
import sys
from typing import Any, Callable, Optional

import typer
from rich.console import Console
from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from rplearn import __version__
from rplearn.errors import InputError, RplearnError

app = typer.Typer(
    name="rplearn",
    help=(
        "Learn drone-with-antenna radiation patterns from calibration flights and predict links.\n\n"
        "Typical session:\n\n"
        "  rplearn simulate --preset smoke -o flight\n\n"
        "  rplearn sync --poses flight/pose_log.parquet --signals flight/signal_log.parquet --link A:B -o data.parquet\n\n"
        "  rplearn fit data.parquet --model sh --degree 10 -o sh10.json\n\n"
        "  rplearn evaluate sh10.json data.parquet\n\n"
        "  rplearn demo -o rplearn-demo"
    ),
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,  # help texts carry units in brackets, e.g. [m/s], which markup would eat
    pretty_exceptions_enable=False,
)
console = Console(stderr=True)
out = Console(soft_wrap=True)


def _fail(message: str) -> None:
    console.print(f"[bold red]error:[/] {message}", highlight=False, soft_wrap=True)
    raise typer.Exit(1)


def user_errors(fn: Callable) -> Callable:
    """Turn user mistakes into one line on stderr and exit code 1."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except RplearnError as exc:
            _fail(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
        except FileNotFoundError as exc:
            _fail(f"{exc.filename}: no such file or directory")
        except OSError as exc:
            _fail(f"{exc.filename}: {exc.strerror or exc}" if exc.filename else str(exc))

    return wrapper


def _progress() -> Progress:
    """Rich progress on a terminal; nothing when standard error is not one (see :func:`_step`)."""
    return Progress(
        SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), console=console, transient=True,
        disable=not console.is_terminal,
    )


def _step(progress: Progress, task: Any) -> Callable[[str], None]:
    """Progress callback: updates the bar on a terminal, prints a plain line otherwise."""

    def report(message: str) -> None:
        if console.is_terminal:
            progress.update(task, description=message)
        else:
            console.print(f"... {message}", highlight=False, soft_wrap=True)

    return report


def _split_list(values: Optional[list[str]]) -> list[str] | None:
    if not values:
        return None
    items = [v.strip() for value in values for v in value.split(",") if v.strip()]
    return items or None


def _pairs(values: Optional[list[str]], what: str) -> dict[str, str]:
    outp: dict[str, str] = {}
    for v in values or []:
        if "=" not in v:
            raise InputError(f"{what}: expected KEY=VALUE, got {v!r}")
        k, val = v.split("=", 1)
        outp[k.strip()] = val.strip()
    return outp


def _reader_options(
    node: Optional[list[str]], receiver: Optional[list[str]], address: Optional[list[str]], pose_topic: Optional[list[str]]
) -> dict[str, Any]:
    """Options of :func:`rplearn.io.read_logs` from the repeated KEY=VALUE flags."""
    opts: dict[str, Any] = {}
    for flag, key, values in (
        ("--node", "nodes", node),
        ("--receiver", "receivers", receiver),
        ("--address", "address_map", address),
        ("--pose-topic", "pose_topics", pose_topic),
    ):
        if values:
            opts[key] = _pairs(values, flag)
    return opts


def _link(text: Optional[str]) -> tuple[str, str] | None:
    if text is None or text.lower() == "all":
        return None
    parts = text.split(":")
    if len(parts) != 2 or not all(parts):
        raise InputError(f"--link: expected TX:RX (e.g. A:B) or 'all', got {text!r}")
    return parts[0], parts[1]


def _write_json(path: str, payload: Any) -> None:
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(payload, fh, indent=1, default=str)


# -------------------------------------------------------------------------------------------


@app.callback()
def main_callback(
    verbose: bool = typer.Option(False, "--verbose", "-v", help="Log progress details."),
    version: bool = typer.Option(False, "--version", help="Print the version and exit."),
) -> None:
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    if version:
        out.print(f"rplearn {__version__}")
        raise typer.Exit(0)


@app.command()
@user_errors
def trajectory(
    out_dir: str = typer.Option("trajectory", "-o", "--out", help="Directory for the per-drone reference CSVs."),
    distance_m: float = typer.Option(10.0, "--distance", help="Distance between the drones = circle diameter [m]."),
    height_m: float = typer.Option(20.0, "--height", help="Height of the circle centre [m]."),
    loops: int = typer.Option(5, "--loops", help="Headings per drone n; heading step 360/n deg."),
    speed_m_s: float = typer.Option(2.0, "--speed", help="Cruise speed along the circle [m/s]."),
    psi0_deg: Optional[list[str]] = typer.Option(None, "--psi0", help="Initial headings of learning units [deg] (default 0,24,48)."),
    test_psi0_deg: Optional[list[str]] = typer.Option(None, "--test-psi0", help="Initial headings of testing units [deg] (default 36)."),
    max_speed: Optional[float] = typer.Option(None, help="Refuse plans faster than this [m/s]."),
    max_accel: Optional[float] = typer.Option(None, help="Refuse plans with larger accelerations [m/s^2]."),
    max_flight_time: Optional[float] = typer.Option(None, help="Flight time per battery; each unit must fit [s]."),
    rate_hz: float = typer.Option(10.0, "--rate", help="Sample rate of the reference files [Hz]."),
    check_model: Optional[str] = typer.Option("sh-10", "--check-model", help="Model whose rank and condition number the plan check reports (e.g. sh-10, bg-7; 'none' to skip)."),
    wind_m_s: float = typer.Option(0.0, "--wind", help="Steady wind for the plan check [m/s] (tilts the drones)."),
) -> None:
    """Plan the paper's calibration campaign (Sec. IV-A), write references t,x,y,z,yaw_deg, and check
    before flying whether the plan will decouple the patterns (coverage, rank, condition number).

    Example: rplearn trajectory --distance 10 --height 20 --loops 5 --max-flight-time 600 -o plan
    """
    from rplearn.learn import ModelSpec
    from rplearn.plan import check_plan
    from rplearn.trajectory import PlanLimits, paper_campaign, summarize_unit, write_references

    learn = [float(v) for v in (_split_list(psi0_deg) or ["0", "24", "48"])]
    test = [float(v) for v in (_split_list(test_psi0_deg) or ["36"])]
    campaign = paper_campaign(
        learning_psi0_deg=learn, testing_psi0_deg=test, distance_m=distance_m, height_m=height_m, n_loops=loops, speed_m_s=speed_m_s
    )
    limits = PlanLimits(max_speed, max_accel, max_flight_time)
    table = Table(title="calibration campaign")
    for col in ("unit", "duration/s", "path/m", "max speed/(m/s)", "max accel/(m/s^2)", "max yaw rate/(deg/s)"):
        table.add_column(col)
    for unit in campaign.units:
        s = summarize_unit(unit, limits)
        table.add_row(s.label, f"{s.duration_s:.0f}", f"{s.path_length_m:.0f}", f"{s.max_speed_m_s:.2f}", f"{s.max_accel_m_s2:.2f}", f"{s.max_yaw_rate_deg_s:.1f}")
    paths = write_references(campaign, out_dir, rate_hz)
    out.print(table)
    out.print(f"wrote {len(paths)} reference files to {out_dir}")
    if check_model and check_model.lower() != "none":
        spec = ModelSpec.parse(check_model)
        if not spec.decouples:
            raise InputError(f"--check-model: {spec.label} has no per-node pattern to check; use sh, bg or poly")
        report = check_plan(campaign, spec.basis(), wind_speed_m_s=wind_m_s)
        out.print("plan check (learning units):\n" + report.summary(), highlight=False)


@app.command()
@user_errors
def simulate(
    preset: str = typer.Option("paper", "--preset", help="paper, trio or smoke."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random effect."),
    out_dir: str = typer.Option("flight", "-o", "--out", help="Output directory."),
    log_format: str = typer.Option("parquet", "--format", help="parquet or csv."),
) -> None:
    """Simulate a calibration flight: raw pose and signal logs plus the true patterns.

    Example: rplearn simulate --preset smoke --seed 1 -o flight
    """
    from rplearn.simulate import simulate as run

    if log_format not in ("parquet", "csv"):
        raise InputError(f"--format: expected parquet or csv, got {log_format!r}")
    with _progress() as p:
        p.add_task(f"simulating preset '{preset}'", total=None)
        result = run(preset, seed=seed, out_dir=out_dir, log_format=log_format)
    out.print(
        f"{len(result.pose_log):,} pose rows, {len(result.signal_log):,} packets, noise {result.noise_std_db:.2f} dB, "
        f"{result.elapsed_s:.1f} s"
    )
    for k, v in result.paths.items():
        out.print(f"  {k}: {v}")


@app.command()
@user_errors
def inspect(
    logs: list[str] = typer.Argument(..., help="Log files: CSV/Parquet, ROS 1/2 bags, PX4 ULog, pcap."),
    node: Optional[list[str]] = typer.Option(None, "--node", help="FILE=NODE for ULogs and one-node tables."),
    receiver: Optional[list[str]] = typer.Option(None, "--receiver", help="FILE=NODE: capturing node of a pcap."),
    address: Optional[list[str]] = typer.Option(None, "--address", help="MAC=NODE: transmitter addresses of pcaps."),
    pose_topic: Optional[list[str]] = typer.Option(None, "--pose-topic", help="TOPIC=NODE for ROS bags."),
    markdown: bool = typer.Option(False, "--markdown", help="Print Markdown instead of text."),
) -> None:
    """Summarise logs: nodes, time spans, rates, RSSI range, gaps, and anything suspicious.

    Example: rplearn inspect flight/pose_log.parquet flight/signal_log.parquet
    """
    from rplearn.inspect import inspect_logs

    report = inspect_logs(logs, **_reader_options(node, receiver, address, pose_topic))
    out.print(report.to_markdown() if markdown else report.to_text(), highlight=False)
    unreadable = [f for f in report.files if f.get("error") is not None]
    if unreadable:
        _fail(f"{len(unreadable)} of {len(report.files)} file(s) could not be read (see above)")


@app.command()
@user_errors
def sync(
    poses: list[str] = typer.Option(..., "--poses", help="Pose log(s): CSV/Parquet, bag, ULog. Repeat for several."),
    signals: list[str] = typer.Option(..., "--signals", help="Signal log(s): CSV/Parquet, bag, pcap. Repeat for several."),
    output: str = typer.Option(..., "-o", "--out", help="Matched dataset (.parquet or .csv)."),
    link: Optional[str] = typer.Option(None, "--link", help="Keep one direction TX:RX (the paper's choice), or 'all'."),
    max_gap_s: float = typer.Option(0.2, "--max-gap", help="Drop samples inside pose gaps longer than this [s]."),
    offset: Optional[list[str]] = typer.Option(None, "--offset", help="NODE=SECONDS clock offset added to a node's pose times."),
    node: Optional[list[str]] = typer.Option(None, "--node", help="FILE=NODE for ULogs and one-node tables."),
    receiver: Optional[list[str]] = typer.Option(None, "--receiver", help="FILE=NODE: capturing node of a pcap."),
    address: Optional[list[str]] = typer.Option(None, "--address", help="MAC=NODE: transmitter addresses of pcaps."),
    pose_topic: Optional[list[str]] = typer.Option(None, "--pose-topic", help="TOPIC=NODE: pose topics of ROS bags."),
    tx_power_dbm: Optional[float] = typer.Option(None, "--tx-power", help="Transmit power for logs without it [dBm]."),
    frequency_hz: Optional[float] = typer.Option(None, "--frequency", help="Carrier frequency for logs without it [Hz]."),
) -> None:
    """Match every signal sample with the interpolated poses of both ends (paper Sec. V-B4).

    Example: rplearn sync --poses flight/pose_log.parquet --signals flight/signal_log.parquet --link A:B -o data.parquet
    """
    from rplearn.datasets import write_table
    from rplearn.io import read_logs
    from rplearn.sync import synchronise

    opts = {"tx_power_dbm": tx_power_dbm, "frequency_hz": frequency_hz, **_reader_options(node, receiver, address, pose_topic)}
    pose_logs, _ = read_logs(poses, **opts)
    signal_logs, _ = read_logs(signals, **opts)
    if pose_logs.pose is None:
        raise InputError(f"{', '.join(poses)}: no pose log found")
    if signal_logs.signal is None:
        raise InputError(f"{', '.join(signals)}: no signal log found")
    try:
        offsets = {k: float(v) for k, v in _pairs(offset, "--offset").items()}
    except ValueError:
        raise InputError(f"--offset: expected NODE=SECONDS with a number, got {', '.join(offset or [])}") from None
    result = synchronise(pose_logs.pose, signal_logs.signal, link=_link(link), max_gap_s=max_gap_s, clock_offsets_s=offsets or None)
    write_table(result.dataset, output)
    out.print(result.summary.to_text(), highlight=False)
    out.print(f"wrote {len(result.dataset):,} matched samples to {output}")


def _dataset(path: str):
    from rplearn.datasets import read_table, validate_matched

    return validate_matched(read_table(path), path)


@app.command()
@user_errors
def fit(
    dataset: str = typer.Argument(..., help="Matched dataset (.parquet or .csv)."),
    model: str = typer.Option("sh", "--model", help="sh, bg, poly, mean or knn (also sh-10, nn-400...)."),
    degree: Optional[int] = typer.Option(None, "--degree", help="SH-L / BG-k / P-k order, or k of knn (defaults 10, 7, 12, 400)."),
    ridge: Optional[float] = typer.Option(None, "--ridge", help="Ridge weight on the diagonal of X^T X (default 1; the paper used 50)."),
    sigma: float = typer.Option(0.5, "--sigma", help="BG kernel variance sigma [rad^2] (paper: about 0.5)."),
    grid: str = typer.Option("paper", "--grid", help="BG nodes: paper or fibonacci."),
    units: Optional[list[str]] = typer.Option(None, "--units", help="Learning units (repeat or comma-separate)."),
    gauge_node: Optional[str] = typer.Option(None, "--gauge-node", help="Fix this node's mean gain instead of splitting equally."),
    gauge_dbi: float = typer.Option(0.0, "--gauge-dbi", help="Sphere-mean gain of --gauge-node [dBi]."),
    output: str = typer.Option(..., "-o", "--out", help="Model file (.json)."),
) -> None:
    """Learn one radiation pattern per node (or a baseline) from a matched dataset.

    Example: rplearn fit data.parquet --model sh --degree 10 --units learn_0,learn_24,learn_48 -o sh10.json
    """
    from rplearn.experiment import provenance
    from rplearn.learn import ModelSpec, fit_model, samples_of

    spec = ModelSpec.parse(model, order=degree, ridge=ridge, sigma_rad2=sigma, grid=grid)
    samples = samples_of(_dataset(dataset), _split_list(units), dataset)
    gauge: Any = {"node": gauge_node, "mean_gain_dbi": gauge_dbi} if gauge_node else "equal-mean"
    fitted = fit_model(samples, spec, gauge=gauge, provenance=provenance(dataset=dataset, model=spec.label, ridge=spec.ridge, units=_split_list(units)))
    fitted.model.save(output)
    msg = f"{spec.label} learned from {len(samples):,} samples in {fitted.ltd_s:.3f} s -> {output}"
    training = getattr(fitted.model, "training", {})
    if "rank" in training:
        msg += f"\n  rank {training['rank']} of {training['n_columns']}, condition number {training['condition_number']:.2f}, training RMSE {training['rmse_db']:.2f} dB"
        for g in training.get("gauges", []):
            msg += f"\n  gauge: {g['text']}"
    out.print(msg, highlight=False)
    for w in training.get("warnings", []):
        console.print(f"warning: {w}", highlight=False, soft_wrap=True)


@app.command()
@user_errors
def evaluate(
    paths: list[str] = typer.Argument(..., help="MODEL.json... DATASET (the last argument is the dataset)."),
    units: Optional[list[str]] = typer.Option(None, "--units", help="Evaluation units (repeat or comma-separate)."),
    json_out: Optional[str] = typer.Option(None, "--json", help="Also write Table I as JSON here."),
    markdown_out: Optional[str] = typer.Option(None, "--markdown", help="Also write Table I as Markdown here."),
) -> None:
    """Table I (RMSE, MAE, |phi|, AIC, LTD, Q95) of models on a dataset.

    Example: rplearn evaluate sh10.json mean.json data.parquet --units test_36
    """
    from rplearn.experiment import provenance
    from rplearn.learn import FittedModel, evaluate_models, samples_of, scores_markdown
    from rplearn.modelfile import load_model

    if len(paths) < 2:
        raise InputError("evaluate: give at least one MODEL.json and a DATASET")
    *model_paths, dataset = paths
    models = [load_model(p) for p in model_paths]
    samples = samples_of(_dataset(dataset), _split_list(units), dataset)
    fitted = [FittedModel.from_model(m) for m in models]
    rows = evaluate_models(fitted, samples)
    md = scores_markdown(rows)
    out.print(md, highlight=False)
    if markdown_out:
        with open(markdown_out, "w") as fh:
            fh.write(md + "\n")
    if json_out:
        _write_json(json_out, {"provenance": provenance(dataset=dataset, models=model_paths), "rows": [r.to_dict() for r in rows]})


@app.command()
@user_errors
def predict(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    dataset: str = typer.Argument(..., metavar="DATASET"),
    output: str = typer.Option(..., "-o", "--out", help="The dataset with gain_pred_db, rssi_pred_dbm and (pattern models) gain_pred_std_db added (.csv or .parquet)."),
) -> None:
    """Predict the joint gain and received power for every row of a dataset.

    Example: rplearn predict sh10.json data.parquet -o pred.csv
    """
    from rplearn.datasets import link_samples, write_table
    from rplearn.link import received_power_dbm
    from rplearn.modelfile import load_model

    model = load_model(model_path)
    df = _dataset(dataset)
    samples = link_samples(df, dataset)
    gain = model.predict_samples(samples)
    df = df.copy()
    df["gain_pred_db"] = gain
    df["rssi_pred_dbm"] = received_power_dbm(df["tx_power_dbm"].to_numpy(), gain, samples.distance_m, df["frequency_hz"].to_numpy())
    if getattr(model, "covariance", None) is not None:
        df["gain_pred_std_db"] = model.predict_samples_std(samples)  # coefficient uncertainty only
    write_table(df, output)
    out.print(f"wrote {len(df):,} predictions to {output}")


@app.command()
@user_errors
def sweep(
    dataset: str = typer.Argument(...),
    model: str = typer.Option("sh", "--model", help="sh, bg or poly."),
    orders: str = typer.Option("3..15", "--orders", help="Range A..B or a list 3,5,8."),
    learn_units: Optional[list[str]] = typer.Option(None, "--learn-units", help="Learning units (default: all but the test units)."),
    test_units: Optional[list[str]] = typer.Option(None, "--test-units", help="Testing units (default: units whose label starts with 'test')."),
    output: Optional[str] = typer.Option(None, "-o", "--out", help="CSV of the sweep."),
    plot_path: Optional[str] = typer.Option(None, "--plot", help="PNG of the sweep (Fig. 10)."),
) -> None:
    """Model-order selection: test RMSE, AIC and LTD against the order (paper Fig. 10).

    Example: rplearn sweep data.parquet --model sh --orders 3..15 -o sweep.csv --plot sweep.png
    """
    from rplearn.experiment import order_sweep
    from rplearn.learn import samples_of

    if ".." in orders:
        a, b = orders.split("..", 1)
        try:
            order_list = list(range(int(a), int(b) + 1))
        except ValueError:
            raise InputError(f"--orders: expected A..B or a comma list, got {orders!r}") from None
    else:
        try:
            order_list = [int(v) for v in orders.split(",")]
        except ValueError:
            raise InputError(f"--orders: expected A..B or a comma list, got {orders!r}") from None
    if not order_list or min(order_list) < 1:
        raise InputError(f"--orders: expected positive orders, A..B with A <= B, got {orders!r}")
    df = _dataset(dataset)
    if "unit" not in df.columns:
        raise InputError(f"{dataset}: a sweep needs a 'unit' column to split learning from testing samples")
    all_units = sorted(df["unit"].astype(str).unique())
    test = _split_list(test_units) or [u for u in all_units if u.startswith("test")]
    learn = _split_list(learn_units) or [u for u in all_units if u not in test]
    if not test or not learn:
        raise InputError(f"{dataset}: cannot split units {', '.join(all_units)} into learning and testing; use --learn-units/--test-units")
    if set(test) & set(learn):
        raise InputError(f"--learn-units and --test-units share {', '.join(sorted(set(test) & set(learn)))}; a test must use unseen data")
    ls = samples_of(df, learn, dataset)
    ts = samples_of(df, test, dataset, nodes=ls.nodes)
    with _progress() as p:
        task = p.add_task("sweeping", total=len(order_list))
        result = order_sweep(ls, ts, model, order_list, stop_after_rises=None, progress=lambda m: p.update(task, advance=1, description=m))
    frame = result.to_frame()
    out.print(frame.to_string(index=False))
    out.print(f"lowest test RMSE at order {result.best_order}")
    if output:
        frame.to_csv(output, index=False)
    if plot_path:
        from rplearn import plot

        plot.plot_order_sweep(result.orders, result.rmse_db, result.aic, result.ltd_s, plot_path)


@app.command()
@user_errors
def export(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    fmt: str = typer.Option("grid", "--format", help="grid (CSV), msi (one file per node) or images (3-D PNG per node)."),
    step_deg: float = typer.Option(5.0, "--step-deg", help="Grid step [deg]."),
    output: str = typer.Option(..., "-o", "--out", help="Output file (grid) or directory (msi, images)."),
    frequency_hz: Optional[float] = typer.Option(None, "--frequency", help="Frequency written into MSI files [Hz] (default: the frequency the model was learned at)."),
) -> None:
    """Export a learned model: grid CSV (node, az_deg, el_deg, gain_db), MSI Planet cuts, 3-D images.

    Example: rplearn export sh10.json --format msi -o patterns/
    """
    from rplearn import export as ex
    from rplearn.modelfile import load_model

    model = load_model(model_path)
    if getattr(model, "kind", "") != "patterns":
        raise InputError(f"{model_path}: a {model.kind} baseline has no per-node pattern to export")
    if fmt == "grid":
        frame = ex.export_grid(model, step_deg, output)
        out.print(f"wrote {len(frame):,} grid values to {output}")
    elif fmt == "msi":
        os.makedirs(output, exist_ok=True)
        for n in model.nodes:
            path = os.path.join(output, f"{n}.msi")
            ex.export_msi(model, n, path, frequency_hz=frequency_hz or model.training.get("frequency_hz"), name=f"rplearn {model.label} node {n}")
            out.print(f"wrote {path}")
    elif fmt == "images":
        paths = ex.export_pattern_images(model, output)
        for p in paths:
            out.print(f"wrote {p}")
    else:
        raise InputError(f"--format: expected grid, msi or images, got {fmt!r}")


@app.command()
@user_errors
def plot(
    model_paths: list[str] = typer.Argument(..., metavar="MODEL.json..."),
    truth: Optional[str] = typer.Option(None, "--truth", help="ground_truth.json of a simulation, drawn beside."),
    dataset: Optional[str] = typer.Option(None, "--dataset", help="Draw the sample directions of this dataset."),
    output: str = typer.Option("patterns.png", "-o", "--out", help="PNG file."),
) -> None:
    """Draw learned patterns in the azimuth-elevation domain (paper Fig. 9).

    Example: rplearn plot sh10.json --truth flight/ground_truth.json --dataset data.parquet -o patterns.png
    """
    from rplearn import plot as plt_
    from rplearn.antennas import load_ground_truth
    from rplearn.datasets import link_samples
    from rplearn.experiment import node_directions
    from rplearn.modelfile import load_model

    models = {}
    for p in model_paths:
        m = load_model(p)
        if getattr(m, "kind", "") != "patterns":
            raise InputError(f"{p}: a {m.kind} baseline has no per-node pattern to draw")
        models[m.label] = m
    gt = load_ground_truth(truth) if truth else None
    nodes = list(next(iter(models.values())).nodes)
    dirs = node_directions(link_samples(_dataset(dataset), dataset)) if dataset else None
    plt_.plot_pattern_maps(models, gt, nodes, dirs, output, center=gt is not None)
    out.print(f"wrote {output}")


@app.command()
@user_errors
def orient(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    tx: str = typer.Option(..., "--tx", help="Transmitting node."),
    rx: str = typer.Option(..., "--rx", help="Receiving node."),
    tx_pos: str = typer.Option(..., "--tx-pos", help="x,y,z ENU [m]."),
    rx_pos: str = typer.Option(..., "--rx-pos", help="x,y,z ENU [m]."),
    turn: str = typer.Option("tx", "--turn", help="tx, rx or both."),
    tx_yaw: float = typer.Option(0.0, "--tx-yaw", help="Current yaw of tx, ENU ccw from east [deg]."),
    rx_yaw: float = typer.Option(0.0, "--rx-yaw", help="Current yaw of rx [deg]."),
    tx_power_dbm: float = typer.Option(20.0, "--tx-power", help="[dBm]."),
    frequency_hz: Optional[float] = typer.Option(None, "--frequency", help="Carrier frequency [Hz] (default: the one the model was learned at)."),
) -> None:
    """Heading that maximises a link, and the received power before and after.

    Example: rplearn orient sh10.json --tx A --rx B --tx-pos 0,0,20 --rx-pos 10,5,25 --turn both
    """
    import numpy as np

    from rplearn.experiment import best_yaw
    from rplearn.geometry import distance_m
    from rplearn.link import received_power_dbm
    from rplearn.modelfile import load_model

    def xyz(text: str, name: str) -> list[float]:
        try:
            v = [float(t) for t in text.split(",")]
        except ValueError:
            v = []
        if len(v) != 3:
            raise InputError(f"{name}: expected x,y,z in metres, got {text!r}")
        return v

    model = load_model(model_path)
    if getattr(model, "kind", "") != "patterns":
        raise InputError(f"{model_path}: a {model.kind} baseline cannot tell which heading is better")
    p_tx, p_rx = xyz(tx_pos, "--tx-pos"), xyz(rx_pos, "--rx-pos")
    frequency_hz = frequency_hz or model.training.get("frequency_hz")
    if not frequency_hz:
        raise InputError(f"{model_path}: the model does not record its frequency; give --frequency")
    r = best_yaw(model, tx, rx, p_tx, p_rx, turn=turn, tx_yaw_deg=tx_yaw, rx_yaw_deg=rx_yaw)
    d = float(distance_m(np.array(p_tx), np.array(p_rx)))
    before = float(received_power_dbm(tx_power_dbm, r.baseline_gain_db, d, frequency_hz))
    after = float(received_power_dbm(tx_power_dbm, r.gain_db, d, frequency_hz))
    out.print(
        f"best yaw: tx {r.tx_yaw_deg:.0f} deg, rx {r.rx_yaw_deg:.0f} deg (ENU, ccw from east)\n"
        f"predicted received power: {before:.1f} dBm now -> {after:.1f} dBm ({after - before:+.1f} dB)",
        highlight=False,
    )


@app.command()
@user_errors
def report(
    dataset: str = typer.Argument(..., help="Matched dataset with a 'unit' column."),
    models: str = typer.Option("m,nn-400,sh-10,p-12,bg-7", "--models", help="Models to learn and compare."),
    test_units: Optional[list[str]] = typer.Option(None, "--test-units", help="Testing units (default: labels starting with 'test')."),
    out_dir: str = typer.Option("rplearn-report", "-o", "--out", help="Output directory."),
) -> None:
    """Learn models on a dataset, test them, and write Table I, pattern maps and report.html.

    Example: rplearn report data.parquet --models m,sh-10 -o report
    """
    from rplearn import plot as plt_
    from rplearn.experiment import node_directions, provenance
    from rplearn.learn import ModelSpec, evaluate_models, fit_model, samples_of, scores_markdown
    from rplearn.patterns import PatternSet
    from rplearn.report import ReportSection, write_report

    df = _dataset(dataset)
    if "unit" not in df.columns:
        raise InputError(f"{dataset}: a report needs a 'unit' column to split learning from testing samples")
    all_units = sorted(df["unit"].astype(str).unique())
    test = _split_list(test_units) or [u for u in all_units if u.startswith("test")]
    learn = [u for u in all_units if u not in test]
    if not test or not learn:
        raise InputError(f"{dataset}: cannot split units {', '.join(all_units)}; use --test-units")
    ls = samples_of(df, learn, dataset)
    ts = samples_of(df, test, dataset, nodes=ls.nodes)
    prov = provenance(dataset=dataset, models=models, test_units=test)
    os.makedirs(out_dir, exist_ok=True)
    fitted = []
    with _progress() as p:
        names = _split_list([models]) or []
        task = p.add_task("learning", total=len(names))
        for name in names:
            spec = ModelSpec.parse(name)
            p.update(task, description=f"learning {spec.label}")
            fitted.append(fit_model(ls, spec, provenance=prov))
            p.advance(task)
    rows = evaluate_models(fitted, ts)
    md = scores_markdown(rows)
    pattern_models = {f.label: f.model for f in fitted if isinstance(f.model, PatternSet)}
    images = [plt_.plot_coverage(node_directions(ls), node_directions(ts), os.path.join(out_dir, "coverage.png"))]
    if pattern_models:
        images.append(plt_.plot_pattern_maps(pattern_models, None, list(ls.nodes), node_directions(ls), os.path.join(out_dir, "patterns.png")))
    path = write_report(out_dir, f"rplearn report: {os.path.basename(dataset)}", md, [ReportSection("Patterns and coverage", "", images)], prov)
    out.print(md, highlight=False)
    out.print(f"wrote {path}")


@app.command()
@user_errors
def demo(
    out_dir: str = typer.Option("rplearn-demo", "-o", "--out", help="Output directory."),
    seed: int = typer.Option(0, "--seed", help="Seed of the simulated flight."),
    preset: str = typer.Option("paper", "--preset", help="Simulated campaign: paper, trio or smoke."),
) -> None:
    """Reproduce the paper's evaluation on a simulated replica of its campaign (Table I, Figs. 5-10, report.html).

    Example: rplearn demo -o rplearn-demo
    """
    from rplearn.experiment import run_demo

    with _progress() as p:
        task = p.add_task("starting", total=None)
        result = run_demo(out_dir, seed=seed, preset=preset, progress=_step(p, task))
    out.print(f"\nTable I on the testing unit ({result.n_test:,} samples; learned on {result.n_learn:,}); "
              f"simulated noise {result.noise_std_db:.2f} dB; 'pattern err' = RMS error of the learned pattern "
              "against the true one over the covered directions (constant removed where two drones cannot identify it):\n", highlight=False)
    out.print(result.table_markdown, highlight=False)
    sw = result.sweep
    out.print(f"\nSH order sweep: lowest test RMSE {min(sw.rmse_db):.3f} dB at SH-{sw.best_order} "
              f"(orders {sw.orders[0]}..{sw.orders[-1]})", highlight=False)
    for case, cols, rank in result.study.rank_cases:
        out.print(f"identifiability, {case}: rank {rank} of {cols} columns", highlight=False)
    out.print(f"\nwrote {result.files.get('report', out_dir)} ({result.elapsed_s:.0f} s)", highlight=False)


def main() -> None:
    """Entry point of the ``rplearn`` script."""
    app()


if __name__ == "__main__":
    main()
