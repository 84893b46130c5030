"""Rows of a matched dataset repeated across the chunks and parts it is read in.

A matched dataset read whole is refused when a row repeats an earlier row in every column
(:func:`rplearn.data.tables.validate_matched`): one sample twice would be learned twice, weighing
it double and making the posterior spreads too narrow. A dataset read a chunk at a time (a big
file), or part by part in other processes (many files, Dask), has its copies in other chunks and
parts. Here every row gets a 64-bit hash of its whole content (:func:`matched_row_hashes`), kept
in row order:

- within one source (a file read in chunks, :class:`SourceHashes`) the hashes of all its rows are
  sorted once at its end: copies are equal neighbours;
- between sources (:meth:`RowCopies.then`, where the statistics of parts are merged, possibly on
  another worker) the later source's hashes are looked up among the earlier ones', and only when
  their time spans overlap: a copy has the very time of the row it copies, so flights at other
  times are never compared.

The count and the first repeated row (its file and row, and the row it copies) are exactly those
of the whole-dataset check, whatever the chunk size and however the parts are merged (a false
match needs a collision of 64-bit hashes: about ``n^2 / 2^65``, 3e-8 for a million rows).

Memory: 8 bytes a row kept (``RowCopies.hashes``), plus, while one source is closed or two are
merged, a sorted copy of one side's hashes (8 bytes a row) and a mask (1 byte a row).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rplearn.data.tables import normalise_times, repeated_rows_message
from rplearn.errors import InputError

_MIX = np.uint64(0x9E3779B97F4A7C15)
_FINAL_1 = np.uint64(0xBF58476D1CE4E5B9)
_FINAL_2 = np.uint64(0x94D049BB133111EB)
_MISSING_TEXT = np.uint64(0x6D697373696E6721)


def _text_hash(values: Sequence[str]) -> np.ndarray:
    """Deterministic 64-bit hashes of strings (the same in every process, unlike ``hash``)."""
    return pd.util.hash_array(np.asarray(list(values), dtype=object)).astype(np.uint64)


#: Rows hashed at a time: each column's few passes then stay in the processor's cache.
_BLOCK_ROWS = 32_768


def _column_words(col: pd.Series) -> tuple[np.ndarray, bool]:
    """The cells of a column as 64-bit words to hash, and whether they are float64 numbers (whose
    bits are hashed, -0.0 as 0.0 and every NaN alike: an integer column hashes as the same
    numbers as floats, its values beyond 2^53 by their exact value); any other value is hashed
    by its text (a value that is not a string marked as such)."""
    if (pd.api.types.is_numeric_dtype(col) or pd.api.types.is_bool_dtype(col)) and not isinstance(col.dtype, pd.CategoricalDtype):
        number = np.ascontiguousarray(col.to_numpy(np.float64, na_value=np.nan))
        if pd.api.types.is_integer_dtype(col):
            inexact = np.abs(number) > _EXACT_INTEGER  # NaN (a missing value) is not
            if inexact.any():  # integers a float cannot hold: by their exact value, not rounded
                return _exact_integer_words(col, number, inexact), False
        return number, True
    codes, uniques = pd.factorize(col, use_na_sentinel=True)
    # a string by its text; any other value marked, so that 1 and "1" stay two values
    words = _text_hash([u if isinstance(u, str) else f"\x00{u}" for u in uniques])
    out = words[codes] if words.size else np.zeros(codes.size, np.uint64)
    if (codes < 0).any():
        out[codes < 0] = _MISSING_TEXT
    return out, False


#: Integers beyond which float64 does not hold every integer (2^53).
_EXACT_INTEGER = float(2**53)


def _exact_integer_words(col: pd.Series, number: np.ndarray, inexact: np.ndarray) -> np.ndarray:
    """Words of an integer column holding values beyond 2^53: the float bits of the others (as
    in a float column; a missing value as NaN) and the text hash of each large one's exact
    value, so that two integers a float64 would round alike hash apart."""
    words = np.add(number, 0.0).view(np.uint64).copy()
    words[np.isnan(number)] = np.array(np.nan).view(np.uint64)
    big = col.to_numpy(object)[inexact]
    words[inexact] = _text_hash([f"\x01{int(v)}" for v in big])
    return words


def matched_row_hashes(chunk: pd.DataFrame) -> np.ndarray:
    """64-bit hash of every row of a matched dataset chunk over all its columns (in name order,
    so the columns' order in a file does not matter), equal for rows equal in every column in any
    chunk or file; times as :func:`~rplearn.data.tables.normalise_times` reads them.

    Each column's word is mixed in by a bijection of the words so far (xor, an odd multiply,
    an xor-shift), a :data:`_BLOCK_ROWS` block of rows at a time, without temporaries."""
    chunk = normalise_times(chunk)
    names = sorted(str(c) for c in chunk.columns)
    columns = [_column_words(chunk[name]) for name in names]
    seed = np.uint64(_text_hash(["\x1f".join(names)])[0])  # other columns, another hash
    n = len(chunk)
    h = np.full(n, seed, np.uint64)
    number = np.empty(min(n, _BLOCK_ROWS), np.float64)
    shifted = np.empty(number.size, np.uint64)
    for start in range(0, n, _BLOCK_ROWS):
        stop = min(start + _BLOCK_ROWS, n)
        hb, num, sh = h[start:stop], number[: stop - start], shifted[: stop - start]
        for words, is_number in columns:
            if is_number:
                np.add(words[start:stop], 0.0, out=num)  # -0.0 + 0.0 is 0.0
                if not np.isfinite(np.add.reduce(num)):
                    num[np.isnan(num)] = np.nan  # one NaN
                np.bitwise_xor(hb, num.view(np.uint64), out=hb)
            else:
                np.bitwise_xor(hb, words[start:stop], out=hb)
            np.multiply(hb, _MIX, out=hb)
            np.right_shift(hb, np.uint64(29), out=sh)
            np.bitwise_xor(hb, sh, out=hb)
        for shift, factor in ((30, _FINAL_1), (27, _FINAL_2)):
            np.right_shift(hb, np.uint64(shift), out=sh)
            np.bitwise_xor(hb, sh, out=hb)
            np.multiply(hb, factor, out=hb)
        np.right_shift(hb, np.uint64(31), out=sh)
        np.bitwise_xor(hb, sh, out=hb)
    return h


def _has_equal_neighbours(hashes: np.ndarray) -> bool:
    ordered = np.sort(hashes)
    return bool(np.any(ordered[1:] == ordered[:-1]))


@dataclass
class RowCopies:
    """The rows of some sources (files, in order) and which of them repeat an earlier one.

    Attributes
    ----------
    sources : list of (str, int)
        Each source's name and row count, in row order.
    hashes : ndarray of uint64
        Every row's hash (:func:`matched_row_hashes`), in row order over the sources.
    t_min_s, t_max_s : float
        Span of the rows' times [s] (NaN without a time column or rows).
    count : int
        Rows that repeat an earlier row.
    first : int
        Position of the first of them in ``hashes`` (-1 when none) ...
    earlier : int
        ... and of the first row it repeats.
    holders : tuple of str
        Sources holding repeated rows.
    """

    sources: list[tuple[str, int]]
    hashes: np.ndarray
    t_min_s: float = float("nan")
    t_max_s: float = float("nan")
    count: int = 0
    first: int = -1
    earlier: int = -1
    holders: tuple[str, ...] = ()

    def place(self, position: int) -> tuple[str, int]:
        """``(source, row in it)`` of a position in :attr:`hashes`."""
        ends = np.cumsum([n for _, n in self.sources])
        k = int(np.searchsorted(ends, position, side="right"))
        return self.sources[k][0], int(position - (ends[k - 1] if k else 0))

    def _overlaps(self, later: RowCopies) -> bool:
        spans = (self.t_min_s, self.t_max_s, later.t_min_s, later.t_max_s)
        if any(np.isnan(s) for s in spans):
            return bool(self.hashes.size and later.hashes.size)  # no time to tell: compare
        return not (later.t_min_s > self.t_max_s or later.t_max_s < self.t_min_s)

    def then(self, later: RowCopies) -> RowCopies:
        """These rows followed by ``later``'s (a new object; neither input changes): a row of
        ``later`` equal to one of these is a copy, found only when the time spans overlap."""
        if not self.hashes.size:
            return later if not self.sources else _shifted(self, later)
        offset = self.hashes.size
        found = np.zeros(later.hashes.size, bool)
        if later.hashes.size and self._overlaps(later):
            ordered = np.sort(self.hashes)
            at = np.searchsorted(ordered, later.hashes).clip(max=ordered.size - 1)
            found = ordered[at] == later.hashes
        cross = int(np.unique(later.hashes[found]).size) if found.any() else 0  # later's own copies counted already
        first, earlier = self.first, self.earlier
        if self.count == 0 and (cross or later.count):
            candidates = [p for p in (later.first if later.count else -1, int(np.argmax(found)) if cross else -1) if p >= 0]
            at_later = min(candidates)
            first = offset + at_later
            h = later.hashes[at_later]
            earlier = (int(np.flatnonzero(self.hashes == h)[0]) if found[at_later]
                       else offset + later.earlier)
        holders = set(self.holders) | set(later.holders)
        if cross:
            holders |= {later.place(p)[0] for p in _source_starts(later, found)}
        t = [v for v in (self.t_min_s, later.t_min_s) if not np.isnan(v)]
        u = [v for v in (self.t_max_s, later.t_max_s) if not np.isnan(v)]
        return RowCopies([*self.sources, *later.sources], np.concatenate([self.hashes, later.hashes]),
                         min(t) if t else float("nan"), max(u) if u else float("nan"),
                         self.count + later.count + cross, first, earlier,
                         tuple(sorted(holders, key=[s for s, _ in [*self.sources, *later.sources]].index)))

    def error(self) -> InputError | None:
        """The refusal of the whole-dataset check (one line naming the file, the count, the first
        repeated row and, in another file, the row it copies), or None without copies."""
        if self.count == 0:
            return None
        source, row = self.place(self.first)
        other, other_row = self.place(self.earlier)
        copy_of = None if other == source else (other, other_row)
        return InputError(repeated_rows_message(source, self.count, row, copy_of, len(self.holders)))


def _source_starts(copies: RowCopies, mask: np.ndarray) -> list[int]:
    """A position of ``mask`` in each source of ``copies`` that has one."""
    out, start = [], 0
    for _, n in copies.sources:
        hit = np.flatnonzero(mask[start:start + n])
        if hit.size:
            out.append(start + int(hit[0]))
        start += n
    return out


def _shifted(empty: RowCopies, later: RowCopies) -> RowCopies:
    """``later`` after sources without rows (their names kept in order)."""
    return RowCopies([*empty.sources, *later.sources], later.hashes, later.t_min_s, later.t_max_s, later.count,
                     later.first, later.earlier, later.holders)


class SourceHashes:
    """The hashes of one source's rows, gathered a chunk at a time (:meth:`add`) and checked
    for copies at its end (:meth:`finish`)."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.chunks: list[np.ndarray] = []
        self.t_min_s, self.t_max_s = float("nan"), float("nan")
        self.repeated = False

    def add(self, chunk: pd.DataFrame) -> bool:
        """Hash a chunk's rows; whether the source has shown a copy so far (within this chunk:
        rows of earlier chunks are compared at :meth:`finish`)."""
        chunk = normalise_times(chunk)
        hashes = matched_row_hashes(chunk)
        self.chunks.append(hashes)
        if "t" in chunk.columns and len(chunk):
            t = pd.to_numeric(chunk["t"], errors="coerce").to_numpy(np.float64)
            if np.isfinite(t).any():
                self.t_min_s = float(np.nanmin([self.t_min_s, np.nanmin(t)]))
                self.t_max_s = float(np.nanmax([self.t_max_s, np.nanmax(t)]))
        self.repeated = self.repeated or _has_equal_neighbours(hashes)
        return self.repeated

    def finish(self) -> RowCopies:
        """Every row's hash and the copies among them."""
        hashes = np.concatenate(self.chunks) if self.chunks else np.zeros(0, np.uint64)
        self.chunks = []
        out = RowCopies([(self.source, hashes.size)], hashes, self.t_min_s, self.t_max_s)
        if not self.repeated and not _has_equal_neighbours(hashes):
            return out
        order = np.argsort(hashes, kind="stable")  # equal hashes keep their rows' order
        ordered = hashes[order]
        later_copies = order[1:][ordered[1:] == ordered[:-1]]
        out.count = int(later_copies.size)
        out.first = int(later_copies.min())
        out.earlier = int(np.flatnonzero(hashes == hashes[out.first])[0])
        out.holders = (self.source,)
        return out


def refuse_copies(each: Sequence[RowCopies]) -> None:
    """Raise the whole-dataset refusal when a row of these sources (in order) repeats an earlier
    row of any of them (:meth:`RowCopies.then`, :meth:`RowCopies.error`)."""
    if not each:
        return
    merged = each[0]
    for later in each[1:]:
        merged = merged.then(later)
    refusal = merged.error()
    if refusal is not None:
        raise refusal


def source_copies(source: str, chunks: Iterable[pd.DataFrame]) -> RowCopies:
    """The hashes and copies of one source's rows, given in chunks (:class:`SourceHashes`)."""
    hashes = SourceHashes(source)
    for chunk in chunks:
        hashes.add(chunk)
    return hashes.finish()


__all__ = ["RowCopies", "SourceHashes", "matched_row_hashes", "refuse_copies", "source_copies"]
