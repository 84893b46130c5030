"""Reading and writing canonical tables (matched datasets, pose and signal logs) as CSV or
Parquet, small JSON results, and the provenance record every output carries.

The table format is chosen by the file extension; anything else is refused rather than guessed.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterable, Iterator, Sequence
from typing import Any, Literal

import pandas as pd

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open, atomic_path, dump_json
from rplearn._version import __version__
from rplearn.data.tables import CSV_DTYPES, normalise_times, validate_matched
from rplearn.errors import InputError
from rplearn.io._common import read_parquet_lean
from rplearn.io.partitions import Part, dataset_parts, is_partitioned, is_url, open_source, with_hive_columns


def _table_error(name: str, path: Any, exc: BaseException) -> str:
    """What the file is instead and the command that would read it, else the parser's complaint
    (:func:`rplearn.io.sniff.table_read_error`)."""
    from rplearn.io.sniff import table_read_error

    return table_read_error(name, path, exc)


@check_types
def read_table(path: str, source: str | None = None) -> pd.DataFrame:
    """Read a CSV or Parquet table chosen by extension, with a one-line error on failure."""
    name = source or str(path)
    if not os.path.exists(path):
        raise InputError(f"{name}: no such file")
    try:
        if str(path).lower().endswith((".parquet", ".pq")):
            return normalise_times(read_parquet_lean(path), name)
        return normalise_times(pd.read_csv(path, dtype=CSV_DTYPES), name)
    except (ValueError, OSError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise InputError(_table_error(name, path, exc)) from None
    except Exception as exc:  # pyarrow raises its own error classes
        raise InputError(_table_error(name, path, exc)) from None


@check_types
def table_rows(path: str) -> int | None:
    """Rows of a Parquet table from its footer (no data read); None for CSV."""
    if not str(path).lower().endswith((".parquet", ".pq")):
        return None
    import pyarrow.parquet as pq

    try:
        if is_url(path):
            with open_source(path) as fh:
                return int(pq.ParquetFile(fh).metadata.num_rows)
        return int(pq.ParquetFile(path).metadata.num_rows)
    except Exception as exc:  # pyarrow's own errors on a corrupt footer
        raise InputError(_table_error(str(path), None if is_url(path) else path, exc)) from None


@check_types
def iter_table(path: str, chunk_rows: int = 500_000, columns: Iterable[str] | None = None) -> Iterator[pd.DataFrame]:
    """A CSV or Parquet table chunk by chunk (at most ``chunk_rows`` rows each), times normalised.

    ``columns`` reads only those columns (the ones a table lacks are left out). Errors name
    the file, as :func:`read_table`.
    """
    name = str(path)
    url = is_url(name)
    if not url and not os.path.exists(path):
        raise InputError(f"{name}: no such file")
    wanted = None if columns is None else list(columns)
    source = None
    try:
        source = open_source(name)
        if name.lower().endswith((".parquet", ".pq")):
            import pyarrow.parquet as pq

            pf = pq.ParquetFile(source)
            cols = None if wanted is None else [c for c in wanted if c in pf.schema_arrow.names]
            for batch in pf.iter_batches(batch_size=chunk_rows, columns=cols):
                yield normalise_times(batch.to_pandas(), name)
        else:
            use = None if wanted is None else (lambda c: c in wanted)
            gz: Literal["gzip", "infer"] = "gzip" if name.lower().endswith(".gz") else "infer"
            for chunk in pd.read_csv(source, dtype=CSV_DTYPES, chunksize=chunk_rows, usecols=use, compression=gz):
                yield normalise_times(chunk, name)
    except InputError:
        raise
    except Exception as exc:  # parsers raise many classes on corrupt bytes
        raise InputError(_table_error(name, None if url else name, exc)) from None
    finally:
        if url and source is not None:
            source.close()


@check_types
def iter_parts(parts: Sequence[Part], chunk_rows: int = 500_000, columns: Iterable[str] | None = None) -> Iterator[pd.DataFrame]:
    """Every part of a dataset (:func:`rplearn.io.partitions.dataset_parts`), a chunk at a
    time, in order, with its Hive columns (see :func:`iter_table`)."""
    wanted = None if columns is None else list(columns)
    for part in parts:
        # the Hive keys are read too: a folder never replaces a column the file holds (with_hive_columns)
        read = None if wanted is None else [*wanted, *(k for k in part.columns if k not in wanted)]
        for chunk in iter_table(part.path, chunk_rows, read):
            chunk = with_hive_columns(chunk, part)
            yield chunk if wanted is None else chunk[[c for c in chunk.columns if c in wanted]]


@check_types
def write_table(df: pd.DataFrame, path: str) -> None:
    """Write a table as Parquet (``.parquet``, ``.pq``) or CSV (``.csv``, ``.csv.gz``).

    Any other extension is refused rather than guessed.
    """
    kind = check_table_path(path)
    with atomic_path(path) as tmp:
        if kind == "parquet":
            df.to_parquet(tmp, index=False)
        else:
            df.to_csv(tmp, index=False)


def _empty_like(columns: Iterable[str]) -> pd.DataFrame:
    """An empty table with these columns (``tx``/``rx`` as text, the rest as numbers)."""
    return pd.DataFrame({c: pd.Series(dtype=object if c in ("tx", "rx", "unit") else float) for c in columns})


@check_types
def write_table_chunks(
    chunks: Iterable[pd.DataFrame], path: str, empty_columns: Iterable[str] = ()
) -> int:
    """Write a table arriving in chunks as Parquet (one row group a chunk) or CSV, atomically.

    Memory holds one chunk. The chunks must share their columns; a later chunk's types are
    cast to the first non-empty chunk's. When ``chunks`` raises, nothing is written (the
    previous file, if any, stays). With no rows at all, an empty table with
    ``empty_columns`` is written.

    Returns
    -------
    int
        Rows written.
    """
    kind = check_table_path(path)
    rows = 0
    with atomic_path(path) as tmp:
        if kind == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            writer = None
            try:
                for chunk in chunks:
                    if chunk.empty:
                        continue
                    table = pa.Table.from_pandas(chunk, preserve_index=False)
                    if writer is None:
                        writer = pq.ParquetWriter(tmp, table.schema)
                    elif table.schema != writer.schema:
                        table = _cast_like(table, writer.schema, path)
                    writer.write_table(table)
                    rows += len(chunk)
            finally:
                if writer is not None:
                    writer.close()
            if writer is None:
                _empty_like(empty_columns).to_parquet(tmp, index=False)
        else:
            import gzip

            opener = gzip.open if str(path).lower().endswith(".gz") else open
            with opener(tmp, "wt", encoding="utf-8", newline="") as fh:
                header: list[str] | None = None
                for chunk in chunks:
                    if header is None:
                        header = list(chunk.columns)
                        chunk.to_csv(fh, index=False)
                    elif not chunk.empty:
                        chunk[header].to_csv(fh, index=False, header=False)
                    rows += len(chunk)
                if header is None:
                    _empty_like(empty_columns).to_csv(fh, index=False)
    return rows


def _cast_like(table: Any, schema: Any, path: str) -> Any:
    """A chunk's Arrow table in the first chunk's schema, or a one-line error naming the column."""
    try:
        return table.select(schema.names).cast(schema)
    except Exception as exc:  # pyarrow's own errors: name the column that differs
        differing = [f.name for f in schema if f.name not in table.column_names
                     or table.schema.field(f.name).type != f.type]
        raise InputError(
            f"{path}: column(s) {', '.join(differing) or '?'} change type between chunks "
            f"({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
        ) from None


@check_types
def check_table_path(path: str) -> str:
    """``"parquet"`` or ``"csv"`` from a table's file name; any other extension is refused."""
    name = str(path).lower()
    if name.endswith((".parquet", ".pq")):
        return "parquet"
    if name.endswith((".csv", ".csv.gz")):
        return "csv"
    raise InputError(f"{path}: unknown table format; name it .csv, .csv.gz, .parquet or .pq")


