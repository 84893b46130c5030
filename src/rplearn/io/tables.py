"""CSV and Parquet logs in the canonical schemas (docs/conventions.md), with their common variants.

Pose tables: ``t, node, x, y, z, qw, qx, qy, qz``. Instead of ``x, y, z`` a table may carry
``lat, lon, alt`` (degrees, metres above the ellipsoid), converted to a local ENU frame with
:mod:`pymap3d` around a stated origin or the log's first fix. Instead of the quaternion it may
carry Euler angles whose names carry their frame: ``roll_deg, pitch_deg, yaw_deg`` (ENU/FLU,
REP-103) or ``roll_ned_deg, pitch_ned_deg, yaw_ned_deg`` (NED/FRD, as autopilots log them).

Signal tables: ``t, tx, rx, rssi_dbm, tx_power_dbm, frequency_hz`` and optional ``unit``;
``tx_power_dbm``, ``frequency_hz`` and ``rx`` may instead be given as constants.

Other column names are renamed through one mapping: :data:`COLUMN_ALIASES` (common vendor
names) updated by the caller's ``columns={"their name": "canonical name"}``.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.data.tables import (
    CSV_DTYPES,
    POSE_COLUMNS,
    SIGNAL_COLUMNS,
    check_attitude_norms,
    check_unit_labels,
    node_ids,
    normalise_times,
    quaternion_norms,
    validate_pose_log,
)
from rplearn.errors import InputError, LogFormatError
from rplearn.io._columns import (
    COLUMN_ALIASES,
    GEODETIC_COLUMNS,
    attitude_columns,
    csv_missing_values,
    position_columns,
    quaternions_wxyz,
    rename_columns,
    with_node,
)
from rplearn.io._common import read_parquet_lean
from rplearn.io._csv_headers import NAMED_LINES, REPEATED_HEADER, REPEATED_HEADER_AT, HeaderScan, csv_source, in_file_lines, scan_csv_headers
from rplearn.io._pose_checks import TrackEnds
from rplearn.io._pose_checks import earlier_rows as _earlier_rows
from rplearn.io._pose_checks import finite_values as _finite_values
from rplearn.io._pose_checks import position_jumps as _position_jumps
from rplearn.io._pose_checks import repeated_poses as _repeated_poses
from rplearn.io._pose_checks import steps_from_last as _steps_from_last
from rplearn.io._time_order import LinkTimes, check_link_time_order
from rplearn.io._time_order import check_time_order as _check_time_order
from rplearn.io.geodetic import geodetic_to_enu

_PARQUET_EXT = (".parquet", ".pq")
#: Signal columns a constant may supply -> the ReaderOptions field that gives it.
_CONSTANT_FIELDS: dict[str, str] = {"rx": "receivers", "tx_power_dbm": "tx_power_dbm", "frequency_hz": "frequency_hz"}


def _table_error(name: str, path: Any, exc: BaseException) -> str:
    """What the file is instead and the command that would read it, else the parser's complaint
    (:func:`rplearn.io.sniff.table_read_error`)."""
    from rplearn.io.sniff import table_read_error

    return table_read_error(name, path, exc)


def table_read_message(source: str, path: Any, exc: BaseException, scan: HeaderScan) -> str:
    """The one-line message of a table file that could not be read (:func:`rplearn.io.sniff.table_read_error`), the
    lines the parser names said as the file's lines (``scan``: the lines repeating the header, which it did not
    read; :func:`rplearn.io._csv_headers.in_file_lines`)."""
    if isinstance(exc, pd.errors.ParserError):
        exc = pd.errors.ParserError(in_file_lines(str(exc), scan.file_line))
    return _table_error(source, path, exc)


def _csv_options(path: Any, columns: Mapping[str, str] | None) -> dict[str, Any]:
    """:func:`csv_missing_values` of a CSV file, from its header line."""
    return csv_missing_values(pd.read_csv(path, nrows=0, skipinitialspace=True).columns, columns)


def read_table_rows(path: str, source: str, columns: Mapping[str, str] | None = None) -> pd.DataFrame:
    """A CSV or Parquet table file's rows as read (times normalised, nothing checked), for the readers here and
    for ``inspect``; a missing, empty or unreadable file is refused naming ``source``. The lines of a CSV file
    that repeat its header (a logger restarted appending, files joined with ``cat``) are dropped, counted in
    ``attrs["repeated_header"]``, the file lines of the first few in ``attrs["repeated_header_lines"]``; a header
    of other columns mid-file is refused naming its line (:mod:`rplearn.io._csv_headers`).

    Parameters
    ----------
    path : str
        The file (Parquet by its extension, else CSV).
    source : str
        The name errors give it.
    columns : mapping of str to str, optional
        The user's column names for the canonical ones (a CSV's missing-value markers follow them).

    Returns
    -------
    pandas.DataFrame
    """
    if not os.path.exists(path):
        raise InputError(f"{source}: no such file")
    parquet = str(path).lower().endswith(_PARQUET_EXT)
    scan = HeaderScan() if parquet else scan_csv_headers(path, source)  # another header mid-file: refused
    try:
        if parquet:
            return normalise_times(read_parquet_lean(path), source)
        with csv_source(path, scan) as handle:
            df = pd.read_csv(handle, skipinitialspace=True, dtype=CSV_DTYPES, **_csv_options(path, columns))
        df = normalise_times(df, source)
        df.attrs[REPEATED_HEADER] = scan.repeated  # lines dropped: said as the drop of that name, with the first lines
        df.attrs[REPEATED_HEADER_AT] = list(scan.lines[:NAMED_LINES])
        return df
    except pd.errors.EmptyDataError:
        raise LogFormatError(f"{source}: empty file, expected a header line and rows") from None
    except Exception as exc:  # parsers raise many classes on corrupt bytes
        raise LogFormatError(table_read_message(source, path, exc, scan)) from None


def table_format(path: str | os.PathLike) -> str:
    """``"parquet"`` or ``"csv"``: how :func:`read_pose_table` and friends read a table file."""
    return "parquet" if str(path).lower().endswith(_PARQUET_EXT) else "csv"


def _enu_positions(
    values: dict[str, np.ndarray],
    position: str,
    origin_geodetic: tuple[float, float, float] | None,
    source: str,
) -> tuple[np.ndarray, tuple[float, float, float] | None]:
    """ENU positions [m], shape (n, 3), and the geodetic origin used (None for ENU tables).

    A geodetic table without ``origin_geodetic`` is expressed around its first fix
    (earliest row).
    """
    if position != "geodetic":
        return np.stack([values["x"], values["y"], values["z"]], axis=-1), None
    lat, lon, alt = values["lat"], values["lon"], values["alt"]
    if origin_geodetic is None:
        i0 = int(np.argmin(values["t"]))
        origin_geodetic = (float(lat[i0]), float(lon[i0]), float(alt[i0]))
    origin = tuple(float(v) for v in origin_geodetic)
    return geodetic_to_enu(lat, lon, alt, origin_geodetic, source), origin  # type: ignore[return-value]


@check_types
def canonical_pose(
    df: pd.DataFrame,
    source: str = "pose log",
    columns: Mapping[str, str] | None = None,
    node: str | None = None,
    origin_geodetic: tuple[float, float, float] | None = None,
    nan_policy: str = "error",
    allow_unsorted: bool = False,
    ends: TrackEnds | None = None,
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Turn a table in any of the pose variants into a canonical pose log.

    Parameters
    ----------
    df : DataFrame
        Table with ``t`` [s], a node (column ``node`` or the ``node`` argument), a position
        (``x, y, z`` ENU [m] or ``lat, lon, alt`` [deg, deg, m]) and an attitude (quaternion
        ``qw, qx, qy, qz`` body FLU -> world ENU, or Euler angles [deg], see the module docstring).
    source : str
        File or log name for messages.
    columns : mapping, optional
        Extra renaming ``{"their name": "canonical name"}``.
    node : str, optional
        Node id of every row when the table has no ``node`` column.
    origin_geodetic : (lat_deg, lon_deg, alt_m), optional
        ENU origin for geodetic tables; by default the log's first fix (earliest row).
    nan_policy : {"error", "drop"}
        Rows with a NaN or non-numeric pose value raise :class:`InputError` or are dropped
        and counted in ``metadata["dropped"]["nan_pose"]``; so are rows with a position
        no place has (``implausible_pose``: an ENU coordinate beyond 1e8 m, a latitude, longitude
        or altitude outside its plausible range, such as a 1e308 sentinel;
        :data:`rplearn.io._pose_checks.POSITION_RANGES`) and rows on the wrong side of a position jump no
        plausible speed explains (``position_jump``: a sentinel such as ``z = -1000`` or
        ``x = y = z = 0`` before the fix; :func:`rplearn.io._pose_checks.position_jumps`), each dropped piece said in
        ``metadata["notes"]``. Whatever the policy, a row identical in every value to an
        earlier row of its node and time (a block written twice) is dropped as a copy
        (``duplicate_pose``, said in the notes); rows of one node and time with different
        values are refused, or with ``"drop"`` all dropped (``conflicting_pose``):
        :func:`rplearn.io._pose_checks.repeated_poses`. The lines of a CSV file that repeat its
        header (:func:`read_table_rows` drops them; ``df.attrs["repeated_header"]``) are counted
        as ``repeated_header``, the file lines of the first few in ``metadata["repeated_header_lines"]``.
    allow_unsorted : bool
        Accept times that go backwards within a node (the rows are sorted); by default
        they raise :class:`LogFormatError`.
    ends : TrackEnds, optional
        For a table read in parts (a file still being written): the rows read before (the
        file row of this part's first row, for messages) and each node's last row kept from
        the parts before, against which its first rows here are checked for a position jump
        (:func:`rplearn.io._pose_checks.steps_from_last`; updated here).

    Returns
    -------
    pose : DataFrame
        Canonical pose log sorted by (node, t).
    metadata : dict
        ``source``, ``position`` ("enu" or "geodetic"), ``attitude`` ("quaternion",
        "euler_enu_flu" or "euler_ned_frd"), ``origin_geodetic`` (or None), ``dropped``
        and, for yaw-only tables, ``level_assumed``.
    """
    if nan_policy not in ("error", "drop"):
        raise InputError(f"nan_policy: expected 'error' or 'drop', got {nan_policy!r}", param="nan_policy")
    try:
        df = rename_columns(df, columns)
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None
    meta: dict[str, Any] = {"source": source, "dropped": {"nan_pose": 0, "implausible_pose": 0, "duplicate_pose": 0,
                                                         "conflicting_pose": 0, "position_jump": 0,
                                                         REPEATED_HEADER: int(df.attrs.get(REPEATED_HEADER, 0))},
                            "origin_geodetic": None, **_header_lines(df)}
    df = with_node(df, node, source)
    pos_cols, meta["position"] = position_columns(df, source)
    df, att_cols, meta["attitude"], level = attitude_columns(df, source)
    if level:
        meta["level_assumed"] = True
    rows = np.arange(len(df)) if ends is None else ends.part_rows(len(df))
    df, values, dropped = _finite_values(df.set_axis(rows), ("t",) + pos_cols + att_cols, nan_policy, source)
    meta["dropped"].update(dropped)
    rows = df.index.to_numpy()
    nodes = df["node"].astype(str).to_numpy()
    if len(nodes) == 0:
        raise InputError(f"{source}: no pose rows")
    pose_part = df[[c for c in ("node", "t", *pos_cols, *att_cols) if c in df.columns]]  # other columns: not the pose
    unique, repeated, notes = _repeated_poses(pose_part, values["t"], nodes, rows, nan_policy, source)
    meta["dropped"].update(repeated)
    if ends is not None:  # a part of a table: rows at or before those read earlier (copies across parts)
        later, repeated_before, before_notes = _earlier_rows(ends, values, nodes, rows, nan_policy, source)
        unique &= later
        notes += before_notes
        for reason, n in repeated_before.items():
            meta["dropped"][reason] += n
    if not unique.all():  # copies (a block written twice) are no step back in time
        df, rows, nodes = df.loc[unique], rows[unique], nodes[unique]
        values = {c: v[unique] for c, v in values.items()}
    if len(nodes) == 0:  # every row of this part a copy of a row read earlier
        if notes:
            meta["notes"] = notes
        return pd.DataFrame({c: pd.Series(dtype=object if c == "node" else np.float64) for c in POSE_COLUMNS}), meta
    t = values["t"]
    if not allow_unsorted:
        _check_time_order(t, nodes, source, rows)  # rows: the file's, some dropped before
    xyz, meta["origin_geodetic"] = _enu_positions(values, meta["position"], origin_geodetic, source)
    keep, jumps = _position_jumps(t, xyz, nodes, rows, nan_policy, source)
    meta["dropped"]["position_jump"] = int((~keep).sum())
    notes += jumps
    if notes:
        meta["notes"] = notes
    if jumps:
        t, nodes, xyz, rows = t[keep], nodes[keep], xyz[keep], rows[keep]
        values = {c: v[keep] for c, v in values.items()}
    if ends is not None:  # a part of a table: each node's first rows checked against its last row before
        keep, jumps = _steps_from_last(ends, t, xyz, nodes, rows, nan_policy, source)
        meta["dropped"]["position_jump"] += int((~keep).sum())
        notes += jumps
        if jumps:
            meta["notes"] = notes
            t, nodes, xyz, rows = t[keep], nodes[keep], xyz[keep], rows[keep]
            values = {c: v[keep] for c, v in values.items()}
        ends.remember(nodes, values)
    q = quaternions_wxyz(values, att_cols, meta["attitude"])
    check_attitude_norms(quaternion_norms(q), source, rows)  # named by the file's row (validate_pose_log: out's)
    out = pd.DataFrame({"t": t, "node": nodes, **dict(zip(("x", "y", "z"), xyz.T)),
                        **dict(zip(("qw", "qx", "qy", "qz"), q.T))})
    return validate_pose_log(out, source), meta


