"""Manoeuvres aimed at a node's body-frame direction (rplearn.plan.aimed): they make it look along it."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.geometry import attitude_from_thrust, great_circle_angle, link_directions
from rplearn.errors import InputError
from rplearn.plan.aimed import aimed_manoeuvres
from rplearn.plan.manoeuvres import CandidateOptions
from rplearn.plan.trajectory import G_M_S2

POSES = {"A": ((-5.0, 0.0, 20.0), 0.0), "B": ((5.0, 0.0, 20.0), 90.0)}


def _closest_view_deg(candidate, node, aim):
    """Smallest angle between ``node``'s view of its peer along the candidate's unit and ``aim`` [deg]."""
    unit = candidate.unit
    ref = unit.sample(20.0)
    up = np.array([0.0, 0.0, G_M_S2])
    q = [attitude_from_thrust(ref.accel_enu_m_s2[:, j, :] + up, ref.yaw_rad[:, j]) for j in (0, 1)]
    d = link_directions(ref.position_enu_m[:, 0, :], q[0], ref.position_enu_m[:, 1, :], q[1])
    az, el = (d.az_tx, d.el_tx) if node == unit.nodes[0] else (d.az_rx, d.el_rx)
    return float(np.degrees(np.min(great_circle_angle(az, el, aim[0], aim[1]))))


@pytest.mark.parametrize("node", ["A", "B"])
def test_every_candidate_aimed_at_a_node_s_direction_makes_it_look_along_it(node):
    aim = (np.radians(-120.0), np.radians(35.0))
    cands = aimed_manoeuvres(POSES, {node: [aim]}, CandidateOptions())
    assert cands and all("direction 1" in c.name for c in cands)
    for c in cands:
        assert _closest_view_deg(c, node, aim) < 4.0, c.name
    # the fixed grid's turn of the same drone does not pass that direction (its elevation is 0)
    assert all(c.unit.label.startswith("aim") for c in cands)


def test_a_static_station_s_aim_is_reached_by_moving_there_and_its_way_counts_as_lead():
    poses = {"G": ((0.0, 0.0, 1.5), 0.0), "D": ((20.0, 0.0, 10.0), 0.0)}
    aim = (np.radians(40.0), np.radians(20.0))
    cands = aimed_manoeuvres(poses, {"G": [aim]}, CandidateOptions(fixed_nodes=("G",)))
    assert sorted(c.unit.kind for c in cands) == ["orbit", "yaw"]
    (c,) = [c for c in cands if c.unit.kind == "yaw"]
    assert c.lead_s > 0 and _closest_view_deg(c, "G", aim) < 1.0
    assert all(c.unit.anchor_turn_deg == 0.0 and _closest_view_deg(c, "G", aim) < 4.0 for c in cands)  # a station never turns


def test_aims_the_heights_or_the_separation_forbid_give_no_candidate():
    poses = {"G": ((0.0, 0.0, 1.5), 0.0), "D": ((20.0, 0.0, 10.0), 0.0)}
    below = (0.0, np.radians(-40.0))  # the drone would have to go underground
    assert aimed_manoeuvres(poses, {"G": [below]}, CandidateOptions(fixed_nodes=("G",))) == []
    low = {"G": ((0.0, 0.0, 1.5), 0.0), "D": ((20.0, 0.0, 4.0), 0.0)}
    behind = (np.radians(180.0), np.radians(5.0))  # the straight way there passes by the station's mast
    assert [c.unit.kind for c in aimed_manoeuvres(low, {"G": [behind]}, CandidateOptions(fixed_nodes=("G",)))] == ["orbit"]
    close = {"A": ((-3.0, 0.0, 20.0), 0.0), "B": ((3.0, 0.0, 20.0), 0.0)}
    opts = CandidateOptions(min_separation_m=5.5)
    for c in aimed_manoeuvres(close, {"A": [(0.5, 1.2)]}, opts):  # none brings them nearer than now
        ref = c.unit.sample(10.0)
        assert np.min(np.linalg.norm(ref.position_enu_m[:, 0] - ref.position_enu_m[:, 1], axis=1)) >= 6.0 - 1e-6


def test_aims_of_a_node_without_a_pose_are_refused():
    with pytest.raises(InputError) as err:
        aimed_manoeuvres(POSES, {"C": [(0.0, 0.0)]})
    assert err.value.param == "aims"


def test_rings_aim_the_elevation_only_with_full_circles_and_no_move_to_a_station_s_aim():
    aim = (np.radians(-120.0), np.radians(35.0))
    for node in ("A", "B"):
        cands = aimed_manoeuvres(POSES, {node: [aim]}, CandidateOptions(), rings=True)
        assert cands and all(c.unit.kind in ("climb_turn", "yaw", "orbit") for c in cands)
        assert all(abs(c.unit.turn_deg) == 360.0 and c.unit.anchor_turn_deg == 0.0 for c in cands if c.unit.kind != "orbit")
        assert all(_closest_view_deg(c, node, aim) < 4.0 for c in cands)  # a full ring at the aim's elevation passes it
    poses = {"G": ((0.0, 0.0, 1.5), 0.0), "D": ((20.0, 0.0, 10.0), 0.0)}
    cands = aimed_manoeuvres(poses, {"G": [(np.radians(40.0), np.radians(20.0))]}, CandidateOptions(fixed_nodes=("G",)), rings=True)
    assert [c.unit.kind for c in cands] == ["orbit"] and cands[0].lead_s == 0.0
