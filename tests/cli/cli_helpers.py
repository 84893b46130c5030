"""What the command-line tests share: running ``rplearn`` as a user does, a smoke flight, and the
check that a refused command says one line and writes nothing.

Imported by the test modules of this folder (pytest puts the folder on ``sys.path``).
"""

from __future__ import annotations

import atexit
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

#: The command line a user types, with this interpreter.
RPLEARN = [sys.executable, "-m", "rplearn.cli"]
#: The smoke flight's files, relative to the working folder.
P, S, D, M = "flight/pose_log.parquet", "flight/signal_log.parquet", "data.parquet", "sh3.json"


def run(args: Sequence[str], cwd: Path | str, env: dict[str, str] | None = None,
        timeout: float = 600) -> subprocess.CompletedProcess[str]:
    """Run ``rplearn ARGS`` in ``cwd`` (``env``: variables added to this process's)."""
    return subprocess.run(RPLEARN + list(args), cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env=None if env is None else {**os.environ, **env})


def run_ok(args: Sequence[str], cwd: Path | str, ok: bool = True) -> subprocess.CompletedProcess[str]:
    """:func:`run` within 5 minutes; with ``ok``, assert that it succeeded (naming the arguments)."""
    proc = run(args, cwd, timeout=300)
    if ok:
        assert proc.returncode == 0, f"{args}: {proc.stderr}"
    return proc


def invoke(args: Sequence[object], ok: bool = True) -> Any:
    """``rplearn ARGS`` in this process (typer's ``CliRunner``, 400 columns); with ``ok``, assert
    that it succeeded (naming the arguments)."""
    from typer.testing import CliRunner

    from rplearn.cli import app

    res = CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
    if ok:
        assert res.exit_code == 0, f"{args}: {res.output}"
    return res


#: Per seed, the folder in which this process simulated, synced and fitted the smoke flight.
_SMOKE_FLIGHTS: dict[int, Path] = {}


def smoke_flight(d: Path, extra: Iterable[Sequence[str]] = (), seed: int = 2) -> Path:
    """Simulate the smoke flight into ``d``, sync it to :data:`D`, fit SH-3 to :data:`M`, then run ``extra``.

    The three commands run once per process (per xdist worker) and seed, in a folder of their
    own; each caller gets a copy of the files they wrote (the same seed writes the same flight),
    so that no test module reads what another one changed. ``extra`` runs in ``d``. All run in
    this process (:func:`invoke_in`): the tests run their own commands as a user's processes.
    """
    base = _SMOKE_FLIGHTS.get(seed)
    if base is None:
        base = Path(tempfile.mkdtemp(prefix=f"rplearn-smoke-{seed}-"))
        atexit.register(shutil.rmtree, base, True)
        _run_all(base, (["simulate", "--preset", "smoke", "--seed", str(seed), "-o", "flight"],
                        ["sync", "--poses", P, "--signals", S, "--link", "all", "-o", D],
                        ["fit", D, "--degree", "3", "-o", M]))
        _SMOKE_FLIGHTS[seed] = base
    shutil.copytree(base, d, dirs_exist_ok=True)
    _run_all(d, extra)
    return d


def _run_all(d: Path, commands: Iterable[Sequence[str]]) -> None:
    """Run each command in ``d`` (in this process: these make a test's inputs, and a process
    of its own would only add a second of start-up to each); assert that each succeeds."""
    for args in commands:
        invoke_in(d, args)


def invoke_in(d: Path | str, args: Sequence[object], ok: bool = True) -> Any:
    """:func:`invoke` with ``d`` as the working folder (relative paths in ``args`` are read and
    written there), for the commands that make a test's inputs."""
    import contextlib

    with contextlib.chdir(d):
        return invoke(args, ok)


def run_here(args: Sequence[object], cwd: Path | str, ok: bool = True) -> subprocess.CompletedProcess[str]:
    """``rplearn ARGS`` in ``cwd``, in this process, answered as :func:`run` answers (exit code,
    stdout and stderr apart): for the commands whose output a test reads, where a process of
    their own would only add its second of start-up. With ``ok``, assert that it succeeded.
    Refusals, whose exit code and stderr line are the point, stay :func:`run`. An exception that
    escaped the command is appended to stderr as the interpreter would print it (``Traceback``),
    so that a test's check for one holds in this process too."""
    import traceback

    res = invoke_in(cwd, args, ok=False)
    if ok:
        assert res.exit_code == 0, f"{args}: {res.output} {res.exception!r}"
    stderr = res.stderr
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        stderr += "".join(traceback.format_exception(res.exception))
    return subprocess.CompletedProcess([str(a) for a in args], res.exit_code, res.stdout, stderr)


def help_text(command: str) -> str:
    """What ``rplearn COMMAND --help`` prints, made in this process from the command that
    :func:`rplearn.cli.main` runs (typer's app as a click group with readable metavars, program
    name ``rplearn``): the same text as the user's process prints; assert that it exits 0."""
    import contextlib
    import io

    import typer

    from rplearn.cli import app
    from rplearn.cli._help import apply_readable_metavars

    # run as main() runs it, its standard output captured (no test runner: it would force its own
    # terminal width, and a fresh install has no click package beside typer's own)
    cmd = apply_readable_metavars(typer.main.get_command(app))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        try:
            cmd.main(args=[command, "--help"], prog_name="rplearn")
            code = 0
        except SystemExit as exc:
            code = exc.code
    assert code == 0, f"{command} --help: {out.getvalue()}"
    return out.getvalue()


def listing(folder: Path) -> list[str]:
    """Every name below ``folder``: a refused command must leave it as it was."""
    return sorted(p.name for p in folder.rglob("*"))


def assert_one_line_error(proc: subprocess.CompletedProcess[str], needle: str, case: str = "") -> None:
    """Exit 1, one ``error:`` line on stderr holding ``needle``, no traceback."""
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 1 and len(lines) == 1 and lines[0].startswith("error:"), (case, proc.stderr)
    assert needle in lines[0], (case, lines[0])
    assert "Traceback" not in proc.stderr


def digests(folder: Path) -> dict[str, str]:
    """Each file's SHA-256 below ``folder``: a refused command must leave every byte as it was."""
    import hashlib

    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}
