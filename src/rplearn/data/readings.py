"""One radio reading, one row: readings reported twice, report periods and report rates.

Some loggers write one radio reading twice: ArduPilot DataFlash logs write every ``RAD``
record twice, 2-6 ms apart with identical values; a ground station's ``.tlog`` carries the same
reading as ``RADIO`` and ``RADIO_STATUS``. Kept as two rows, such a reading counts twice in
cross-validation, standard errors and every threshold that counts samples, and a radio that
reports once a second looks like one reporting at 100-200 Hz.

A row is a **repeated reading** of the row before it on the same link (same ``tx`` and ``rx``,
in time order) when every column but ``t`` is equal and it follows it by at most
``fraction`` (default :data:`REPEAT_FRACTION`) of the link's report period
(:func:`report_period_s`), on a link where such close copies are **systematic**: at least
:data:`REPEAT_MIN_SHARE` of its consecutive rows are (a logger that writes readings twice
doubles every one of them). The first copy is kept.

The rule never merges the packets of a radio that reports at a steady rate, however fast and
however often its RSSI repeats (each packet follows the one before by about one period, ten
times the window), nor the few packets of a radio with random timing (Wi-Fi) that happen to
arrive close together with the same RSSI (with exponential intervals, about 10% of its
packets follow the one before by less than a tenth of the report period estimated here, so that
even with a constant RSSI they stay below the 25% share). It can merge distinct packets only when a link sends most of them in pairs far
closer than its usual spacing *and* every column of both (RSSI, and any extra column such as a
frame type or a sequence number) is equal. ``SyncOptions(repeat_fraction=0)`` keeps every row.
A log read in chunks is judged chunk by chunk (200,000 rows, a reading repeated across two
chunks is found).
"""

from __future__ import annotations

from collections.abc import Mapping, MutableMapping
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types

#: Two rows of one link with equal values this close (a fraction of the link's report period)
#: are one reading reported twice. A tenth of the period: far above the 2-6 ms between the two
#: copies of a 1 Hz radio's reading, far below the spacing of distinct reports.
REPEAT_FRACTION: float = 0.1
#: Intervals shorter than this fraction of the link's 75th-percentile interval are left out
#: of its report period (they are the gaps between copies of one reading).
_SHORT_INTERVAL_FRACTION = 0.25
#: Close copies are merged only on a link where at least this share of consecutive rows are
#: close copies (doubled readings give 50%, a radio with random timing about 10%).
REPEAT_MIN_SHARE: float = 0.25


@check_types
def report_period_s(t_s: np.ndarray) -> float:
    """The usual interval between a link's distinct reports [s], even when readings are doubled.

    The median of the positive intervals between consecutive (sorted) times that are at least
    a quarter of their 75th percentile: for a steady radio the median interval; for a radio
    whose every reading is logged two or three times a few ms apart, the interval between
    readings, not between copies. NaN with fewer than two distinct finite times.

    Parameters
    ----------
    t_s : ndarray
        Times of one link's rows [s], in any order.
    """
    t = np.asarray(t_s, np.float64)[np.isfinite(t_s)]
    if not np.all(t[1:] >= t[:-1]):  # a link's times come sorted from repeated_readings: no second sort
        t = np.sort(t)
    d = np.diff(t)
    d = d[d > 0]
    if d.size == 0:
        return float("nan")
    long = d[d >= _SHORT_INTERVAL_FRACTION * np.quantile(d, 0.75)]
    return float(np.median(long))


def value_hashes(signal: pd.DataFrame) -> np.ndarray:
    """64-bit hash of every row's columns other than ``t`` (numbers as float64, the rest as text),
    equal for equal rows of any chunk of one log."""
    out = np.zeros(len(signal), np.uint64)
    for c in signal.columns:
        if c == "t":
            continue
        col = signal[c]
        if pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col):
            h = pd.util.hash_array(col.to_numpy(np.float64, na_value=np.nan))
        else:
            try:  # each distinct cell hashed once (text columns of a long log name a few nodes)
                codes, values = _distinct(col, "\x00missing")
                h = pd.util.hash_array(values)[codes]
            except TypeError:  # not all text (numbers or lists in a text column): hash their text
                values = col.to_numpy(dtype=object, na_value="\x00missing")
                h = pd.util.hash_array(values.astype(str).astype(object))
        with np.errstate(over="ignore"):
            out = out * np.uint64(1099511628211) ^ h  # FNV-style combination, column order matters
    return out


#: ``pd.factorize(column, use_na_sentinel=True)`` of a column: (codes, distinct cells).
Factorized = tuple[np.ndarray, Any]
#: One link in :func:`repeated_reading_mask`: its rows in time order, name, times [s] (after the
#: carried row, if any), report period [s], carried row, close pairs (None: none to compare).
_Link = tuple[np.ndarray, str, np.ndarray, float, "tuple[float, int, float] | None", "np.ndarray | None"]


