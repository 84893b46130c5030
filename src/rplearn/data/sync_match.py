"""The matched dataset of :func:`rplearn.data.sync.synchronise`, built once from arrays.

Internal to :mod:`rplearn.data.sync` (issue 30: building the matched DataFrame was 41% of a
sync). The float columns are gathered straight into one preallocated block, which becomes the
DataFrame without a copy; the node columns are taken from the factorised node ids (one string
per node, not one per row).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from collections.abc import Mapping, Sequence

from rplearn.core.geometry import slerp_wxyz
from rplearn.data.poses import PoseTrack
from rplearn.data.tables import MATCHED_COLUMNS, POSE_FIELDS, node_ids

#: Float columns of the matched dataset, in the order of the block.
_SIGNAL_FLOATS: tuple[str, ...] = ("t", "rssi_dbm", "tx_power_dbm", "frequency_hz")
_FLOAT_COLUMNS: tuple[str, ...] = _SIGNAL_FLOATS + tuple(f"{end}_{f}" for end in ("tx", "rx") for f in POSE_FIELDS)


def node_column(uniques: np.ndarray, codes: np.ndarray) -> pd.api.extensions.ExtensionArray | np.ndarray:
    """The node ids ``uniques[codes]`` as the text column ``astype(str)`` would make, taken per code."""
    return pd.Series(np.asarray(uniques).astype(str)).array.take(codes)


def node_codes(tx: pd.Series, rx: pd.Series) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both ends' node ids as codes into one array of distinct ids: ``(tx_code, rx_code, uniques)``.

    ``uniques[tx_code]`` equals :func:`~rplearn.data.tables.node_ids` of ``tx`` row by row
    (a missing cell is ``""``), but the text of each distinct cell is made once, not per row.
    """
    codes, raw = [], []
    for col in (tx, rx):
        c, u = pd.factorize(col, use_na_sentinel=True)  # NA: -1
        codes.append(c)
        raw.append(np.append(node_ids(pd.Series(u)), ""))  # the last: a missing cell
    ids = np.concatenate(raw).astype(object)
    merged, uniques = pd.factorize(ids)  # distinct raw cells with the same text are one node
    n_tx = len(raw[0])
    return merged[codes[0]], merged[n_tx + codes[1]], np.asarray(uniques, dtype=object)


def interpolate_end(
    tracks: Mapping[str, PoseTrack], node_ids: Sequence[str], node_code: np.ndarray, t_s: np.ndarray,
    max_gap_s: float, rows: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~rplearn.data.poses.interpolate_nodes` as columns: ``(pose, status)``, ``pose``
    of shape (7, n) holding ``x, y, z, qw, qx, qy, qz`` (NaN outside ``rows``).

    One ``searchsorted`` per node; each field is written once into its own contiguous row,
    from which the matched dataset takes its columns without a strided gather.
    """
    n = len(t_s)
    pose = np.full((7, n), np.nan)
    status = np.zeros(n, np.int8)
    for code, node in enumerate(node_ids):
        sel = np.flatnonzero((node_code == code) & rows)
        if not sel.size:
            continue
        track = tracks[node]
        if track.static:
            pos, quat, status[sel] = track.interpolate(t_s[:1], max_gap_s)
            pose[:3, sel] = pos[0][:, None]
            pose[3:, sel] = quat[0][:, None]
            continue
        i, frac, status[sel] = track.brackets(t_s[sel], max_gap_s)
        i1 = i + 1
        for j in range(3):  # p0 + fraction * (p1 - p0), as PoseTrack.interpolate
            column = track.position_xyz[:, j]
            p0 = column[i]
            p = column[i1] - p0
            p *= frac
            p += p0
            pose[j, sel] = p
        pose[3:, sel] = slerp_wxyz(track.quat_wxyz[i], track.quat_wxyz[i1], frac).T
    return pose, status


def matched_frame(
    signal: pd.DataFrame, idx: np.ndarray, values: dict[str, np.ndarray], node_codes: dict[str, np.ndarray],
    uniques: np.ndarray, poses: dict[str, tuple[np.ndarray, np.ndarray]],
) -> pd.DataFrame:
    """The kept rows ``idx`` in :data:`MATCHED_COLUMNS` order, then the extra signal columns.

    ``values``: the signal's float columns (``t`` on the common clock); ``node_codes``: the
    codes of ``tx`` and ``rx`` into ``uniques``; ``poses``: per end, :func:`interpolate_end`
    of every signal row.
    """
    m = idx.size
    block = np.empty((len(_FLOAT_COLUMNS), m), np.float64)
    for k, c in enumerate(_SIGNAL_FLOATS):
        np.take(values[c], idx, out=block[k])
    k = len(_SIGNAL_FLOATS)
    for end in ("tx", "rx"):
        for j in range(7):
            np.take(poses[end][0][j], idx, out=block[k + j])
        k += 7
    out = pd.DataFrame(block.T, columns=list(_FLOAT_COLUMNS), copy=False)
    for j, end in enumerate(("tx", "rx")):
        out.insert(1 + j, end, node_column(uniques, node_codes[end][idx]))
    if tuple(out.columns) != MATCHED_COLUMNS:  # the block's layout must follow the table's
        out = out[list(MATCHED_COLUMNS)]
    for c in [c for c in signal.columns if c not in MATCHED_COLUMNS]:
        out[c] = pd.Series(signal[c].array[idx], index=out.index)  # keeps the column's dtype (text stays text)
    return out


__all__: list[str] = []
