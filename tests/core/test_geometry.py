"""Geometry (paper eq. 3): frames, attitudes, and directions seen in the body frame."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from rplearn.core import geometry as g
from rplearn.errors import InputError

finite = st.floats(-100, 100, allow_nan=False)
angle = st.floats(-np.pi, np.pi, allow_nan=False)


def _quat(draw_vals):
    q = np.asarray(draw_vals, float)
    return q / np.linalg.norm(q)


quats = arrays(np.float64, 4, elements=st.floats(-1, 1)).filter(lambda q: np.linalg.norm(q) > 0.1).map(_quat)
points = arrays(np.float64, 3, elements=finite)


def _angle_diff(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


@settings(max_examples=200, deadline=None)
@given(quats, quats, points, points, quats, points)
def test_common_rotation_and_translation_changes_no_direction(qa, qb, pa, pb, qw, shift):
    if np.linalg.norm(pa - pb) < 1e-3:
        return
    before = g.link_directions(pa, qa, pb, qb)
    rot = g.quat_wxyz_to_matrix(qw)
    after = g.link_directions(
        rot @ pa + shift, g.quat_wxyz_multiply(qw, qa), rot @ pb + shift, g.quat_wxyz_multiply(qw, qb)
    )
    # azimuth is undefined straight up/down: compare unit vectors instead of angles
    ub = g.unit_vector(before.az_tx, before.el_tx)
    ua = g.unit_vector(after.az_tx, after.el_tx)
    np.testing.assert_allclose(ua, ub, atol=1e-9)
    np.testing.assert_allclose(g.unit_vector(after.az_rx, after.el_rx), g.unit_vector(before.az_rx, before.el_rx), atol=1e-9)


@settings(max_examples=200, deadline=None)
@given(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), angle, angle, points, points)
def test_yawing_a_node_by_psi_shifts_its_azimuth_by_minus_psi(roll, pitch, yaw, psi, pa, pb):
    # yaw about the world vertical (pre-multiplied), the way a multirotor turns
    if np.linalg.norm(pa - pb) < 1e-2:
        return
    q = g.quat_wxyz_from_euler(0.0, 0.0, yaw)  # level drone
    az0, el0 = g.direction_in_body(pa, q, pb)
    if abs(el0) > np.radians(89):
        return
    q2 = g.quat_wxyz_multiply(g.quat_wxyz_from_yaw(psi), q)
    az1, el1 = g.direction_in_body(pa, q2, pb)
    assert _angle_diff(az1, az0 - psi) < 1e-9
    assert abs(el1 - el0) < 1e-9


@settings(max_examples=100, deadline=None)
@given(quats, quats, points, points)
def test_swapping_tx_and_rx_swaps_the_directions(qa, qb, pa, pb):
    if np.linalg.norm(pa - pb) < 1e-3:
        return
    d = g.link_directions(pa, qa, pb, qb)
    s = g.link_directions(pb, qb, pa, qa)
    np.testing.assert_allclose([s.az_tx, s.el_tx, s.az_rx, s.el_rx], [d.az_rx, d.el_rx, d.az_tx, d.el_tx], atol=1e-12)


def test_level_drones_facing_each_other_see_each_other_ahead():
    q_east = g.quat_wxyz_from_yaw(0.0)
    q_west = g.quat_wxyz_from_yaw(np.pi)
    d = g.link_directions([0, 0, 10], q_east, [10, 0, 10], q_west)
    np.testing.assert_allclose([d.az_tx, d.el_tx, d.az_rx, d.el_rx], [0, 0, 0, 0], atol=1e-12)


def test_elevation_signs_are_opposite_for_level_drones():
    q = g.quat_wxyz_from_yaw(0.3)
    d = g.link_directions([0, 0, 0], q, [3, 4, 5], q)
    np.testing.assert_allclose(d.el_tx, np.arctan2(5, 5), atol=1e-12)
    np.testing.assert_allclose(d.el_rx, -d.el_tx, atol=1e-12)


# --- PX4 NED / FRD by hand ------------------------------------------------------------------


def test_ned_position_to_enu_by_hand():
    # 3 m north, 4 m east, 5 m down -> x east 4, y north 3, z up -5
    np.testing.assert_allclose(g.ned_to_enu([3.0, 4.0, 5.0]), [4.0, 3.0, -5.0])


def test_px4_identity_attitude_faces_north():
    # PX4 q = identity: FRD body aligned with NED, nose north. In ENU/FLU the nose points
    # north = +y, i.e. yaw +90 deg counter-clockwise from east, level.
    q = g.quat_ned_frd_to_enu_flu([1.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(q, g.quat_wxyz_from_yaw(np.pi / 2), atol=1e-12)
    roll, pitch, yaw = g.euler_from_quat_wxyz(q)
    np.testing.assert_allclose([roll, pitch, yaw], [0, 0, np.pi / 2], atol=1e-12)


def test_px4_heading_east_is_enu_yaw_zero():
    # heading 90 deg (clockwise from north) = east = ENU yaw 0
    q = g.quat_wxyz_from_euler_ned_frd_deg(0.0, 0.0, 90.0)
    np.testing.assert_allclose(g.euler_from_quat_wxyz(q), [0, 0, 0], atol=1e-12)


def test_px4_nose_up_pitch_is_rep103_negative_pitch():
    # NED pitch +10 deg raises the nose; REP-103 FLU pitch is positive nose-down, so -10 deg.
    q = g.quat_wxyz_from_euler_ned_frd_deg(0.0, 10.0, 90.0)  # heading east, nose up
    roll, pitch, yaw = g.euler_from_quat_wxyz(q)
    np.testing.assert_allclose([roll, np.degrees(pitch), yaw], [0, -10.0, 0], atol=1e-9)
    nose_world = g.rotate_body_to_world(q, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(nose_world, [np.cos(np.radians(10)), 0, np.sin(np.radians(10))], atol=1e-12)


def test_px4_right_wing_down_roll():
    # NED roll +20 deg: right wing down. In FLU the left wing (+y) goes up.
    q = g.quat_wxyz_from_euler_ned_frd_deg(20.0, 0.0, 0.0)  # heading north
    left_world = g.rotate_body_to_world(q, [0.0, 1.0, 0.0])
    # nose north (+y ENU), left wing points west (-x) and is raised by 20 deg
    np.testing.assert_allclose(left_world, [-np.cos(np.radians(20)), 0, np.sin(np.radians(20))], atol=1e-12)


def test_ned_drone_sees_target_to_its_right():
    # Drone at origin heading north (PX4). Target 10 m east: to the right, azimuth -90 deg (FLU).
    q = g.quat_ned_frd_to_enu_flu([1.0, 0, 0, 0])
    az, el = g.direction_in_body(np.zeros(3), q, g.ned_to_enu([0.0, 10.0, 0.0]))
    np.testing.assert_allclose([np.degrees(az), el], [-90.0, 0.0], atol=1e-9)


def test_conversion_round_trips():
    rng = np.random.default_rng(0)
    q = rng.normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    back = g.quat_enu_flu_to_ned_frd(g.quat_ned_frd_to_enu_flu(q))
    assert np.allclose(np.abs(np.einsum("ij,ij->i", back, q)), 1.0)
    m = g.quat_wxyz_to_matrix(q)
    assert np.allclose(np.abs(np.einsum("ij,ij->i", g.matrix_to_quat_wxyz(m), q)), 1.0)
    r, p, y = g.euler_from_quat_wxyz(q)
    assert np.allclose(np.abs(np.einsum("ij,ij->i", g.quat_wxyz_from_euler(r, p, y), q)), 1.0)


def test_bad_quaternions_are_refused():
    with pytest.raises(InputError, match="NaN"):
        g.direction_in_body([0, 0, 0], [np.nan, 0, 0, 0], [1, 0, 0])
    with pytest.raises(InputError, match="zero norm"):
        g.direction_in_body([0, 0, 0], [0, 0, 0, 0], [1, 0, 0])


def test_great_circle_angle_matches_dot_product():
    rng = np.random.default_rng(1)
    a1, a2 = rng.uniform(-np.pi, np.pi, (2, 100))
    e1, e2 = np.arcsin(rng.uniform(-1, 1, (2, 100)))
    dot = np.einsum("ij,ij->i", g.unit_vector(a1, e1), g.unit_vector(a2, e2))
    np.testing.assert_allclose(g.great_circle_angle(a1, e1, a2, e2), np.arccos(np.clip(dot, -1, 1)), atol=1e-7)


def test_attitude_from_thrust_equals_the_checked_matrix_conversion_to_the_bit():
    # orthonormal-by-construction matrices skip scipy's checks; near the heading they are kept
    rng = np.random.default_rng(5)
    thrust = rng.normal(0.0, 30.0, (20000, 3))
    thrust[:, 2] += 9.81
    yaw = rng.uniform(-7.0, 7.0, 20000)
    thrust[0] = [np.cos(yaw[0]), np.sin(yaw[0]), 1e-4]  # 0.006 deg from the heading
    thrust[1] = [0.0, 0.0, 1.0]
    zb = thrust / np.linalg.norm(thrust, axis=-1, keepdims=True)
    xc = np.stack([np.cos(yaw), np.sin(yaw), np.zeros_like(yaw)], axis=-1)
    yb = np.cross(zb, xc)
    yb /= np.linalg.norm(yb, axis=-1, keepdims=True)
    expected = g.matrix_to_quat_wxyz(np.stack([np.cross(yb, zb), yb, zb], axis=-1))
    assert g.attitude_from_thrust(thrust[1:], yaw[1:]).tobytes() == expected[1:].tobytes()
    assert g.attitude_from_thrust(thrust, yaw).tobytes() == expected.tobytes()


def test_attitude_from_thrust_runs_on_a_scipy_without_assume_valid(monkeypatch):
    # pyproject allows scipy 1.15, whose Rotation.from_matrix takes no ``assume_valid``: the checked conversion then
    from scipy.spatial.transform import Rotation

    plain = Rotation.from_matrix

    def old_from_matrix(matrix):
        return plain(matrix)

    rng = np.random.default_rng(6)
    thrust = rng.normal(0.0, 30.0, (500, 3)) + [0.0, 0.0, 9.81]
    yaw = rng.uniform(-3.0, 3.0, 500)
    expected = g.attitude_from_thrust(thrust, yaw)
    monkeypatch.setattr(Rotation, "from_matrix", staticmethod(old_from_matrix))
    assert g.attitude_from_thrust(thrust, yaw).tobytes() == expected.tobytes()
