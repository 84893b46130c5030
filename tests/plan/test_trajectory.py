"""Trajectory units, campaigns and group schedules (paper Sec. IV-A, Fig. 3; Sec. V-C)."""

from __future__ import annotations

import os

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rplearn.errors import InputError, PlanError
from rplearn.plan.campaign import Campaign, group_campaign, link_graph_identifies_gains, pair_schedule, paper_campaign, write_references
from rplearn.plan.trajectory import PlanLimits, TrajectoryUnit, summarize_unit


def _elevation_second_from_first_deg(ref) -> np.ndarray:
    d = ref.position_enu_m[:, 1, :] - ref.position_enu_m[:, 0, :]
    return np.degrees(np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1])))


@settings(max_examples=25, deadline=None)
@given(
    distance=st.floats(4.0, 30.0),
    psi0=st.floats(0.0, 359.0),
    speed=st.floats(0.5, 4.0),
    line_az=st.floats(-180.0, 180.0),
)
def test_drones_stay_d_apart(distance: float, psi0: float, speed: float, line_az: float) -> None:
    unit = TrajectoryUnit(
        distance_m=distance, height_m=distance, psi0_deg=psi0, speed_m_s=speed, n_loops=3, line_azimuth_deg=line_az
    )
    ref = unit.sample(20.0)
    d = np.linalg.norm(ref.position_enu_m[:, 0] - ref.position_enu_m[:, 1], axis=1)
    np.testing.assert_allclose(d, distance, rtol=1e-9)
    # the circle is centred between the drones at the start height, and never below ground
    centre = ref.position_enu_m.mean(axis=1)
    np.testing.assert_allclose(centre[:, 2], distance, atol=1e-9)
    assert ref.position_enu_m[:, :, 2].min() >= distance / 2 - 1e-9


def test_every_loop_sweeps_elevation_through_minus_90_to_90() -> None:
    unit = TrajectoryUnit(n_loops=5)
    ref = unit.sample(50.0)
    el = _elevation_second_from_first_deg(ref)
    loops = sorted(set(ref.loop_index[ref.loop_index >= 0]))
    assert loops == list(range(2 * unit.n_loops))
    for i in loops:
        sel = ref.loop_index == i
        assert el[sel].min() < -89.0 and el[sel].max() > 89.0, f"loop {i}"
        # the line between the drones turns through a full revolution: both horizontal directions
        d = ref.position_enu_m[sel, 1, 0] - ref.position_enu_m[sel, 0, 0]
        assert d.min() < -0.99 * unit.distance_m and d.max() > 0.99 * unit.distance_m


def test_heading_schedule_is_the_papers() -> None:
    n = 5
    psi0 = 24.0
    unit = TrajectoryUnit(psi0_deg=psi0, n_loops=n)
    step = 360.0 / n  # paper Sec. V-C: n = 5 gives 72 deg
    assert unit.heading_step_deg == pytest.approx(72.0)
    ref = unit.sample(20.0)
    for i in range(2 * n):
        sel = ref.loop_index == i
        yaw = np.degrees(ref.yaw_rad[sel])
        # headings are constant during a loop
        assert np.ptp(np.unwrap(np.radians(yaw), axis=0), axis=0).max() < 1e-9
        first, second = yaw[0]
        if i < n:  # the first drone sweeps, the second holds psi0
            exp_first, exp_second = psi0 + i * step, psi0
        else:  # then the second sweeps, the first holds psi0
            exp_first, exp_second = psi0, psi0 + (i - n) * step
        assert np.cos(np.radians(first - exp_first)) == pytest.approx(1.0)
        assert np.cos(np.radians(second - exp_second)) == pytest.approx(1.0)
    # the sweeping drone visits every heading step once per phase
    sched = unit.heading_schedule_deg()
    assert sorted(np.mod(sched[:n, 0], 360)) == pytest.approx(sorted(np.mod(psi0 + step * np.arange(n), 360)))


