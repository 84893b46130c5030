"""The matched dataset of :func:`rplearn.data.sync.synchronise`, built once from arrays.

Internal to :mod:`rplearn.data.sync` (issue 30: building the matched DataFrame was 41% of a
sync). The float columns are gathered straight into one preallocated block, which becomes the
DataFrame without a copy; the node columns are taken from the factorised node ids (one string
per node, not one per row).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from rplearn.core.geometry import slerp_weights
from rplearn.data.poses import STATUS_OUT_OF_SPAN, STATUS_POSE_GAP, PoseTrack, TrackSet
from rplearn.data.tables import MATCHED_COLUMNS, POSE_FIELDS, node_id_codes

#: Float columns of the matched dataset, in the order of the block.
_SIGNAL_FLOATS: tuple[str, ...] = ("t", "rssi_dbm", "tx_power_dbm", "frequency_hz")
_FLOAT_COLUMNS: tuple[str, ...] = _SIGNAL_FLOATS + tuple(f"{end}_{f}" for end in ("tx", "rx") for f in POSE_FIELDS)

#: Rows interpolated at once: small enough for the temporaries to stay in cache (and be reused
#: by the allocator instead of mapped afresh), large enough for numpy's loops.
BLOCK_ROWS = 1 << 15


def node_column(uniques: np.ndarray, codes: np.ndarray, index: pd.Index) -> pd.Series:
    """The node ids ``uniques[codes]`` as the text column ``astype(str)`` would make, taken per code."""
    return pd.Series(pd.Series(np.asarray(uniques).astype(str)).array.take(codes), index=index)


def node_codes(
    tx: pd.Series, rx: pd.Series, cells: Mapping[str, tuple[np.ndarray, Any]] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both ends' node ids as codes into one array of distinct ids: ``(tx_code, rx_code, uniques)``.

    ``uniques[tx_code]`` equals :func:`~rplearn.data.tables.node_ids` of ``tx`` row by row
    (a missing cell is ``""``), but the text of each distinct cell is made once, not per row;
    ``cells``: the ``pd.factorize`` of ``tx`` and ``rx`` (:func:`factorize_ends`), when made.
    """
    cells = cells or {}
    tx_code, tx_ids = node_id_codes(tx, factorized=cells.get("tx"))
    rx_code, rx_ids = node_id_codes(rx, factorized=cells.get("rx"))
    merged, uniques = pd.factorize(np.concatenate([tx_ids, rx_ids]))  # one code per node over both ends
    return merged[tx_code], merged[tx_ids.size + rx_code], np.asarray(uniques, dtype=object)


def factorize_ends(signal: pd.DataFrame) -> dict[str, tuple[np.ndarray, Any]]:
    """``pd.factorize(column, use_na_sentinel=True)`` of ``tx`` and ``rx``: made once per chunk,
    read by the node codes and the link codes of :mod:`rplearn.data.readings`."""
    return {end: pd.factorize(signal[end], use_na_sentinel=True) for end in ("tx", "rx")}


