"""The typer application, the terminal output, and the parsing shared by every command module.

This is the only part of rplearn that knows flag names: library errors name the parameter at
fault (:attr:`rplearn.errors.RplearnError.param`), and :func:`with_flag` turns that into the
flag that sets it. Nothing printed here interprets user data as Rich markup.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import logging
import math
import os
import re
import signal
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import Any

import typer
from rich.console import Console
from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.text import Text
from typer.core import TyperGroup

from rplearn._version import __version__
from rplearn.cli._usage import usage_message
from rplearn.errors import BadValueError, InputError, RplearnError


def _is_usage_error(exc: BaseException) -> bool:
    """A click usage error (a bad value, an unknown flag or command, a missing argument), but not
    the help that ``rplearn`` alone prints (exit 2 too)."""
    names = {c.__name__ for c in type(exc).__mro__}
    return "UsageError" in names and "NoArgsIsHelpError" not in names


class OneLineUsageGroup(TyperGroup):
    """The command group whose usage errors, its own and its commands', are one line on standard
    error, ``error: --noise: 'abc' is not a number`` (:func:`rplearn.cli._usage.usage_message`),
    with click's exit code 2 (click prints the usage, a hint and the error on three lines)."""

    def make_context(self, info_name: str | None, args: list[str], parent: Any = None, **extra: Any) -> Any:
        try:
            return super().make_context(info_name, args, parent, **extra)
        except Exception as exc:
            _one_line_usage(exc)
            raise

    def invoke(self, ctx: Any) -> Any:
        try:
            return super().invoke(ctx)
        except Exception as exc:
            _one_line_usage(exc)
            raise


def _one_line_usage(exc: BaseException) -> None:
    """Print a usage error as one line and exit with code 2; anything else goes on."""
    if _is_usage_error(exc):
        console.print(Text.assemble(("error:", "bold red"), " ", usage_message(exc)), soft_wrap=True)
        raise typer.Exit(2) from None


app = typer.Typer(
    cls=OneLineUsageGroup,
    name="rplearn",
    help=(
        "Learn drone-with-antenna radiation patterns from calibration flights and predict links.\n\n"
        "Typical session:\n\n"
        "  rplearn simulate --preset smoke -o flight\n\n"
        "  rplearn sync --poses flight/pose_log.parquet --signals flight/signal_log.parquet --link A:B -o data.parquet\n\n"
        "  rplearn fit data.parquet --model sh --order 10 -o sh10.json\n\n"
        "  rplearn evaluate sh10.json data.parquet\n\n"
        "  rplearn demo -o rplearn-demo"
    ),
    no_args_is_help=True,
    add_completion=True,  # --install-completion / --show-completion for bash, zsh, fish, PowerShell
    rich_markup_mode=None,  # help texts carry units in brackets, e.g. [m/s], which markup would eat
    pretty_exceptions_enable=False,
)
console = Console(stderr=True)
out = Console(soft_wrap=True)

#: Library parameters and option fields (``RplearnError.param``) -> the flag that sets them,
#: where the command's own option of that name does not say it (see :func:`command_flag`).
PARAM_FLAGS: dict[str, str] = {
    "nodes": "--node FILE=NODE", "receivers": "--receiver FILE=NODE", "address_map": "--address MAC=NODE",
    "pose_topics": "--pose-topic TOPIC=NODE", "rssi_topics": "--rssi-topic TOPIC=TX:RX", "rssi_field": "--rssi-field",
    "msg_definitions": "--msg-definition TYPE=FILE.msg", "tx_power_dbm": "--tx-power DBM",
    "frequency_hz": "--frequency HZ", "nan_policy": "--nan-policy", "allow_unsorted": "--allow-unsorted",
    "require_valid": "--require-valid", "link": "--link TX:RX", "max_gap_s": "--max-gap",
    "clock_offsets_s": "--offset NODE=SECONDS", "on_unknown_node": "--on-unknown-node",
    "pattern_of": "--as DRONE=NODE", "times_s": "--at", "step_s": "--step", "positions": "--pos DRONE=X,Y,Z",
    "start_yaw_deg": "--yaw DRONE=DEG", "fixed": "--fixed", "turn": "--turn", "units": "--units",
    "test_units": "--test-units", "learn_units": "--learn-units", "order": "--order", "ridge": "--ridge",
    "sigma_rad2": "--sigma", "grid": "--grid", "gauge_node": "--gauge-node", "gauge_dbi": "--gauge-dbi", "prior": "--prior NODE=MODEL.json",
    "caution_z": "--caution", "n_draws": "--draws",
    "models": "--models", "paper_models": "--paper-models", "repeats": "--repeats", "orders": "--orders", "n_neighbors": "--order",
    "ground_level_m": "--ground-level", "relative_permittivity": "--permittivity",
    "path_loss": "--path-loss", "link_offsets": "--link-offsets",
    "station_geodetic": "--station LAT,LON,ALT", "station": "--station-node", "station_heading_deg": "--station-heading", "ulog_radio": "--ulog-radio",
}


