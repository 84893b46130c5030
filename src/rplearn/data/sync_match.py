"""The matched dataset of :func:`rplearn.data.sync.synchronise`, built once from arrays.

Internal to :mod:`rplearn.data.sync` (issue 30: building the matched DataFrame was 41% of a
sync). The float columns are gathered straight into one preallocated block, which becomes the
DataFrame without a copy; the node columns are taken from the factorised node ids (one string
per node, not one per row).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from rplearn.core.geometry import slerp_wxyz
from rplearn.data.poses import PoseTrack
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


def node_codes(tx: pd.Series, rx: pd.Series) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both ends' node ids as codes into one array of distinct ids: ``(tx_code, rx_code, uniques)``.

    ``uniques[tx_code]`` equals :func:`~rplearn.data.tables.node_ids` of ``tx`` row by row
    (a missing cell is ``""``), but the text of each distinct cell is made once, not per row.
    """
    tx_code, tx_ids = node_id_codes(tx)
    rx_code, rx_ids = node_id_codes(rx)
    merged, uniques = pd.factorize(np.concatenate([tx_ids, rx_ids]))  # one code per node over both ends
    return merged[tx_code], merged[tx_ids.size + rx_code], np.asarray(uniques, dtype=object)


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

    One ``searchsorted`` per node, in blocks of :data:`BLOCK_ROWS`; each field is written
    once into its own contiguous row of the matched dataset's block (:func:`float_block`).
    """
    n = len(t_s)
    status = np.zeros(n, np.int8)
    covered = np.zeros(n, bool)
    for code, node in enumerate(node_ids):
        sel = np.flatnonzero((node_code == code) & rows)
        if not sel.size:
            continue
        covered[sel] = True
        track = tracks[node]
        if track.static:
            pos, quat, status[sel] = track.interpolate(t_s[:1], max_gap_s)
            pose[:3, sel] = pos[0][:, None]
            pose[3:, sel] = quat[0][:, None]
            continue
        for start in range(0, sel.size, BLOCK_ROWS):  # blocks: the temporaries stay in cache
            rows_b = sel[start : start + BLOCK_ROWS]
            i, frac, status[rows_b] = track.brackets(t_s[rows_b], max_gap_s)
            i1 = i + 1
            for j in range(3):  # p0 + fraction * (p1 - p0), as PoseTrack.interpolate
                column = track.position_xyz[:, j]
                p0 = column[i]
                p = column[i1] - p0
                p *= frac
                p += p0
                pose[j, rows_b] = p
            pose[3:, rows_b] = slerp_wxyz(track.quat_wxyz[i], track.quat_wxyz[i1], frac).T
    if not covered.all():
        pose[:, ~covered] = np.nan
    return status


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
    if m < n:  # kept rows to the front, row by row through one buffer (idx is increasing)
        buffer = np.empty(m, np.float64)
        for row in block:
            np.take(row, idx, out=buffer)
            row[:m] = buffer
    data = block[:, :m] if 2 * m >= n else np.ascontiguousarray(block[:, :m])  # no mostly idle buffer
    out = pd.DataFrame(data.T, columns=list(_FLOAT_COLUMNS), copy=False)
    for j, end in enumerate(("tx", "rx")):
        out.insert(1 + j, end, node_column(uniques, node_codes[end][idx], out.index))
    if tuple(out.columns) != MATCHED_COLUMNS:  # the block's layout must follow the table's
        out = out[list(MATCHED_COLUMNS)]
    for c in [c for c in signal.columns if c not in MATCHED_COLUMNS]:
        out[c] = pd.Series(signal[c].array[idx], index=out.index)  # keeps the column's dtype (text stays text)
    return out


__all__: list[str] = []