def _distinct(col: pd.Series, missing: str, factorized: Factorized | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(codes, values)`` with ``values[codes]`` equal to ``col.to_numpy(dtype=object, na_value=missing)``
    and ``values`` distinct, without making one object per row (``factorized``: the column's
    ``pd.factorize``, when already made)."""
    codes, uniques = factorized if factorized is not None else pd.factorize(col, use_na_sentinel=True)
    values = np.append(np.asarray(uniques, dtype=object), np.array([missing], dtype=object))
    codes = np.where(codes < 0, len(values) - 1, codes)
    merged, distinct = pd.factorize(values)  # a missing cell and the text `missing` are one value
    return merged[codes], np.asarray(distinct, dtype=object)


def _link_codes(signal: pd.DataFrame, cells: Mapping[str, Factorized] | None = None) -> tuple[np.ndarray, list[str]]:
    """Code of each row's directed link and the link names ``"tx\x00rx"``."""
    cells = cells or {}
    tx, tx_names = _distinct(signal["tx"], "", cells.get("tx"))
    rx, rx_names = _distinct(signal["rx"], "", cells.get("rx"))
    key = tx.astype(np.int64) * (len(rx_names) + 1) + rx
    size = len(tx_names) * (len(rx_names) + 1)
    if size <= key.size + 4096:  # a table of every possible pair: links numbered by key (any numbering will do)
        pairs = np.flatnonzero(np.bincount(key, minlength=size))
        lookup = np.zeros(size, np.intp)
        lookup[pairs] = np.arange(pairs.size)
        codes = lookup[key]
    else:
        codes, pairs = pd.factorize(key)
    names = [f"{tx_names[p // (len(rx_names) + 1)]}\x00{rx_names[p % (len(rx_names) + 1)]}" for p in pairs]
    return codes, names


def _by_link_in_time_order(t: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """``np.lexsort((t, codes))``: the rows by link, each link's in time order (ties in row order).

    A log already in time order (most are) needs only a stable sort of the small link codes.
    """
    if t.size > 1 and bool(np.all(t[1:] >= t[:-1])):  # False with any NaN: then the full sort
        small = codes.astype(np.min_scalar_type(max(int(codes.max()), 0)))
        return np.argsort(small, kind="stable")
    return np.lexsort((t, codes))


@check_types
def repeated_readings(
    signal: pd.DataFrame,
    fraction: float = REPEAT_FRACTION,
    t_s: np.ndarray | None = None,
    carry: MutableMapping[str, tuple[float, int, float]] | None = None,
) -> np.ndarray:
    """Mask of rows that repeat the reading of the row before them on their link (see module doc).

    Parameters
    ----------
    signal : DataFrame
        Signal log with ``t``, ``tx``, ``rx`` and any other columns (all compared).
    fraction : float
        Largest interval between two copies, as a fraction of the link's report period
        (:func:`report_period_s`); 0 finds none.
    t_s : ndarray, optional
        Times to use instead of the column ``t`` (e.g. on the common clock) [s].
    carry : dict, optional
        For a log read in chunks: per link, the time [s], value hash and report period [s] of
        the last row of the earlier chunks; read and updated, so that a reading repeated across
        a chunk boundary is found and a link with too few rows in a chunk uses its earlier period.

    Returns
    -------
    ndarray of bool
        True for every copy after the first.
    """
    return repeated_reading_mask(signal, fraction, t_s, carry)


@check_types
def repeated_reading_mask(
    signal: pd.DataFrame,
    fraction: float = REPEAT_FRACTION,
    t_s: np.ndarray | None = None,
    carry: MutableMapping[str, tuple[float, int, float]] | None = None,
    cells: Mapping[str, Factorized] | None = None,
) -> np.ndarray:
    """:func:`repeated_readings`, reusing the ``pd.factorize`` of ``tx`` and ``rx`` in ``cells``.

    Rows are hashed (:func:`value_hashes`) only where a link's close pairs could reach
    :data:`REPEAT_MIN_SHARE`: a row's hash is its own, whichever rows are hashed with it.
    """
    n = len(signal)
    mask = np.zeros(n, bool)
    if n == 0 or not fraction > 0:
        return mask
    t = np.asarray(t_s if t_s is not None else pd.to_numeric(signal["t"], errors="coerce"), np.float64)
    codes, names = _link_codes(signal, cells)
    order = _by_link_in_time_order(t, codes)
    starts = np.flatnonzero(np.r_[True, codes[order][1:] != codes[order][:-1]])
    ends = np.r_[starts[1:], n]
    links: list[_Link] = []
    for s, e in zip(starts, ends):  # first pass: times, periods and close pairs
        rows = order[s:e]
        name = names[codes[rows[0]]]
        tr = t[rows]
        if carry is None and _too_few_close_pairs(tr, fraction):  # no period needed
            links.append((rows, name, tr, float("nan"), None, None))
            continue
        period = report_period_s(tr)
        before = carry.get(name) if carry is not None else None
        if before is not None:
            if not np.isfinite(period):
                period = before[2]
            tr = np.r_[before[0], tr]
        close = None
        if np.isfinite(period):
            with np.errstate(invalid="ignore"):
                dt = np.diff(tr)
                close = (dt >= 0) & (dt <= fraction * period)
            if not close.sum() >= REPEAT_MIN_SHARE * close.size:  # fewer equal pairs still
                close = None
        links.append((rows, name, tr, period, before, close))
    hashes = _hashes_needed(signal, links, carry is not None)
    for rows, name, tr, period, before, close in links:  # second pass: equal values
        lead: list[np.uint64] = [] if before is None else [np.uint64(before[1])]
        if close is not None:
            hr = np.r_[lead, hashes[rows]].astype(np.uint64) if lead else hashes[rows]
            same = close & (hr[1:] == hr[:-1])
            if same.sum() >= REPEAT_MIN_SHARE * same.size:
                mask[rows[rows.size - same.size:]] = same
        if carry is not None:
            finite = np.flatnonzero(np.isfinite(tr))
            if finite.size:
                last = int(finite[-1])
                h = lead[0] if lead and last == 0 else hashes[rows[last - len(lead)]]
                carry[name] = (float(tr[last]), int(h), period)
    return mask


def _too_few_close_pairs(t_s: np.ndarray, fraction: float) -> bool:
    """Whether a link (times ``t_s`` in time order, NaN last) certainly has fewer than
    :data:`REPEAT_MIN_SHARE` close pairs, without its report period's two partial sorts.

    The period (:func:`report_period_s`) is the median of the intervals ``d`` from a quarter of
    their 75th percentile up: of at least the top quarter of ``d``, so at most the value of rank
    ``0.875 n + 1`` of ``d``. Twice the mean interval bounds it whenever 90% of ``d`` lie below
    that; then the pairs closer than ``fraction`` times that bound are at least the close pairs.
    """
    t = t_s[np.isfinite(t_s)]
    if not np.all(t[1:] >= t[:-1]):
        t = np.sort(t)
    d = np.diff(t)
    d = d[d > 0]
    if d.size == 0:
        return True  # no period: no pair is compared
    bound = 2.0 * float(np.mean(d))
    if not np.count_nonzero(d <= bound) >= 0.9 * d.size + 2:
        return False
    with np.errstate(invalid="ignore"):
        dt = np.diff(t_s)
        close = np.count_nonzero((dt >= 0) & (dt <= fraction * bound))
    return bool(close < REPEAT_MIN_SHARE * dt.size)


def _hashes_needed(signal: pd.DataFrame, links: list[_Link], last_rows: bool) -> np.ndarray:
    """:func:`value_hashes` of the rows the links compare (those of close pairs) and, with
    ``last_rows``, each link's last row of finite time; zero elsewhere."""
    need = [rows for rows, _, _, _, _, close in links if close is not None]
    if last_rows:
        for rows, _, tr, _, before, _ in links:
            finite = np.flatnonzero(np.isfinite(tr[0 if before is None else 1:]))
            if finite.size:
                need.append(rows[finite[-1:]])
    out = np.zeros(len(signal), np.uint64)
    if need:
        rows = np.unique(np.concatenate(need))
        out[rows] = value_hashes(signal.iloc[rows])
    return out


def duplicate_rows(signal: pd.DataFrame) -> np.ndarray:
    """Mask of rows repeating an earlier row exactly, in every column (the first copy is False)."""
    mask = np.zeros(len(signal), bool)
    if signal.empty:
        return mask
    # Only rows sharing a time can repeat each other: compare whole rows within those (few)
    # rows only, which is 10x faster than hashing every row of a long log.
    t = signal["t"].to_numpy() if "t" in signal.columns else None
    if t is not None:
        try:
            order = np.argsort(t, kind="stable")
            same = np.flatnonzero(t[order][1:] == t[order][:-1])
        except TypeError:  # times of mixed types: compare everything
            candidates = np.arange(len(signal))
        else:
            if same.size == 0:
                return mask
            candidates = np.unique(np.concatenate([order[same], order[same + 1]]))
    else:
        candidates = np.arange(len(signal))
    subset = signal.iloc[candidates]
    try:
        repeated = subset.duplicated(keep="first").to_numpy(bool)
    except TypeError:  # unhashable cells (lists): compare their text
        repeated = subset.astype(str).duplicated(keep="first").to_numpy(bool)
    mask[candidates[repeated]] = True
    return mask


@check_types
def report_rate_hz(t_s: np.ndarray, repeated: np.ndarray | None = None) -> float:
    """Report rate of one link [Hz]: 1 / the median interval between its readings, copies of one
    reading (``repeated``) left out; NaN with fewer than two distinct times."""
    t = np.asarray(t_s, np.float64)
    if repeated is not None:
        t = t[~np.asarray(repeated, bool)]
    t = np.sort(t[np.isfinite(t)])
    d = np.diff(t)
    d = d[d > 0]
    return float(1.0 / np.median(d)) if d.size else float("nan")


__all__ = ["REPEAT_FRACTION", "REPEAT_MIN_SHARE", "duplicate_rows", "repeated_reading_mask", "repeated_readings",
           "report_period_s", "report_rate_hz", "value_hashes"]