def say(text: str) -> None:
    """Print a result line on standard output, verbatim (no markup, no highlighting)."""
    out.print(Text(text), soft_wrap=True)


def note(text: str, kind: str = "note") -> None:
    """Print a note or warning on standard error, verbatim."""
    console.print(Text(f"{kind}: {text}"), soft_wrap=True)


def fail(message: str, code: int = 1) -> None:
    """Print ``error: message`` on standard error and exit with ``code`` (1: an error in the input
    or the run; 2: a usage error)."""
    console.print(Text.assemble(("error:", "bold red"), " ", message), soft_wrap=True)
    raise typer.Exit(code)


class FlagError(Exception):
    """A flag's value that is none of its words or not of its form, refused while a command's
    options were built from its flags, before any input was read (:func:`flag_values`): a usage
    error, one line with exit code 2 (:func:`user_errors`).

    Parameters
    ----------
    error : BadValueError
        The error, its message and parameter as the library raised them.
    param : str, optional
        The parameter the error is about when the library's is another command's flag (e.g.
        ``paper_models`` for a model name of ``report --paper-models``, which the library checks
        as a ``model``).
    """

    def __init__(self, error: BadValueError, param: str | None = None) -> None:
        super().__init__(str(error))
        self.error = error
        self.param = param or error.param


@contextlib.contextmanager
def flag_values(param: str | None = None) -> Iterator[None]:
    """Mark a flag's value refused inside as a usage error (:class:`FlagError`: exit 2): wrap the
    parsing of flag values and the building of a command's options from its flags, before any
    input file is read. A value that is none of the flag's words or not of its form
    (:class:`rplearn.errors.BadValueError`) then exits 2, like click's own usage errors; any other
    error (a value out of its range or against another flag, an error in the input or the run)
    goes on to exit 1. ``param``: the parameter to name instead of the library's."""
    try:
        yield
    except BadValueError as exc:
        raise FlagError(exc, param) from exc


def command_flag(command: Callable | None, param: str) -> str | None:
    """The flag of the command's option named ``param`` (for parameters whose flag differs
    between commands, e.g. ``step_deg``: ``--step`` of headings, ``--step-deg`` of export)."""
    option = inspect.signature(command).parameters.get(param) if command is not None else None
    if option is None or not isinstance(option.default, typer.models.OptionInfo):
        return None
    decls = option.default.param_decls or (f"--{param.replace('_', '-')}",)
    return next((d.split("/")[0] for d in decls if d.startswith("--")), None)


def declared_flags(command: Callable | None) -> set[str] | None:
    """Every ``--flag`` the command declares (None: no command, any flag goes)."""
    if command is None:
        return None
    found: set[str] = set()
    for option in inspect.signature(command).parameters.values():
        if isinstance(option.default, typer.models.OptionInfo):
            decls = option.default.param_decls or (f"--{option.name.replace('_', '-')}",)
            for decl in decls:
                found.update(d for d in decl.split("/") if d.startswith("--"))
    return found


def flag_table(names: Iterable[str], command: Callable | None, flags: Mapping[str, str] | None) -> dict[str, str]:
    """Parameter name -> flag (with its metavar, e.g. ``--node FILE=NODE``) for the names the
    command can set: its own table, then :data:`PARAM_FLAGS`, then its option of that name."""
    declared = declared_flags(command)
    table = {}
    for name in names:
        flag = (flags or {}).get(name) or PARAM_FLAGS.get(name) or command_flag(command, name)
        if flag and (declared is None or flag.split()[0] in declared):
            table[name] = flag
    return table


