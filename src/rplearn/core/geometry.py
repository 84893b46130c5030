"""Frames, attitudes and the direction of one node seen from another (paper eq. 3).

Conventions (docs/conventions.md): the world frame is ENU (x east, y north, z up) in metres; the body
frame is FLU (x forward, y left, z up); attitudes are unit quaternions rotating body vectors
into the world, scalar first ``(qw, qx, qy, qz)``. Every conversion from other conventions
(PX4's NED world / FRD body, Euler angles) lives in this module and nowhere else.

Azimuth ``az = atan2(y, x)`` in (-pi, pi], 0 = forward, +pi/2 = left; elevation
``el = atan2(z, hypot(x, y))`` in [-pi/2, pi/2], positive up, both of the other node's
position expressed in this node's body frame.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn.errors import InputError

FloatArray = NDArray[np.float64]

#: Rotation taking NED coordinates to ENU coordinates (swap x/y, negate z). Symmetric, own inverse.
R_ENU_FROM_NED: FloatArray = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: Rotation taking FLU body coordinates to FRD body coordinates (negate y and z). Own inverse.
R_FRD_FROM_FLU: FloatArray = np.diag([1.0, -1.0, -1.0])


class Directions(NamedTuple):
    """Directions of a link as seen by both ends [rad].

    ``az_tx, el_tx``: direction of the receiver in the transmitter's body frame;
    ``az_rx, el_rx``: direction of the transmitter in the receiver's body frame.
    """

    az_tx: FloatArray
    el_tx: FloatArray
    az_rx: FloatArray
    el_rx: FloatArray


def _as_quat_wxyz(quat_wxyz: ArrayLike, name: str = "quaternion") -> FloatArray:
    q = np.asarray(quat_wxyz, dtype=np.float64)
    if q.shape[-1] != 4:
        raise InputError(f"{name}: expected (..., 4) quaternions (qw, qx, qy, qz), got shape {q.shape}")
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    for bad, what in ((~np.isfinite(norm), "contain NaN or inf"), (norm < 1e-9, "have zero norm")):
        if np.any(bad):
            first = np.argwhere(bad[..., 0])[0]
            at = f"index {int(first[0])}" if first.size == 1 else f"index {tuple(int(i) for i in first)}"
            raise InputError(f"{name}: {int(np.sum(bad))} quaternion(s) {what}, the first at {at}")
    return q / norm


@check_types
def rotate_world_to_body(quat_wxyz_body_to_world: ArrayLike, vec_world: ArrayLike) -> FloatArray:
    """Express world-frame vectors in the body frame, ``v_body = R(q)^T v_world``.

    Parameters
    ----------
    quat_wxyz_body_to_world : array_like, shape (..., 4)
        Attitude, unit quaternion body -> world, scalar first.
    vec_world : array_like, shape (..., 3)
        Vectors in the world frame.

    Returns
    -------
    ndarray, shape (..., 3)
        The same vectors in the body frame.
    """
    q = _as_quat_wxyz(quat_wxyz_body_to_world)
    v = np.asarray(vec_world, dtype=np.float64)
    w = q[..., :1]
    u = -q[..., 1:]  # conjugate: world -> body
    # v' = v + 2 w (u x v) + 2 u x (u x v)
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


@check_types
def rotate_body_to_world(quat_wxyz_body_to_world: ArrayLike, vec_body: ArrayLike) -> FloatArray:
    """Express body-frame vectors in the world frame, ``v_world = R(q) v_body``."""
    q = _as_quat_wxyz(quat_wxyz_body_to_world)
    v = np.asarray(vec_body, dtype=np.float64)
    w = q[..., :1]
    u = q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


@check_types
def azimuth_elevation(vec_body: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Azimuth and elevation of body-frame vectors (paper eq. 3) [rad].

    ``az = atan2(y, x)`` in (-pi, pi]; ``el = atan2(z, hypot(x, y))`` in [-pi/2, pi/2].
    """
    v = np.asarray(vec_body, dtype=np.float64)
    az = np.arctan2(v[..., 1], v[..., 0])
    az = np.where(az == -np.pi, np.pi, az)
    el = np.arctan2(v[..., 2], np.hypot(v[..., 0], v[..., 1]))
    return az, el