def test_turns_between_loops_hover_and_turn_forward() -> None:
    unit = TrajectoryUnit(n_loops=4, yaw_rate_deg_s=45.0)
    ref = unit.sample(50.0)
    turning = ref.loop_index < 0
    assert turning.any()
    speed = np.linalg.norm(ref.velocity_enu_m_s[turning], axis=-1)
    assert speed.max() == 0.0
    # heading changes happen only while hovering
    dyaw = np.abs(np.angle(np.exp(1j * np.diff(ref.yaw_rad, axis=0))))
    moving = ~turning[1:] & ~turning[:-1]
    assert dyaw[moving].max() < 1e-9


def test_units_with_different_psi0_interleave_headings() -> None:
    campaign = paper_campaign()
    roles = {u.label: u.role for u in campaign.units}
    assert sorted(roles.values()) == ["learning", "learning", "learning", "testing"]
    learn = np.concatenate([u.heading_schedule_deg().ravel() for u in campaign.units if u.role == "learning"])
    test = np.concatenate([u.heading_schedule_deg().ravel() for u in campaign.units if u.role == "testing"])
    learn_set = np.unique(np.mod(np.round(learn, 9), 360.0))
    test_set = np.unique(np.mod(np.round(test, 9), 360.0))
    # learning headings are evenly spread (step 360/15 = 24 deg) and testing headings fall
    # strictly between them (never on a learning heading)
    gaps = np.diff(np.concatenate([learn_set, [learn_set[0] + 360.0]]))
    np.testing.assert_allclose(gaps, 360.0 / learn_set.size)
    for h in test_set:
        dist = np.abs(np.angle(np.exp(1j * np.radians(learn_set - h)), deg=True))
        assert dist.min() == pytest.approx(gaps[0] / 2)


def test_summary_matches_sampled_reference() -> None:
    unit = TrajectoryUnit(speed_m_s=2.0, accel_m_s2=0.8, distance_m=12.0, n_loops=3)
    s = summarize_unit(unit)
    ref = unit.sample(200.0)
    assert s.duration_s == pytest.approx(ref.t_s[-1], abs=1 / 200)
    assert s.path_length_m == pytest.approx(2 * 3 * np.pi * 12.0)
    speed = np.linalg.norm(ref.velocity_enu_m_s, axis=-1)
    acc = np.linalg.norm(ref.accel_enu_m_s2, axis=-1)
    assert speed.max() == pytest.approx(s.max_speed_m_s, rel=1e-6)
    assert acc.max() == pytest.approx(s.max_accel_m_s2, rel=1e-3)
    # path length by integrating the speed of each drone
    dist = np.sum(0.5 * (speed[1:] + speed[:-1]) * np.diff(ref.t_s)[:, None], axis=0)
    np.testing.assert_allclose(dist, s.path_length_m, rtol=1e-3)
    # the reference velocity and acceleration are the derivatives of the position
    dt = np.diff(ref.t_s)[:, None, None]
    fd_vel = np.diff(ref.position_enu_m, axis=0) / dt
    mid_vel = 0.5 * (ref.velocity_enu_m_s[1:] + ref.velocity_enu_m_s[:-1])
    np.testing.assert_allclose(fd_vel, mid_vel, atol=2e-3)


def test_short_loop_never_reaches_cruise_speed() -> None:
    unit = TrajectoryUnit(speed_m_s=20.0, accel_m_s2=1.0, distance_m=4.0, height_m=5.0, n_loops=1)
    s = summarize_unit(unit)
    assert s.max_speed_m_s < 20.0
    assert s.max_speed_m_s == pytest.approx(np.sqrt(1.0 * np.pi * 4.0))


