"""Geometry of a swarm's links, every (time, ordered pair) at once (issue 30).

Each drone's attitude is turned into a rotation matrix once per time, not once per link it
takes part in (a drone of ``n`` is in ``2 (n - 1)`` links a time), and each end's direction is
then the matrix's transpose times the pair's vector: nine multiplications per end, no per-link
quaternion normalisation or cross products. The directions equal
:func:`rplearn.core.geometry.link_directions`'s to rounding (about 1e-15 rad).
"""

from __future__ import annotations

import numpy as np

from rplearn.core.geometry import Directions, quat_wxyz_to_matrix

FloatArray = np.ndarray


def pose_rotations(quat_wxyz: np.ndarray, present: np.ndarray) -> np.ndarray:
    """Body (FLU) -> world (ENU) rotation matrices of every drone at every time.

    Parameters
    ----------
    quat_wxyz : ndarray, shape (drones, times, 4)
        Attitudes (any norm); rows where the drone has no pose may hold NaN.
    present : ndarray of bool, shape (times, drones)
        Whether each drone has a pose at each time.

    Returns
    -------
    ndarray, shape (drones * times, 9)
        Row ``drone * times + time`` holds the matrix row by row (identity where absent).
    """
    known = present.T[..., None]
    q = np.where(known, quat_wxyz, np.array([1.0, 0.0, 0.0, 0.0]))
    n, m = q.shape[:2]
    return quat_wxyz_to_matrix(q).reshape(n * m, 9)


def _end_directions(rot: np.ndarray, dx: np.ndarray, dy: np.ndarray, dz: np.ndarray) -> tuple[FloatArray, FloatArray]:
    """Azimuth and elevation [rad] of world vectors ``(dx, dy, dz)`` in the body frames whose
    rotations (body -> world, rows of 9) are ``rot``: ``R^T d`` (paper eq. 3)."""
    bx = dx * rot[:, 0] + dy * rot[:, 3] + dz * rot[:, 6]
    by = dx * rot[:, 1] + dy * rot[:, 4] + dz * rot[:, 7]
    bz = dx * rot[:, 2] + dy * rot[:, 5] + dz * rot[:, 8]
    az = np.arctan2(by, bx)
    az[az == -np.pi] = np.pi
    el = np.arctan2(bz, np.hypot(bx, by))
    return az, el


def pair_directions(
    rotations: np.ndarray, n_times: int, time_index: np.ndarray, tx: np.ndarray, rx: np.ndarray,
    delta_m: np.ndarray,
) -> Directions:
    """Directions of both ends of links ``tx[i] -> rx[i]`` at times ``time_index[i]`` [rad].

    Parameters
    ----------
    rotations : ndarray, shape (drones * n_times, 9)
        From :func:`pose_rotations`.
    n_times : int
        Times of ``rotations``.
    time_index, tx, rx : ndarray of int
        Each link's time and its two drones.
    delta_m : ndarray, shape (links, 3)
        ``position[rx] - position[tx]`` in ENU [m].
    """
    dx, dy, dz = delta_m[:, 0], delta_m[:, 1], delta_m[:, 2]
    az_tx, el_tx = _end_directions(rotations[tx * n_times + time_index], dx, dy, dz)
    az_rx, el_rx = _end_directions(rotations[rx * n_times + time_index], -dx, -dy, -dz)
    return Directions(az_tx, el_tx, az_rx, el_rx)


__all__ = ["pair_directions", "pose_rotations"]
