"""The in-process runner of the command-line tests (:func:`cli_helpers.run_here`) answers as a
user's process answers: the tests that moved refusals into this process rely on it.

Each check here holds against a real process where one is needed (the exit code, standard output
and standard error of ``python -m rplearn.cli`` compared byte for byte), and shows that what pytest
does to this process (its warning filters and recorder, its log capture, its working folder and
environment) does not leak into what a command shows.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
from cli_helpers import FRESH_WARNING_FILTERS, run, run_here

from rplearn.errors import InputError

#: Commands whose whole answer (exit code, stdout, stderr) the runner must give as a process
#: gives it: a user error, typer's usage error (its box is as wide as the process's terminal),
#: the version, a refusal from the environment, the shell completion script of an environment
#: variable, and no command at all (the help, exit 2).
SAME_ANSWER = {
    "missing input": (["fit", "missing.parquet", "-o", "m.json"], None),
    "unknown option": (["fit", "--no-such-flag"], None),
    "version": (["--version"], None),
    "SOURCE_DATE_EPOCH out of range": (["trajectory", "-o", "plan"], {"SOURCE_DATE_EPOCH": "-1"}),
    "completion script": ([], {"_RPLEARN_COMPLETE": "source_bash"}),
    "no command": ([], None),
}


def test_the_runner_answers_as_a_process_answers(tmp_path):
    for case, (args, env) in SAME_ANSWER.items():
        proc = run(args, tmp_path, env)
        here = run_here(args, tmp_path, ok=False, env=env)
        assert (here.returncode, here.stdout, here.stderr) == (proc.returncode, proc.stdout, proc.stderr), case
    assert list(tmp_path.iterdir()) == []


def test_the_runner_has_a_fresh_interpreters_warning_filters():
    """:data:`cli_helpers.FRESH_WARNING_FILTERS` are those of a fresh interpreter that imported the
    command line (pytest's own, e.g. ``error::RuntimeWarning:rplearn.*``, are not)."""
    code = "import warnings, rplearn.cli; print([(a, m, c.__name__, mod, n) for a, m, c, mod, n in warnings.filters])"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONWARNINGS", "PYTHONDEVMODE")}
    fresh = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True).stdout
    assert fresh.strip() == str([(a, m, c.__name__, mod, n) for a, m, c, mod, n in FRESH_WARNING_FILTERS])


@pytest.fixture
def noisy_output_check(monkeypatch):
    """``trajectory``'s first step made to warn (a UserWarning, a DeprecationWarning, a RuntimeWarning
    pytest's filters make an error here), log (a warning, an info), write to file descriptor 2 as a
    C library does, and refuse."""
    import rplearn.io.files

    def check_output_folder(path):
        warnings.warn("a warning the user sees", UserWarning, stacklevel=1)
        warnings.warn("a deprecation a user's process hides", DeprecationWarning, stacklevel=1)
        warnings.warn("a runtime warning", RuntimeWarning, stacklevel=1)
        logging.getLogger("rplearn.probe").warning("a logged warning")
        logging.getLogger("rplearn.probe").info("a logged detail")
        os.write(2, b"a C library's line on descriptor 2\n")
        raise InputError(f"{path}: refused by the probe")

    monkeypatch.setattr(rplearn.io.files, "check_output_folder", check_output_folder)


def test_the_runner_shows_warnings_and_logs_as_a_process(noisy_output_check, tmp_path, caplog):
    with warnings.catch_warnings(record=True) as recorded:  # nothing reaches pytest's recorder
        warnings.simplefilter("always")
        for _ in range(2):  # a second run shows the warnings again, as a second process does
            proc = run_here(["trajectory", "-o", "plan"], tmp_path, ok=False)
            lines = proc.stderr.splitlines()
            assert proc.returncode == 1 and "error: plan: refused by the probe" in lines, proc.stderr
            assert lines.count("a C library's line on descriptor 2") == 1, proc.stderr
            assert sum("UserWarning: a warning the user sees" in line for line in lines) == 1, proc.stderr
            assert sum("RuntimeWarning: a runtime warning" in line for line in lines) == 1, proc.stderr
            assert "WARNING rplearn.probe: a logged warning" in lines, proc.stderr
            assert "deprecation" not in proc.stderr and "a logged detail" not in proc.stderr
            assert proc.stdout == ""
    assert recorded == [] and caplog.records == []
    verbose = run_here(["-v", "trajectory", "-o", "plan"], tmp_path, ok=False)
    assert "INFO rplearn.probe: a logged detail" in verbose.stderr.splitlines(), verbose.stderr
    # PYTHONWARNINGS of the environment turns the warning into an error: it escapes as a traceback
    strict = run_here(["trajectory", "-o", "plan"], tmp_path, ok=False, env={"PYTHONWARNINGS": "error::UserWarning"})
    assert strict.returncode == 1 and "Traceback" in strict.stderr and strict.stderr.rstrip().endswith("UserWarning: a warning the user sees")
    assert "PYTHONWARNINGS" not in os.environ
    assert list(tmp_path.iterdir()) == []


def test_the_runner_leaves_this_process_as_it_found_it(monkeypatch, tmp_path):
    """The command sees its own command line (written into outputs' provenance), working folder,
    environment and an empty standard input; this process gets its own back, with its logging and
    warning filters."""
    import rplearn.io.files

    seen = {}

    def check_output_folder(path):
        seen.update(argv=sys.argv[1:], cwd=Path.cwd(), variable=os.environ.get("RPLEARN_PROBE_VARIABLE"), stdin=sys.stdin.read(),
                    command=rplearn.io.files.provenance()["command"])
        raise InputError("seen")

    monkeypatch.setattr(rplearn.io.files, "check_output_folder", check_output_folder)
    cwd, argv, filters = Path.cwd(), sys.argv[:], warnings.filters[:]
    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    proc = run_here(["trajectory", "-o", "plan"], tmp_path, ok=False, env={"RPLEARN_PROBE_VARIABLE": "0"})
    assert proc.returncode == 1 and proc.stderr == "error: seen\n", proc.stderr
    assert seen == {"argv": ["trajectory", "-o", "plan"], "cwd": tmp_path, "variable": "0", "stdin": "",
                    "command": "rplearn trajectory -o plan"}
    assert Path.cwd() == cwd and sys.argv == argv and warnings.filters == filters
    assert root.handlers == handlers and root.level == level and "RPLEARN_PROBE_VARIABLE" not in os.environ


def test_an_exception_escaping_a_command_is_a_traceback(monkeypatch, tmp_path):
    import rplearn.io.files

    def check_output_folder(path):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(rplearn.io.files, "check_output_folder", check_output_folder)
    proc = run_here(["trajectory", "-o", "plan"], tmp_path, ok=False)
    assert proc.returncode == 1 and proc.stderr.startswith("Traceback") and proc.stderr.rstrip().endswith("ZeroDivisionError: a bug")
