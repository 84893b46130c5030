"""The matched dataset of :func:`rplearn.data.sync.synchronise`, built once from arrays.

Internal to :mod:`rplearn.data.sync` (issue 30: building the matched DataFrame was 41% of a
sync). The float columns are gathered straight into one preallocated block, which becomes the
DataFrame without a copy; the node columns are taken from the factorised node ids (one string
per node, not one per row).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from rplearn.data.tables import MATCHED_COLUMNS, POSE_FIELDS

#: Float columns of the matched dataset, in the order of the block.
_SIGNAL_FLOATS: tuple[str, ...] = ("t", "rssi_dbm", "tx_power_dbm", "frequency_hz")
_FLOAT_COLUMNS: tuple[str, ...] = _SIGNAL_FLOATS + tuple(f"{end}_{f}" for end in ("tx", "rx") for f in POSE_FIELDS)


def node_column(uniques: np.ndarray, codes: np.ndarray) -> pd.api.extensions.ExtensionArray | np.ndarray:
    """The node ids ``uniques[codes]`` as the text column ``astype(str)`` would make, taken per code."""
    return pd.Series(np.asarray(uniques).astype(str)).array.take(codes)


def matched_frame(
    signal: pd.DataFrame, idx: np.ndarray, values: dict[str, np.ndarray], node_codes: dict[str, np.ndarray],
    uniques: np.ndarray, poses: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]],
) -> pd.DataFrame:
    """The kept rows ``idx`` in :data:`MATCHED_COLUMNS` order, then the extra signal columns.

    ``values``: the signal's float columns (``t`` on the common clock); ``node_codes``: the
    codes of ``tx`` and ``rx`` into ``uniques``; ``poses``: per end, positions (n, 3),
    quaternions (n, 4) and status of every signal row.
    """
    m = idx.size
    block = np.empty((len(_FLOAT_COLUMNS), m), np.float64)
    for k, c in enumerate(_SIGNAL_FLOATS):
        np.take(values[c], idx, out=block[k])
    k = len(_SIGNAL_FLOATS)
    for end in ("tx", "rx"):
        pos, quat, _ = poses[end]
        block[k:k + 3] = pos[idx].T
        block[k + 3:k + 7] = quat[idx].T
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