def _rendered(flag: str, value: str | None) -> str:
    """A flag as the user types it, for a field ``name`` (None), ``name=True``, ``name='x'``,
    ``name=1.5`` or ``name={...}``: the flag with its metavar, alone, with the value, with the
    number, with its metavar."""
    name = flag.split()[0]
    if value == "True":
        return name
    if value and value[0] in "'\"" and value[-1] == value[0]:
        return f"{name} {value[1:-1]}"
    if value and re.fullmatch(r"[-+]?\d+(\.\d*)?([eE][-+]?\d+)?", value):  # a number: as the user types it
        return f"{name} {value}"
    return flag


def with_flag(
    message: str,
    param: str | None,
    command: Callable | None = None,
    flags: Mapping[str, str] | None = None,
    related: Iterable[str] = (),
) -> str:
    """The message with the flags that set the parameters it names.

    Library messages name parameters as ``"name: ..."`` or ``"name, other: ..."`` at the
    start, ``"name ..."`` at the start, ``"(name ...)"``, or as option fields
    ``ReaderOptions.name`` / ``name=value``; ``related`` are more parameter names the message
    uses (:attr:`rplearn.errors.RplearnError.related`), replaced wherever they stand as words.
    Only flags the command declares are used. When the message does not name the flag of
    ``param``, it is appended.
    """
    head, sep, rest = message.partition(":")
    leading = [n.strip() for n in head.split(",")] if sep else []
    candidates = {n for n in leading if n.isidentifier()} | set(related) | set(flags or {}) | ({param} if param else set())
    fields = set(re.findall(r"(?:\b\w+Options\.)(\w+)|\b(\w+)=", message))
    candidates |= {a or b for a, b in fields}
    table = flag_table(sorted(candidates), command, flags)
    if leading and all(n in table for n in leading):
        message = ", ".join(table[n].split()[0] for n in leading) + sep + rest
    for name, flag in table.items():
        value = r"(?:=('[^']*'|\"[^\"]*\"|\{[^}]*\}|[^,)\s]+))?"
        message = re.sub(rf"\b\w+Options\.{name}\b{value}", lambda m: _rendered(flag, m.group(1)), message)  # noqa: B023 (used at once)
        message = re.sub(rf"(?<![\w.-]){name}=('[^']*'|\"[^\"]*\"|\{{[^}}]*\}}|[^,)\s]+)", lambda m: _rendered(flag, m.group(1)), message)  # noqa: B023
        message = re.sub(rf"(^|\()({name})(?=[:) ]|$)", lambda m: m.group(1) + flag.split()[0], message)  # noqa: B023
        if name in related:
            message = re.sub(rf"(?<![\w.-]){name}(?![\w=])", flag.split()[0], message)
    param_flag = table.get(param or "")
    if param_flag is None or param_flag.split()[0] in message:
        return message
    return f"{message} (set it with {param_flag})"


def user_errors(fn: Callable | None = None, *, flags: Mapping[str, str] | None = None) -> Callable:
    """Turn user mistakes into one line on stderr: exit code 1 for an error in the input or the
    run, 2 for a flag's value refused before any input was read (:func:`flag_values`), 130 for
    Ctrl-C.

    ``flags`` maps the library parameters of this command whose flag has another name
    (e.g. ``{"n_loops": "--loops"}``).
    """

    def decorate(func: Callable) -> Callable:
        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            try:
                return func(*args, **kwargs)
            except FlagError as flag:
                exc = flag.error
                first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                fail(with_flag(first, flag.param, func, flags, exc.related), 2)
            except RplearnError as exc:
                first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                fail(with_flag(first, exc.param, func, flags, exc.related))
            except FileNotFoundError as exc:
                fail(f"{exc.filename}: no such file or directory" if exc.filename else str(exc))
            except OSError as exc:
                fail(f"{exc.filename}: {exc.strerror or exc}" if exc.filename else str(exc))
            except KeyboardInterrupt:  # Ctrl-C: a partial output was removed on the way out (rplearn._atomic)
                from rplearn._atomic import written_outputs

                done = written_outputs()
                what = f"{', '.join(done)} written whole before it" if done else "nothing was written"
                console.print(Text.assemble(("error:", "bold red"), f" interrupted (Ctrl-C); {what}"), soft_wrap=True)
                raise typer.Exit(130) from None

        return wrapper

    return decorate(fn) if fn is not None else decorate


