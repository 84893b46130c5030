"""Manoeuvre units and the candidates flyable from the current poses (issue 27, item 3)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign
from rplearn.plan.ground import GroundPassUnit
from rplearn.plan.manoeuvres import CandidateOptions, ManoeuvreUnit, candidate_manoeuvres
from rplearn.plan.trajectory import TrajectoryUnit

PAIR = {"A": ((-5.0, 0.0, 20.0), 0.0), "B": ((5.0, 0.0, 20.0), 0.0)}


def _unit(kind, **kw):
    return ManoeuvreUnit(nodes=("B", "A"), kind=kind, anchor_enu_m=(5.0, 0.0, 20.0), start_enu_m=(-5.0, 0.0, 20.0), **kw)


def test_a_yaw_turn_stays_in_place_and_turns_once_around():
    u = _unit("yaw")
    # trapezoid: 360 deg at 30 deg/s with 60 deg/s^2 ramps = 12 s cruise-equivalent + 0.5 s
    assert u.duration_s == pytest.approx(12.5)
    ref = u.sample(20.0)
    assert np.allclose(ref.position_enu_m[:, 1], (-5.0, 0.0, 20.0)) and np.allclose(ref.position_enu_m[:, 0], (5.0, 0.0, 20.0))
    turned = np.unwrap(ref.yaw_rad[:, 1])
    assert turned[-1] - turned[0] == pytest.approx(2 * np.pi, abs=1e-9) and np.all(np.diff(turned) >= -1e-12)
    assert u.end_pose()[0] == pytest.approx((-5.0, 0.0, 20.0))


def test_an_orbit_keeps_its_distance_and_elevation_and_its_velocity_is_the_derivative():
    u = _unit("orbit", elevation_deg=45.0, distance_m=6.0)
    ref = u.sample(50.0)
    anchor = np.array([5.0, 0.0, 20.0])
    d = ref.position_enu_m[:, 1] - anchor
    on_circle = np.abs(np.linalg.norm(d, axis=1) - 6.0) < 1e-6
    assert on_circle[-1] and on_circle.mean() > 0.5  # the transit, then the circle
    el = np.degrees(np.arctan2(d[on_circle, 2], np.hypot(d[on_circle, 0], d[on_circle, 1])))
    assert np.allclose(el, 45.0)
    bearing = np.unwrap(np.arctan2(d[on_circle, 1], d[on_circle, 0]))
    assert bearing.max() - bearing.min() == pytest.approx(2 * np.pi, abs=0.01)  # a full circle
    v_num = np.gradient(ref.position_enu_m[:, 1], ref.t_s, axis=0)
    assert np.max(np.abs(v_num - ref.velocity_enu_m_s[:, 1])[2:-2]) < 0.05
    assert np.max(np.linalg.norm(ref.velocity_enu_m_s[:, 1], axis=1)) <= 1.5 + 1e-9
    assert np.allclose(ref.yaw_rad[:, 1], 0.0)  # heading fixed in the world


def test_a_spiral_climbs_and_turns_at_once():
    spiral, then = _unit("spiral", elevation_deg=30.0), _unit("climb_turn", elevation_deg=30.0)
    climb, turn = _unit("climb", elevation_deg=30.0), _unit("yaw")
    assert spiral.duration_s == pytest.approx(max(climb.duration_s, turn.duration_s))
    assert then.duration_s == pytest.approx(climb.duration_s + turn.duration_s)
    end = spiral.end_pose()[0]
    assert end[2] == pytest.approx(20.0 + 10.0 * np.tan(np.radians(30.0)))


@pytest.mark.parametrize(("kw", "param"), [
    (dict(kind="hover"), "kind"),
    (dict(kind="orbit", elevation_deg=95.0), "elevation_deg"),
    (dict(kind="yaw", speed_m_s=0.0), "speed_m_s"),
    (dict(kind="orbit", elevation_deg=10.0, distance_m=0.2), "distance_m"),
])
def test_bad_manoeuvres_are_refused_naming_the_field(kw, param):
    with pytest.raises(InputError) as err:
        _unit(**kw)
    assert err.value.param == param


def test_candidates_never_move_a_fixed_node_and_respect_the_heights():
    poses = {"G": ((0.0, 0.0, 1.5), 10.0), "D": ((40.0, 5.0, 15.0), 190.0)}
    cands = candidate_manoeuvres(poses, CandidateOptions(fixed_nodes=("G",), min_height_m=5.0))
    assert cands and all("G" not in c.ends for c in cands)
    for c in cands:
        ref = c.unit.sample(5.0)
        j = list(c.unit.nodes).index("G")
        assert np.allclose(ref.position_enu_m[:, j], (0.0, 0.0, 1.5))
        assert ref.position_enu_m[:, 1 - j, 2].min() >= 5.0 - 1e-6
    assert any(isinstance(c.unit, GroundPassUnit) for c in cands)
    assert not any(isinstance(c.unit, TrajectoryUnit) for c in cands)


def test_two_drones_get_every_kind_and_the_paper_units_where_they_are():
    cands = candidate_manoeuvres(PAIR)
    kinds = {getattr(c.unit, "kind", type(c.unit).__name__) for c in cands}
    assert {"yaw", "climb", "climb_turn", "spiral", "orbit", "TrajectoryUnit"} <= kinds
    paper = [c for c in cands if isinstance(c.unit, TrajectoryUnit) and c.unit.psi0_deg == 0.0]
    assert paper and all(c.lead_s == pytest.approx(0.0, abs=1e-9) for c in paper)  # it starts where they are
    assert len({c.unit.label for c in cands}) == len(cands)
    with pytest.raises(InputError):
        candidate_manoeuvres({"A": PAIR["A"]})


def test_the_simulator_flies_a_sequence_of_manoeuvres():
    from rplearn.sim import simulate
    from rplearn.sim.presets import make_preset

    units = (_unit("yaw", label="m1"), _unit("spiral", elevation_deg=20.0, label="m2"))
    config = make_preset("smoke")
    sim = simulate(replace(config, campaign=Campaign(units, gap_s=1.0)), seed=2)  # type: ignore[arg-type]
    assert set(sim.signal_log["unit"]) == {"m1", "m2"}
    b = sim.pose_log[sim.pose_log["node"] == "B"]
    assert np.allclose(b[["x", "y"]].median().to_numpy(), (5.0, 0.0), atol=0.5)


def _closest(unit, others=()):
    ref = unit.sample(20.0)
    pts = [ref.position_enu_m[:, 0], ref.position_enu_m[:, 1], *[np.broadcast_to(np.asarray(p, float), ref.position_enu_m[:, 0].shape)
                                                                  for p in others]]
    return min(float(np.min(np.linalg.norm(a - b, axis=1))) for i, a in enumerate(pts) for b in pts[i + 1:])


def test_no_candidate_brings_two_nodes_nearer_than_the_separation():
    steep = {"A": ((0.0, 0.0, 20.0), 0.0), "B": ((3.0, 0.0, 27.0), 0.0)}  # 7.6 m apart, 3 m horizontally
    everything = candidate_manoeuvres(steep, CandidateOptions(min_separation_m=0.0))
    assert min(_closest(c.unit) for c in everything) < 4.0  # without the limit a descent passes 3 m away
    for limit in (5.0, 7.0):
        kept = candidate_manoeuvres(steep, CandidateOptions(min_separation_m=limit))
        assert kept and len(kept) < len(everything)
        assert min(_closest(c.unit) for c in kept) >= limit - 1e-9


def test_nodes_already_nearer_than_the_separation_may_stay_as_near_but_never_come_nearer():
    near = {"A": ((-1.5, 0.0, 20.0), 0.0), "B": ((1.5, 0.0, 20.0), 0.0)}
    cands = candidate_manoeuvres(near, CandidateOptions(min_separation_m=5.0))
    assert any(getattr(c.unit, "kind", "") == "yaw" for c in cands)  # turning in place is still offered
    assert all(_closest(c.unit) >= 3.0 - 1e-6 for c in cands)


def test_a_hovering_anchor_turns_once_around_while_the_mover_flies():
    climb = _unit("climb", elevation_deg=30.0)
    both = replace(climb, anchor_turn_deg=360.0, label="")
    assert both.label != climb.label
    assert both.duration_s == pytest.approx(max(climb.duration_s, _unit("yaw").duration_s))
    ref = both.sample(20.0)
    turned = np.unwrap(ref.yaw_rad[:, 0])
    assert turned[-1] - turned[0] == pytest.approx(2 * np.pi, abs=1e-9)
    assert np.allclose(ref.position_enu_m[:, 0], (5.0, 0.0, 20.0))
    assert both.end_pose()[0] == pytest.approx(climb.end_pose()[0])  # the mover holds its end meanwhile
    held = ref.t_s >= climb.duration_s
    assert held.any() and np.allclose(ref.accel_enu_m_s2[held, 1], 0.0) and np.allclose(ref.velocity_enu_m_s[held, 1], 0.0)
    assert both.anchor_end_yaw_deg() == pytest.approx(0.0, abs=1e-9)


def test_only_a_drone_anchor_turns_never_a_ground_station():
    pair = candidate_manoeuvres(PAIR)
    turning = [c for c in pair if getattr(c.unit, "anchor_turn_deg", 0.0) != 0.0]
    assert turning and all(c.unit.nodes[0] in c.ends for c in turning)
    assert not any(getattr(c.unit, "anchor_turn_deg", 0.0) for c in candidate_manoeuvres(PAIR, CandidateOptions(anchor_turns=False)))
    poses = {"G": ((0.0, 0.0, 1.5), 10.0), "D": ((40.0, 5.0, 15.0), 190.0)}
    assert not any(getattr(c.unit, "anchor_turn_deg", 0.0) for c in candidate_manoeuvres(poses, CandidateOptions(fixed_nodes=("G",))))


def test_a_negative_separation_is_refused_naming_the_field():
    with pytest.raises(InputError) as err:
        CandidateOptions(min_separation_m=-1.0)
    assert err.value.param == "min_separation_m"


def test_revisit_candidates_see_their_directions_again_a_pass_later():
    """A 720-degree turn and a two-lap orbit fly the same headings (and ring) twice, and take
    twice as long at cruise; revisits=1 offers none of them."""
    cands = candidate_manoeuvres(PAIR)
    twice = [c for c in cands if "by 720 deg" in c.name or "2 laps" in c.name]
    assert any(c.unit.kind == "yaw" for c in twice) and any(c.unit.kind == "orbit" for c in twice)
    assert len({c.unit.label for c in cands}) == len(cands)
    for c in twice:
        once = next(o for o in cands if o.name == c.name.replace(" by 720 deg", "").replace(", 2 laps", ""))
        assert once.unit.duration_s < c.unit.duration_s < 2.0 * once.unit.duration_s + 1e-6
        ref = c.unit.sample(10.0)
        half = ref.t_s.size // 2
        if c.unit.kind == "yaw":  # the second turn repeats the first turn's headings
            spread = np.degrees(np.abs(np.angle(np.exp(1j * (ref.yaw_rad[:, 1]))))).max()
            assert spread > 170.0
        else:  # the orbit ends where it began its circles, having passed every point twice
            xy = ref.position_enu_m[half:, 1, :2]
            assert np.ptp(xy[:, 0]) > 1.0 and np.ptp(xy[:, 1]) > 1.0
        if c.unit.anchor_turn_deg:
            assert c.unit.anchor_turn_deg == pytest.approx(720.0)
    assert not [c for c in candidate_manoeuvres(PAIR, CandidateOptions(revisits=1)) if "720" in c.name or "laps" in c.name]
    with pytest.raises(InputError):
        CandidateOptions(revisits=0)
    with pytest.raises(InputError):
        _unit("orbit", laps=0)


def test_an_arc_goes_over_the_anchor_on_its_circle_to_the_mirrored_elevation():
    u = _unit("arc", sweep_deg=180.0, distance_m=6.0, turn_deg=360.0)
    ref = u.sample(50.0)
    anchor = np.array([5.0, 0.0, 20.0])
    d = ref.position_enu_m[:, 1] - anchor
    on_circle = np.abs(np.linalg.norm(d, axis=1) - 6.0) < 1e-6
    assert on_circle[-1] and on_circle.mean() > 0.5  # the transit to 6 m, then the arc
    assert np.allclose(d[on_circle, 1], 0.0)  # in the vertical plane of anchor and mover
    assert d[:, 2].max() == pytest.approx(6.0, abs=1e-3)  # over the anchor's zenith
    assert np.array(u.end_pose()[0]) - anchor == pytest.approx((6.0, 0.0, 0.0), abs=1e-9)  # the other side, at the mirrored elevation (0 deg)
    v_num = np.gradient(ref.position_enu_m[:, 1], ref.t_s, axis=0)
    assert np.max(np.abs(v_num - ref.velocity_enu_m_s[:, 1])[2:-2]) < 0.05
    a_num = np.gradient(ref.velocity_enu_m_s[:, 1], ref.t_s, axis=0)
    inside = on_circle & (np.arange(on_circle.size) > np.argmax(on_circle) + 2)
    err = np.linalg.norm(a_num - ref.accel_enu_m_s2[:, 1], axis=1)[inside][:-3]
    assert np.quantile(err, 0.95) < 0.02  # the acceleration is the derivative (but at the profile's steps)
    turned = np.unwrap(ref.yaw_rad[:, 1])
    assert turned[-1] - turned[0] == pytest.approx(2 * np.pi, abs=1e-9)  # the turn meanwhile
    under = _unit("arc", sweep_deg=-180.0, distance_m=6.0, turn_deg=0.0)
    assert (under.sample(20.0).position_enu_m[:, 1, 2] - 20.0).min() == pytest.approx(-6.0, abs=1e-3)
    with pytest.raises(InputError) as err:
        _unit("arc", sweep_deg=0.0)
    assert err.value.param == "sweep_deg"


def test_arcs_are_offered_only_where_the_heights_allow_and_can_be_left_out():
    cands = candidate_manoeuvres(PAIR, CandidateOptions(min_height_m=16.0, arcs=True))
    arcs = [c for c in cands if getattr(c.unit, "kind", "") == "arc"]
    assert arcs and {c.unit.sweep_deg for c in arcs} == {180.0}  # 20 m high: 10 m or 6 m under reaches 10 or 14 m
    for c in arcs:
        assert c.unit.sample(5.0).position_enu_m[:, 1, 2].min() >= 16.0 - 1e-6
    every = candidate_manoeuvres(PAIR, CandidateOptions(arcs=True))
    assert len({c.unit.label for c in every}) == len(every)  # labels stay unique with the arcs
    arcs = [c for c in every if getattr(c.unit, "kind", "") == "arc"]
    assert any(c.unit.sweep_deg == -180.0 for c in arcs)
    assert not any(getattr(c.unit, "kind", "") == "arc" for c in candidate_manoeuvres(PAIR))  # off by default
