"""Pose-signal matching of signal logs too big for memory, chunk by chunk.

:func:`synchronise_stream` gives the same samples and the same counts as
:func:`rplearn.data.sync.synchronise` on the whole log (for a time-sorted log, also in the
same order), while holding one chunk of the signal log at a time:

- a row that repeats a row of an *earlier chunk* is a ``duplicate`` as it would be in one
  piece: every row's 64-bit hash is kept (8 bytes a row; 40 MB for 5 million rows), so a
  duplicate is found whatever the distance between the copies (a false match needs a 64-bit
  hash collision, about 1e-6 for 5 million rows);
- the chosen link (``SyncOptions(link=...)``) and ``min_samples`` are checked when the last
  chunk has been matched, with the messages of :func:`~rplearn.data.sync.synchronise`. A
  writer that consumes the stream inside an atomic write (:func:`synchronise_to_parquet`,
  :func:`rplearn.io.files.write_table_chunks`) therefore leaves no file when they fail.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_path
from rplearn.data.phases import flight_phases
from rplearn.data.poses import tracks_of_checked_log
from rplearn.data.sync import (
    SyncOptions,
    SyncResult,
    SyncSummary,
    check_link_nodes,
    check_receiver_offsets,
    finish_summary,
    match_chunk,
    sync_options_or_default,
)
from rplearn.data.tables import MATCHED_COLUMNS, SIGNAL_COLUMNS, non_unit_quaternion_rows, validate_pose_log


@check_types
def row_hashes(signal: pd.DataFrame) -> np.ndarray:
    """64-bit hash of every row of a signal log chunk, equal for equal rows of any chunk.

    Numbers are hashed as float64 (a column read as integers in one chunk and as floats in
    another hashes alike), everything else as text, a missing cell as one sentinel.
    """
    cols = {}
    for c in signal.columns:
        col = signal[c]
        if pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col):
            cols[c] = col.to_numpy(np.float64, na_value=np.nan)
        else:  # text; a missing cell hashes as one sentinel whatever the column's dtype
            missing = col.isna().to_numpy()
            cols[c] = np.where(missing, "\x00missing", col.astype(object).astype(str).to_numpy(dtype=object))
    frame = pd.DataFrame(cols, index=range(len(signal)))
    return pd.util.hash_pandas_object(frame, index=False).to_numpy(np.uint64)


def conform_chunk(chunk: pd.DataFrame, extra_columns: Mapping[str, str] | list[str]) -> pd.DataFrame:
    """A signal chunk with the canonical columns, then exactly ``extra_columns``.

    Logs read in chunks (or several files) need not agree on their extra columns, nor on the
    type a column seems to have in one chunk (all empty here, text there): every chunk gets
    every extra column of the whole stream, with one type for the whole stream, so that one
    schema is written and equal rows hash alike. ``extra_columns`` maps each column to
    ``"number"`` (float64, missing as NaN: a column whose every value in every file is a
    number) or ``"text"`` (pandas' string dtype, missing kept missing); a list means all text.
    """
    kinds = dict(extra_columns) if isinstance(extra_columns, Mapping) else {c: "text" for c in extra_columns}
    out = chunk[[c for c in SIGNAL_COLUMNS if c in chunk.columns]].copy()
    for c, kind in kinds.items():
        if kind == "number":
            out[c] = (pd.to_numeric(chunk[c], errors="coerce").to_numpy(np.float64, na_value=np.nan)
                      if c in chunk.columns else np.full(len(chunk), np.nan))
        elif c in chunk.columns:
            col = chunk[c]
            missing = col.isna().to_numpy()
            text = col.astype(object).where(~missing, None)
            out[c] = pd.array([None if v is None else str(v) for v in text], dtype=pd.StringDtype())
        else:
            out[c] = pd.array([None] * len(chunk), dtype=pd.StringDtype())
    return out


class _SeenRows:
    """Hashes of the rows of earlier chunks, sorted for look-up."""

    def __init__(self) -> None:
        self.sorted = np.empty(0, np.uint64)

    def repeats(self, hashes: np.ndarray) -> np.ndarray:
        """Mask of hashes seen in an earlier chunk; then remember these."""
        if self.sorted.size:
            pos = np.searchsorted(self.sorted, hashes).clip(max=self.sorted.size - 1)
            seen = self.sorted[pos] == hashes
        else:
            seen = np.zeros(hashes.size, bool)
        # two sorted runs: the stable sort (timsort) merges them in linear time
        self.sorted = np.sort(np.concatenate([self.sorted, np.sort(hashes)]), kind="stable")
        return seen


def _pairs(signal: pd.DataFrame) -> set[tuple[str, str]]:
    """The (tx, rx) directions of a chunk."""
    both = pd.DataFrame({"tx": signal["tx"].astype(str), "rx": signal["rx"].astype(str)}).drop_duplicates()
    return set(zip(both["tx"], both["rx"]))


@check_types
def synchronise_stream(
    pose_log: pd.DataFrame,
    signal_chunks: Iterable[pd.DataFrame],
    options: SyncOptions | None = None,
    source: str = "signal log",
) -> Iterator[SyncResult]:
    """Match a signal log chunk by chunk; yields one :class:`SyncResult` per chunk, and, if
    there is any, a last one without rows whose summary carries the notes on the whole log (the window, the airborne
    filter, the fixed nodes, the ``max_gap_s`` the poses need).

    The pose log is held in memory (a 100 Hz log of an hour is 360,000 rows per node); the
    signal log is consumed lazily, so memory stays bounded by the chunk size (plus 8 bytes a
    row for duplicate detection across chunks). Merge the per-chunk summaries with
    :meth:`SyncSummary.merge`. Options as in :func:`~rplearn.data.sync.synchronise`.

    A chunk's ``attrs`` may name its file (``"source"``) and the file row of its first row
    (``"first_row"``) for messages; by default rows are counted over the whole stream.

    Raises
    ------
    InputError
        As :func:`~rplearn.data.sync.synchronise`; the link, the receivers' clock offsets and ``min_samples``
        checks after the last chunk.
    """
    options = sync_options_or_default(options)
    pose = validate_pose_log(pose_log, "pose log")
    tracks = tracks_of_checked_log(pose, options.clock_offsets_s, "pose log", options.max_gap_s)
    non_unit = non_unit_quaternion_rows(pose)
    phases = flight_phases(pose_log, tracks, options.clock_offsets_s, options.airborne_margin_m)
    carry: dict = {}  # the last reading of each link, for readings repeated across chunks
    seen = _SeenRows()
    pairs: set[tuple[str, str]] = set()
    receivers: set[str] = set()  # with clock offsets per receiver: the receivers the rows name (a few node ids)
    per_receiver = isinstance(options.signal_clock_offset_s, Mapping)
    n_out = 0
    total = SyncSummary()
    for chunk in signal_chunks:
        repeats = seen.repeats(row_hashes(chunk)) if len(chunk) else np.zeros(0, bool)
        if options.link is not None and len(chunk) and {"tx", "rx"} <= set(chunk.columns):
            pairs |= _pairs(chunk)
        if per_receiver and "rx" in chunk.columns:
            receivers.update(chunk["rx"].astype(str).unique())
        where = str(chunk.attrs.get("source", source))
        first_row = int(chunk.attrs.get("first_row", total.n_in))
        result = match_chunk(tracks, chunk, options, where, seen_before=repeats, first_row=first_row,
                              phases=phases, carry=carry)
        result.summary.non_unit_quaternions, non_unit = non_unit, 0  # counted once, in the first chunk
        n_out += result.summary.n_out
        total.merge(result.summary)
        yield result
    if options.link is not None:
        check_link_nodes(pd.DataFrame(sorted(pairs), columns=["tx", "rx"]), options.link, source)
    check_receiver_offsets(options.signal_clock_offset_s, receivers, source)
    notes = list(total.notes)
    finish_summary(total, tracks, phases, options, source)  # raises when too few matched
    if len(total.notes) > len(notes):
        yield SyncResult(pd.DataFrame(columns=list(MATCHED_COLUMNS)),
                         SyncSummary(notes=total.notes[len(notes):], fixed_nodes=total.fixed_nodes))


@check_types
def synchronise_to_parquet(
    pose_log: pd.DataFrame,
    signal_chunks: Iterable[pd.DataFrame],
    out_path: str,
    options: SyncOptions | None = None,
    source: str = "signal log",
) -> SyncSummary:
    """Stream a signal log through :func:`synchronise_stream` into one Parquet file.

    Parameters
    ----------
    pose_log : DataFrame
        Canonical pose log.
    signal_chunks : iterable of DataFrame
        Signal-log chunks, e.g. :func:`rplearn.io.tables.iter_signal_table`.
    out_path : str
        Parquet file to write (one row group per non-empty chunk); written atomically, so
        nothing is left when matching fails.
    options : SyncOptions, optional
        As for :func:`synchronise_stream`.
    source : str
        Name of the signal log in messages.

    Returns
    -------
    SyncSummary
        Counts over the whole log.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    total = SyncSummary()
    with atomic_path(out_path) as tmp:
        writer = None
        schema = None
        try:
            for res in synchronise_stream(pose_log, signal_chunks, options, source):
                total.merge(res.summary)
                if res.dataset.empty:
                    continue
                table = pa.Table.from_pandas(res.dataset, preserve_index=False)
                if writer is None or schema is None:
                    schema = table.schema
                    writer = pq.ParquetWriter(tmp, schema)
                else:
                    table = table.select(schema.names).cast(schema)
                writer.write_table(table)
            if writer is None:  # nothing matched: write an empty file with the canonical columns
                empty = pd.DataFrame({c: pd.Series(dtype=str if c in ("tx", "rx") else float)
                                      for c in MATCHED_COLUMNS})
                empty.to_parquet(tmp, index=False)
        finally:
            if writer is not None:
                writer.close()
    return total


__all__ = ["conform_chunk", "row_hashes", "synchronise_stream", "synchronise_to_parquet"]
