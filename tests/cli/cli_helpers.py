"""What the command-line tests share: running ``rplearn`` as a user does, a smoke flight, and the
check that a refused command says one line and writes nothing.

Imported by the test modules of this folder (pytest puts the folder on ``sys.path``).
"""

from __future__ import annotations

import atexit
import contextlib
import io
import os
import shutil
import subprocess
import sys
import tempfile
import warnings
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

#: The command line a user types, with this interpreter.
RPLEARN = [sys.executable, "-m", "rplearn.cli"]
#: The smoke flight's files, relative to the working folder.
P, S, D, M = "flight/pose_log.parquet", "flight/signal_log.parquet", "data.parquet", "sh3.json"
#: A real telemetry log: ArduPilot with a SiK radio at 915 MHz, a ground station ``gcs`` and a
#: drone ``sys1``, one reading a second each way.
REAL_TLOG = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_16-58-51.tlog"


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


def real_log_fit(d: Path) -> Path:
    """Sync :data:`REAL_TLOG` in ``d`` to ``m.parquet`` (every link, 20 dBm at 915 MHz) and fit it
    with ``--order auto`` to ``earlier.json``, each command as :func:`run_here` runs it: ``d``."""
    run_here(["sync", "--poses", REAL_TLOG, "--signals", REAL_TLOG, "--tx-power", "20", "--frequency", "915e6",
              "--link", "all", "-o", "m.parquet"], d)
    run_here(["fit", "m.parquet", "--order", "auto", "-o", "earlier.json"], d)
    return d


def _run_all(d: Path, commands: Iterable[Sequence[str]]) -> None:
    """Run each command in ``d`` (in this process: these make a test's inputs, and a process
    of its own would only add a second of start-up to each); assert that each succeeds."""
    for args in commands:
        invoke_in(d, args)


def invoke_in(d: Path | str, args: Sequence[object], ok: bool = True) -> Any:
    """:func:`invoke` with ``d`` as the working folder (relative paths in ``args`` are read and
    written there), for the commands that make a test's inputs."""
    with contextlib.chdir(d):
        return invoke(args, ok)


