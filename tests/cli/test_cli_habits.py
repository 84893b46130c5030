"""The command line follows its ecosystem's habits (issue 26, item 2): ``python -m rplearn``,
shell completion, ``inspect --json``, and messages for natural mistakes that name what the file
is and the command that would work.

The commands run in this process (:func:`here`, :func:`cli_helpers.run_here`: the exit code,
stdout and stderr of a user's process) except where the process is the point: ``python -m
rplearn --help``, the bash completion script of ``python -m rplearn``, ``fit --help`` of the user's
process against the text made here, and one refusal (``fit --order x``) so that the process
boundary stays covered."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from cli_helpers import REAL_TLOG, D, help_text, run_here, smoke_flight

ROOT = Path(__file__).resolve().parents[2]
TLOG = REAL_TLOG
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}


def run(*args: str, cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    """``python -m rplearn ARGS`` as a process of its own."""
    return subprocess.run([sys.executable, "-m", "rplearn", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300, env=env or ENV)


def here(*args: str, cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    """What :func:`run` answers, from this process (:func:`cli_helpers.run_here`)."""
    return run_here(list(args), cwd, ok=False, env=env)


def _no_constant(name: str) -> float:
    raise ValueError(f"not strict JSON: {name}")


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> Path:
    """A simulated flight (``f/``), its matched dataset (``d.parquet``, every link: ``sync``'s
    default) and a model fitted in this process (``m.json``: an input of the tests, whose own
    commands run as ``python -m rplearn``). The flight and dataset
    are a copy of the worker's smoke flight (:func:`cli_helpers.smoke_flight`: seed 2, the same
    commands), which the other command-line tests share."""
    d = smoke_flight(tmp_path_factory.mktemp("habits"))
    (d / "flight").rename(d / "f")
    (d / D).rename(d / "d.parquet")
    run_here(["fit", "d.parquet", "--degree", "4", "-o", "m.json"], d)
    return d


def test_python_dash_m_rplearn_is_the_command(flight):
    proc = run("--help", cwd=flight)
    assert proc.returncode == 0
    assert "Usage: rplearn " in proc.stdout and "fit" in proc.stdout


def test_bash_completion_script_and_a_completion(flight):
    # the script `rplearn --show-completion` prints under bash (shell detection aside: typer's
    # source_<shell> instruction names the shell), for bash (from `python -m rplearn`), zsh and fish
    proc = subprocess.run([sys.executable, "-m", "rplearn"], cwd=flight, capture_output=True, text=True, timeout=120,
                          env={**ENV, "_RPLEARN_COMPLETE": "source_bash"})
    assert proc.returncode == 0 and "complete_bash" in proc.stdout, proc
    assert "complete" in proc.stdout and "_RPLEARN_COMPLETE=complete_bash" in proc.stdout
    for shell in ("zsh", "fish"):
        proc = here(cwd=flight, env={"_RPLEARN_COMPLETE": f"source_{shell}"})
        assert proc.returncode == 0 and f"complete_{shell}" in proc.stdout, (shell, proc)
    # what bash asks through that script: complete `rplearn fi` and `rplearn inspect --js`
    env = {"_RPLEARN_COMPLETE": "complete_bash", "COMP_WORDS": "rplearn fi", "COMP_CWORD": "1"}
    got = here(cwd=flight, env=env)
    assert got.stdout.split() == ["fit"], got
    env.update(COMP_WORDS="rplearn inspect --js", COMP_CWORD="2")
    got = here(cwd=flight, env=env)
    assert "--json" in got.stdout.split()


def test_inspect_json_is_strict_json_with_times_from_the_log_start(flight):
    proc = here("inspect", "--json", "f/pose_log.parquet", "f/signal_log.parquet", cwd=flight)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout, parse_constant=_no_constant)
    assert doc["schema"] == "rplearn.inspect" and doc["start_s"] >= 0.0
    assert {n["node"] for n in doc["nodes"]} == {"A", "B"}
    assert min(n["t_start_s"] for n in doc["nodes"]) == pytest.approx(0.0, abs=1.0)  # relative, not epoch
    assert all(lk["rate_hz"] > 0 for lk in doc["links"])
    assert here("inspect", "--json", "--markdown", "f/pose_log.parquet", cwd=flight).returncode == 1


def test_inspect_json_of_a_real_tlog_parses_strictly(tmp_path):
    proc = here("inspect", "--json", str(TLOG), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout, parse_constant=_no_constant)
    assert doc["files"][0]["format"] == "tlog" and doc["links"]


@pytest.mark.parametrize("args", [("fit", "{tlog}", "-o", "x.json"), ("evaluate", "m.json", "{tlog}"),
                                  ("predict", "m.json", "{tlog}", "-o", "p.parquet")])
def test_a_raw_log_given_for_a_dataset_names_the_sync_command(flight, args):
    proc = here(*[a.format(tlog=TLOG) for a in args], cwd=flight)
    assert proc.returncode == 1
    line = proc.stderr.strip()
    assert len(line.splitlines()) == 1 and "Traceback" not in line
    assert "raw MAVLink" in line and f"rplearn sync --poses {TLOG} --signals {TLOG}" in line
    assert "UnicodeDecodeError" not in line


def test_the_sync_command_a_raw_log_hint_names_runs_once_its_placeholders_are_filled(flight):
    # the hint named `sync --poses X --signals X` alone, which a MAVLink log then refused for
    # the radios' power and band it does not carry: the user had to ask twice
    proc = here("fit", str(TLOG), "-o", "x.json", cwd=flight)
    command = proc.stderr.split("`")[1].split()
    assert command[:2] == ["rplearn", "sync"] and "DBM" in command and "HZ" in command
    filled = [{"DBM": "20", "HZ": "433e6"}.get(a, a) for a in command[1:]]
    ran = here(*filled, cwd=flight)
    assert ran.returncode == 0, ran.stderr
    assert (flight / "data.parquet").exists()


def test_a_raw_logs_hint_quotes_a_path_with_spaces(flight, tmp_path):
    import shlex
    import shutil
    spaced = tmp_path / "my log.tlog"
    shutil.copy(TLOG, spaced)
    proc = here("fit", str(spaced), "-o", "x.json", cwd=flight)
    command = proc.stderr.split("`")[1]
    assert shlex.split(command)[3] == str(spaced), command


def test_predict_with_its_arguments_swapped_says_so(flight):
    proc = here("predict", "d.parquet", "m.json", "-o", "p.parquet", cwd=flight)
    assert proc.returncode == 1
    assert "d.parquet: a table (a dataset?), not a model file: are the arguments in the wrong order?" in proc.stderr
    assert "utf-8" not in proc.stderr


def test_a_model_file_given_for_a_dataset_says_what_it_is(flight):
    proc = here("fit", "m.json", "-o", "y.json", cwd=flight)
    assert proc.returncode == 1
    assert "m.json: a JSON file (a model file?), not a table" in proc.stderr and "ParserError" not in proc.stderr


def test_swapped_pose_and_signal_logs_say_swap_them(flight):
    proc = here("sync", "--poses", "f/signal_log.parquet", "--signals", "f/pose_log.parquet", "-o", "s.parquet",
                cwd=flight)
    assert proc.returncode == 1
    assert "no pose log found" in proc.stderr and "swap --poses and --signals" in proc.stderr
    assert not (flight / "s.parquet").exists()


def test_a_corrupt_table_still_gets_the_parsers_one_line(tmp_path):
    """No hint applies: the parser's complaint, on one line."""
    bad = tmp_path / "bad.csv"
    bad.write_text('t,tx,rx\n1,"A\n')
    proc = here("fit", str(bad), "-o", "x.json", cwd=tmp_path)
    assert proc.returncode == 1 and len(proc.stderr.strip().splitlines()) == 1


