"""Commands that show or hand on what was learned: ``export``, ``plot`` and ``demo``."""

from __future__ import annotations

import typer

from rplearn.cli._app import app, flag_values, progress_bar, say, step, user_errors


@app.command()
@user_errors
def export(
    model_path: str = typer.Argument(..., metavar="MODEL.json"),
    fmt: str = typer.Option("grid", "--format", help="grid (CSV), msi (one file per node) or images (3-D PNG per node)."),
    step_deg: float = typer.Option(5.0, "--step-deg", help="Grid step [deg]."),
    output: str = typer.Option(..., "-o", "--out", help="Output file (grid) or directory (msi, images)."),
    frequency_hz: float | None = typer.Option(None, "--frequency", help="Frequency written into MSI files [Hz] (default: the frequency the model was learned "
                                                                        "at)."),
) -> None:
    """Export a learned model: grid CSV (node, az_deg, el_deg, gain_db), MSI Planet cuts, 3-D images.

    Example: rplearn export sh10.json --format msi -o patterns/
    """
    from rplearn.workflows.planning import check_export_format, export_model_file

    with flag_values():
        check_export_format(fmt)
    for path in export_model_file(model_path, fmt, output, step_deg, frequency_hz):
        say(f"wrote {path}")


@app.command()
@user_errors
def plot(
    model_paths: list[str] = typer.Argument(..., metavar="MODEL.json..."),
    truth: str | None = typer.Option(None, "--truth", help="ground_truth.json of a simulation, drawn beside."),
    dataset: str | None = typer.Option(None, "--dataset", help="Draw the sample directions of this dataset."),
    output: str = typer.Option("patterns.png", "-o", "--out", help="PNG file."),
    spread: str | None = typer.Option(None, "--spread", help="Also draw each node's own-pattern spread (posterior std, uncovered directions hatched) to this "
                                                             "PNG."),
) -> None:
    """Draw learned patterns in the azimuth-elevation domain (paper Fig. 9).

    Example: rplearn plot sh10.json --truth flight/ground_truth.json --dataset data.parquet -o patterns.png --spread spread.png
    """
    from rplearn.workflows.planning import draw_pattern_files

    say(f"wrote {draw_pattern_files(model_paths, output, truth, dataset, spread)}")
    if spread:
        say(f"wrote {spread}")


@app.command()
@user_errors
def demo(
    out_dir: str = typer.Option("rplearn-demo", "-o", "--out", help="Output directory."),
    seed: int = typer.Option(0, "--seed", help="Seed of the simulated flight."),
    preset: str = typer.Option("paper", "--preset", help="Simulated campaign: paper, trio, smoke, ground, pathloss or tworay."),
) -> None:
    """Reproduce the paper's evaluation on a simulated replica of its campaign (Table I, Figs. 5-10, report.html).

    Example: rplearn demo -o rplearn-demo
    """
    from rplearn.io.files import check_output_folder
    from rplearn.sim.presets import make_preset
    from rplearn.workflows.demo import run_demo

    with flag_values():
        make_preset(preset)  # a name of no preset refused before anything is simulated
    check_output_folder(out_dir)
    with progress_bar() as p:
        task = p.add_task("starting", total=None)
        result = run_demo(out_dir, seed=seed, preset=preset, progress=step(p, task))
    say(result.summary())