def run_here(args: Sequence[object], cwd: Path | str, ok: bool = True, *,
             env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """``rplearn ARGS`` in ``cwd``, in this process, answered as :func:`run` answers: the exit
    code, standard output and standard error of the user's process, apart. With ``ok``, assert
    that it succeeded. ``env``: variables added to this process's for the command (``os.environ``
    is restored after it).

    It runs the command as :func:`rplearn.cli.main` does (typer's app as a click group with
    readable metavars, program name ``rplearn``, ``sys.argv`` of ``python -m rplearn.cli``) and
    gives it what a fresh ``python -m rplearn.cli`` has where a test can tell:

    - standard output and error of its own, neither a terminal, its text decoded as
      ``subprocess.run(text=True)`` decodes a pipe; an empty standard input;
    - Python warnings shown on that standard error under a fresh interpreter's filters
      (:data:`FRESH_WARNING_FILTERS`, with ``PYTHONWARNINGS`` from the environment), the
      once-per-location registries reset (pytest's own filters and recorder set aside);
    - the root logger without handlers, as ``logging.basicConfig`` of the command finds it in a
      fresh process (so its warnings reach that standard error), every logger's level restored after;
    - the outputs written so far (:func:`rplearn._atomic.written_outputs`) empty, as at start-up;
    - an exception escaping the command printed as the interpreter prints it (``Traceback``) and
      exit code 1, as Python exits;
    - what C code writes to file descriptors 1 and 2 (a library's ``printf``) read too, after
      what Python wrote.

    What stays a process of its own (:func:`run`): the order of Python's and C's writes, signals
    and Ctrl-C, kills, ``python -m``, start-up and import-time behaviour, dask clusters, several
    processes at once.
    """
    res = _in_process([str(a) for a in args], Path(cwd), env or {})
    if ok:
        assert res.returncode == 0, f"{args}: {res.stdout} {res.stderr}"
    return res


def answer(args: Sequence[object], cwd: Path | str, process: bool = False,
           env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """What ``rplearn ARGS`` answers in ``cwd`` (exit code, stdout, stderr; not asserted): from a
    process of its own with ``process`` (:func:`run`), else from this one (:func:`run_here`, the
    same answer without a second of start-up). Each module that runs refusals keeps one in a process."""
    if process:
        return run([str(a) for a in args], cwd, env)
    return run_here(args, cwd, ok=False, env=env)


#: The warning filters of a fresh ``python -m rplearn.cli`` (no ``-W``, no ``PYTHONWARNINGS``,
#: no development mode), after rplearn's imports: CPython's defaults, rplearn installs none
#: (tests/cli/test_cli_in_process.py compares them with a fresh interpreter's).
FRESH_WARNING_FILTERS: list[tuple[Any, ...]] = [
    ("default", None, DeprecationWarning, "__main__", 0),
    ("ignore", None, DeprecationWarning, None, 0),
    ("ignore", None, PendingDeprecationWarning, None, 0),
    ("ignore", None, ImportWarning, None, 0),
    ("ignore", None, ResourceWarning, None, 0),
]


def _pipe() -> io.TextIOWrapper:
    """A text stream as a process's standard output or error into a pipe (UTF-8, not a terminal)."""
    return io.TextIOWrapper(io.BytesIO(), encoding="utf-8", errors="backslashreplace", write_through=True)


def _piped_text(stream: io.TextIOWrapper) -> str:
    """What ``subprocess.run(text=True)`` reads from the pipe (universal newlines)."""
    stream.flush()
    data = stream.buffer.getvalue()  # type: ignore[attr-defined]
    return data.decode("utf-8", errors="replace").replace("\r\n", "\n").replace("\r", "\n")


def _show_warning(message: Any, category: type[Warning], filename: str, lineno: int,
                  file: Any = None, line: str | None = None) -> None:
    """:func:`warnings.showwarning` of a fresh interpreter: the formatted warning on ``sys.stderr``."""
    (file or sys.stderr).write(warnings.formatwarning(message, category, filename, lineno, line))


@contextlib.contextmanager
def _fresh_process_state(argv: list[str], cwd: Path, env: dict[str, str]) -> Iterator[tuple[io.TextIOWrapper, io.TextIOWrapper]]:
    """This process made to look, to a command, as a fresh ``python -m rplearn.cli ARGV`` in
    ``cwd`` with ``env`` added (see :func:`run_here`); everything put back on exit."""
    import logging

    import rplearn.cli
    from rplearn import _atomic
    from rplearn.cli import _app

    stdout, stderr = _pipe(), _pipe()
    stdin = io.TextIOWrapper(io.BytesIO(b""), encoding="utf-8")
    saved_environ = dict(os.environ)
    saved_argv = sys.argv
    saved_written = list(_atomic._WRITTEN)
    saved_once = dict(warnings.onceregistry)
    root = logging.getLogger()
    saved_root = (root.handlers[:], root.level, root.disabled)
    loggers = [root, *(lg for lg in logging.Logger.manager.loggerDict.values() if isinstance(lg, logging.Logger))]
    saved_levels = [(lg, lg.level) for lg in loggers]
    consoles = [(c, c._color_system) for c in (_app.console, _app.out)]
    with contextlib.ExitStack() as stack:
        stack.callback(os.environ.update, saved_environ)
        stack.callback(lambda: [os.environ.pop(k) for k in set(os.environ) - set(saved_environ)])
        stack.enter_context(contextlib.chdir(cwd))
        stack.enter_context(warnings.catch_warnings())
        try:
            os.environ.update(env)
            sys.argv = [os.path.join(os.path.dirname(rplearn.cli.__file__), "__main__.py"), *argv]
            _atomic._WRITTEN.clear()
            warnings.onceregistry.clear()
            warnings.filters[:] = FRESH_WARNING_FILTERS
            if os.environ.get("PYTHONWARNINGS"):
                warnings._processoptions(os.environ["PYTHONWARNINGS"].split(","))  # type: ignore[attr-defined]
            warnings._filters_mutated()  # type: ignore[attr-defined]  # every module's once-per-location registry is stale
            warnings.showwarning = _show_warning
            root.handlers, root.disabled = [], False
            root.setLevel(logging.WARNING)
            with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
                saved_stdin, sys.stdin = sys.stdin, stdin
                try:
                    for console, _ in consoles:  # a terminal or not, colours or not: as a fresh process detects them
                        console._color_system = console._detect_color_system()
                    yield stdout, stderr
                finally:
                    sys.stdin = saved_stdin
        finally:
            for handler in root.handlers:
                if handler not in saved_root[0]:
                    handler.close()
            root.handlers, root.disabled = saved_root[0], saved_root[2]
            root.setLevel(saved_root[1])
            for logger, level in saved_levels:
                logger.setLevel(level)
            for console, color_system in consoles:
                console._color_system = color_system
            _atomic._WRITTEN[:] = saved_written
            warnings.onceregistry.clear()
            warnings.onceregistry.update(saved_once)
            sys.argv = saved_argv


@contextlib.contextmanager
def _descriptors_captured() -> Iterator[dict[int, str]]:
    """What is written to file descriptors 1 and 2 inside the block (C libraries write there,
    past ``sys.stdout``): yields a dict that holds, on exit, each descriptor's text as
    ``subprocess.run(text=True)`` reads it."""
    import ctypes

    def flush_c_stdio() -> None:
        with contextlib.suppress(OSError, AttributeError, TypeError):
            ctypes.CDLL(None).fflush(None)

    found: dict[int, str] = {}
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        flush_c_stdio()
        saved = [(fd, os.dup(fd)) for fd in (1, 2)]
        try:
            os.dup2(out.fileno(), 1)
            os.dup2(err.fileno(), 2)
            yield found
        finally:
            flush_c_stdio()
            for fd, copy in saved:
                os.dup2(copy, fd)
                os.close(copy)
            for fd, sink in ((1, out), (2, err)):
                sink.seek(0)
                found[fd] = sink.read().decode("utf-8", errors="replace").replace("\r\n", "\n").replace("\r", "\n")


def _in_process(argv: list[str], cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """Run ``rplearn ARGV`` as :func:`rplearn.cli.main` runs it, in :func:`_fresh_process_state`;
    what reached the file descriptors themselves follows what Python wrote (a process would
    interleave them: the tests read lines and counts, not that order)."""
    import traceback

    import typer

    from rplearn.cli import app
    from rplearn.cli._help import apply_readable_metavars

    with _descriptors_captured() as raw, _fresh_process_state(argv, cwd, env) as (stdout, stderr):
        try:
            apply_readable_metavars(typer.main.get_command(app))(args=argv, prog_name="rplearn")
            code: Any = 0
        except SystemExit as exc:
            code = exc.code
        except Exception as exc:  # noqa: BLE001 - what would escape main(): the interpreter prints it, exits 1
            sys.stderr.write("".join(traceback.format_exception(exc)))
            code = 1
        if code is None:
            code = 0
        elif not isinstance(code, int):  # sys.exit("text"): the text on stderr, exit 1
            sys.stderr.write(f"{code}\n")
            code = 1
        out_text, err_text = _piped_text(stdout), _piped_text(stderr)
    return subprocess.CompletedProcess(["rplearn", *argv], code, out_text + raw[1], err_text + raw[2])


def help_text(command: str) -> str:
    """What ``rplearn COMMAND --help`` prints, made in this process from the command that
    :func:`rplearn.cli.main` runs (typer's app as a click group with readable metavars, program
    name ``rplearn``): the same text as the user's process prints; assert that it exits 0."""
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
