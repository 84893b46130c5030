"""The one write path of rplearn: every file is written whole or not at all.

:func:`check_output` refuses, before any work, an output that is one of the command's inputs
(the same file after resolving links), that exists but is not a regular file (a folder, a
device such as ``/dev/full``), or whose folder does not exist (outputs never create their
folder, except output *directories* the caller creates on purpose). :func:`atomic_path` then
yields a unique temporary name beside the output; when the block succeeds the file is flushed to
disk (``fsync``) and renamed over the output (``os.replace``, atomic on POSIX), and on any
failure the temporary file is removed, so that the previous output stays intact and no partial
file is ever seen, even with concurrent writers of the same output.

This module is at the bottom of the layers (standard library only), so that every layer that
writes (data, io, plan, sim, viz, workflows) writes through it.
"""

from __future__ import annotations

import json
import math
import os
import stat
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from typing import IO, Any

from rplearn.errors import InputError

__all__ = ["atomic_open", "atomic_path", "check_output", "dump_json", "strict_json", "written_outputs"]

PathLike = str | os.PathLike[str]


def _same_file(a: str, b: str) -> bool:
    """Whether two paths name one file (after links; also for files that do not exist yet)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def _inside(path: str, folder: str) -> bool:
    """Whether ``path`` lies below ``folder`` (symbolic links resolved)."""
    try:
        return os.path.commonpath([os.path.realpath(path), os.path.realpath(folder)]) == os.path.realpath(folder)
    except ValueError:  # different drives
        return False


def check_output(path: PathLike, inputs: Iterable[PathLike] = (), param: str | None = None) -> str:
    """Refuse an output path before any work is done; return it as a string.

    Parameters
    ----------
    path : path
        File to be written.
    inputs : iterable of paths
        The files the command reads; the output may be none of them.
    param : str, optional
        Name of the parameter that gave ``path``, for the error.

    Raises
    ------
    InputError
        When ``path`` is an input, exists but is not a regular file, or its folder is missing.
    """
    name = os.fspath(path)
    for source in inputs:
        if source is not None and _same_file(name, os.fspath(source)):
            spelled = "" if os.fspath(source) == name else f" ({os.fspath(source)})"
            raise InputError(f"{name}: is also an input of this command{spelled}; write the output elsewhere", param=param)
        if source is not None and os.path.isdir(os.fspath(source)) and _inside(name, os.fspath(source)):
            raise InputError(f"{name}: is inside {os.fspath(source)}, a dataset folder this command reads (the file "
                             "would join the dataset); write the output elsewhere", param=param)
    if os.path.lexists(name):
        mode = os.stat(name).st_mode if os.path.exists(name) else 0
        if not stat.S_ISREG(mode):
            kind = "a directory" if stat.S_ISDIR(mode) else "not a regular file"
            raise InputError(f"{name}: is {kind}; give a file name to write", param=param)
    folder = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(folder):
        raise InputError(f"{name}: cannot write into a non-existent directory {folder}", param=param)
    return name


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _fsync_dir(folder: str) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


#: Every output this process has written (replaced) so far, in order: what an interrupted
#: command did leave behind (:func:`written_outputs`).
_WRITTEN: list[str] = []


def written_outputs() -> tuple[str, ...]:
    """The outputs this process has written so far (each replaced whole by :func:`atomic_path`)."""
    return tuple(dict.fromkeys(_WRITTEN))


@contextmanager
def atomic_path(path: PathLike, inputs: Iterable[PathLike] = (), param: str | None = None) -> Iterator[str]:
    """Yield a temporary path beside ``path`` to write; replace ``path`` with it on success.

    The temporary name ends with the output's own name, so that writers that choose a format
    by extension (``.csv.gz``, ``.parquet``, ``.png``) choose the same one. An ``OSError`` on
    the temporary file (a full disk, a folder that takes no files) is raised naming ``path``. The file gets the
    permissions a new file would (``0666 & ~umask``), or those of the file it replaces.
    """
    name = check_output(path, inputs, param)
    folder, base = os.path.split(os.path.abspath(name))
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".rplearn-", suffix=f"-{base}")
    except OSError as exc:
        raise InputError(f"{name}: cannot create a file in {folder} ({exc.strerror})", param=param) from None
    os.close(fd)
    try:
        try:
            yield tmp
        except OSError as exc:
            if exc.filename is not None and os.fspath(exc.filename) != tmp:
                raise
            # a write to the temporary file failed: name the output, not the temporary file
            raise OSError(exc.errno, f"cannot write ({exc.strerror or exc})", name) from None
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        mode = stat.S_IMODE(os.stat(name).st_mode) if os.path.isfile(name) else 0o666 & ~_umask()
        os.chmod(tmp, mode)
        os.replace(tmp, name)
        _WRITTEN.append(name)
        _fsync_dir(folder)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


@contextmanager
def atomic_open(
    path: PathLike, mode: str = "w", inputs: Iterable[PathLike] = (), param: str | None = None, **kwargs: Any
) -> Iterator[IO[Any]]:
    """:func:`open` for writing through :func:`atomic_path` (``mode`` ``"w"`` or ``"wb"``)."""
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open: mode must be 'w' or 'wb', got {mode!r}")
    with atomic_path(path, inputs, param) as tmp:
        with open(tmp, mode, **kwargs) as fh:
            yield fh


# -- strict JSON ---------------------------------------------------------------------------
def strict_json(value: Any) -> Any:
    """``value`` made strict JSON: a non-finite float (NaN, +-Infinity) becomes None (``null``).

    Mappings become dicts with string keys, tuples and sets lists, and array-likes with a
    ``tolist`` method (numpy arrays and scalars) their Python values; anything else is returned
    as it is (``json.dump`` then says what it cannot write). Every JSON file rplearn writes goes
    through it (:func:`dump_json`), so that strict parsers (``JSON.parse``, ``json.loads`` with a
    ``parse_constant`` that refuses) read it: JSON has no NaN.
    """
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, (str, int, bool)) or value is None:
        return value
    if isinstance(value, dict) or hasattr(value, "items"):
        return {str(k): strict_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        return [strict_json(v) for v in value]
    if hasattr(value, "tolist"):
        return strict_json(value.tolist())
    return value


def dump_json(value: Any, fh: IO[str], **kwargs: Any) -> None:
    """``json.dump`` of :func:`strict_json` of ``value`` into ``fh``, refusing NaN (``allow_nan=False``);
    ``kwargs`` as ``json.dump`` (``indent``, ``default``, ...)."""
    json.dump(strict_json(value), fh, allow_nan=False, **kwargs)
