"""What a matched dataset says about how its flight was flown: which nodes held still and how
often each link direction reported.

A model file keeps both (``training.fixed_nodes``, ``training.packet_rate_hz``) so that the next
flight's plan (``rplearn trajectory --optimize --from-model``) is made for the same layout (a
ground station and a drone, or two drones) and the same radio, not for the planner's defaults.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: A node holds still when nearly all its learning rows (:data:`STILL_SHARE`) put it within
#: :data:`STILL_RADIUS_M` of its median position and :data:`STILL_ANGLE_DEG` of its mean attitude:
#: a ground station logged with its own GPS and attitude estimate wanders by a metre or two and
#: by degrees (the simulator's station by 1 m and 19 deg of heading), a station ``sync`` holds at
#: one pose not at all, while a drone of a calibration flight moves tens of metres and turns
#: through every heading. A GPS glitch in a few rows does not make a station move.
STILL_RADIUS_M = 5.0
STILL_ANGLE_DEG = 30.0
STILL_SHARE = 0.99
#: Rows read at most to tell who held still (every k-th row, evenly over the flight: the share
#: above holds in such a sample as in the whole, at a bounded cost on a dataset of millions).
LAYOUT_ROWS = 100_000
#: Packet rates a fit records [Hz]: outside them two readings a nanosecond apart, or one in hours,
#: say nothing of the radio (none recorded).
RECORDED_RATE_HZ = (1e-3, 1e5)

_POSE = ("x", "y", "z", "qw", "qx", "qy", "qz")


def fixed_nodes(rows: pd.DataFrame) -> tuple[str, ...] | None:
    """The nodes that hold still over a matched dataset (module constants), as transmitter and
    as receiver alike, sorted (None: the rows carry no poses of both ends).

    Parameters
    ----------
    rows : DataFrame
        Matched samples with ``tx``, ``rx`` and both ends' poses (``tx_x`` ... ``rx_qz``).
    """
    columns = [f"{end}_{c}" for end in ("tx", "rx") for c in _POSE]
    if len(rows) == 0 or any(c not in rows.columns for c in columns):
        return None
    rows = rows.iloc[::-(-len(rows) // LAYOUT_ROWS)]
    poses = np.concatenate([rows[[f"{end}_{c}" for c in _POSE]].to_numpy("float64") for end in ("tx", "rx")])
    codes, names = pd.factorize(pd.concat([rows["tx"], rows["rx"]], ignore_index=True).astype(str))
    return tuple(sorted(str(name) for k, name in enumerate(names) if holds_still(poses[codes == k])))


def holds_still(poses: np.ndarray) -> bool:
    """Whether the rows ``x, y, z, qw, qx, qy, qz`` of one node stay near one pose (module
    constants): the rule :func:`fixed_nodes` reads a flight by, and ``simulate --plan`` a plan's
    references (:func:`rplearn.plan.campaign.still_nodes`)."""
    if not np.all(np.isfinite(poses)):
        return False
    position, q = poses[:, :3], poses[:, 3:]
    norm = np.linalg.norm(q, axis=1)
    if np.any(norm <= 0.0):
        return False
    q = q / norm[:, None]
    # the mean attitude: the principal axis of sum q q^T (a quaternion and its negative alike)
    mean = np.linalg.eigh(q.T @ q)[1][:, -1]
    angle_deg = np.degrees(2.0 * np.arccos(np.clip(np.abs(q @ mean), 0.0, 1.0)))
    distance_m = np.linalg.norm(position - np.median(position, axis=0), axis=1)
    return bool(np.quantile(distance_m, STILL_SHARE) <= STILL_RADIUS_M
                and np.quantile(angle_deg, STILL_SHARE) <= STILL_ANGLE_DEG)


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
    if not rates:
        return None
    rate = float(np.median(rates))
    return rate if RECORDED_RATE_HZ[0] <= rate <= RECORDED_RATE_HZ[1] else None
