"""The fields the MAVLink and DataFlash readers rely on, checked where they are read, and the
noise pymavlink prints kept off the terminal (for :mod:`rplearn.io._mavlink_records`).

A DataFlash log declares each message's fields in an ``FMT`` record (binary: its length in
bytes, a struct format, the column names; text: the same as a line). pymavlink trusts those
declarations: a column the reader needs and the FMT does not declare is an ``AttributeError``
from inside pymavlink, a value that is not a number (text logs) a ``ValueError``, and an FMT
whose declared length disagrees with its format makes pymavlink (and its C indexer) print one
line per byte it cannot frame. Here every field is read through :func:`number`, every message
type is checked against :data:`DATAFLASH_FIELDS` on its first record
(:func:`dataflash_time_field`), every FMT length against its format
(:func:`check_dataflash_lengths`), and :func:`library_quiet` holds both file descriptors 1 and 2
while pymavlink runs, so that what reaches the user is one :class:`LogFormatError` naming the
file, the message and the field.
"""

from __future__ import annotations

import contextlib
import math
import os
import struct
import sys
import threading
from collections.abc import Iterator
from typing import Any

from rplearn.errors import LogFormatError

#: The fields the DataFlash reader reads from each message (besides its time, TimeUS or TimeMS).
DATAFLASH_FIELDS: dict[str, tuple[str, ...]] = {
    "ATT": ("Roll", "Pitch", "Yaw"),
    "POS": ("Lat", "Lng", "Alt"),
    "GPS": ("Status", "Lat", "Lng", "Alt"),
    "RAD": ("RSSI", "RemRSSI", "Noise", "RemNoise", "RxErrors", "Fixed"),
    "ORGN": ("Type", "Lat", "Lng", "Alt"),
    "ARM": ("ArmState",),
    "EV": ("Id",),
}
#: A DataFlash message's time: microseconds since boot, or milliseconds in older logs.
TIME_FIELDS: tuple[tuple[str, float], ...] = (("TimeUS", 1e-6), ("TimeMS", 1e-3))

_QUIET = threading.Lock()


def _flush_c_stdio() -> None:
    """Flush the C library's stdio buffers (pymavlink's C indexer prints with them)."""
    try:
        import ctypes

        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):  # pragma: no cover - a platform without a C library handle
        pass


@contextlib.contextmanager
def library_quiet() -> Iterator[None]:
    """Send what a library prints (Python ``print`` and C ``printf``, to stdout or stderr) to
    the null device while the block runs (a corrupt log makes pymavlink print a line per byte)."""
    with _QUIET, open(os.devnull, "wb") as sink, open(os.devnull, "w", encoding="utf-8") as text:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(AttributeError, OSError, ValueError):
                stream.flush()
        saved: list[tuple[int, int]] = []
        try:
            for fd in (1, 2):
                with contextlib.suppress(OSError):
                    saved.append((fd, os.dup(fd)))
                    os.dup2(sink.fileno(), fd)
            with contextlib.redirect_stdout(text), contextlib.redirect_stderr(text):
                yield
        finally:
            _flush_c_stdio()
            for fd, copy in saved:
                os.dup2(copy, fd)
                os.close(copy)


def check_dataflash_lengths(conn: Any, source: str) -> None:
    """Refuse a binary DataFlash log one of whose ``FMT`` records declares a length that is not
    its format's (3 header bytes + the struct size): its records cannot be framed."""
    if not hasattr(conn, "data_map"):  # a text log has no lengths to frame by
        return
    for fmt in list(getattr(conn, "formats", {}).values()):
        try:
            need = 3 + struct.calcsize(fmt.msg_struct)
        except (struct.error, AttributeError, TypeError):
            raise LogFormatError(f"{source}: the FMT of {fmt.name} declares an unreadable format {getattr(fmt, 'format', '?')!r}") from None
        if int(fmt.len) != need:
            raise LogFormatError(
                f"{source}: the FMT of {fmt.name} declares a length of {int(fmt.len)} bytes, its format {fmt.format!r} takes {need}: its records cannot be read"
            )


def dataflash_time_field(msg: Any, kind: str, source: str) -> tuple[str, float]:
    """The time field of a DataFlash message type and its unit [s], after checking that its
    ``FMT`` declares every field in :data:`DATAFLASH_FIELDS` (one line naming the first missing
    one, the message and the file)."""
    columns = list(getattr(getattr(msg, "fmt", None), "columns", None) or msg.get_fieldnames())
    time = next(((name, unit) for name, unit in TIME_FIELDS if name in columns), None)
    if time is None:
        raise LogFormatError(
            f"{source}: {kind} messages have no TimeUS (nor TimeMS) field (its FMT declares {','.join(columns) or 'no fields'}): their time is unknown"
        )
    for name in DATAFLASH_FIELDS.get(kind, ()):
        if name not in columns:
            raise LogFormatError(
                f"{source}: {kind} messages have no {name} field (its FMT declares {','.join(columns)}): the reader needs {', '.join(DATAFLASH_FIELDS[kind])}"
            )
    return time


def number(msg: Any, kind: str, name: str, source: str, default: float | None = None) -> float:
    """Field ``name`` of a message as a float: a missing field (unless ``default`` is given) or
    a value that is not a number is a :class:`LogFormatError` naming the message, field and file."""
    try:
        value = getattr(msg, name)
    except AttributeError:
        if default is not None:
            return default
        raise LogFormatError(f"{source}: a {kind} message has no {name} field") from None
    except (ValueError, TypeError, IndexError, struct.error) as exc:
        raise LogFormatError(f"{source}: {kind} field {name} is not a number ({exc})") from None
    try:
        out = float(value)
    except (TypeError, ValueError, OverflowError):
        raise LogFormatError(f"{source}: {kind} field {name} is not a number ({value!r})") from None
    if math.isinf(out) and name in ("TimeUS", "TimeMS"):
        raise LogFormatError(f"{source}: {kind} field {name} is not a time ({value!r})")
    return out


__all__ = ["DATAFLASH_FIELDS", "TIME_FIELDS", "check_dataflash_lengths", "dataflash_time_field", "library_quiet", "number"]
