"""Commands that learn and test: ``fit``, ``evaluate``, ``predict``, ``sweep`` and ``report``."""

from __future__ import annotations

import typer

from rplearn.cli._app import app, flag_values, note, pairs, parts_step, progress_bar, say, split_list, step, user_errors
from rplearn.cli._app import orders as parse_orders
from rplearn.errors import BadValueError, InputError

#: Help of ``--dask`` (fit, evaluate).
DASK_HELP = ("Run on Dask, part by part (pattern models): local (2 worker processes), local:N, or a scheduler address "
             "tcp://host:8786; needs pip install 'rplearn[dask]'. The dataset may be a directory, a glob, a "
             "comma-separated list or a URL (s3://..., with its fsspec plugin) of Parquet/CSV files.")


@app.command()
@user_errors(flags={"priors": "--prior", "prior_std_db": "--prior-std"})
def fit(
    dataset: str = typer.Argument(..., help="Matched dataset (.parquet or .csv), or many: a directory, a glob, a comma-separated list or a URL."),
    model: str = typer.Option("sh", "--model", help="sh, bg, poly, mean or knn (also sh-10, nn-400...)."),
    degree: str | None = typer.Option(None, "--order", "--degree", help="SH-L / BG-k / P-k order, k of knn, or 'auto': order (SH) and smoothing "
                                      "chosen by cross-validation over flight units (default for sh; bg, poly, knn default to 7, 12, 400). "
                                      "--degree is the same option under its older name."),
    ridge: float | None = typer.Option(None, "--ridge", help="Pattern models: ridge weight on the diagonal of X^T X (default 1; the paper used 50)."),
    sigma: float | None = typer.Option(None, "--sigma", help="BG only: kernel variance sigma [rad^2] (default 0.5, about the paper's)."),
    grid: str | None = typer.Option(None, "--grid", help="BG only: nodes on the paper grid (default) or fibonacci."),
    units: list[str] | None = typer.Option(None, "--units", help="Learning units (repeat or comma-separate; default: all but units labelled test...). A "
                                                                 "dataset without units (a .tlog) names its 5 stretches of time flight[1/5]..flight[4/5], "
                                                                 "test[5/5]."),
    gauge_node: str | None = typer.Option(None, "--gauge-node", help="Pattern models: fix this node's mean gain instead of splitting equally."),
    gauge_dbi: float | None = typer.Option(None, "--gauge-dbi", help="Sphere-mean gain of --gauge-node [dBi] (default 0)."),
    prior: list[str] | None = typer.Option(None, "--prior", help="NODE=MODEL.json: shrink NODE's pattern toward the shape of this (reference) model instead of "
                                                                 "toward zero (its level comes from the data, see --prior-level); with --order auto. "
                                                                 "Above the chosen order the model keeps the prior's own degrees (to the largest "
                                                                 "candidate order) unless the held-out flights find them worse than the prior cut."),
    prior_level: str = typer.Option("data", "--prior-level", help="Where the level of the --prior patterns comes from: data (default: the prior gives only its "
                                                                  "shape, so a constant added to every RSSI value only shifts the predictions) or prior (its "
                                                                  "absolute dBi: calibrated power and a trusted reference)."),
    prior_std: float | None = typer.Option(None, "--prior-std", help="How far [dB RMS] the --prior patterns may be from the truth (a vendor's tolerance): the "
                                                                     "spread of predictions where the flight never looked (default: learned from their misfit "
                                                                     "where it looked)."),
    loss: str = typer.Option("ls", "--loss", help="ls (least squares) or huber: for logs with plateaus and dropouts, samples far from the pattern pull only as "
                                                  "hard as 1.345 robust standard deviations (a pattern model of fixed order)."),
    path_loss_kind: str = typer.Option("free", "--path-loss", help="Environment term of pattern models: free (free space, eq. 1), log-distance (learn the "
                                                                   "path-loss exponent; refused when the distance does not vary independently of the "
                                                                   "directions) or two-ray (a ground reflection from the antenna heights)."),
    ground_level: float = typer.Option(0.0, "--ground-level", help="two-ray: ENU height of the ground plane [m]."),
    permittivity: float = typer.Option(15.0, "--permittivity", help="two-ray: relative permittivity of the ground (15 medium dry ground, ITU-R P.527; ~30 wet, "
                                                                    "3-7 very dry)."),
    polarization: str = typer.Option("vertical", "--polarization", help="two-ray: vertical (upright whips) or horizontal."),
    learn_offsets: bool = typer.Option(True, "--link-offsets/--no-link-offsets", help="Pattern models: learn one electronics offset per link logged in both "
                                                                                      "directions (non-reciprocal radios; the two directions' offsets sum to "
                                                                                      "0)."),
    dask: str | None = typer.Option(None, "--dask", help=DASK_HELP),
    output: str = typer.Option(..., "-o", "--out", help="Model file (.json)."),
) -> None:
    """Learn one radiation pattern per node (or a baseline) from a matched dataset.

    Example: rplearn fit data.parquet --model sh --order 10 --units learn_0,learn_24,learn_48 -o sh10.json
    """
    from rplearn.core.environment import PathLoss
    from rplearn.core.gauge import Gauge
    from rplearn.models.options import FitOptions
    from rplearn.models.spec import ModelSpec, check_fit_options
    from rplearn.workflows.learning import fit_dataset

    with flag_values():  # the flags' values, before the dataset is read: a bad one is a usage error
        two_ray_flags_note(path_loss_kind, ground_level, permittivity, polarization)
        auto, order = degree_option(degree, model)
        spec = ModelSpec.parse(model, order=order, ridge=ridge, sigma_rad2=sigma, grid=grid)
        check_fit_options(spec, order=order, ridge=ridge, sigma_rad2=sigma, grid=grid, model=model)
        options = FitOptions(
            gauge=Gauge(gauge_node, gauge_dbi), path_loss=PathLoss(path_loss_kind, ground_level, permittivity, polarization),
            link_offsets=learn_offsets, loss=loss, auto=auto, priors=pairs(prior, "--prior"), prior_std_db=prior_std,
            prior_level=prior_level,
        )
        options.check(spec)
        if dask is not None:
            from rplearn.workflows.fleet import parse_dask

            parse_dask(dask)  # its form; its budget (local:N) an error of the run
    with progress_bar() as p:
        task = p.add_task("learning", total=None)
        outcome = fit_dataset(dataset, spec, split_list(units), options=options, output=output, dask=dask,
                              progress=parts_step(p, task, "statistics"))
    for line in outcome.units.notes:
        note(f"{line} (pass --units to choose)" if outcome.units.defaulted else line)
    say(outcome.summary())
    for line in outcome.warnings:
        note(line, "warning")
    if output and outcome.fitted.model.training.drift_std_db is not None:
        import shlex

        say(f"plan the next flight: rplearn trajectory --optimize --from-model {shlex.quote(output)} -o next_plan")