@check_types
def direction_in_body(
    position_xyz_self: ArrayLike,
    quat_wxyz_self: ArrayLike,
    position_xyz_other: ArrayLike,
) -> tuple[FloatArray, FloatArray]:
    """Direction (az, el) of another node seen in this node's body frame (paper eq. 3) [rad].

    Parameters
    ----------
    position_xyz_self, position_xyz_other : array_like, shape (n, 3)
        ENU positions [m].
    quat_wxyz_self : array_like, shape (n, 4)
        Attitude of this node, body (FLU) -> world (ENU), scalar first.

    Returns
    -------
    az, el : ndarray, shape (n,)
        Azimuth and elevation [rad].
    """
    delta_world = np.asarray(position_xyz_other, np.float64) - np.asarray(position_xyz_self, np.float64)
    return azimuth_elevation(rotate_world_to_body(quat_wxyz_self, delta_world))


@check_types
def link_directions(
    tx_position_xyz: ArrayLike,
    tx_quat_wxyz: ArrayLike,
    rx_position_xyz: ArrayLike,
    rx_quat_wxyz: ArrayLike,
) -> Directions:
    """Directions of both ends of a link: each end's view of the other (paper eq. 3) [rad]."""
    az_tx, el_tx = direction_in_body(tx_position_xyz, tx_quat_wxyz, rx_position_xyz)
    az_rx, el_rx = direction_in_body(rx_position_xyz, rx_quat_wxyz, tx_position_xyz)
    return Directions(az_tx, el_tx, az_rx, el_rx)


@check_types
def distance_m(position_xyz_a: ArrayLike, position_xyz_b: ArrayLike) -> FloatArray:
    """Euclidean distance between positions [m]."""
    d = np.asarray(position_xyz_b, np.float64) - np.asarray(position_xyz_a, np.float64)
    return np.sqrt(np.einsum("...i,...i->...", d, d))


@check_types
def unit_vector(az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
    """Unit vectors (..., 3) of directions given by azimuth and elevation [rad]."""
    az = np.asarray(az_rad, np.float64)
    el = np.asarray(el_rad, np.float64)
    ce = np.cos(el)
    return np.stack([ce * np.cos(az), ce * np.sin(az), np.sin(el)], axis=-1)


@check_types
def great_circle_angle(az1: ArrayLike, el1: ArrayLike, az2: ArrayLike, el2: ArrayLike) -> FloatArray:
    """Great-circle angle between directions [rad], accurate at all separations (haversine form)."""
    az1, el1, az2, el2 = (np.asarray(a, np.float64) for a in (az1, el1, az2, el2))
    s = np.sin((el2 - el1) / 2.0) ** 2 + np.cos(el1) * np.cos(el2) * np.sin((az2 - az1) / 2.0) ** 2
    return 2.0 * np.arcsin(np.sqrt(np.clip(s, 0.0, 1.0)))


# ---------------------------------------------------------------------------------------------
# Quaternions, rotation matrices, Euler angles


@check_types
def quat_wxyz_to_matrix(quat_wxyz: ArrayLike) -> FloatArray:
    """Rotation matrices (..., 3, 3) of unit quaternions (scalar first)."""
    q = _as_quat_wxyz(quat_wxyz)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    m = np.empty(q.shape[:-1] + (3, 3))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - w * z)
    m[..., 0, 2] = 2 * (x * z + w * y)
    m[..., 1, 0] = 2 * (x * y + w * z)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - w * x)
    m[..., 2, 0] = 2 * (x * z - w * y)
    m[..., 2, 1] = 2 * (y * z + w * x)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return m


@check_types
def matrix_to_quat_wxyz(matrix: ArrayLike) -> FloatArray:
    """Unit quaternions (scalar first, qw >= 0) of rotation matrices (..., 3, 3)."""
    from scipy.spatial.transform import Rotation

    m = np.asarray(matrix, np.float64)
    return _quat_wxyz_of_matrix(m, Rotation.from_matrix(m.reshape(-1, 3, 3)).as_quat())


def _quat_wxyz_of_matrix(m: FloatArray, q_xyzw: FloatArray) -> FloatArray:
    """Scalar-first quaternions (qw >= 0) of the matrices ``m`` from scipy's ``(x, y, z, w)``."""
    q = np.concatenate([q_xyzw[:, 3:], q_xyzw[:, :3]], axis=1)
    q = np.where(q[:, :1] < 0, -q, q)
    return q.reshape(m.shape[:-2] + (4,))


@check_types
def quat_wxyz_multiply(q1: ArrayLike, q2: ArrayLike) -> FloatArray:
    """Hamilton product ``q1 * q2`` (apply q2 first, then q1), scalar first."""
    a = np.asarray(q1, np.float64)
    b = np.asarray(q2, np.float64)
    w1, x1, y1, z1 = np.moveaxis(a, -1, 0)
    w2, x2, y2, z2 = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ],
        axis=-1,
    )


