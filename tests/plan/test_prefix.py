"""A manoeuvre's first seconds flown as a unit of their own (issue 27, item 3: the best prefix)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign
from rplearn.plan.manoeuvres import Candidate, ManoeuvreUnit
from rplearn.plan.prefix import PrefixUnit, braking_s, cut_candidate, prefix_cuts


def _orbit():
    return ManoeuvreUnit(nodes=("B", "A"), kind="orbit", anchor_enu_m=(5.0, 0.0, 20.0), start_enu_m=(-5.0, 0.0, 20.0),
                         elevation_deg=30.0)


def test_a_prefix_follows_the_unit_up_to_its_cut_then_holds_at_rest():
    whole = _orbit()
    cut = PrefixUnit(whole, 20.0)
    speed = float(np.linalg.norm(whole.evaluate(np.array([20.0])).velocity_enu_m_s[0, 1]))
    assert speed == pytest.approx(whole.speed_m_s)  # mid-orbit, at cruise: braking at accel_m_s2 counted
    assert cut.brake_s == pytest.approx(speed / whole.accel_m_s2, rel=1e-6)
    assert cut.duration_s == pytest.approx(20.0 + cut.brake_s) and cut.brake_s > 1.0
    assert cut.nodes == whole.nodes and cut.role == "learning"
    assert cut.label == f"{whole.label}_first20s"
    t = np.linspace(0.0, 20.0, 81)
    a, b = whole.evaluate(t, 3.0), cut.evaluate(t, 3.0)
    for name in ("t_s", "position_enu_m", "velocity_enu_m_s", "accel_enu_m_s2", "yaw_rad"):
        assert np.allclose(getattr(a, name), getattr(b, name)), name
    after = cut.evaluate(np.array([20.0, 25.0, 40.0]))
    assert np.allclose(after.position_enu_m, whole.evaluate(np.array([20.0])).position_enu_m)
    assert np.allclose(after.velocity_enu_m_s[1:], 0.0) and np.allclose(after.accel_enu_m_s2[1:], 0.0)
    assert np.abs(whole.evaluate(np.array([20.0])).velocity_enu_m_s).max() > 0.1  # cut mid-orbit
    assert cut.sample(4.0).t_s[-1] == 20.0 and cut.sample(4.0).t_s.size == 81
    for bad in (0.0, whole.duration_s + 1.0, float("nan")):
        with pytest.raises(InputError) as err:
            PrefixUnit(whole, bad)
        assert err.value.param == "cut_s"


def test_braking_after_a_cut_turn_is_its_yaw_rate_over_the_yaw_acceleration_and_none_at_the_end():
    turn = ManoeuvreUnit(nodes=("B", "A"), kind="yaw", anchor_enu_m=(5.0, 0.0, 20.0), start_enu_m=(-5.0, 0.0, 20.0),
                         turn_deg=360.0)
    mid = turn.duration_s / 2.0  # at cruise yaw rate, standing still
    assert braking_s(turn, mid) == pytest.approx(turn.yaw_rate_deg_s / turn.yaw_accel_deg_s2, rel=1e-3)
    assert braking_s(turn, turn.duration_s) == 0.0 and braking_s(_orbit(), _orbit().duration_s) == 0.0
    assert PrefixUnit(turn, turn.duration_s).duration_s == turn.duration_s  # the whole: ends at rest


def test_the_cuts_are_whole_blocks_at_least_two_long_and_the_whole_comes_last():
    assert prefix_cuts(240, 4.0, 4, 5.0) == [60, 120, 180, 240]
    assert prefix_cuts(250, 4.0, 4, 5.0) == [60, 120, 180, 250]  # 62, 125, 187 rounded down to blocks of 20
    assert prefix_cuts(50, 4.0, 4, 5.0) == [50]  # 12 and 25 rows are under two blocks; 37 too
    assert prefix_cuts(240, 4.0, 1, 5.0) == [240]
    with pytest.raises(InputError) as err:
        prefix_cuts(240, 4.0, 0, 5.0)
    assert err.value.param == "parts"


def test_a_cut_candidate_ends_where_the_cut_falls_and_the_simulator_flies_only_the_prefix():
    from rplearn.data.sync import synchronise
    from rplearn.sim import simulate
    from rplearn.sim.presets import make_preset

    whole = _orbit()
    cand = Candidate("orbit of A", whole, 2.0, {"A": whole.end_pose()})
    cut = cut_candidate(cand, 15.0)
    pos = whole.evaluate(np.array([15.0]))
    assert cut.ends["A"][0] == pytest.approx(tuple(pos.position_enu_m[0, 1]))
    assert cut.ends["A"][1] == pytest.approx(np.degrees(pos.yaw_rad[0, 1]))
    assert set(cut.ends) == {"A"} and cut.duration_s == pytest.approx(2.0 + 15.0 + 1.5) and "first 15 of" in cut.name  # lead, prefix, braking
    config = make_preset("smoke")
    config = replace(config, radio=replace(config.radio, link_offsets_db=(), dropouts=0))
    flown = simulate(replace(config, campaign=Campaign((replace(cut.unit, label="p00"),), gap_s=0.0)), seed=3)
    t = synchronise(flown.pose_log, flown.signal_log).dataset["t"].to_numpy()
    assert t.size > 0 and t.max() - t.min() <= 15.0 + 0.5