def _rssi_cells(col: pd.Series) -> np.ndarray:
    """The RSSI column as float [dBm]; where a cell holds text that is no number ("-70dBm",
    "n/a") the column keeps that text (object dtype), so that ``sync`` counts the row as
    ``unparsable_rssi``, not as a missing value (``nan_rssi``)."""
    values = pd.to_numeric(col, errors="coerce").to_numpy(np.float64, na_value=np.nan)
    if pd.api.types.is_numeric_dtype(col):
        return values
    missing = np.flatnonzero(np.isnan(values))
    words = col.iloc[missing].astype(str).str.strip().str.lower()
    text = col.iloc[missing].notna().to_numpy() & ~words.isin(("", "nan", "+nan", "-nan", "<na>")).to_numpy()
    if not text.any():
        return values
    out = values.astype(object)
    out[missing[text]] = col.iloc[missing[text]].astype(str).to_numpy()
    return out


@check_types
def canonical_signal(
    df: pd.DataFrame,
    source: str = "signal log",
    columns: Mapping[str, str] | None = None,
    rx: str | None = None,
    tx_power_dbm: float | None = None,
    frequency_hz: float | None = None,
    first_row: int = 0,
) -> pd.DataFrame:
    """Turn a signal table into the canonical signal schema without dropping any row.

    ``rx``, ``tx_power_dbm`` and ``frequency_hz`` fill a column the table lacks. NaN or
    sentinel values are kept: :func:`rplearn.data.sync.synchronise` drops and counts them; an
    RSSI cell of text that is no number is kept as that text (the column is then of object
    dtype), counted as ``unparsable_rssi``, not ``nan_rssi``.
    Extra columns are kept after the canonical ones.

    ``first_row`` is the file row of the table's first row (a chunk of a file), for messages.

    Raises
    ------
    InputError
        On a missing column that no argument supplies, or an empty cell in a ``unit`` column
        (:func:`~rplearn.data.tables.check_unit_labels`: a sample of no trajectory unit,
        which every learning command refuses).
    """
    try:
        df = rename_columns(df, columns)
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None
    check_unit_labels(df, source, first_row)
    fill = {"rx": rx, "tx_power_dbm": tx_power_dbm, "frequency_hz": frequency_hz}
    for c, v in fill.items():
        if c not in df.columns and v is not None:
            df = df.assign(**{c: v})
    missing = [c for c in SIGNAL_COLUMNS if c not in df.columns]
    if missing:
        fillable = [f for c, f in _CONSTANT_FIELDS.items() if c in missing]
        raise InputError(
            f"{source}: missing column(s) {', '.join(missing)}; expected {', '.join(SIGNAL_COLUMNS)}"
            " (rx, tx_power_dbm and frequency_hz may be given as constants: ReaderOptions.receivers, "
            "ReaderOptions.tx_power_dbm, ReaderOptions.frequency_hz; or rx=, tx_power_dbm=, frequency_hz=)",
            param=fillable[0] if fillable else None,
        )
    out = pd.DataFrame(index=range(len(df)))
    for c in SIGNAL_COLUMNS:
        col = df[c].to_numpy()
        if c in ("tx", "rx"):
            out[c] = node_ids(pd.Series(col))
        elif c == "rssi_dbm":
            out[c] = _rssi_cells(pd.Series(col))
        else:
            out[c] = pd.to_numeric(pd.Series(col), errors="coerce").to_numpy(np.float64, na_value=np.nan)
    for c in df.columns:
        if c not in SIGNAL_COLUMNS:
            out[c] = df[c].to_numpy()
    return out


