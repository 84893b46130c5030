"""rplearn.cli._app: library messages name parameters; the command line names the flags."""

from __future__ import annotations

from typing import Optional

import typer

from rplearn.cli._app import with_flag


def fit_like(
    gauge_node: Optional[str] = typer.Option(None, "--gauge-node"),
    gauge_dbi: Optional[float] = typer.Option(None, "--gauge-dbi"),
    frequency_hz: Optional[float] = typer.Option(None, "--frequency"),
    step_deg: float = typer.Option(5.0, "--step"),
) -> None:
    """A command with the options the messages below name."""


def test_a_leading_parameter_becomes_its_flag():
    assert with_flag("ridge, grid: not used by M", "ridge") == "--ridge, --grid: not used by M"
    assert with_flag("max_gap_s: expected a positive number", "max_gap_s") == "--max-gap: expected a positive number"
    assert with_flag("step_deg: expected a positive grid step", "step_deg", fit_like) == "--step: expected a positive grid step"


def test_command_options_are_named_by_flag_wherever_they_stand():
    text = with_flag("gauge_dbi needs gauge_node (which node's mean gain it fixes)", "gauge_dbi", fit_like)
    assert text == "--gauge-dbi needs --gauge-node (which node's mean gain it fixes)"


def test_column_names_stay_column_names():
    text = with_flag("d.csv: missing column frequency_hz", None, fit_like)
    assert text == "d.csv: missing column frequency_hz"


def test_a_flag_the_message_does_not_name_is_appended():
    text = with_flag("p.csv: times go backwards (allow_unsorted=True)", "allow_unsorted")
    assert text == "p.csv: times go backwards (allow_unsorted=True) (set it with --allow-unsorted)"
    assert with_flag("no parameter at fault", None) == "no parameter at fault"


def test_user_data_is_printed_verbatim_not_as_markup(tmp_path):
    import subprocess
    import sys

    name = "no[b]such[/b]:fire:.parquet"
    proc = subprocess.run([sys.executable, "-m", "rplearn.cli", "fit", name, "-o", "m.json"], cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.strip() == f"error: {name}: no such file"
