"""Datasets in many files: a directory, a glob, a comma-separated list, local or any fsspec URL.

A fleet's flights are logged as partitioned Parquet (one file per flight or per day, often in
Hive-style folders such as ``flight=0007/part-0.parquet``) on a disk or in object storage. Such
a dataset is named by one string, the *dataset spec*:

- a file (``flights.parquet``): one part, the usual case;
- a directory: every ``.parquet``, ``.pq``, ``.csv`` and ``.csv.gz`` file below it, sorted by
  path (hidden files and folders, and those starting with ``_``, are skipped, as Spark and Dask
  write metadata there);
- a glob (``logs/2026-*/*.parquet``), or files separated by commas;
- any of these as a URL (``s3://bucket/fleet/``, ``gs://...``, ``file:///data/fleet``), read
  with fsspec (installed with ``rplearn[dask]``; each store needs its own fsspec plugin, e.g.
  ``s3fs``).

Hive ``key=value`` folder names below the root become columns of the rows read from the files
beneath them. A folder never replaces a column the file holds: a file's ``unit`` (or ``tx``,
``rx``, ...) column is kept over a ``unit=...`` folder name (Spark and Dask write the folder
value out of the file, so both are present only when the file was written otherwise). A
folder named after a measurement (``rssi_dbm``, ``t`` or a pose column:
:data:`MEASURED_COLUMNS`) is refused naming the folder, the column and the file: it would
either give every sample of its files one invented value, or contradict the values the files
hold (``rssi_dbm=-50/``).

Every file is identified by its device and inode (:func:`file_identity`) before any work: the
same file named twice (``a.parquet,./a.parquet``, by relative and absolute path, or as a file
and a symbolic link to it in one folder) is refused naming both spellings, never read twice.
"""

from __future__ import annotations

import glob
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from rplearn._argtypes import check_types
from rplearn.errors import InputError

#: Columns that hold one measurement per sample: a Hive folder may not set them (see the
#: module docstring).
MEASURED_COLUMNS: tuple[str, ...] = ("t", "rssi_dbm", *(f"{end}_{c}" for end in ("tx", "rx")
                                                        for c in ("x", "y", "z", "qw", "qx", "qy", "qz")))

#: File endings of the tables a partitioned dataset is made of.
TABLE_SUFFIXES: tuple[str, ...] = (".parquet", ".pq", ".csv", ".csv.gz")


@check_types
@dataclass(frozen=True)
class Part:
    """One file of a dataset.

    Attributes
    ----------
    path : str
        Local path or URL.
    columns : mapping of str to str
        Hive ``key=value`` folder names between the dataset's root and the file.
    """

    path: str
    columns: Mapping[str, str] = field(default_factory=dict)


def is_url(spec: str) -> bool:
    """Whether a path is a URL (``scheme://...``), read with fsspec."""
    head, sep, _ = str(spec).partition("://")
    return bool(sep) and head.replace("+", "").replace("-", "").isalnum() and len(head) > 1


@check_types
def is_partitioned(spec: str) -> bool:
    """Whether a dataset spec names more than a single local file: a directory, a glob, a
    comma-separated list or a URL (see the module docstring)."""
    spec = str(spec)
    if is_url(spec) or "," in spec and not os.path.exists(spec):
        return True
    if os.path.isdir(spec):
        return True
    return glob.has_magic(spec) and not os.path.exists(spec)


def _is_table(path: str) -> bool:
    name = os.path.basename(path)
    return path.lower().endswith(TABLE_SUFFIXES) and not name.startswith((".", "_"))


def _hidden(rel: str) -> bool:
    return any(p.startswith((".", "_")) for p in rel.replace("\\", "/").split("/")[:-1])


def hive_columns(root: str, path: str) -> dict[str, str]:
    """``key=value`` folder names between ``root`` and ``path`` (Hive partitioning)."""
    rel = os.path.relpath(path, root) if not is_url(path) else path[len(root):].lstrip("/")
    out: dict[str, str] = {}
    for piece in rel.replace("\\", "/").split("/")[:-1]:
        key, sep, value = piece.partition("=")
        if sep and key:
            out[key] = value
    return out


def _filesystem(url: str) -> tuple[Any, str]:
    try:
        import fsspec
    except ImportError:
        raise InputError(f"{url}: reading URLs needs fsspec: pip install 'rplearn[dask]' (and the store's "
                         "plugin, e.g. s3fs for s3://)", param="dataset") from None
    try:
        return fsspec.core.url_to_fs(url)
    except (ImportError, ValueError) as exc:
        raise InputError(f"{url}: {type(exc).__name__}: {exc}", param="dataset") from None


def _url_parts(spec: str) -> list[Part]:
    fs, path = _filesystem(spec)
    try:
        if glob.has_magic(path):
            found, root = sorted(fs.glob(path)), path.split("*")[0].rsplit("/", 1)[0]
        elif fs.isdir(path):
            found, root = sorted(fs.find(path)), path.rstrip("/")
        elif fs.exists(path):
            found, root = [path], path.rsplit("/", 1)[0]
        else:
            raise InputError(f"{spec}: no such file", param="dataset")
    except InputError:
        raise
    except Exception as exc:  # each store raises its own errors
        raise InputError(f"{spec}: cannot list ({type(exc).__name__}: {exc})", param="dataset") from None
    parts = []
    for p in found:
        rel = p[len(root):].lstrip("/")
        if _is_table(p) and not _hidden(rel):
            parts.append(Part(fs.unstrip_protocol(p), hive_columns(root, p)))
    return parts