def progress_bar() -> Progress:
    """Rich progress on a terminal; nothing when standard error is not one (see :func:`step`)."""
    return Progress(
        SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), console=console, transient=True,
        disable=not console.is_terminal,
    )


def step(progress: Progress, task: Any) -> Callable[[str], None]:
    """Progress callback: updates the bar on a terminal, prints a plain line otherwise."""

    def report(message: str) -> None:
        if console.is_terminal:
            progress.update(task, description=Text(message))  # type: ignore[arg-type]  # rich renders a Text as is (no markup)
        else:
            console.print(Text(f"... {message}"), soft_wrap=True)

    return report


def parts_step(progress: Progress, task: Any, what: str, noun: str = "part") -> Callable[[int, int], None]:
    """Progress callback ``(parts done, parts)`` of work over a dataset's files: the bar on a
    terminal, otherwise a plain line at every tenth of the parts."""

    def report(done: int, total: int) -> None:
        if console.is_terminal:
            progress.update(task, description=Text(f"{what}: {done:,} of {total:,} {noun}(s)"))  # type: ignore[arg-type]  # as above
        elif total > 1 and (done == total or done % max(total // 10, 1) == 0):
            console.print(Text(f"... {what}: {done:,} of {total:,} {noun}(s)"), soft_wrap=True)

    return report


# -------------------------------------------------------------------------------------------
# Parsing flag values


def split_list(values: list[str] | None) -> list[str] | None:
    """Values of a repeatable, comma-separable flag (None when none given)."""
    if not values:
        return None
    items = [v.strip() for value in values for v in value.split(",") if v.strip()]
    return items or None


def pairs(values: list[str] | None, flag: str) -> dict[str, str]:
    """KEY=VALUE values of a repeatable flag; a key given twice with different values is refused."""
    found: dict[str, str] = {}
    for v in values or []:
        if "=" not in v:
            raise BadValueError(f"{flag}: expected KEY=VALUE, got {v!r}")
        k, val = (part.strip() for part in v.split("=", 1))
        if not k or not val:
            raise BadValueError(f"{flag}: expected KEY=VALUE, got {v!r} (no {'key' if not k else 'value'})")
        if k in found and found[k] != val:
            raise InputError(f"{flag}: {k} is given twice, as {found[k]} and as {val}")
        found[k] = val
    return found


def numbers(values: Mapping[str, str], flag: str, what: str) -> dict[str, float]:
    """KEY=NUMBER pairs as floats."""
    try:
        return {k: float(v) for k, v in values.items()}
    except ValueError:
        given = ", ".join(f"{k}={v}" for k, v in values.items())
        raise BadValueError(f"{flag}: expected {what} with a number, got {given}") from None


def floats(values: list[str] | None, flag: str, what: str) -> list[float] | None:
    """Numbers of a repeatable, comma-separable flag (None when none given)."""
    items = split_list(values)
    if items is None:
        return None
    try:
        return [float(v) for v in items]
    except ValueError:
        raise BadValueError(f"{flag}: expected {what}, got {', '.join(items)}") from None


def xyz(text: str, flag: str) -> list[float]:
    """``x,y,z`` in metres."""
    try:
        v = [float(t) for t in text.split(",")]
    except ValueError:
        v = []
    if len(v) != 3:
        raise BadValueError(f"{flag}: expected x,y,z in metres, got {text!r}")
    if not all(math.isfinite(c) for c in v):  # nan/inf parse as floats: no place
        raise InputError(f"{flag}: expected three finite numbers x,y,z in metres, got {text!r}")
    return v


def link(text: str | None) -> tuple[str, str] | None:
    """``TX:RX`` of ``--link`` (None for 'all' or when not given)."""
    if text is None or text.lower() == "all":
        return None
    parts = text.split(":")
    if len(parts) != 2 or not all(parts):
        raise BadValueError(f"--link: expected TX:RX (e.g. A:B) or 'all', got {text!r}")
    return parts[0], parts[1]


def orders(text: str) -> Sequence[int]:
    """Model orders ``A..B`` (a ``range``, never made into a list: ``1..100000000`` is refused by
    the samples, not by listing it) or ``3,5,8`` of ``--orders``."""
    try:
        if ".." in text:
            a, b = text.split("..", 1)
            found: Sequence[int] = range(int(a), int(b) + 1)
        else:
            found = [int(v) for v in text.split(",")]
    except ValueError:
        raise BadValueError(f"--orders: expected A..B or a comma list, got {text!r}") from None
    if not found or (found[0] if isinstance(found, range) else min(found)) < 1:
        raise InputError(f"--orders: expected positive orders, A..B with A <= B, got {text!r}")
    return found


def geodetic_flag(text: str | None, flag: str) -> tuple[float, ...] | None:
    """``LAT,LON,ALT`` [deg, deg, m] as three numbers (checked further by ReaderOptions), or None."""
    if text is None:
        return None
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3:
        raise BadValueError(f"{flag}: expected LAT,LON,ALT (e.g. 41.185,-96.010,330), got {text!r}")
    return values


def reader_options(
    node: list[str] | None = None, receiver: list[str] | None = None, address: list[str] | None = None,
    pose_topic: list[str] | None = None, rssi_topic: list[str] | None = None, rssi_field: str | None = None,
    msg_definition: list[str] | None = None, **fields: Any,
) -> Any:
    """:class:`rplearn.io.ReaderOptions` from the reader flags.

    ``rssi_topic`` holds TOPIC=TX:RX; ``fields`` (other ReaderOptions fields:
    ``tx_power_dbm``, ``frequency_hz``, ``nan_policy``, ``allow_unsorted``,
    ``require_valid``) are passed on when not None.
    """
    from rplearn.io import ReaderOptions

    opts: dict[str, Any] = {}
    for flag, key, values in (
        ("--node", "nodes", node),
        ("--receiver", "receivers", receiver),
        ("--address", "address_map", address),
        ("--pose-topic", "pose_topics", pose_topic),
        ("--msg-definition", "msg_definitions", msg_definition),
    ):
        if values:
            opts[key] = pairs(values, flag)
    if rssi_topic:
        topics: dict[str, tuple[str, str]] = {}
        for topic, ends in pairs(rssi_topic, "--rssi-topic").items():
            parts = ends.split(":")
            if len(parts) != 2 or not all(p.strip() for p in parts):
                raise BadValueError(f"--rssi-topic: expected TOPIC=TX:RX (e.g. /B/rssi=A:B), got {topic}={ends}")
            topics[topic] = (parts[0].strip(), parts[1].strip())
        opts["rssi_topics"] = topics
    if rssi_field:
        opts["rssi_field"] = rssi_field
    opts.update({k: v for k, v in fields.items() if v is not None})
    return ReaderOptions(**opts)


def exit_on_sigterm() -> None:
    """Turn SIGTERM (a job scheduler stopping the run) into a normal exit, so that a file being
    written is removed and the previous one kept (:mod:`rplearn._atomic`)."""

    def handler(signum: int, frame: Any) -> None:
        raise SystemExit(128 + signum)

    signal.signal(signal.SIGTERM, handler)


def print_version(value: bool) -> None:
    if value:
        say(f"rplearn {__version__}")
        raise typer.Exit(0)


@app.callback()
def main_callback(
    verbose: bool = typer.Option(False, "--verbose", "-v", help="Log progress details."),
    version: bool = typer.Option(
        False, "--version", help="Print the version and exit.", callback=print_version, is_eager=True
    ),
) -> None:
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    if os.environ.get("SOURCE_DATE_EPOCH"):  # checked once for every output (model files, figures' metadata)
        from rplearn.io.files import source_date_epoch

        try:
            source_date_epoch()
        except RplearnError as exc:
            fail(str(exc))