@app.command()
@user_errors(flags={"mounts": "--mount"})
def reference(
    patterns: list[str] = typer.Argument(..., help="NODE=FILE: a reference pattern (CSV az_deg/el_deg or phi/theta + gain_dbi, or MSI Planet) per node."),
    mount: list[str] | None = typer.Option(None, "--mount", help="NODE=ROLL,PITCH,YAW: the antenna frame in the body frame [deg] (e.g. 180,0,0 hanging upside "
                                                                 "down)."),
    output: str = typer.Option(..., "-o", "--out", help="Model file (.json)."),
) -> None:
    """Turn measured or vendor antenna patterns into a model (usable by predict, links, orient, plot, report).

    Example: rplearn reference A=dipole.csv B=patch.msi --mount A=180,0,0 -o reference.json
    """
    from rplearn.workflows.planning import reference_model_file

    with flag_values():
        files = pairs(patterns, "PATTERN")
        mounts = {node: _mount(node, text) for node, text in pairs(mount, "--mount").items()}
    model = reference_model_file(files, output, mounts)
    say(f"reference model of {', '.join(model.nodes)} ({model.label}) -> {output}")
    for node, info in (model.training.reference or {}).items():
        say(f"  {node}: {info['source']}, mount (roll, pitch, yaw) {tuple(info['mount_rpy_deg'])} deg, "
            f"expansion residual {info['expansion_rmse_db']:.3f} dB RMS")


def _mount(node: str, text: str) -> tuple[float, ...]:
    """``--mount NODE=ROLL,PITCH,YAW`` [deg] as three numbers."""
    parts = text.split(",")
    try:
        angles = tuple(float(x) for x in parts)
    except ValueError:
        raise BadValueError(f"--mount: expected NODE=ROLL,PITCH,YAW in degrees, got {node}={text}") from None
    if len(parts) != 3:
        raise BadValueError(f"--mount: expected NODE=ROLL,PITCH,YAW in degrees, got {node}={text}")
    return angles


def two_ray_flags_note(kind: str, ground_level: float, permittivity: float, polarization: str) -> None:
    """Say when two-ray flags were given without ``--path-loss two-ray`` (``kind``: they change
    nothing then)."""
    given = [flag for flag, value, default in (("--ground-level", ground_level, 0.0), ("--permittivity", permittivity, 15.0),
                                                ("--polarization", polarization, "vertical")) if value != default]
    if given and kind != "two-ray":
        note(f"{', '.join(given)} set the two-ray ground reflection; with --path-loss {kind} they are ignored")


