"""What a matched dataset says about how its flight was flown: which nodes held still and how
often each link direction reported.

A model file keeps both (``training.fixed_nodes``, ``training.packet_rate_hz``) so that the next
flight's plan (``rplearn trajectory --optimize --from-model``) is made for the same layout (a
ground station and a drone, or two drones) and the same radio, not for the planner's defaults.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: A node whose every learning row puts it within this of one position [m] and one attitude
#: (quaternion components) holds still: ``sync`` holds a node logged with identical rows (a
#: ground station, a parked drone) at that pose, so its rows are equal up to a file's rounding.
STILL_POSITION_M = 1e-3
STILL_QUATERNION = 1e-6

_POSE = ("x", "y", "z", "qw", "qx", "qy", "qz")


def fixed_nodes(rows: pd.DataFrame) -> tuple[str, ...] | None:
    """The nodes that hold still in every row of a matched dataset, as transmitter and as
    receiver alike, sorted (None: the rows carry no poses of both ends).

    Parameters
    ----------
    rows : DataFrame
        Matched samples with ``tx``, ``rx`` and both ends' poses (``tx_x`` ... ``rx_qz``).
    """
    columns = [f"{end}_{c}" for end in ("tx", "rx") for c in _POSE]
    if len(rows) == 0 or any(c not in rows.columns for c in columns):
        return None
    poses = np.concatenate([rows[[f"{end}_{c}" for c in _POSE]].to_numpy("float64") for end in ("tx", "rx")])
    codes, names = pd.factorize(pd.concat([rows["tx"], rows["rx"]], ignore_index=True).astype(str))
    tolerance = np.array([STILL_POSITION_M] * 3 + [STILL_QUATERNION] * 4)
    still = [str(name) for k, name in enumerate(names)
             if bool(np.all(np.ptp(poses[codes == k], axis=0) <= tolerance))]
    return tuple(sorted(still))


def packet_rate_hz(rows: pd.DataFrame) -> float | None:
    """The rate at which a link direction reported [Hz]: the median over the directions of
    each direction's median rate between consecutive readings (gaps between flights, outages
    and dropped rows do not lower it); None without two readings of one direction at distinct times.

    Parameters
    ----------
    rows : DataFrame
        Matched samples with ``t`` [s], ``tx`` and ``rx``.
    """
    if len(rows) < 2 or any(c not in rows.columns for c in ("t", "tx", "rx")):
        return None
    rates = []
    for _, group in rows.groupby([rows["tx"].astype(str), rows["rx"].astype(str)], sort=True):
        t = np.unique(group["t"].to_numpy("float64"))
        step = np.diff(t[np.isfinite(t)])
        if step.size:
            rates.append(1.0 / float(np.median(step)))
    return float(np.median(rates)) if rates else None