def test_limits_refuse_a_plan_with_a_clear_message() -> None:
    unit = TrajectoryUnit(speed_m_s=3.0)
    ok = summarize_unit(unit, PlanLimits(max_speed_m_s=5.0, max_accel_m_s2=5.0, max_flight_time_s=600.0))
    assert ok.max_speed_m_s == pytest.approx(3.0)
    with pytest.raises(PlanError, match=r"peak speed is 3 m/s, above the limit 2 m/s \(max_speed_m_s\)"):
        summarize_unit(unit, PlanLimits(max_speed_m_s=2.0))
    with pytest.raises(PlanError, match="max_accel_m_s2"):
        summarize_unit(unit, PlanLimits(max_accel_m_s2=0.5))
    with pytest.raises(PlanError, match="max_flight_time_s"):
        Campaign((unit,)).summarize(PlanLimits(max_flight_time_s=60.0))


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"distance_m": -1.0}, "distance_m"),
        ({"n_loops": 0}, "n_loops"),
        ({"nodes": ("A", "A")}, "nodes"),
        ({"height_m": 3.0}, "height_m"),
        ({"role": "training"}, "role"),
        ({"speed_m_s": float("nan")}, "speed_m_s"),
    ],
)
def test_bad_unit_parameters_name_the_field(kwargs: dict, field: str) -> None:
    with pytest.raises(InputError, match=field):
        TrajectoryUnit(**kwargs)


def test_campaign_times_and_roles() -> None:
    c = paper_campaign()
    starts = c.start_times_s()
    durations = np.array([u.duration_s for u in c.units])
    np.testing.assert_allclose(np.diff(starts), durations[:-1] + c.gap_s)
    assert c.duration_s == pytest.approx(starts[-1] + durations[-1])
    assert [u.label for u in c.with_role("testing").units] == ["test_36"]
    assert c.nodes == ("A", "B") and c.links() == [("A", "B")]
    with pytest.raises(InputError, match="unique"):
        Campaign((c.units[0], c.units[0]))


def test_write_references(tmp_path) -> None:
    c = paper_campaign(n_loops=2, speed_m_s=3.0)
    paths = write_references(c, str(tmp_path), rate_hz=5.0)
    assert len(paths) == 2 * len(c.units)
    first = pd.read_csv(paths[0])
    assert list(first.columns) == ["t", "x", "y", "z", "yaw_deg"]
    assert os.path.basename(paths[0]) == f"{c.units[0].label}_A.csv"
    assert first["t"].iloc[0] == 0.0
    assert first["t"].iloc[-1] == pytest.approx(c.units[0].duration_s, abs=0.2)
    second = pd.read_csv(paths[1])
    d = np.hypot(np.hypot(first.x - second.x, first.y - second.y), first.z - second.z)
    np.testing.assert_allclose(d, 10.0, atol=1e-3)


def test_link_graph_odd_cycles() -> None:
    assert not link_graph_identifies_gains([("A", "B")])
    assert link_graph_identifies_gains([("A", "B"), ("B", "C"), ("C", "A")])
    # an even cycle alone leaves an alternating constant free
    assert not link_graph_identifies_gains([("A", "B"), ("B", "C"), ("C", "D"), ("D", "A")])
    # every connected part needs its own odd cycle
    assert not link_graph_identifies_gains([("A", "B"), ("B", "C"), ("C", "A"), ("D", "E")])
    assert not link_graph_identifies_gains([])


@pytest.mark.parametrize("n", [3, 4, 5, 7])
def test_pair_schedule_identifies_absolute_gains(n: int) -> None:
    nodes = [chr(ord("A") + i) for i in range(n)]
    pairs = pair_schedule(nodes)
    assert link_graph_identifies_gains(pairs)
    assert {x for p in pairs for x in p} == set(nodes)
    assert len(set(map(frozenset, pairs))) == len(pairs)


def test_group_campaign_flies_every_scheduled_pair() -> None:
    c = group_campaign(("A", "B", "C"), learning_psi0_deg=(0.0,), testing_psi0_deg=(36.0,))
    assert c.links() == [("A", "B"), ("A", "C"), ("B", "C")]
    assert len(c.units) == 6
    assert pair_schedule(["A", "B"]) == [("A", "B")]
    with pytest.raises(InputError):
        pair_schedule(["A"])