@check_types
def read_pose_table(path: str, **options: Any) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read a pose log from CSV or Parquet (by extension); options of :func:`canonical_pose`.

    Returns ``(pose, metadata)``.
    """
    source = str(path)
    df = read_table_rows(str(path), source)
    pose, meta = canonical_pose(df, source=source, **options)
    meta["format"] = table_format(source)
    return pose, meta


@check_types
def read_signal_table(path: str, allow_unsorted: bool = False, **options: Any) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read a signal log from CSV or Parquet; options of :func:`canonical_signal`; times that go
    back within a link are refused (:func:`check_link_time_order`) unless ``allow_unsorted``.

    Returns ``(signal, metadata)``; ``metadata["dropped"]["repeated_header"]``: the lines of a CSV
    file that repeat its header, dropped (:func:`read_table_rows`).
    """
    source = str(path)
    df = read_table_rows(str(path), source, options.get("columns"))
    signal = canonical_signal(df, source=source, **options)
    if not allow_unsorted:
        check_link_time_order(signal, source)
    meta = {"source": source, "format": table_format(source), "rows": int(len(signal)), **_header_lines(df)}
    return signal, {**meta, "dropped": {REPEATED_HEADER: int(df.attrs.get(REPEATED_HEADER, 0))}}


def _header_lines(df: pd.DataFrame) -> dict[str, list[int]]:
    """``{"repeated_header_lines": [...]}``: the file lines of the first header lines repeated mid-file that
    :func:`read_table_rows` dropped from ``df`` (empty without any)."""
    lines = [int(n) for n in df.attrs.get(REPEATED_HEADER_AT, ())]
    return {REPEATED_HEADER_AT: lines} if lines else {}