@check_types
def quat_wxyz_from_yaw(yaw_rad: ArrayLike) -> FloatArray:
    """Quaternions of pure yaw rotations about the world z axis (ENU, counter-clockwise)."""
    half = 0.5 * np.asarray(yaw_rad, np.float64)
    zeros = np.zeros_like(half)
    return np.stack([np.cos(half), zeros, zeros, np.sin(half)], axis=-1)


@check_types
def quat_wxyz_from_euler(roll_rad: ArrayLike, pitch_rad: ArrayLike, yaw_rad: ArrayLike) -> FloatArray:
    """Quaternions from aerospace yaw-pitch-roll angles in the same frame pair [rad].

    ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (intrinsic z-y'-x''). In ENU/FLU (REP-103) yaw is
    counter-clockwise from east and a positive pitch lowers the nose; in NED/FRD yaw is the
    heading clockwise from north and a positive pitch raises the nose.
    """
    r = np.asarray(roll_rad, np.float64) / 2.0
    p = np.asarray(pitch_rad, np.float64) / 2.0
    y = np.asarray(yaw_rad, np.float64) / 2.0
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.stack(
        [
            cy * cp * cr + sy * sp * sr,
            cy * cp * sr - sy * sp * cr,
            cy * sp * cr + sy * cp * sr,
            sy * cp * cr - cy * sp * sr,
        ],
        axis=-1,
    )