def interpolate_end(
    tracks: Mapping[str, PoseTrack],
    node_ids: Sequence[str],
    node_code: np.ndarray,
    t_s: np.ndarray,
    max_gap_s: float,
    rows: np.ndarray,
    pose: np.ndarray,
) -> np.ndarray:
    """:func:`~rplearn.data.poses.interpolate_nodes` written as rows of ``pose`` (7, n):
    ``x, y, z, qw, qx, qy, qz`` (NaN outside ``rows``); returns the status of every row.

    One ``searchsorted`` per node gives each row its pose interval in the tracks' one store
    (:class:`~rplearn.data.poses.TrackSet`); then all rows, whatever their node, are
    interpolated in blocks of :data:`BLOCK_ROWS`, each field written once into its own
    contiguous row of the matched dataset's block (:func:`float_block`). The arithmetic is that
    of :meth:`PoseTrack.interpolate <rplearn.data.poses.PoseTrack.interpolate>`, bit for bit.
    """
    store = TrackSet.of(tracks)
    n = len(t_s)
    status = np.zeros(n, np.int8)
    before = np.zeros(n, np.intp)  # row of the pose before each time in the store
    which = np.full(len(node_ids), -1, np.intp)  # node code -> moving track (-1: none)
    spans: list[tuple[float, float, bool]] = []  # each moving track's first and last time, still
    covered = np.zeros(n, bool)
    static: list[tuple[PoseTrack, np.ndarray]] = []
    for code, node in enumerate(node_ids):
        sel = np.flatnonzero((node_code == code) & rows)
        if not sel.size:
            continue
        covered[sel] = True
        track = store[node]
        if track.static:
            static.append((track, sel))
            continue
        tk = track.t_s
        before[sel] = pose_before(store, node, t_s[sel])
        which[code] = len(spans)
        spans.append((float(tk[0]), float(tk[-1]), track.still))
    if spans:
        _interpolate_rows(store, before, which[node_code], spans, (t_s, max_gap_s), (pose, status))
    for track, sel in static:  # its one pose at every time
        pos, quat, status[sel] = track.interpolate(t_s[:1], max_gap_s)
        pose[:3, sel] = pos[0][:, None]
        pose[3:, sel] = quat[0][:, None]
    if not covered.all():
        pose[:, ~covered] = np.nan
        status[~covered] = 0
    return status


def pose_before(store: TrackSet, node: str, t_s: np.ndarray) -> np.ndarray:
    """Store row of the pose before each time ``t_s`` [s] of a ``node`` of two poses or more:
    ``np.clip(np.searchsorted(tk, t_s, side="right") - 1, 0, len(tk) - 2)`` plus the node's first
    store row, as :meth:`PoseTrack.brackets <rplearn.data.poses.PoseTrack.brackets>` finds it.

    ``numpy.interp`` of the store rows at the node's times (its search starts from the last
    interval found, so times in order cost no binary search) lands on that row or, rounded up,
    on the next one; one comparison with the pose time puts it back.
    """
    track = store[node]
    first = store.first_row[node]
    last = first + track.t_s.shape[0] - 1
    rows = np.interp(t_s, track.t_s, np.arange(first, last + 1, dtype=np.float64))
    i = rows.astype(np.intp)  # rows >= first >= 0: the floor (NaN: anything, clipped)
    np.clip(i, first, last, out=i)
    i -= store.t_s[i] > t_s  # rounded up past the time (or before the first pose)
    np.clip(i, first, last - 1, out=i)
    return i


def _interpolate_rows(
    store: TrackSet,
    before: np.ndarray,
    track_of_row: np.ndarray,
    spans: list[tuple[float, float, bool]],
    times: tuple[np.ndarray, float],
    outputs: tuple[np.ndarray, np.ndarray],
) -> None:
    """Poses and statuses of every row from its store row ``before`` and its moving track
    ``track_of_row`` (-1: none; such rows get meaningless values), in blocks."""
    t_s, max_gap_s = times
    pose, status = outputs
    first = np.array([s[0] for s in spans] + [np.nan])  # [-1]: rows without a moving track
    last = np.array([s[1] for s in spans] + [np.nan])
    still = np.array([s[2] for s in spans] + [True])
    tk, position, quat = store.t_s, store.position_xyz, store.quat_wxyz
    top = tk.shape[0] - 1
    with np.errstate(divide="ignore", invalid="ignore"):  # rows without a track: 0 / 0
        for start in range(0, t_s.shape[0], BLOCK_ROWS):  # blocks: the temporaries stay in cache
            block = slice(start, start + BLOCK_ROWS)
            i = before[block]
            i1 = i + 1
            np.minimum(i1, top, out=i1)
            t = t_s[block]
            k = track_of_row[block]
            t0 = tk.take(i)
            t1 = tk.take(i1)  # as PoseTrack.brackets
            on_sample = (t == t0) | (t == t1)
            t1 -= t0
            st = status[block]
            st[(t1 > max_gap_s) & ~on_sample & ~still[k]] = STATUS_POSE_GAP
            st[(t < first[k]) | (t > last[k]) | ~np.isfinite(t)] = STATUS_OUT_OF_SPAN
            frac = t - t0
            frac /= t1
            np.clip(frac, 0.0, 1.0, out=frac)
            p0 = np.take(position, i, axis=0)
            p1 = np.take(position, i1, axis=0)
            for j in range(3):  # p0 + fraction * (p1 - p0), as PoseTrack.interpolate
                p = np.subtract(p1[:, j], p0[:, j], out=pose[j, block])
                p *= frac
                p += p0[:, j]
            slerp_into(np.take(quat, i, axis=0), np.take(quat, i1, axis=0), frac, pose[3:, block])