def degree_option(degree: str | None, model: str) -> tuple[bool, int | None]:
    """``(auto, order)`` from ``--order`` and ``--model``: 'auto' (the default for a bare ``sh``)
    or a whole number."""
    text = (degree or "").strip().lower()
    bare_sh = model.strip().lower() in ("sh", "spherical", "spherical-harmonics")
    if text == "auto" or (not text and bare_sh):
        return True, None
    if not text:
        return False, None
    try:
        value = float(text)
    except ValueError:
        raise BadValueError(f"--order: expected a whole number or 'auto', got {degree!r}") from None
    if not value.is_integer():
        raise BadValueError(f"--order: expected a whole number or 'auto', got {degree!r}")
    return False, int(value)


@app.command()
@user_errors
def evaluate(
    paths: list[str] = typer.Argument(..., help="MODEL.json... DATASET (the last argument is the dataset)."),
    units: list[str] | None = typer.Option(None, "--units", help="Evaluation units (repeat or comma-separate; a dataset without units: its stretches of time "
                                                                 "flight[1/5]..test[5/5], as fit names them)."),
    json_out: str | None = typer.Option(None, "--json", help="Also write Table I as JSON here."),
    markdown_out: str | None = typer.Option(None, "--markdown", help="Also write Table I as Markdown here."),
    dask: str | None = typer.Option(None, "--dask", help=DASK_HELP),
    sensitivity_dbm: float | None = typer.Option(
        None, "--sensitivity", metavar="DBM",
        help="Also score each model's predicted availability P(RSSI >= DBM) against the observed samples "
             "(up: RSSI >= DBM; down: below it, or an outage event): Brier score, skill against the learning "
             "data's share up, reliability table."),
) -> None:
    """Table I (RMSE, MAE, |phi|, AIC, LTD, Q95) of models on a dataset.

    Example: rplearn evaluate sh10.json mean.json data.parquet --units test_36 --sensitivity -90
    """
    from rplearn.workflows.learning import evaluate_model_files

    if len(paths) < 2:
        raise InputError("evaluate: give at least one MODEL.json and a DATASET")
    if dask is not None:
        from rplearn.workflows.fleet import parse_dask

        with flag_values():
            parse_dask(dask)  # its form; its budget (local:N) an error of the run
    *model_paths, dataset = paths
    with progress_bar() as p:
        task = p.add_task("predicting", total=None)
        outcome = evaluate_model_files(model_paths, dataset, split_list(units), json_out, markdown_out, dask=dask,
                                       progress=parts_step(p, task, "predictions"), sensitivity_dbm=sensitivity_dbm)
    for line in outcome.units.warnings:
        note(line, "warning")
    for line in outcome.units.notes:
        note(f"{line} (pass --units to choose)")
    say(outcome.markdown)


@app.command()
@user_errors
def predict(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    dataset: str = typer.Argument(..., metavar="DATASET"),
    output: str = typer.Option(..., "-o", "--out", help="Where to write the dataset with the predictions added (.csv or .parquet)."),
    sensitivity: str | None = typer.Option(None, "--sensitivity", metavar="DBM|RADIO",
                                     help="Also each row's availability, P(RSSI >= this): dBm or a radio (sik, esp32-11b, wifi-6mbps, ...)."),
) -> None:
    """Predict the joint gain and received power for every row of a dataset of poses.

    DATASET has the columns of a matched dataset (see rplearn sync) except rssi_dbm, which
    may be absent: links that were never flown can be predicted. Added columns:
    gain_pred_db, the joint gain G_tx + G_rx [dB]; rssi_pred_dbm, the received power
    [dBm]; and for pattern models gain_pred_std_db, the standard error of gain_pred_db from
    the learned coefficients alone [dB], and rssi_pred_std_db, the spread of one new packet's
    RSSI around rssi_pred_dbm, adding the training residual (fading, noise, misfit) [dB].
    With --sensitivity: availability, the probability that the RSSI reaches it.

    Example: rplearn predict sh10.json data.parquet -o pred.csv --sensitivity esp32-11b
    """
    from rplearn.analysis.radios import sensitivity_dbm
    from rplearn.workflows.learning import predict_file

    with flag_values():
        level = None if sensitivity is None else sensitivity_dbm(sensitivity)
    prediction = predict_file(model_path, dataset, output, level)
    if prediction.mismatch is not None:
        note(prediction.mismatch.describe(dataset, model_path), "warning")
    say(prediction.summary(output))
    for line in prediction.notes:
        note(line)
    for line in prediction.warnings:
        note(line, "warning")


