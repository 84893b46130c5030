"""Loop sweeps: the paper unit's circles with one drone or both turning (issue 27, item 3)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign
from rplearn.plan.manoeuvres import CandidateOptions, candidate_manoeuvres
from rplearn.plan.sweeps import LoopSweepUnit, loop_sweeps
from rplearn.plan.trajectory import TrajectoryUnit

PAIR = {"A": ((-5.0, 0.0, 20.0), 0.0), "B": ((5.0, 0.0, 20.0), 0.0)}


def test_a_sweep_is_the_paper_units_second_half_for_the_second_drone():
    paper = TrajectoryUnit(n_loops=4, psi0_deg=10.0)
    sweep = LoopSweepUnit(n_loops=4, psi0_deg=10.0, turning="second")
    assert np.array_equal(sweep.heading_schedule_deg(), paper.heading_schedule_deg()[4:])
    first = LoopSweepUnit(n_loops=4, psi0_deg=10.0, turning="first")
    assert np.array_equal(first.heading_schedule_deg(), paper.heading_schedule_deg()[:4])
    # n loops of the same circle and the same turns between them: the paper unit's duration is one
    # sweep's, one turn back to psi0 and another sweep's
    turn_back_s = max(90.0 / paper.yaw_rate_deg_s, 1.0)
    assert paper.duration_s == pytest.approx(2 * sweep.duration_s + turn_back_s)
    assert sweep.path_length_m == pytest.approx(paper.path_length_m / 2)


def test_both_drones_turning_changes_their_relative_heading_every_loop():
    both = LoopSweepUnit(n_loops=5, turning="both").heading_schedule_deg()
    assert sorted(both[:, 0] % 360) == sorted(both[:, 1] % 360) == [0.0, 72.0, 144.0, 216.0, 288.0]
    assert len(set(np.round((both[:, 1] - both[:, 0]) % 360, 6))) == 5
    ref = LoopSweepUnit(n_loops=5, turning="both").sample(10.0)
    loops = sorted(set(ref.loop_index) - {-1})
    assert loops == [0, 1, 2, 3, 4]


@pytest.mark.parametrize("kw, param", [(dict(turning="left"), "turning"), (dict(turning="both", n_loops=4), "n_loops"),
                                       (dict(turning="both", n_loops=1), "n_loops"), (dict(height_m=4.0), "height_m")])
def test_bad_sweeps_are_refused_naming_the_field(kw, param):
    with pytest.raises(InputError) as e:
        LoopSweepUnit(**kw)
    assert e.value.param == param


def test_sweeps_are_offered_where_the_library_units_are_unless_left_out():
    assert not [c for c in candidate_manoeuvres(PAIR, CandidateOptions(sweeps=False)) if isinstance(c.unit, LoopSweepUnit)]
    cands = candidate_manoeuvres(PAIR, CandidateOptions(library_loops=(1, 2, 5)))
    sweeps = [c for c in cands if isinstance(c.unit, LoopSweepUnit)]
    # per heading psi0: one loop, 2 loops with A or B turning, 5 loops with A, B or both turning
    assert len(sweeps) == 3 * (1 + 2 + 3)
    assert len({c.unit.label for c in cands}) == len(cands)
    at_zero = [c for c in sweeps if c.unit.psi0_deg == 0.0]
    assert all(c.lead_s == pytest.approx(0.0, abs=1e-9) for c in at_zero)  # they start where the drones are
    for c in sweeps:  # back where they started: the ends are the circle's start points
        assert np.allclose(c.ends["A"][0], PAIR["A"][0], atol=1e-6) and np.allclose(c.ends["B"][0], PAIR["B"][0], atol=1e-6)
    names = [n for n, _ in loop_sweeps(TrajectoryUnit(nodes=("A", "B"), n_loops=2))]
    assert names == ["loop sweep 2 loops, A turning psi0=0 (A,B)", "loop sweep 2 loops, B turning psi0=0 (A,B)"]


def test_the_simulator_flies_a_sweep():
    from rplearn.sim import simulate
    from rplearn.sim.presets import make_preset

    unit = LoopSweepUnit(nodes=("A", "B"), n_loops=3, distance_m=6.0, height_m=20.0, turning="first", label="s1")
    config = make_preset("smoke")
    sim = simulate(replace(config, campaign=Campaign((unit,), gap_s=1.0)), seed=3)  # type: ignore[arg-type]
    assert set(sim.signal_log["unit"]) == {"s1"}
    z = sim.pose_log[sim.pose_log["node"] == "B"]["z"].to_numpy()
    assert z.max() - z.min() == pytest.approx(6.0, abs=1.5)  # B went over and under A on the circle