def slerp_into(q0: np.ndarray, q1: np.ndarray, fraction: np.ndarray, out: np.ndarray) -> None:
    """:func:`~rplearn.core.geometry.slerp_wxyz` of ``q0``, ``q1`` (m, 4) written transposed into
    ``out`` (4, m), bit for bit, one component at a time (no reduction along rows of four).

    The dot product sums its products in the order of ``einsum`` (``(p0 + p2) + (p1 + p3)``),
    the norm its squares in the order of ``numpy.linalg.norm`` (``((s0 + s1) + s2) + s3``);
    tests/data/test_sync_match.py holds them to ``slerp_wxyz``'s bits.
    """
    a = [q0[:, c] for c in range(4)]
    b = [q1[:, c] for c in range(4)]
    dot = a[0] * b[0]
    dot += a[2] * b[2]
    odd = a[1] * b[1]
    odd += a[3] * b[3]
    dot += odd
    w0, w1 = slerp_weights(dot, fraction)
    for c in range(4):
        np.multiply(w0, a[c], out=out[c])
        out[c] += w1 * b[c]
    norm = out[0] * out[0]
    for c in range(1, 4):
        norm += out[c] * out[c]
    np.sqrt(norm, out=norm)
    out /= np.where(out[0] < 0.0, -norm, norm)  # qw >= 0


def float_block(n: int) -> np.ndarray:
    """An empty block for the float columns of ``n`` signal rows, rows named by :func:`block_row`."""
    return np.empty((len(_FLOAT_COLUMNS), n), np.float64)


def block_row(column: str) -> int:
    """Row of the float ``column`` (a signal column or the first pose field of an end) in the block."""
    return _FLOAT_COLUMNS.index(column)


def matched_frame(
    signal: pd.DataFrame,
    idx: np.ndarray,
    block: np.ndarray,
    node_codes: dict[str, np.ndarray],
    uniques: np.ndarray,
) -> pd.DataFrame:
    """The kept rows ``idx`` in :data:`MATCHED_COLUMNS` order, then the extra signal columns.

    ``block``: the float columns of every signal row (:func:`float_block`, ``t`` on the common
    clock, the poses by :func:`interpolate_end`), compacted in place to the kept rows (it is
    the dataset's storage afterwards); ``node_codes``: the codes of ``tx`` and ``rx`` into
    ``uniques``.
    """
    m, n = idx.size, block.shape[1]
    lo = int(idx[0]) if m else 0  # rows dropped before the first kept one: left where they are
    holes = m > 0 and int(idx[-1]) != lo + m - 1  # idx is increasing: a hole in between, or none
    moved = np.flatnonzero(idx != np.arange(lo, lo + m)) if holes else np.zeros(0, np.intp)
    if moved.size:  # the kept rows after the first hole to the front, row by row through one buffer
        j = int(moved[0])
        buffer = np.empty(m - j, np.float64)
        for row in block:
            np.take(row, idx[j:], out=buffer)
            row[lo + j : lo + m] = buffer
    data = block[:, lo : lo + m]
    if 2 * m < n:  # no mostly idle buffer
        data = np.ascontiguousarray(data)
    out = pd.DataFrame(data.T, columns=list(_FLOAT_COLUMNS), copy=False)
    for j, end in enumerate(("tx", "rx")):
        out.insert(1 + j, end, node_column(uniques, node_codes[end][idx], out.index))
    if tuple(out.columns) != MATCHED_COLUMNS:  # the block's layout must follow the table's
        out = out[list(MATCHED_COLUMNS)]
    for c in [c for c in signal.columns if c not in MATCHED_COLUMNS]:
        out[c] = pd.Series(signal[c].array[idx], index=out.index)  # keeps the column's dtype (text stays text)
    return out


__all__: list[str] = []