@app.command()
@user_errors
def sweep(
    dataset: str = typer.Argument(...),
    model: str = typer.Option("sh", "--model", help="sh, bg or poly."),
    orders: str = typer.Option("3..15", "--orders", help="Range A..B or a list 3,5,8."),
    learn_units: list[str] | None = typer.Option(None, "--learn-units", help="Learning units (default: all but the test units)."),
    test_units: list[str] | None = typer.Option(None, "--test-units", help="Testing units (default: units whose label starts with 'test')."),
    output: str | None = typer.Option(None, "-o", "--out", help="The sweep as a table (.csv or .parquet)."),
    plot_path: str | None = typer.Option(None, "--plot", help="PNG of the sweep (Fig. 10)."),
) -> None:
    """Model-order selection: test RMSE, AIC and LTD against the order (paper Fig. 10).

    Example: rplearn sweep data.parquet --model sh --orders 3..15 -o sweep.csv --plot sweep.png
    """
    from rplearn.analysis.sweep import check_sweep_kind
    from rplearn.models.spec import ModelSpec
    from rplearn.workflows.learning import sweep_dataset

    with flag_values():
        order_list = parse_orders(orders)
        check_sweep_kind(ModelSpec.parse(model).kind)  # a name of no model, or none swept, refused before the dataset is read
    with progress_bar() as p:
        task = p.add_task("sweeping", total=len(order_list))
        result = sweep_dataset(
            dataset, model, order_list, split_list(learn_units), split_list(test_units),
            progress=lambda m: p.update(task, advance=1, description=m), output=output, plot_path=plot_path,
        )
    for line in result.notes:
        note(line)
    say(result.summary())


@app.command()
@user_errors
def report(
    dataset: str = typer.Argument(..., help="Matched dataset (without a 'unit' column it is cut into stretches of time flight[1/5]..test[5/5])."),
    model: str | None = typer.Option(None, "--model", metavar="MODEL.json", help="The model to report on (default: the cross-validated SH model, learned here "
                                                                                 "on the learning units as `rplearn fit` does)."),
    paper_models: str | None = typer.Option(None, "--paper-models", metavar="LIST", help="Also the paper's Table I of these models, e.g. 'paper' "
                                                                                         "(m,nn-400,sh-10,p-12,bg-7), 'paper,auto' or 'm,sh-10'; learning time "
                                                                                         "the median of --repeats runs."),
    repeats: int = typer.Option(5, "--repeats", metavar="N", help="Learning runs per Table I model (its learning time is their median)."),
    test_units: list[str] | None = typer.Option(None, "--test-units", help="Testing units (default: labels starting with 'test')."),
    out_dir: str = typer.Option("rplearn-report", "-o", "--out", help="Output directory."),
    path_loss_kind: str = typer.Option("free", "--path-loss", help="Environment term of the pattern models: free, log-distance or two-ray (see fit)."),
    ground_level: float = typer.Option(0.0, "--ground-level", help="two-ray: ENU height of the ground plane [m]."),
    permittivity: float = typer.Option(15.0, "--permittivity", help="two-ray: relative permittivity of the ground."),
    polarization: str = typer.Option("vertical", "--polarization", help="two-ray: vertical or horizontal."),
    learn_offsets: bool = typer.Option(True, "--link-offsets/--no-link-offsets", help="Pattern models: learn one electronics offset per link logged in both "
                                                                                      "directions."),
    sensitivity_dbm: float | None = typer.Option(
        None, "--sensitivity", metavar="DBM",
        help="Also score the model's predicted availability P(RSSI >= DBM) on the held-out units (outage events count "
             "as down) and draw its reliability diagram."),
) -> None:
    """Report one model on a dataset: held-out scores, measured vs predicted over time, residuals,
    polar cuts, spread and 3-D patterns in report.html (and the paper's Table I on request).

    Example: rplearn report data.parquet -o report; rplearn report data.parquet --model sh.json --paper-models paper,auto
    """
    from rplearn.core.environment import PathLoss
    from rplearn.io.files import check_output_folder
    from rplearn.models.options import FitOptions
    from rplearn.workflows.report import ReportOptions, learn_and_report, paper_model_names

    with flag_values():
        two_ray_flags_note(path_loss_kind, ground_level, permittivity, polarization)
        options = FitOptions(path_loss=PathLoss(path_loss_kind, ground_level, permittivity, polarization),
                             link_offsets=learn_offsets)
        asked = ReportOptions(repeats, sensitivity_dbm)
    with flag_values("paper_models"):  # its names are checked as models: not report's --model MODEL.json
        paper_model_names((split_list([paper_models]) or []) if paper_models else [])
    check_output_folder(out_dir)
    with progress_bar() as p:
        task = p.add_task("learning", total=None)
        outcome = learn_and_report(dataset, out_dir, model, (split_list([paper_models]) or []) if paper_models else [],
                                   split_list(test_units), progress=step(p, task), options=options,
                                   report=asked)
    for line in outcome.notes:
        note(line)
    say(outcome.summary())
