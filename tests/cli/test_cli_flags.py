"""rplearn.cli._app: library messages name parameters; the command line names the flags."""

from __future__ import annotations

import typer

from rplearn.cli._app import with_flag


def fit_like(
    gauge_node: str | None = typer.Option(None, "--gauge-node"),
    gauge_dbi: float | None = typer.Option(None, "--gauge-dbi"),
    frequency_hz: float | None = typer.Option(None, "--frequency"),
    step_deg: float = typer.Option(5.0, "--step"),
) -> None:
    """A command with the options the messages below name."""


def test_a_leading_parameter_becomes_its_flag():
    assert with_flag("ridge, grid: not used by M", "ridge") == "--ridge, --grid: not used by M"
    assert with_flag("max_gap_s: expected a positive number", "max_gap_s") == "--max-gap: expected a positive number"
    assert with_flag("step_deg: expected a positive grid step", "step_deg", fit_like) == "--step: expected a positive grid step"


def test_related_parameters_are_named_by_flag_wherever_they_stand():
    text = with_flag("gauge_dbi needs gauge_node (which node's mean gain it fixes)", "gauge_dbi", fit_like,
                     related=("gauge_node",))
    assert text == "--gauge-dbi needs --gauge-node (which node's mean gain it fixes)"


def test_user_data_and_column_names_are_left_alone():
    assert with_flag("d.csv: missing column frequency_hz", None, fit_like) == "d.csv: missing column frequency_hz"
    text = with_flag("positions: drones step_deg, B", "positions", fit_like)
    assert text == "positions: drones step_deg, B"  # fit_like has no --pos: nothing to name


def test_option_fields_become_flags_with_their_values():
    assert with_flag("p.csv: NaN rows (nan_policy='drop')", "nan_policy") == "p.csv: NaN rows (--nan-policy drop)"
    assert with_flag("p.csv: unsorted (allow_unsorted=True)", "allow_unsorted") == "p.csv: unsorted (--allow-unsorted)"
    text = with_flag("b.bag: name them (ReaderOptions.pose_topics={topic: node}, ReaderOptions.rssi_topics={topic: (tx, rx)})", "pose_topics")
    assert text == "b.bag: name them (--pose-topic TOPIC=NODE, --rssi-topic TOPIC=TX:RX)"


def test_a_flag_is_appended_only_when_the_command_has_it():
    assert with_flag("p.csv: times go backwards", "allow_unsorted") == "p.csv: times go backwards (set it with --allow-unsorted)"
    assert with_flag("d.parquet: unknown unit(s) x", "units", fit_like) == "d.parquet: unknown unit(s) x"
    assert with_flag("no parameter at fault", None) == "no parameter at fault"


def test_user_data_is_printed_verbatim_not_as_markup(tmp_path):
    import subprocess
    import sys

    name = "no[b]such[/b]:fire:.parquet"
    proc = subprocess.run([sys.executable, "-m", "rplearn.cli", "fit", name, "-o", "m.json"], cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.strip() == f"error: {name}: no such file"