def _help(command: str, cwd: Path) -> str:
    """``rplearn COMMAND --help``'s text, made in this process (``cli_helpers.help_text``: the
    text is the point; ``python -m rplearn --help`` as a process is tested above)."""
    return help_text(command)


COMMANDS = ("trajectory", "simulate", "inspect", "sync", "fit", "evaluate", "predict", "sweep", "report", "links",
            "headings", "orient", "export", "plot", "demo")


@pytest.mark.parametrize("command", COMMANDS)
def test_help_shows_readable_metavars_not_python_types(command, tmp_path):
    import re

    text = _help(command, tmp_path)
    assert not re.search(r"<(str|int|float|bool|list\[[a-z]+\]|Path)>", text), text
    assert not re.search(r"\{[a-z_]+\}", text.splitlines()[0]), text.splitlines()[0]


def test_help_lists_choices_and_units(tmp_path):
    assert "--turn [tx|rx|both]" in _help("orient", tmp_path)
    fit = _help("fit", tmp_path)
    assert run("fit", "--help", cwd=tmp_path).stdout == fit  # the user's process prints the text made here
    assert "--prior-level [data|prior]" in fit and "--prior NODE=MODEL.json" in fit and "--model KIND" in fit
    sync = _help("sync", tmp_path)
    assert "--frequency HZ" in sync and "--max-gap SECONDS" in sync and "--poses FILE" in sync
    assert "--rssi-scale [dbm|relative]" in sync
    assert "Usage: rplearn predict [OPTIONS] MODEL.json DATASET" in _help("predict", tmp_path)


def test_the_listed_choices_are_the_librarys():
    """The words the help lists are exactly those the library accepts (the CLI may not import
    the numeric layers, so it keeps its own list: this test keeps the two equal)."""
    from rplearn.cli._help import CHOICES
    from rplearn.core.environment import PATH_LOSS_KINDS
    from rplearn.core.lsq.solver import PRIOR_LEVELS
    from rplearn.sim.presets import PRESET_NAMES

    assert set(CHOICES[("*", "--path-loss")]) == set(PATH_LOSS_KINDS)
    assert set(CHOICES[("*", "--prior-level")]) == set(PRIOR_LEVELS)
    assert set(CHOICES[("simulate", "--preset")]) == {*PRESET_NAMES, "fleet"}
    assert set(CHOICES[("demo", "--preset")]) == set(PRESET_NAMES)


def test_order_is_the_model_size_and_degree_its_alias(flight):
    """``fit --order`` names the model size (SH-L, BG-k, P-k, k of knn); ``--degree`` is kept
    as an alias and the help says so; both give the same model."""
    text = _help("fit", flight)
    assert "--order, --degree ORDER|auto" in text and "--degree is the same option" in " ".join(text.split())
    # the same option parser in this process as in the user's (the refusal below runs as a process)
    run_here(["fit", "d.parquet", "--order", "3", "-o", "o3.json"], flight)
    run_here(["fit", "d.parquet", "--degree", "3", "-o", "d3.json"], flight)
    a, b = (json.loads((flight / n).read_text())["model"]["coefficients"] for n in ("o3.json", "d3.json"))
    assert a == b
    bad = run("fit", "d.parquet", "--order", "x", "-o", "x.json", cwd=flight)
    assert bad.returncode == 2 and "--order" in bad.stderr  # a usage error
