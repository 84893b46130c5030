"""The ``rplearn`` command line: thin wrappers that parse, call one library function, print.

Every user error (a subclass of :class:`rplearn.errors.RplearnError`, a missing file) prints one
line ``error: ...`` on standard error and exits with code 1, without a traceback.
"""

from __future__ import annotations

import functools
import inspect as _inspect
import json
import logging
import os
import re
from typing import Any, Callable, Optional

import typer
from rich.console import Console
from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from rplearn._version import __version__
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


#: Library parameters and option fields (``RplearnError.param``) -> the flag that sets them.
_PARAM_FLAGS: dict[str, str] = {
    "nodes": "--node FILE=NODE", "receivers": "--receiver FILE=NODE", "address_map": "--address MAC=NODE",
    "pose_topics": "--pose-topic TOPIC=NODE", "rssi_topics": "--rssi-topic TOPIC=TX:RX", "rssi_field": "--rssi-field",
    "msg_definitions": "--msg-definition TYPE=FILE.msg", "tx_power_dbm": "--tx-power DBM",
    "frequency_hz": "--frequency HZ", "nan_policy": "--nan-policy", "allow_unsorted": "--allow-unsorted",
    "require_valid": "--require-valid", "link": "--link TX:RX", "max_gap_s": "--max-gap",
    "clock_offsets_s": "--offset NODE=SECONDS", "on_unknown_node": "--on-unknown-node",
    "pattern_of": "--as DRONE=NODE", "times_s": "--at", "step_s": "--step", "positions": "--pos DRONE=X,Y,Z",
    "start_yaw_deg": "--yaw DRONE=DEG", "fixed": "--fixed", "turn": "--turn",
}


def _command_flag(command: Callable | None, param: str) -> str | None:
    """The flag of the command's option named ``param`` (for parameters whose flag differs
    between commands, e.g. ``step_deg``: ``--step`` of headings, ``--step-deg`` of export)."""
    option = _inspect.signature(command).parameters.get(param) if command is not None else None
    if option is None or not isinstance(option.default, typer.models.OptionInfo):
        return None
    return next((d for d in option.default.param_decls or () if d.startswith("--")), None)


def _with_flag(message: str, param: str | None, command: Callable | None = None) -> str:
    """The message with the flag that sets ``param``.

    Library messages name the parameter at fault as ``"param: ..."``, ``"param ..."`` at the
    start, or ``"(param ...)"``; there the flag replaces the name. Otherwise the flag is
    appended, unless the message names it already.
    """
    flag = _PARAM_FLAGS.get(param or "") or (_command_flag(command, param) if param else None)
    if flag is None:
        return message
    name = flag.split()[0]
    message = re.sub(rf"(^|\()({re.escape(param)})(?=[:) ]|$)", lambda m: m.group(1) + name, message)
    if name in message:
        return message
    return f"{message} (set it with {flag})"


