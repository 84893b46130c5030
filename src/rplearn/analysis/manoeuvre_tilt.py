"""The drones' steady lean in a wind, read from their poses (for the next-best manoeuvre's features).

A drone holding its position in a steady wind tilts its thrust against the wind's drag; its body
z axis then stays off the vertical while it turns, and the directions it sees a peer from are
those of the level references turned by that lean.
:attr:`rplearn.analysis.manoeuvres.ManoeuvreOptions.steady_accel_enu_m_s2` carries it into the
ranking's features; :func:`steady_tilt_accel` estimates it from a pose table.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.geometry import quat_wxyz_to_matrix
from rplearn.errors import InputError
from rplearn.plan.trajectory import G_M_S2

#: Span of positions at each end of a window whose slope is the velocity there [s].
VELOCITY_WINDOW_S = 1.0


@check_types
def steady_tilt_accel(poses: pd.DataFrame, fixed_nodes: Sequence[str] = (), last_s: float | None = None) -> tuple[float, float, float]:
    """The horizontal acceleration the drones' mean tilt carries beyond their own [m/s^2] (ENU),
    for :attr:`ManoeuvreOptions.steady_accel_enu_m_s2`: per drone, ``g`` times the horizontal
    over the vertical part of its body z axis in the world, averaged over its poses of the last
    ``last_s`` seconds (None: all), less its own mean acceleration there (the change of its
    velocity over the window, each end's velocity the slope of its positions over
    :data:`VELOCITY_WINDOW_S`); the drones averaged by their pose counts. What is left is the
    steady wind's drag they lean against.

    Parameters
    ----------
    poses : DataFrame
        A pose table (``t, node, x, y, qw, qx, qy, qz``; ENU/FLU).
    fixed_nodes : sequence of str
        Nodes that stand on the ground (left out).
    last_s : float, optional
        Window at the end of the table [s].
    """
    need = ("t", "node", "x", "y", "qw", "qx", "qy", "qz")
    miss = [c for c in need if c not in poses.columns]
    if miss:
        raise InputError(f"poses: missing column(s) {', '.join(miss)}", param="poses")
    keep = ~poses["node"].astype(str).isin([str(n) for n in fixed_nodes])
    if last_s is not None:
        keep &= poses["t"] >= float(poses["t"].max()) - float(last_s)
    total, count = np.zeros(2), 0
    for _, part in poses.loc[keep].sort_values("t", kind="stable").groupby(poses.loc[keep, "node"].astype(str), sort=True):
        z = quat_wxyz_to_matrix(part[["qw", "qx", "qy", "qz"]].to_numpy(np.float64))[:, :, 2]
        lean = G_M_S2 * np.mean(z[:, :2] / np.maximum(z[:, 2:3], 1e-6), axis=0)
        total += part.shape[0] * (lean - _mean_accel(part["t"].to_numpy(np.float64), part[["x", "y"]].to_numpy(np.float64)))
        count += part.shape[0]
    if count == 0:
        return (0.0, 0.0, 0.0)
    return (float(total[0] / count), float(total[1] / count), 0.0)


def _mean_accel(t_s: np.ndarray, xy_m: np.ndarray) -> np.ndarray:
    """Mean horizontal acceleration over a pose window: the change of velocity between its two
    ends' spans over the time between their middles (zero for a window too short to hold two
    spans)."""
    if float(t_s[-1] - t_s[0]) < 2.0 * VELOCITY_WINDOW_S:
        return np.zeros(2)
    head, tail = t_s <= t_s[0] + VELOCITY_WINDOW_S, t_s >= t_s[-1] - VELOCITY_WINDOW_S
    if head.sum() < 2 or tail.sum() < 2:
        return np.zeros(2)
    v0 = np.polyfit(t_s[head] - t_s[0], xy_m[head], 1)[0]
    v1 = np.polyfit(t_s[tail] - t_s[-1], xy_m[tail], 1)[0]
    return np.asarray((v1 - v0) / float(np.mean(t_s[tail]) - np.mean(t_s[head])), np.float64)


__all__ = ["VELOCITY_WINDOW_S", "steady_tilt_accel"]
