"""The ``rplearn`` command line: one small module per command group, each command parsing its
flags, calling one library function and printing the result object it returns.

- :mod:`~rplearn.cli.campaign`: ``trajectory``, ``simulate``
- :mod:`~rplearn.cli.logs`: ``inspect``, ``sync``
- :mod:`~rplearn.cli.learning`: ``fit``, ``evaluate``, ``predict``, ``sweep``, ``report``
- :mod:`~rplearn.cli.live`: ``live``, ``replay``
- :mod:`~rplearn.cli.swarm`: ``links``, ``headings``, ``orient``
- :mod:`~rplearn.cli.outputs`: ``export``, ``plot``, ``demo``

Every user error (a subclass of :class:`rplearn.errors.RplearnError`, a missing file) prints one
line ``error: ...`` on standard error, naming the flag to change where the library names the
parameter at fault, and exits with code 1, without a traceback; a usage error (a bad number, an
unknown flag, a missing argument, a flag's value that is none of its words or not of its form) is
one line too, naming the flag and the value, exit code 2 (:mod:`rplearn.cli._usage`,
:func:`rplearn.cli._app.flag_values`); Ctrl-C exits with code 130.
"""

from __future__ import annotations

# Importing a command module registers its commands; --help lists them in this order, the
# order of a calibration campaign.
from rplearn.cli import (
    campaign,  # noqa: E402,F401,I001
    learning,  # noqa: E402,F401
    live,  # noqa: E402,F401
    logs,  # noqa: E402,F401
    outputs,  # noqa: E402,F401
    swarm,  # noqa: E402,F401
)
from rplearn.cli._app import app, exit_on_sigterm

__all__ = ["app", "main"]


def main() -> None:
    """Entry point of the ``rplearn`` script (and of ``python -m rplearn``): the typer app as a
    click group, with readable metavars (:mod:`rplearn.cli._help`)."""
    import typer

    from rplearn.cli._help import apply_readable_metavars

    exit_on_sigterm()
    try:
        apply_readable_metavars(typer.main.get_command(app))(prog_name="rplearn")
    finally:  # the command is over (its outputs written or removed): a late Ctrl-C must not interrupt the shutdown
        import signal

        signal.signal(signal.SIGINT, signal.SIG_IGN)