#: What each kind of output file is named: its suffixes, and what it is (for the refusal).
OUTPUT_KINDS: dict[str, tuple[tuple[str, ...], str]] = {
    "model": ((".json",), "a model file (JSON)"),
    "png": ((".png",), "a PNG image"),
    "grid": ((".csv",), "a grid CSV"),
    "html": ((".html", ".htm"), "an HTML page"),
}


@check_types
def check_output_kind(path: str, kind: str, param: str = "output") -> str:
    """Refuse, before any work, an output whose name says another kind of file than the one
    written (:data:`OUTPUT_KINDS`: a model written as ``pose_log.parquet``, a PNG as ``x.csv``:
    a file another command would then read as what its name says; a name without a suffix says no
    kind and is taken), a name ending with a separator (a folder: written as a file only after the
    work, which then failed), or an empty name (a fit that saved nothing, with exit 0); ``param`` names
    the parameter that gave it."""
    suffixes, what = OUTPUT_KINDS[kind]
    if not str(path).strip():
        raise InputError(f"{param}: an empty file name; give the file to write ({what})", param=param)
    if str(path).endswith(tuple(filter(None, ("/", os.sep, os.altsep)))):  # a folder, written as a file after the work
        raise InputError(f"{path}: names a folder; give the file to write ({what})", param=param)
    name = os.path.basename(str(path))
    if "." in name.lstrip(".") and not name.lower().endswith(suffixes):  # a name without a suffix says no kind
        raise InputError(f"{path}: {what} is written here, but the name says otherwise; name it "
                         f"{' or '.join(suffixes)}", param=param)
    return path