def _signal_chunks(batches: Iterator[pd.DataFrame], source: str, allow_unsorted: bool, scan: HeaderScan,
                   options: Mapping[str, Any]) -> Iterator[pd.DataFrame]:
    """The canonical chunks of :func:`iter_signal_table`, their links' time order checked across them."""
    state = LinkTimes()
    first_row = 0
    for chunk in batches:
        out = canonical_signal(chunk, source=source, first_row=first_row, **options)
        if not allow_unsorted:
            check_link_time_order(out, source, first_row, state)
        first_row += len(out)
        out.attrs[REPEATED_HEADER], out.attrs[REPEATED_HEADER_AT] = scan.repeated, list(scan.lines[:NAMED_LINES])
        yield out


@check_types
def iter_signal_table(
    path: str, chunk_rows: int = 200_000, allow_unsorted: bool = False, header_scan: HeaderScan | None = None,
    **options: Any,
) -> Iterator[pd.DataFrame]:
    """Read a big CSV or Parquet signal log in chunks of at most ``chunk_rows`` rows.

    Each chunk goes through :func:`canonical_signal` (options as there), and, unless
    ``allow_unsorted``, :func:`check_link_time_order` (across chunks). Memory stays bounded
    by the chunk size: CSV through pandas' chunked reader, Parquet by record batches. The lines
    of a CSV file that repeat its header are dropped (another header is refused naming its line:
    :mod:`rplearn.io._csv_headers`); every chunk's ``attrs["repeated_header"]`` says how many the
    file holds, ``attrs["repeated_header_lines"]`` the file lines of the first few. ``header_scan``: that scan of
    the CSV file (:func:`scan_csv_headers`) when the caller made it already (``sync``, which reads the file's extra
    columns first): the file is not scanned again.
    """
    source = str(path)
    if not os.path.exists(path):
        raise InputError(f"{source}: no such file")
    if chunk_rows < 1:
        raise InputError(f"chunk_rows must be positive, got {chunk_rows}")
    scan = HeaderScan()
    try:
        if source.lower().endswith(_PARQUET_EXT):
            import pyarrow.parquet as pq

            pf = pq.ParquetFile(path)
            batches: Iterator[pd.DataFrame] = (
                normalise_times(b.to_pandas(), source) for b in pf.iter_batches(batch_size=chunk_rows)
            )
            yield from _signal_chunks(batches, source, allow_unsorted, scan, options)
        else:
            scan = scan_csv_headers(path, source) if header_scan is None else header_scan
            with csv_source(path, scan) as handle:
                batches = (normalise_times(c, source)
                           for c in pd.read_csv(handle, chunksize=chunk_rows, skipinitialspace=True, dtype=CSV_DTYPES,
                                                **_csv_options(path, options.get("columns"))))
                yield from _signal_chunks(batches, source, allow_unsorted, scan, options)
    except (InputError, LogFormatError):
        raise
    except Exception as exc:
        raise LogFormatError(table_read_message(source, path, exc, scan)) from None