def user_errors(fn: Callable) -> Callable:
    """Turn user mistakes into one line on stderr and exit code 1."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except RplearnError as exc:
            _fail(_with_flag(str(exc).splitlines()[0] if str(exc) else type(exc).__name__, exc.param, fn))
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
        k, val = (part.strip() for part in v.split("=", 1))
        if k in outp and outp[k] != val:
            raise InputError(f"{what}: {k} is given twice, as {outp[k]} and as {val}")
        outp[k] = val
    return outp


def _is_test_unit(unit: str) -> bool:
    """Units labelled test... (any case) are held out for testing by default."""
    return str(unit).lower().startswith("test")


def _reader_options(
    node: Optional[list[str]], receiver: Optional[list[str]], address: Optional[list[str]], pose_topic: Optional[list[str]],
    rssi_topic: Optional[list[str]] = None, rssi_field: Optional[str] = None, msg_definition: Optional[list[str]] = None,
    **flags: Any,
) -> Any:
    """:class:`~rplearn.io.options.ReaderOptions` of :func:`rplearn.io.read_logs` from the flags.

    ``rssi_topic`` holds TOPIC=TX:RX; ``flags`` (other ReaderOptions fields: ``tx_power_dbm``,
    ``frequency_hz``, ``nan_policy``, ``allow_unsorted``, ``require_valid``) are passed on
    when not None.
    """
    from rplearn.io.options import ReaderOptions

    opts: dict[str, Any] = {}
    for flag, key, values in (
        ("--node", "nodes", node),
        ("--receiver", "receivers", receiver),
        ("--address", "address_map", address),
        ("--pose-topic", "pose_topics", pose_topic),
        ("--msg-definition", "msg_definitions", msg_definition),
    ):
        if values:
            opts[key] = _pairs(values, flag)
    if rssi_topic:
        topics: dict[str, tuple[str, str]] = {}
        for topic, ends in _pairs(rssi_topic, "--rssi-topic").items():
            parts = ends.split(":")
            if len(parts) != 2 or not all(p.strip() for p in parts):
                raise InputError(f"--rssi-topic: expected TOPIC=TX:RX (e.g. /B/rssi=A:B), got {topic}={ends}")
            topics[topic] = (parts[0].strip(), parts[1].strip())
        opts["rssi_topics"] = topics
    if rssi_field:
        opts["rssi_field"] = rssi_field
    if flags.get("nan_policy") is not None and flags["nan_policy"] not in ("drop", "error"):
        raise InputError(f"--nan-policy: expected drop or error, got {flags['nan_policy']!r}")
    opts.update({k: v for k, v in flags.items() if v is not None})
    return ReaderOptions(**opts)


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


def _print_version(value: bool) -> None:
    if value:
        out.print(f"rplearn {__version__}")
        raise typer.Exit(0)


@app.callback()
def main_callback(
    verbose: bool = typer.Option(False, "--verbose", "-v", help="Log progress details."),
    version: bool = typer.Option(
        False, "--version", help="Print the version and exit.", callback=_print_version, is_eager=True
    ),
) -> None:
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s")


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
    """Plan a calibration campaign and check it before flying.

    Plans the paper's campaign (Sec. IV-A), writes references t,x,y,z,yaw_deg per drone, and
    checks before flying whether the plan will decouple the patterns (coverage, rank,
    condition number).

    Example: rplearn trajectory --distance 10 --height 20 --loops 5 --max-flight-time 600 -o plan
    """
    from rplearn.models.spec import ModelSpec
    from rplearn.plan.campaign import paper_campaign, write_references
    from rplearn.plan.check import check_plan
    from rplearn.plan.trajectory import PlanLimits, summarize_unit

    # Library messages name the parameter at fault (exc.param) and the parameters of their
    # remedies, as "name: ..." or "(name)"; here they name the flags that set them.
    flags = {
        "distance_m": "--distance", "height_m": "--height", "n_loops": "--loops", "speed_m_s": "--speed",
        "learning_psi0_deg": "--psi0", "testing_psi0_deg": "--test-psi0", "rate_hz": "--rate",
        "max_speed_m_s": "--max-speed", "max_accel_m_s2": "--max-accel", "max_flight_time_s": "--max-flight-time",
    }

    def with_flags(exc: RplearnError) -> RplearnError:
        message = str(exc)
        if exc.param in flags and message.startswith(f"{exc.param}:"):
            message = flags[exc.param] + message[len(exc.param):]
        for name, flag in flags.items():
            message = message.replace(f"({name})", f"({flag})")
        return type(exc)(message)  # no param: the message names the flag already

    spec = None
    if check_model and check_model.lower() != "none":  # refuse a bad model before writing files
        spec = ModelSpec.parse(check_model)
        if not spec.decouples:
            raise InputError(f"--check-model: {spec.label} has no per-node pattern to check; use sh, bg or poly")
    learn = [float(v) for v in (_split_list(psi0_deg) or ["0", "24", "48"])]
    test = [float(v) for v in (_split_list(test_psi0_deg) or ["36"])]
    table = Table(title="calibration campaign")
    for col in ("unit", "duration/s", "path/m", "max speed/(m/s)", "max accel/(m/s^2)", "max yaw rate/(deg/s)"):
        table.add_column(col)
    try:
        campaign = paper_campaign(
            learning_psi0_deg=learn, testing_psi0_deg=test, distance_m=distance_m, height_m=height_m, n_loops=loops, speed_m_s=speed_m_s
        )
        limits = PlanLimits(max_speed, max_accel, max_flight_time)
        for unit in campaign.units:
            s = summarize_unit(unit, limits)
            table.add_row(s.label, f"{s.duration_s:.0f}", f"{s.path_length_m:.0f}", f"{s.max_speed_m_s:.2f}", f"{s.max_accel_m_s2:.2f}", f"{s.max_yaw_rate_deg_s:.1f}")
        paths = write_references(campaign, out_dir, rate_hz)
    except RplearnError as exc:
        raise with_flags(exc) from None
    out.print(table)
    out.print(f"wrote {len(paths)} reference files to {out_dir}")
    if spec is not None:
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
    from rplearn.sim.simulate import simulate as run

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
    rssi_topic: Optional[list[str]] = typer.Option(None, "--rssi-topic", help="TOPIC=TX:RX: RSSI topic of ROS bags, packets from TX received by RX."),
    rssi_field: Optional[str] = typer.Option(None, "--rssi-field", help="Field of the RSSI [dBm] in --rssi-topic messages, dots for nested fields (default rssi)."),
    msg_definition: Optional[list[str]] = typer.Option(None, "--msg-definition", help="TYPE=FILE.msg: custom message type a bag does not describe (e.g. pkg/msg/LinkQuality=LinkQuality.msg)."),
    require_valid: bool = typer.Option(False, "--require-valid/--accept-invalid", help="Drop ULog positions the autopilot flags invalid (xy_valid or z_valid = 0), or keep them (default)."),
    markdown: bool = typer.Option(False, "--markdown", help="Print Markdown instead of text."),
) -> None:
    """Summarise logs: nodes, time spans, rates, RSSI range, gaps, and anything suspicious.

    Example: rplearn inspect flight/pose_log.parquet flight/signal_log.parquet
    """
    from rplearn.io.inspect import inspect_logs

    report = inspect_logs(logs, _reader_options(
        node, receiver, address, pose_topic, rssi_topic, rssi_field, msg_definition, require_valid=require_valid))
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
    rssi_topic: Optional[list[str]] = typer.Option(None, "--rssi-topic", help="TOPIC=TX:RX: RSSI topic of ROS bags, packets from TX received by RX."),
    rssi_field: Optional[str] = typer.Option(None, "--rssi-field", help="Field of the RSSI [dBm] in --rssi-topic messages, dots for nested fields (default rssi)."),
    msg_definition: Optional[list[str]] = typer.Option(None, "--msg-definition", help="TYPE=FILE.msg: custom message type a bag does not describe (e.g. pkg/msg/LinkQuality=LinkQuality.msg)."),
    tx_power_dbm: Optional[float] = typer.Option(None, "--tx-power", help="Transmit power for logs without it [dBm]."),
    frequency_hz: Optional[float] = typer.Option(None, "--frequency", help="Carrier frequency for logs without it [Hz]."),
    nan_policy: str = typer.Option("error", "--nan-policy", help="Pose-table rows with NaN or non-numeric values: error (default) or drop (counted)."),
    allow_unsorted: bool = typer.Option(False, "--allow-unsorted", help="Accept pose tables whose times go backwards within a node (the rows are sorted)."),
    require_valid: bool = typer.Option(False, "--require-valid/--accept-invalid", help="Drop ULog positions the autopilot flags invalid (xy_valid or z_valid = 0), or keep them (default)."),
    on_unknown_node: str = typer.Option("drop", "--on-unknown-node", help="Signals naming a node without a pose log: drop (counted, default) or error."),
) -> None:
    """Match every signal sample with the interpolated poses of both ends (paper Sec. V-B4).

    Example: rplearn sync --poses flight/pose_log.parquet --signals flight/signal_log.parquet --link A:B -o data.parquet
    """
    from rplearn.io.files import check_table_path, write_table
    from rplearn.io import read_logs
    from rplearn.data.sync import SyncOptions, synchronise

    check_table_path(output)

    opts = _reader_options(
        node, receiver, address, pose_topic, rssi_topic, rssi_field, msg_definition, tx_power_dbm=tx_power_dbm,
        frequency_hz=frequency_hz, nan_policy=nan_policy, allow_unsorted=allow_unsorted, require_valid=require_valid)
    pose_logs, pose_meta = read_logs(poses, opts)
    _print_reader_drops(pose_meta)
    signal_logs, _ = read_logs(signals, opts)
    if pose_logs.pose is None:
        raise InputError(f"{', '.join(poses)}: no pose log found")
    if signal_logs.signal is None:
        raise InputError(f"{', '.join(signals)}: no signal log found")
    try:
        offsets = {k: float(v) for k, v in _pairs(offset, "--offset").items()}
    except ValueError:
        raise InputError(f"--offset: expected NODE=SECONDS with a number, got {', '.join(offset or [])}") from None
    sync_options = SyncOptions(link=_link(link), max_gap_s=max_gap_s, clock_offsets_s=offsets or None,
                               on_unknown_node=on_unknown_node)
    result = synchronise(pose_logs.pose, signal_logs.signal, sync_options, source=", ".join(signals))
    write_table(result.dataset, output)
    out.print(result.summary.to_text(), highlight=False)
    out.print(f"wrote {len(result.dataset):,} matched samples to {output}")


def _print_reader_drops(meta: dict[str, Any]) -> None:
    """Say what the readers dropped or assumed, file by file."""
    for f in meta.get("files", []):
        for reason, count in (f.get("dropped") or {}).items():
            if count:
                out.print(f"{f.get('source', 'log')}: dropped {count:,} pose row(s) ({reason})", highlight=False, markup=False)
        if f.get("level_assumed"):
            out.print(f"{f.get('source', 'log')}: yaw only, so level flight (roll = pitch = 0) is assumed", highlight=False, markup=False)


def _dataset(path: str, require_rssi: bool = True):
    from rplearn.data.tables import validate_matched
    from rplearn.io.files import read_table

    return validate_matched(read_table(path), path, require_rssi=require_rssi)


def _dataset_units(df: Any) -> list[str]:
    return sorted(df["unit"].astype(str).unique()) if "unit" in df.columns else []


def _default_learning_units(df: Any, dataset: str) -> list[str] | None:
    """All units but those labelled ``test...`` (None: every row), and say which were used."""
    units = _dataset_units(df)
    learn = [u for u in units if not _is_test_unit(u)]
    if not units:
        return None
    if not learn:
        console.print(f"note: {dataset}: every unit is labelled test...; learning from all of them", highlight=False)
        return None
    left_out = [u for u in units if u not in learn]
    if left_out:
        console.print(f"note: learning from units {', '.join(learn)}; left out {', '.join(left_out)} (pass --units to choose)", highlight=False)
    return learn


@app.command()
@user_errors
def fit(
    dataset: str = typer.Argument(..., help="Matched dataset (.parquet or .csv)."),
    model: str = typer.Option("sh", "--model", help="sh, bg, poly, mean or knn (also sh-10, nn-400...)."),
    degree: Optional[int] = typer.Option(None, "--degree", help="SH-L / BG-k / P-k order, or k of knn (defaults 10, 7, 12, 400)."),
    ridge: Optional[float] = typer.Option(None, "--ridge", help="Pattern models: ridge weight on the diagonal of X^T X (default 1; the paper used 50)."),
    sigma: Optional[float] = typer.Option(None, "--sigma", help="BG only: kernel variance sigma [rad^2] (default 0.5, about the paper's)."),
    grid: Optional[str] = typer.Option(None, "--grid", help="BG only: nodes on the paper grid (default) or fibonacci."),
    units: Optional[list[str]] = typer.Option(None, "--units", help="Learning units (repeat or comma-separate; default: all but units labelled test...)."),
    gauge_node: Optional[str] = typer.Option(None, "--gauge-node", help="Pattern models: fix this node's mean gain instead of splitting equally."),
    gauge_dbi: Optional[float] = typer.Option(None, "--gauge-dbi", help="Sphere-mean gain of --gauge-node [dBi] (default 0)."),
    output: str = typer.Option(..., "-o", "--out", help="Model file (.json)."),
) -> None:
    """Learn one radiation pattern per node (or a baseline) from a matched dataset.

    Example: rplearn fit data.parquet --model sh --degree 10 --units learn_0,learn_24,learn_48 -o sh10.json
    """
    from rplearn.io.files import provenance
    from rplearn.models.fit import fit_model
    from rplearn.data.units import samples_of
    from rplearn.models.spec import ModelSpec

    spec = ModelSpec.parse(model, order=degree, ridge=ridge, sigma_rad2=sigma, grid=grid)
    _check_fit_options(model, spec, degree, ridge, sigma, grid, gauge_node, gauge_dbi)
    df = _dataset(dataset)
    chosen = _split_list(units) or _default_learning_units(df, dataset)
    samples = samples_of(df, chosen, dataset)
    gauge: Any = {"node": gauge_node, "mean_gain_dbi": gauge_dbi or 0.0} if gauge_node else "equal-mean"
    fitted = fit_model(samples, spec, gauge=gauge, provenance=provenance(dataset=dataset, model=spec.label, ridge=spec.ridge, units=chosen))
    fitted.model.save(output)
    msg = f"{spec.label} learned from {len(samples):,} samples in {fitted.ltd_s:.3f} s -> {output}"
    training = fitted.model.training
    if "rank" in training:
        msg += f"\n  rank {training['rank']} of {training['n_columns']}, condition number {training['condition_number']:.2f}, training RMSE {training['rmse_db']:.2f} dB"
        for g in training.get("gauges", []):
            msg += f"\n  gauge: {g['text']}"
    out.print(msg, highlight=False)
    for w in training.get("warnings", []):
        console.print(f"warning: {w}", highlight=False, soft_wrap=True)


def _check_fit_options(
    model: str,
    spec: Any,
    degree: Optional[int],
    ridge: Optional[float],
    sigma: Optional[float],
    grid: Optional[str],
    gauge_node: Optional[str],
    gauge_dbi: Optional[float],
) -> None:
    """Refuse options that the chosen model would silently ignore or that contradict it."""
    given = {"--ridge": ridge, "--sigma": sigma, "--grid": grid, "--gauge-node": gauge_node, "--degree": degree}
    if spec.kind in ("mean", "knn"):
        unused = [k for k in ("--ridge", "--sigma", "--grid", "--gauge-node") if given[k] is not None]
        if spec.kind == "mean" and degree is not None:
            unused.append("--degree")
        if unused:
            raise InputError(f"{', '.join(unused)}: not used by {spec.label}, a baseline without patterns")
    elif spec.kind != "bg":
        unused = [k for k in ("--sigma", "--grid") if given[k] is not None]
        if unused:
            raise InputError(f"{', '.join(unused)}: used by BG models only, not by {spec.label}")
    if gauge_dbi is not None and gauge_node is None:
        raise InputError("--gauge-dbi needs --gauge-node (which node's mean gain it fixes)")
    if degree is not None and spec.order is not None and int(degree) != spec.order:
        raise InputError(f"--model {model} already sets the order {spec.order}; --degree {degree} contradicts it")


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
    from rplearn.io.files import provenance
    from rplearn.models.fit import FittedModel, evaluate_models, scores_markdown
    from rplearn.data.units import samples_of
    from rplearn.models.load import load_model

    if len(paths) < 2:
        raise InputError("evaluate: give at least one MODEL.json and a DATASET")
    *model_paths, dataset = paths
    models = [load_model(p) for p in model_paths]
    df = _dataset(dataset)
    samples = samples_of(df, _evaluation_units(df, _split_list(units), models, dataset), dataset)
    fitted = [FittedModel.from_model(m) for m in models]
    rows = _distinct_labels(evaluate_models(fitted, samples), model_paths)
    md = scores_markdown(rows)
    out.print(md, highlight=False)
    if markdown_out:
        with open(markdown_out, "w") as fh:
            fh.write(md + "\n")
    if json_out:
        _write_json(json_out, {"provenance": provenance(dataset=dataset, models=model_paths), "rows": [r.to_dict() for r in rows]})


def _distinct_labels(rows: list[Any], model_paths: list[str]) -> list[Any]:
    """Table I rows, with the file name added where two models share a label (e.g. two SH-10)."""
    import dataclasses
    from collections import Counter

    counts = Counter(r.model for r in rows)
    return [
        dataclasses.replace(r, model=f"{r.model} ({os.path.basename(p)})") if counts[r.model] > 1 else r
        for r, p in zip(rows, model_paths)
    ]


def _evaluation_units(df: Any, units: list[str] | None, models: list[Any], dataset: str) -> list[str] | None:
    """The units to score on: as given, else those no model learned from; say which, and warn
    when a score would be a training score."""
    trained = sorted({str(u) for m in models for u in (m.provenance.get("parameters", {}).get("units") or [])})
    available = _dataset_units(df)
    if not available:
        sources = {str(m.provenance.get("parameters", {}).get("dataset")) for m in models}
        if os.path.basename(dataset) in {os.path.basename(p) for p in sources}:
            console.print(
                f"warning: {dataset} has no unit column and a model learned from a file of this name: "
                "these are probably training scores", highlight=False,
            )
    if units is None and trained and available:
        unseen = [u for u in available if u not in trained]
        if unseen:
            console.print(f"note: scoring on units {', '.join(unseen)}, which no model learned from (pass --units to choose)", highlight=False)
            return unseen
    chosen = units if units is not None else (available or None)
    overlap = sorted(set(chosen or available) & set(trained))
    if overlap:
        console.print(f"warning: scoring on unit(s) {', '.join(overlap)} that a model learned from: these are training scores", highlight=False)
    elif units is None and available:
        console.print(f"note: scoring on all units ({', '.join(available)}); pass --units to choose", highlight=False)
    return chosen


@app.command()
@user_errors
def predict(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    dataset: str = typer.Argument(..., metavar="DATASET"),
    output: str = typer.Option(..., "-o", "--out", help="Where to write the dataset with the predictions added (.csv or .parquet)."),
) -> None:
    """Predict the joint gain and received power for every row of a dataset of poses.

    DATASET has the columns of a matched dataset (see rplearn sync) except rssi_dbm, which
    may be absent: links that were never flown can be predicted. Added columns:
    gain_pred_db, the joint gain G_tx + G_rx [dB]; rssi_pred_dbm, the received power
    [dBm]; and for pattern models gain_pred_std_db, the standard error of gain_pred_db from
    the learned coefficients alone [dB], and rssi_pred_std_db, the spread of one new packet's
    RSSI around rssi_pred_dbm, adding the training residual (fading, noise, misfit) [dB].

    Example: rplearn predict sh10.json data.parquet -o pred.csv
    """
    import numpy as np

    from rplearn.data.tables import link_samples
    from rplearn.io.files import check_table_path, write_table
    from rplearn.core.link import received_power_dbm
    from rplearn.models.load import load_model

    check_table_path(output)
    model = load_model(model_path)
    df = _dataset(dataset, require_rssi=False)
    samples = link_samples(df, dataset, require_rssi=False)
    _warn_frequency_mismatch(model, df["frequency_hz"].to_numpy(np.float64), model_path, dataset)
    gain = model.predict_gain(samples)
    df = df.copy()
    df["gain_pred_db"] = gain
    df["rssi_pred_dbm"] = received_power_dbm(df["tx_power_dbm"].to_numpy(), gain, samples.distance_m, df["frequency_hz"].to_numpy())
    std = model.predict_gain_std(samples)
    if std is not None:
        df["gain_pred_std_db"] = std
        residual_db = float(model.training.get("rmse_db", np.nan))
        df["rssi_pred_std_db"] = np.sqrt(std**2 + residual_db**2)
    write_table(df, output)
    measured = np.isfinite(samples.joint_gain_db)
    line = f"wrote {len(df):,} predictions to {output}"
    if measured.any():
        err = gain[measured] - samples.joint_gain_db[measured]
        line += f" (RMSE against the {int(measured.sum()):,} measured RSSI values: {float(np.sqrt(np.mean(err**2))):.2f} dB)"
    out.print(line, highlight=False)


def _warn_frequency_mismatch(model: Any, frequency_hz: Any, model_path: str, dataset: str) -> None:
    """Warn when rows are at a carrier frequency other than the one the model learned at."""
    import numpy as np

    learned = model.frequency_hz
    if learned is None or len(frequency_hz) == 0:
        return
    off = np.abs(np.asarray(frequency_hz) / float(learned) - 1.0) > 0.05
    if np.any(off):
        console.print(
            f"warning: {dataset}: {int(off.sum()):,} row(s) at {float(np.median(np.asarray(frequency_hz)[off])) / 1e9:.3f} GHz, "
            f"but {model_path} learned at {float(learned) / 1e9:.3f} GHz; antenna patterns change with frequency",
            highlight=False, soft_wrap=True,
        )


@app.command()
@user_errors
def links(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    poses: list[str] = typer.Argument(..., metavar="POSE_LOG...", help="Pose log(s) of the drones: a plan or a flight (CSV/Parquet, bag, ULog)."),
    output: str = typer.Option(..., "-o", "--out", help="Predicted links, one row per time and ordered pair (.csv or .parquet)."),
    tx_power_dbm: float = typer.Option(..., "--tx-power", help="Transmit power of every drone [dBm]."),
    frequency_hz: Optional[float] = typer.Option(None, "--frequency", help="Carrier frequency [Hz] (default: the one the model was learned at)."),
    pattern: Optional[list[str]] = typer.Option(None, "--as", help="DRONE=NODE: the drone carries the antenna learned as NODE (repeat)."),
    step_s: float = typer.Option(1.0, "--step", help="Spacing of the prediction times over the span all logs cover [s]."),
    at: Optional[list[str]] = typer.Option(None, "--at", help="Predict at these times instead [s] (repeat or comma-separate)."),
    min_rssi_dbm: float = typer.Option(-85.0, "--min-rssi", help="RSSI a link needs in each direction to be up [dBm]."),
    max_gap_s: float = typer.Option(2.0, "--max-gap", help="A drone is absent inside pose-log gaps longer than this [s]."),
    connectivity_out: Optional[str] = typer.Option(None, "--connectivity", help="Also write the per-time connectivity table here (.csv or .parquet)."),
    plot_out: Optional[str] = typer.Option(None, "--plot", help="Also plot RSSI, threshold and bottleneck over time here (.png)."),
    node: Optional[list[str]] = typer.Option(None, "--node", help="FILE=NODE for ULogs and one-node tables."),
    pose_topic: Optional[list[str]] = typer.Option(None, "--pose-topic", help="TOPIC=NODE: pose topics of ROS bags."),
    nan_policy: str = typer.Option("error", "--nan-policy", help="Pose rows with NaN or non-numeric values: error (default) or drop (counted)."),
    allow_unsorted: bool = typer.Option(False, "--allow-unsorted", help="Accept pose tables whose times go backwards within a node (the rows are sorted)."),
) -> None:
    """Predict every link of a swarm over time and whether it stays connected.

    For each time and ordered pair of drones: distance, predicted joint gain and RSSI with
    its spread, and whether the link is up. Per time: the pairs up both ways, the number of
    connected groups, and the bottleneck RSSI (the swarm is connected for any threshold
    below it). Drones that were not in the calibration flight use the pattern of the
    antenna they carry (--as).

    Example: rplearn links sh10.json plan_poses.csv --tx-power 20 --as C=A --as D=B --plot links.png -o links.csv
    """
    from rplearn.io.files import check_table_path, write_table
    from rplearn.io import read_logs
    from rplearn.models.load import load_model
    from rplearn.analysis.swarm import predict_swarm

    for path in (output, connectivity_out):
        if path:
            check_table_path(path)

    model = load_model(model_path)
    logs, meta = read_logs(poses, _reader_options(node, None, None, pose_topic, nan_policy=nan_policy, allow_unsorted=allow_unsorted))
    if logs.pose is None:
        raise InputError(f"{', '.join(poses)}: no pose log found")
    _print_reader_drops(meta)
    if frequency_hz is not None:
        _warn_frequency_mismatch(model, [frequency_hz], model_path, "--frequency")
    times = None
    if at:
        try:
            times = [float(v) for v in _split_list(at) or []]
        except ValueError:
            raise InputError(f"--at: expected times in seconds, got {', '.join(at)}") from None
    result = predict_swarm(
        model, logs.pose, tx_power_dbm, frequency_hz, pattern_of=_pairs(pattern, "--as"), step_s=step_s,
        times_s=times, min_rssi_dbm=min_rssi_dbm, max_gap_s=max_gap_s, source=", ".join(poses),
    )
    write_table(result.links, output)
    if connectivity_out:
        write_table(result.connectivity, connectivity_out)
    if plot_out:
        from rplearn.viz.charts import plot_swarm

        plot_swarm(result, plot_out)
    out.print(result.summary(), highlight=False, markup=False)
    out.print(f"wrote {len(result.links):,} predicted links to {output}")


@app.command()
@user_errors
def headings(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    pos: list[str] = typer.Option(..., "--pos", help="DRONE=x,y,z: hover position, ENU [m] (repeat for every drone)."),
    tx_power_dbm: float = typer.Option(..., "--tx-power", help="Transmit power of every drone [dBm]."),
    yaw: Optional[list[str]] = typer.Option(None, "--yaw", help="DRONE=DEG: current yaw, ENU ccw from east [deg] (default 0)."),
    fixed: Optional[list[str]] = typer.Option(None, "--fixed", help="Drones that must keep their yaw (repeat or comma-separate)."),
    pattern: Optional[list[str]] = typer.Option(None, "--as", help="DRONE=NODE: the drone carries the antenna learned as NODE."),
    frequency_hz: Optional[float] = typer.Option(None, "--frequency", help="Carrier frequency [Hz] (default: the one the model was learned at)."),
    step_deg: float = typer.Option(5.0, "--step", help="Yaw grid [deg]."),
    output: Optional[str] = typer.Option(None, "-o", "--out", help="Also write the chosen yaws here (.csv or .json)."),
) -> None:
    """Yaws for a hovering swarm that keep it best connected (maximise the bottleneck RSSI).

    Every drone in turn takes the yaw that maximises the weakest link the swarm needs to stay
    connected, until nothing improves: a local optimum, never worse than the current yaws.

    Example: rplearn headings sh10.json --pos A=0,0,20 --pos B=40,0,20 --pos C=20,30,25 --as C=A --tx-power 20
    """
    from rplearn.models.load import load_model
    from rplearn.analysis.headings import best_swarm_headings

    positions = {}
    for drone, text in _pairs(pos, "--pos").items():
        try:
            xyz = [float(v) for v in text.split(",")]
        except ValueError:
            xyz = []
        if len(xyz) != 3:
            raise InputError(f"--pos {drone}: expected x,y,z in metres, got {text!r}")
        positions[drone] = xyz
    try:
        start = {d: float(v) for d, v in _pairs(yaw, "--yaw").items()}
    except ValueError:
        raise InputError(f"--yaw: expected DRONE=DEG with a number, got {', '.join(yaw or [])}") from None
    unknown = sorted(set(start) - set(positions))
    if unknown:
        raise InputError(f"--yaw names drone(s) {', '.join(unknown)} without a --pos")
    result = best_swarm_headings(
        load_model(model_path), positions, tx_power_dbm, frequency_hz, pattern_of=_pairs(pattern, "--as"),
        start_yaw_deg=start, fixed=_split_list(fixed) or (), step_deg=step_deg,
    )
    out.print(result.summary(), highlight=False, markup=False)
    if output:
        table = {"yaw_deg": result.yaw_deg, "bottleneck_dbm": result.bottleneck_dbm, "start_bottleneck_dbm": result.start_bottleneck_dbm}
        if output.endswith(".json"):
            _write_json(output, table)
        else:
            import pandas as pd

            pd.DataFrame({"drone": list(result.yaw_deg), "yaw_deg": list(result.yaw_deg.values())}).to_csv(output, index=False)
        out.print(f"wrote {output}")


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
    from rplearn.analysis.sweep import order_sweep
    from rplearn.data.units import samples_of

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
    test = _split_list(test_units) or [u for u in all_units if _is_test_unit(u)]
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
        from rplearn.viz import charts

        charts.plot_order_sweep(result.orders, result.rmse_db, result.aic, result.ltd_s, plot_path)


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
    from rplearn.io import export as ex
    from rplearn.models.base import model_frequency_hz
    from rplearn.models.load import load_model

    model = load_model(model_path)
    if model.kind != "patterns":
        raise InputError(f"{model_path}: a {model.kind} baseline has no per-node pattern to export")
    if fmt == "grid":
        frame = ex.export_grid(model, step_deg, output)
        out.print(f"wrote {len(frame):,} grid values to {output}")
    elif fmt == "msi":
        frequency_hz = model_frequency_hz(model, frequency_hz)
        os.makedirs(output, exist_ok=True)
        for n in model.nodes:
            path = os.path.join(output, f"{n}.msi")
            ex.export_msi(model, n, path, frequency_hz=frequency_hz, name=f"rplearn {model.label} node {n}")
            out.print(f"wrote {path}")
    elif fmt == "images":
        from rplearn.viz.images import export_pattern_images

        paths = export_pattern_images(model, output)
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
    from rplearn.viz import plot as plt_
    from rplearn.sim.antennas import load_ground_truth
    from rplearn.data.tables import link_samples
    from rplearn.analysis.pattern_error import node_directions
    from rplearn.models.load import load_model

    models = {}
    for p in model_paths:
        m = load_model(p)
        if m.kind != "patterns":
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
    from rplearn.analysis.headings import best_yaw
    from rplearn.models.load import load_model

    def xyz(text: str, name: str) -> list[float]:
        try:
            v = [float(t) for t in text.split(",")]
        except ValueError:
            v = []
        if len(v) != 3:
            raise InputError(f"{name}: expected x,y,z in metres, got {text!r}")
        return v

    model = load_model(model_path)
    if model.kind != "patterns":
        raise InputError(f"{model_path}: a {model.kind} baseline cannot tell which heading is better")
    p_tx, p_rx = xyz(tx_pos, "--tx-pos"), xyz(rx_pos, "--rx-pos")
    r = best_yaw(model, tx, rx, p_tx, p_rx, turn=turn, tx_yaw_deg=tx_yaw, rx_yaw_deg=rx_yaw,
                 tx_power_dbm=tx_power_dbm, frequency_hz=frequency_hz)
    out.print(r.summary(), highlight=False)


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
    from rplearn.viz import plot as plt_
    from rplearn.io.files import provenance
    from rplearn.analysis.pattern_error import node_directions
    from rplearn.models.fit import evaluate_models, fit_model, scores_markdown
    from rplearn.data.units import samples_of
    from rplearn.models.spec import ModelSpec
    from rplearn.viz.report import ReportSection, write_report

    names = _split_list([models]) or []
    if not names:
        raise InputError("--models: give at least one model, e.g. m,sh-10")
    specs = [ModelSpec.parse(name) for name in names]  # refuse a bad name before writing anything
    df = _dataset(dataset)
    if "unit" not in df.columns:
        raise InputError(f"{dataset}: a report needs a 'unit' column to split learning from testing samples")
    all_units = sorted(df["unit"].astype(str).unique())
    test = _split_list(test_units) or [u for u in all_units if _is_test_unit(u)]
    learn = [u for u in all_units if u not in test]
    if not test or not learn:
        raise InputError(f"{dataset}: cannot split units {', '.join(all_units)}; use --test-units")
    ls = samples_of(df, learn, dataset)
    ts = samples_of(df, test, dataset, nodes=ls.nodes)
    prov = provenance(dataset=dataset, models=models, test_units=test)
    os.makedirs(out_dir, exist_ok=True)
    fitted = []
    with _progress() as p:
        task = p.add_task("learning", total=len(specs))
        for spec in specs:
            p.update(task, description=f"learning {spec.label}")
            fitted.append(fit_model(ls, spec, provenance=prov))
            p.advance(task)
    rows = evaluate_models(fitted, ts)
    md = scores_markdown(rows)
    pattern_models = {f.label: f.model for f in fitted if f.model.kind == "patterns"}
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
    from rplearn.workflows import run_demo

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