@check_types
def check_output_path(path: str, inputs: Iterable[str | None] = (), param: str = "output") -> str:
    """Refuse an output path before any work: one of the files of the ``inputs`` (path specs:
    lists, globs, folders, links; :func:`rplearn.io.resolve.check_outputs`), not a regular file,
    or in a folder that does not exist (see :func:`rplearn._atomic.check_output`); ``param``
    names the parameter that gave it, for the error."""
    from rplearn.io.resolve import check_outputs

    check_outputs({param: path}, inputs)
    return path


@check_types
def check_output_folder(path: str, param: str = "out_dir") -> str:
    """Refuse an output folder before any work: a path that exists and is not a folder (a file
    the command would fail on, after its work, or that a user meant as an input), or a folder
    that cannot be created where a parent is a file. ``param`` names the parameter that gave it.

    Raises
    ------
    InputError
        Naming the path and ``param``.
    """
    if os.path.lexists(path) and not os.path.isdir(path):
        raise InputError(f"{path}: is a file, not a folder: this command writes a folder of files there",
                         param=param)
    parent = os.path.dirname(os.path.abspath(path))
    while not os.path.lexists(parent):
        parent = os.path.dirname(parent)
    if not os.path.isdir(parent):
        raise InputError(f"{path}: cannot create a folder inside {parent}, which is a file", param=param)
    return path


#: The last second of 9999 (UTC): the latest time stamp that time.gmtime and datetime format.
MAX_SOURCE_DATE_EPOCH = 253402300799


@check_types
def source_date_epoch() -> float | None:
    """``SOURCE_DATE_EPOCH`` [s] when set (reproducible outputs), else None (now).

    Raises
    ------
    InputError
        Unless it is whole seconds from 0 to :data:`MAX_SOURCE_DATE_EPOCH`.
    """
    value = os.environ.get("SOURCE_DATE_EPOCH")
    if not value:
        return None
    try:
        seconds = int(value)
    except ValueError:
        raise InputError(f"SOURCE_DATE_EPOCH: expected whole seconds since 1970, got {value!r}") from None
    if not 0 <= seconds <= MAX_SOURCE_DATE_EPOCH:
        raise InputError(f"SOURCE_DATE_EPOCH: expected whole seconds from 0 to {MAX_SOURCE_DATE_EPOCH} (1970 to the "
                         f"end of 9999), got {value!r}")
    return float(seconds)


@check_types
def provenance(command: str | None = None, **parameters: Any) -> dict[str, Any]:
    """What made an output: library version, command line, parameters, time."""
    return {
        "rplearn_version": __version__,
        "command": command if command is not None else " ".join(["rplearn", *sys.argv[1:]]),
        "parameters": parameters,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(source_date_epoch())),
    }


@check_types
def read_dataset(path: str, require_rssi: bool = True) -> pd.DataFrame:
    """Read and check a matched dataset (docs/conventions.md schema; see :func:`validate_matched`).

    Parameters
    ----------
    path : str
        CSV or Parquet file, or a dataset in many files (a directory, a glob, a comma-separated
        list or a URL: :mod:`rplearn.io.partitions`), read whole.
    require_rssi : bool
        False for datasets of poses to predict, whose ``rssi_dbm`` may be absent.
    """
    if is_partitioned(path):
        parts = dataset_parts(path)
        frames = [list(iter_parts([part], 2_000_000)) for part in parts]
        if require_rssi:  # a copy named by its file and row, as a streamed fit names it
            from rplearn.data.row_copies import refuse_copies, source_copies

            refuse_copies([source_copies(part.path, chunks) for part, chunks in zip(parts, frames, strict=True)])
        flat = [f for each in frames for f in each]
        table = pd.concat(flat, ignore_index=True) if len(flat) > 1 else flat[0]
    else:
        table = read_table(path)
    checked = validate_matched(table, path, require_rssi=require_rssi)
    if checked.empty:  # a header without samples: nothing to learn, score, predict or draw
        raise InputError(f"{path}: the dataset has no rows (its columns, no samples)")
    return checked


@check_types
def write_json(path: str, payload: Any) -> None:
    """Write a small JSON result (Table I, chosen yaws, ...) with one-space indentation, as strict
    JSON: a non-finite number is ``null`` (:func:`rplearn._atomic.strict_json`)."""
    with atomic_open(path, "w", encoding="utf-8") as fh:
        dump_json(payload, fh, indent=1, default=str)