def test_yaw_rate_summary_matches_reference_and_limit() -> None:
    unit = TrajectoryUnit(n_loops=5, yaw_rate_deg_s=40.0)
    s = summarize_unit(unit)
    ref = unit.sample(500.0)
    rate = np.degrees(np.abs(np.angle(np.exp(1j * np.diff(ref.yaw_rad, axis=0))))) / np.diff(ref.t_s)[:, None]
    assert rate.max() == pytest.approx(s.max_yaw_rate_deg_s, rel=1e-3)
    assert s.max_yaw_rate_deg_s == pytest.approx(40.0 * np.pi / 2, rel=1e-9)
    with pytest.raises(PlanError, match="max_yaw_rate_deg_s"):
        summarize_unit(unit, PlanLimits(max_yaw_rate_deg_s=30.0))


def test_wording_names_parameters_and_real_remedies():
    """Library messages name the parameters (never command-line flags) and carry them as ``param``."""
    from rplearn.errors import InputError, PlanError
    from rplearn.plan.campaign import paper_campaign
    from rplearn.plan.trajectory import PlanLimits, summarize_unit

    with pytest.raises(InputError, match=r"^n_loops: expected a positive integer, got 0$") as e:
        paper_campaign(n_loops=0)
    assert e.value.param == "n_loops"
    with pytest.raises(InputError, match=r"^distance_m: expected a positive finite number") as e:
        paper_campaign(distance_m=-1.0)
    assert e.value.param == "distance_m"
    with pytest.raises(InputError, match=r"^height_m: expected more than half the distance") as e:
        paper_campaign(height_m=3.0)
    assert e.value.param == "height_m"
    unit = paper_campaign(speed_m_s=5.0).units[0]
    with pytest.raises(PlanError) as e:
        summarize_unit(unit, PlanLimits(max_speed_m_s=1.0))
    msg = str(e.value)
    assert e.value.param == "max_speed_m_s"
    assert "above the limit 1 m/s (max_speed_m_s)" in msg and "lower the cruise speed (speed_m_s)" in msg
    assert "loop count" not in msg
    with pytest.raises(PlanError, match=r"fly fewer headings \(n_loops\), a smaller circle \(distance_m\)") as e:
        summarize_unit(unit, PlanLimits(max_flight_time_s=1.0))
    assert e.value.param == "max_flight_time_s"
    for limits in (PlanLimits(max_speed_m_s=1.0), PlanLimits(max_accel_m_s2=0.1), PlanLimits(max_flight_time_s=1.0)):
        with pytest.raises(PlanError) as e:
            summarize_unit(unit, limits)
        assert "--" not in str(e.value)


def test_cli_trajectory_names_the_flags(tmp_path):
    """The command line maps the parameters of library messages back to its flags."""
    from typer.testing import CliRunner

    from rplearn.cli import app

    runner = CliRunner()
    res = runner.invoke(app, ["trajectory", "--loops", "0", "--check-model", "none", "-o", str(tmp_path / "a")])
    assert res.exit_code == 1
    assert "--loops: expected a positive integer, got 0" in res.output
    res = runner.invoke(app, ["trajectory", "--speed", "5", "--max-speed", "1", "--check-model", "none", "-o", str(tmp_path / "b")])
    assert res.exit_code == 1
    assert "above the limit 1 m/s (--max-speed)" in res.output and "lower the cruise speed (--speed)" in res.output
    assert "max_speed_m_s" not in res.output and "speed_m_s" not in res.output


def test_help_summary_of_trajectory_is_complete():
    from typer.testing import CliRunner

    from rplearn.cli import app

    res = CliRunner().invoke(app, ["--help"], env={"COLUMNS": "120"})
    line = next(ln for ln in res.output.splitlines() if ln.strip().startswith("trajectory"))
    assert line.split("trajectory", 1)[1].strip() == "Plan a calibration campaign and check it before flying."