@check_types
def table_columns(path: str, columns: Mapping[str, str] | None = None) -> list[str]:
    """Column names of a CSV or Parquet table after renaming (its header only is read)."""
    source = str(path)
    try:
        if source.lower().endswith(_PARQUET_EXT):
            import pyarrow.parquet as pq

            names = list(pq.ParquetFile(path).schema_arrow.names)
        else:
            names = list(pd.read_csv(path, nrows=0, skipinitialspace=True).columns)
    except Exception as exc:
        raise LogFormatError(_table_error(source, path, exc)) from None
    return [str(c) for c in rename_columns(pd.DataFrame(columns=names), columns).columns]


def table_kind(path: str, columns: Mapping[str, str] | None = None) -> str:
    """``"pose"`` or ``"signal"``: which canonical log a table holds, judged by its header."""
    source = str(path)
    if source.lower().endswith(_PARQUET_EXT):
        try:
            import pyarrow.parquet as pq

            names = list(pq.read_schema(path).names)
        except Exception as exc:
            raise LogFormatError(f"{source}: cannot read Parquet schema ({type(exc).__name__})") from None
    else:
        if not os.path.exists(path):
            raise InputError(f"{source}: no such file")
        try:
            names = list(pd.read_csv(path, nrows=0, skipinitialspace=True, dtype=CSV_DTYPES).columns)
        except Exception as exc:
            raise LogFormatError(f"{source}: cannot read CSV header ({type(exc).__name__})") from None
    renamed = set(rename_columns(pd.DataFrame(columns=names), columns).columns)
    if {"rssi_dbm", "tx"} <= renamed:
        return "signal"
    if "t" in renamed and ({"x", "y", "z"} <= renamed or set(GEODETIC_COLUMNS) <= renamed):
        return "pose"
    raise InputError(
        f"{source}: header is neither a pose log (t, node, x|lat, ...) nor a signal log "
        f"(t, tx, rx, rssi_dbm, ...): {', '.join(map(str, names[:12]))}"
    )


__all__ = [
    "COLUMN_ALIASES",
    "canonical_pose",
    "canonical_signal",
    "LinkTimes",
    "check_link_time_order",
    "csv_missing_values",
    "iter_signal_table",
    "table_columns",
    "read_pose_table",
    "read_signal_table",
    "read_table_rows",
    "rename_columns",
    "table_format",
    "table_kind",
]
