"""Usage errors (a flag's value that is no number, an unknown flag or command, a missing argument or
value) are one line on standard error naming the flag and the value, exit code 2
(``rplearn.cli._usage``); they were click's usage line, hint and ``Error: Invalid value for
'--noise': Input should be a valid number, unable to parse string as a number``."""

from __future__ import annotations

import inspect

import pytest
from cli_helpers import run, run_here

from rplearn.cli import app


def number_flags() -> list[tuple[str, str, str]]:
    """(command, flag, 'number' or 'whole number') of every option of every command that takes a
    number (``float``, ``int``, optional or not, or a list of them)."""
    found = []
    for command in app.registered_commands:
        name = command.name or command.callback.__name__.replace("_", "-")
        for param in inspect.signature(command.callback).parameters.values():
            kinds = {t.strip().removeprefix("list[").removesuffix("]") for t in str(param.annotation).split("|")} - {"None"}
            decls = [d for d in getattr(param.default, "param_decls", None) or () if d.startswith("--")]
            if decls and kinds in ({"float"}, {"int"}):
                found.append((name, max(decls, key=len), "a number" if kinds == {"float"} else "a whole number"))
    return found


def one_line(proc, expected: str) -> None:
    assert (proc.returncode, proc.stdout, proc.stderr) == (2, "", f"error: {expected}\n"), proc.stderr


def test_every_number_flag_of_every_command_refuses_a_word_in_one_line(tmp_path):
    flags = number_flags()
    assert len(flags) > 50 and ("trajectory", "--noise", "a number") in flags and ("links", "--draws", "a whole number") in flags
    for command, flag, kind in flags:
        one_line(run_here([command, flag, "abc"], tmp_path, ok=False), f"{flag}: 'abc' is not {kind}")
    assert list(tmp_path.iterdir()) == []


def test_a_word_for_a_number_in_a_users_process(tmp_path):
    one_line(run(["trajectory", "--optimize", "--noise", "abc"], tmp_path), "--noise: 'abc' is not a number")
    one_line(run(["fit", "d.parquet", "--prior-std", "x", "-o", "m.json"], tmp_path), "--prior-std: 'x' is not a number")


@pytest.mark.parametrize("args, expected", [
    (["links", "m.json", "p.csv", "--draws", "0"], "--draws: expected a whole number >= 1, got '0'"),
    (["links", "m.json", "p.csv", "--draws", "2.5"], "--draws: '2.5' is not a whole number"),
    (["fit", "--no-such-flag"], "--no-such-flag: no such flag of rplearn fit (see rplearn fit --help)"),
    (["--bogus"], "--bogus: no such flag of rplearn; did you mean --verbose? (see rplearn --help)"),
    (["fit"], "rplearn fit: missing argument DATASET (see rplearn fit --help)"),
    (["links"], "rplearn links: missing argument MODEL.json (see rplearn links --help)"),
    (["fit", "d.parquet"], "rplearn fit: missing option --out (see rplearn fit --help)"),
    (["sync", "--poses"], "--poses: expects a value after it"),
    (["fitt"], "rplearn: no such command 'fitt'; did you mean 'fit'? (see rplearn --help)"),
])
def test_usage_errors_are_one_line_naming_the_flag(tmp_path, args, expected):
    one_line(run_here(args, tmp_path, ok=False), expected)


def test_an_extra_argument_is_one_line(tmp_path):
    proc = run_here(["fit", "a", "b", "-o", "m.json"], tmp_path, ok=False)
    assert proc.returncode == 2 and proc.stdout == "" and len(proc.stderr.splitlines()) == 1, proc.stderr
    assert proc.stderr.startswith("error: rplearn fit: got unexpected extra argument") and "(b)" in proc.stderr


def test_a_commands_own_bad_parameter_is_one_line(tmp_path):
    """``links --pair`` raises typer's BadParameter from the command's body."""
    (tmp_path / "m.json").write_text("{}")
    (tmp_path / "p.csv").write_text("t,node\n")
    proc = run_here(["links", "m.json", "p.csv", "--tx-power", "20", "-o", "l.csv", "--pair", "A-B"], tmp_path, ok=False)
    one_line(proc, "--pair needs --sensitivity")


def test_help_and_no_command_are_unchanged(tmp_path):
    bare = run_here([], tmp_path, ok=False)
    assert bare.returncode == 2 and "Usage: rplearn [OPTIONS] COMMAND" in bare.stdout + bare.stderr and "Commands" in bare.stdout + bare.stderr
    helped = run_here(["fit", "--help"], tmp_path, ok=False)
    assert helped.returncode == 0 and helped.stdout.startswith("Usage: rplearn fit [OPTIONS] DATASET")