def _local_parts(spec: str) -> list[Part]:
    if os.path.isdir(spec):
        parts = []
        for folder, dirs, files in os.walk(spec):
            dirs[:] = sorted(d for d in dirs if not d.startswith((".", "_")))
            parts += [Part(os.path.join(folder, f), hive_columns(spec, os.path.join(folder, f)))
                      for f in sorted(files) if _is_table(f)]
        return sorted(parts, key=lambda p: p.path)
    if os.path.isfile(spec):
        return [Part(spec)]
    if glob.has_magic(spec):
        root = os.path.dirname(spec.split("*")[0].split("?")[0].split("[")[0]) or "."
        found = [p for p in sorted(glob.glob(spec, recursive=True)) if os.path.isfile(p)]
        if not found:  # a pattern that matches nothing, or a file name with brackets that does not exist
            raise InputError(f"{spec}: no such file", param="dataset")
        return [Part(p, hive_columns(root, p)) for p in found if _is_table(p)]
    raise InputError(f"{spec}: no such file", param="dataset")


@check_types
def dataset_parts(spec: str) -> list[Part]:
    """The files of a dataset spec (see the module docstring), sorted; an error when none.

    Raises
    ------
    InputError
        When a path does not exist, a URL cannot be listed, or no table file is found.
    """
    spec = str(spec)
    pieces = [s.strip() for s in spec.split(",")] if "," in spec and not os.path.exists(spec) else [spec]
    parts: list[Part] = []
    for piece in pieces:
        if not piece:
            continue
        parts += _url_parts(piece) if is_url(piece) else _local_parts(piece)
    if not parts:
        raise InputError(f"{spec}: no table files ({', '.join(TABLE_SUFFIXES)}) found", param="dataset")
    refuse_repeated([p.path for p in parts], spec, param="dataset")
    return parts


@check_types
def file_identity(path: str) -> tuple[Any, ...]:
    """What identifies a file whatever its spelling: ``(st_dev, st_ino)`` of a local file (after
    symbolic links; a ``file://`` URL is a local file), else the URL without its protocol's
    spelling (``s3://b/k`` and ``s3a://b/k`` are not merged: each store is asked as given).
    A local file that cannot be stat-ed is identified by its real path."""
    name = str(path)
    if name.startswith("file://"):
        name = name[len("file://"):]
    elif is_url(name):
        head, _, rest = name.partition("://")
        return ("url", head.lower(), "/".join(p for p in rest.split("/") if p not in ("", ".")))
    try:
        st = os.stat(name)
    except OSError:
        return ("path", os.path.realpath(name))
    return (st.st_dev, st.st_ino)


@check_types
def refuse_repeated(paths: Sequence[str], spec: str, param: str | None = None) -> None:
    """Refuse a file named twice among ``paths`` (by :func:`file_identity`), naming both spellings.

    Raises
    ------
    InputError
        ``"<spec>: <a> and <b> are one file (named twice); give it once"``.
    """
    seen: dict[tuple[Any, ...], str] = {}
    for path in paths:
        key = file_identity(path)
        if key in seen:
            first = seen[key]
            how = "named twice" if first == path else "named twice: a link or another spelling of it"
            raise InputError(f"{spec}: {first} and {path} are one file ({how}); give it once", param=param)
        seen[key] = path


def open_source(path: str) -> Any:
    """A local path as it is, a URL as an open binary file (fsspec)."""
    if not is_url(path):
        return path
    fs, inner = _filesystem(path)
    return fs.open(inner, "rb")


def _hive_folder(part: Part, key: str) -> str:
    """The folder of ``part`` whose name is ``key=...`` (for messages)."""
    pieces = part.path.replace("\\", "/").split("/")
    for i in range(len(pieces) - 2, -1, -1):
        if pieces[i].partition("=")[0] == key:
            return "/".join(pieces[: i + 1])
    return f"{key}={part.columns[key]}"


@check_types
def with_hive_columns(chunk: pd.DataFrame, part: Part) -> pd.DataFrame:
    """``chunk`` with the part's Hive columns added where it lacks them (as strings); a column
    the file holds is kept as it is.

    Raises
    ------
    InputError
        Naming the folder, the column and the file, when a folder is named after a measurement
        (:data:`MEASURED_COLUMNS`; see the module docstring).
    """
    for key, value in part.columns.items():
        if key in MEASURED_COLUMNS:
            held = (f"{part.path} holds its own {key} values" if key in chunk.columns
                    else f"it would give every sample of {part.path} {key} = {value}")
            raise InputError(f"{_hive_folder(part, key)}: a folder named after the measurement {key} ({held}); "
                             "a measurement comes from the files, never from a folder name: rename the folder",
                             param="dataset")
    extra = {k: v for k, v in part.columns.items() if k not in chunk.columns}
    if not extra:
        return chunk
    return chunk.assign(**{k: pd.Series([v] * len(chunk), index=chunk.index, dtype=object) for k, v in extra.items()})


__all__ = ["MEASURED_COLUMNS", "Part", "TABLE_SUFFIXES", "dataset_parts", "file_identity", "hive_columns",
           "is_partitioned", "is_url", "open_source", "refuse_repeated", "with_hive_columns"]