@check_types
def euler_from_quat_wxyz(quat_wxyz: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Aerospace (roll, pitch, yaw) [rad] of quaternions, inverse of :func:`quat_wxyz_from_euler`."""
    q = _as_quat_wxyz(quat_wxyz)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


@check_types
def yaw_from_quat_wxyz(quat_wxyz: ArrayLike) -> FloatArray:
    """Heading of the body x axis projected on the horizontal plane, ENU ccw from east [rad]."""
    return euler_from_quat_wxyz(quat_wxyz)[2]


@check_types
def ned_to_enu(position_xyz_ned: ArrayLike) -> FloatArray:
    """Convert NED positions or vectors to ENU: ``(n, e, d) -> (e, n, -d)``."""
    v = np.asarray(position_xyz_ned, np.float64)
    return np.stack([v[..., 1], v[..., 0], -v[..., 2]], axis=-1)


@check_types
def enu_to_ned(position_xyz_enu: ArrayLike) -> FloatArray:
    """Convert ENU positions or vectors to NED: ``(e, n, u) -> (n, e, -u)``."""
    return ned_to_enu(position_xyz_enu)


@check_types
def quat_ned_frd_to_enu_flu(quat_wxyz_frd_to_ned: ArrayLike) -> FloatArray:
    """Convert an attitude FRD body -> NED world (PX4) into FLU body -> ENU world.

    ``R_enu_flu = R_ENU_FROM_NED @ R_ned_frd @ R_FRD_FROM_FLU``. In quaternions this is
    ``q_enu_flu = q(R_ENU_FROM_NED) * q_ned_frd * q(R_FRD_FROM_FLU)`` with the two fixed
    rotations a 180 deg turn about (1, 1, 0)/sqrt(2) and about x respectively.
    """
    q = _as_quat_wxyz(quat_wxyz_frd_to_ned, "NED/FRD quaternion")
    s = np.sqrt(0.5)
    q_enu_ned = np.array([0.0, s, s, 0.0])
    q_frd_flu = np.array([0.0, 1.0, 0.0, 0.0])
    out = quat_wxyz_multiply(quat_wxyz_multiply(q_enu_ned, q), q_frd_flu)
    return np.where(out[..., :1] < 0, -out, out)


@check_types
def quat_enu_flu_to_ned_frd(quat_wxyz_flu_to_enu: ArrayLike) -> FloatArray:
    """Inverse of :func:`quat_ned_frd_to_enu_flu` (the same two fixed rotations, own inverses)."""
    return quat_ned_frd_to_enu_flu(quat_wxyz_flu_to_enu)


@check_types
def quat_wxyz_from_euler_ned_frd_deg(
    roll_ned_deg: ArrayLike, pitch_ned_deg: ArrayLike, yaw_ned_deg: ArrayLike
) -> FloatArray:
    """ENU/FLU attitude quaternions from autopilot Euler angles (NED/FRD, heading cw from north) [deg]."""
    q_ned = quat_wxyz_from_euler(
        np.radians(roll_ned_deg), np.radians(pitch_ned_deg), np.radians(yaw_ned_deg)
    )
    return quat_ned_frd_to_enu_flu(q_ned)


@check_types
def quat_wxyz_from_euler_enu_flu_deg(
    roll_deg: ArrayLike, pitch_deg: ArrayLike, yaw_deg: ArrayLike
) -> FloatArray:
    """ENU/FLU attitude quaternions from REP-103 Euler angles (yaw ccw from east) [deg]."""
    return quat_wxyz_from_euler(np.radians(roll_deg), np.radians(pitch_deg), np.radians(yaw_deg))


@check_types
def wrap_angle_rad(angle_rad: ArrayLike) -> FloatArray:
    """Wrap angles into (-pi, pi] [rad]."""
    a = np.asarray(angle_rad, np.float64)
    w = np.mod(a + np.pi, 2.0 * np.pi) - np.pi
    return np.where(w == -np.pi, np.pi, w)


@check_types
def slerp_weights(dot: np.ndarray, fraction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The weights ``w0, w1`` of ``q0`` and ``q1`` in a slerp, from their dot products and the
    fractions (n,): the shorter arc (``w1`` negated where the dot is negative), a normalised
    linear interpolation for nearly equal quaternions. Shared by :func:`slerp_wxyz` and the
    block interpolation of ``sync``, which must agree bit for bit.
    """
    negative = dot < 0.0
    theta = np.arccos(np.minimum(np.abs(dot), 1.0))
    sin_theta = np.sin(theta)
    near = sin_theta < 1e-6
    rest = 1.0 - fraction
    w0 = np.sin(rest * theta)
    w1 = np.sin(fraction * theta)
    safe = np.where(near, 1.0, sin_theta)
    w0 /= safe
    w1 /= safe
    if near.any():  # nearly equal quaternions: normalised linear interpolation
        w0[near] = rest[near]
        w1[near] = fraction[near]
    return w0, np.where(negative, -w1, w1)  # the shorter arc: q1 negated


@check_types
def slerp_wxyz(q0: np.ndarray, q1: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation between unit quaternions, row by row.

    Takes the shorter arc (``q1`` is negated when ``q0 . q1 < 0``), equal to
    :class:`scipy.spatial.transform.Slerp` between two keys; falls back to a normalised
    linear interpolation for nearly equal quaternions. Output has ``qw >= 0``.

    Parameters
    ----------
    q0, q1 : ndarray, shape (n, 4)
        Unit quaternions, scalar first.
    fraction : ndarray, shape (n,)
        Interpolation fraction in [0, 1].
    """
    dot = np.einsum("ij,ij->i", q0, q1)
    w0, w1 = slerp_weights(dot, np.broadcast_to(np.asarray(fraction, np.float64), dot.shape))
    out = w0[:, None] * q0
    out += w1[:, None] * q1
    norm = np.linalg.norm(out, axis=1)  # (not einsum: its other rounding moves results by an ulp)
    np.negative(norm, out=norm, where=out[:, 0] < 0.0)  # qw >= 0
    out /= norm[:, None]
    return out


@check_types
def attitude_from_thrust(thrust_dir_enu: FloatArray, yaw_rad: FloatArray) -> FloatArray:
    """Quaternions (FLU -> ENU) of drones whose body z axis is the thrust direction.

    The body x axis is the heading direction projected on the plane perpendicular to the
    thrust (the geometric controller's convention, Lee et al. 2010).
    """
    zb = thrust_dir_enu / np.linalg.norm(thrust_dir_enu, axis=-1, keepdims=True)
    xc = np.stack([np.cos(yaw_rad), np.sin(yaw_rad), np.zeros_like(yaw_rad)], axis=-1)
    yb = np.cross(zb, xc)
    yb_norm = np.linalg.norm(yb, axis=-1, keepdims=True)
    yb /= yb_norm
    xb = np.cross(yb, zb)
    m = np.stack([xb, yb, zb], axis=-1)  # columns are the body axes in the world
    if not (np.all(yb_norm >= _SURELY_ORTHOGONAL) and np.all(np.isfinite(m))):
        return matrix_to_quat_wxyz(m)
    from scipy.spatial.transform import Rotation

    # orthonormal columns, right-handed, to ~1e-14 (the thrust at least 0.6 degrees from the
    # heading): scipy's checks (determinant, Gram matrix within 1e-12 of the identity) pass
    # and change nothing, so they are skipped; the quaternions are the same to the bit
    try:
        q_xyzw = Rotation.from_matrix(m.reshape(-1, 3, 3), assume_valid=True).as_quat()
    except TypeError:  # a scipy without ``assume_valid`` (pyproject allows 1.15): the checked conversion
        return matrix_to_quat_wxyz(m)
    return _quat_wxyz_of_matrix(m, q_xyzw)


#: Least norm of ``thrust x heading`` (unit vectors) with which :func:`attitude_from_thrust`
#: skips scipy's orthogonality checks: its matrices are then orthonormal to ~1e-14.
_SURELY_ORTHOGONAL = 1e-2
