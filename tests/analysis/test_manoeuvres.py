"""Next-best manoeuvre ranking: the rank-k posterior update and the per-node spread (issue 27, item 3)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from rplearn.analysis.manoeuvre_posterior import ManoeuvrePosterior
from rplearn.analysis.manoeuvres import ManoeuvreOptions, greedy_plan, manoeuvre_rows, pattern_spreads, prior_penalty_weight, rank_manoeuvres, target_metrics
from rplearn.core.gauge import EQUAL_MEAN
from rplearn.core.geometry import Directions
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.errors import InputError
from rplearn.models.own_posterior import OwnPrior, own_pattern_posterior
from rplearn.models.spec import ModelSpec
from rplearn.plan.manoeuvres import CandidateOptions, ManoeuvreUnit

SPEC = ModelSpec("sh", 4)
NODES = ("A", "B")
POSES = {"A": ((-5.0, 0.0, 20.0), 0.0), "B": ((5.0, 0.0, 20.0), 0.0)}


def _options(**kw):
    weight = prior_penalty_weight(SPEC.basis(), 3.0, 4.0, SPEC.ridge_weight)
    cands = CandidateOptions(elevations_deg=(-30.0, 0.0, 30.0), library_loops=(1,))
    return ManoeuvreOptions(noise_std_db=4.0, packet_rate_hz=20.0, penalty_weight=weight, candidates=cands, **kw)


def test_the_prior_weight_gives_the_stated_spread_before_any_data():
    opts = _options()
    spreads = pattern_spreads(NormalEquations(SPEC.basis(), 2), SPEC, NODES, replace(opts, target_points=2048))
    assert spreads["A"] == pytest.approx(3.0, rel=1e-3) and spreads["B"] == pytest.approx(3.0, rel=1e-3)
    # beyond what the ridge alone allows at this order: no smoothing, the ridge's spread
    assert prior_penalty_weight(SPEC.basis(), 6.0, 4.0, SPEC.ridge_weight) == 0.0
    with pytest.raises(InputError) as err:
        prior_penalty_weight(SPEC.basis(), 0.0, 4.0, SPEC.ridge_weight)
    assert err.value.param == "prior_std_db"


def test_woodbury_and_the_refactored_precision_agree():
    rng = np.random.default_rng(1)
    p = SPEC.basis().n_coef
    metrics = target_metrics(SPEC.basis(), NODES, _options())
    a = rng.standard_normal((3 * 2 * p, 2 * p))
    precision = a.T @ a / 16.0 + np.eye(2 * p)
    post = ManoeuvrePosterior(precision, metrics, 16.0)
    for k in (5, 3 * 2 * p):  # fewer rows than columns (Woodbury), more (one new factor)
        rows = rng.standard_normal((k, 2 * p))
        direct = np.linalg.inv(precision + 2.5 * rows.T @ rows / 16.0)
        assert np.allclose(post.updated(rows, 2.5), direct, atol=1e-10)


def test_the_predicted_spread_is_the_spread_after_adding_the_manoeuvre_s_samples():
    """With one packet per feature row, a manoeuvre's predicted spreads are exactly those of the
    statistics with its samples added (the same directions through NormalEquations.add)."""
    opts = replace(_options(), packet_rate_hz=2.0, sample_rate_hz=4.0)  # weight 2 * 2 / 4 = 1 packet per row
    normal = NormalEquations(SPEC.basis(), 2)
    unit = ManoeuvreUnit(nodes=("B", "A"), kind="spiral", anchor_enu_m=(5.0, 0.0, 20.0), start_enu_m=(-5.0, 0.0, 20.0),
                         elevation_deg=30.0, yaw_rate_deg_s=opts.candidates.yaw_rate_deg_s)
    ranked = [r for r in rank_manoeuvres(normal, SPEC, NODES, POSES, opts) if r.candidate.unit == unit]
    assert len(ranked) == 1
    rows = manoeuvre_rows(unit, NODES, SPEC.basis(), 4.0)
    ref = unit.sample(4.0)
    from rplearn.core.geometry import attitude_from_thrust, link_directions

    q = [attitude_from_thrust(ref.accel_enu_m_s2[:, j] + [0, 0, 9.80665], ref.yaw_rad[:, j]) for j in (0, 1)]
    d = link_directions(ref.position_enu_m[:, 0], q[0], ref.position_enu_m[:, 1], q[1])
    n = d.az_tx.size
    normal.add(Directions(*d), np.ones(n, int), np.zeros(n, int))  # B (index 1) -> A (index 0)
    assert rows.shape == (n, 2 * SPEC.basis().n_coef)
    after = pattern_spreads(normal, SPEC, NODES, opts)
    assert ranked[0].spread_after_db == pytest.approx(after, rel=1e-8)


def test_ranking_a_yaw_turn_helps_the_turning_drone_most_and_the_list_is_sorted():
    ranked = rank_manoeuvres(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, _options(rate="spread"))
    rates = [r.reduction_db_per_s for r in ranked]
    assert rates == sorted(rates, reverse=True) and rates[0] > 0
    yaw_a = next(r for r in ranked if r.name == "yaw turn of A")
    assert yaw_a.spread_after_db["A"] < yaw_a.spread_after_db["B"] <= yaw_a.spread_before_db["B"] + 1e-9
    assert yaw_a.duration_s == pytest.approx(12.5) and "yaw turn of A" in yaw_a.text()


def test_the_poses_may_be_a_pose_table_and_its_last_row_per_node_counts():
    rows = []
    for t, (ax, bx) in enumerate(((-9.0, 9.0), (-5.0, 5.0))):
        rows += [(float(t), "A", ax, 0.0, 20.0, 1.0, 0.0, 0.0, 0.0), (float(t), "B", bx, 0.0, 20.0, 1.0, 0.0, 0.0, 0.0)]
    table = pd.DataFrame(rows, columns=["t", "node", "x", "y", "z", "qw", "qx", "qy", "qz"])
    normal = NormalEquations(SPEC.basis(), 2)
    from_table = rank_manoeuvres(normal, SPEC, NODES, table, _options())
    from_map = rank_manoeuvres(normal, SPEC, NODES, POSES, _options())
    assert [r.name for r in from_table] == [r.name for r in from_map]
    with pytest.raises(InputError) as err:
        rank_manoeuvres(normal, SPEC, NODES, table[table["node"] == "A"], _options())
    assert err.value.param == "poses" and "B" in str(err.value)
    with pytest.raises(InputError) as err:
        rank_manoeuvres(normal, SPEC, ("A", "B", "C"), POSES, _options())
    assert err.value.param == "nodes"


@pytest.mark.parametrize(("kw", "param"), [(dict(noise_std_db=0.0), "noise_std_db"), (dict(target_el_deg=(10.0, -10.0)), "target_el_deg"),
                                           (dict(aggregate="mean"), "aggregate"), (dict(penalty_weight=-1.0), "penalty_weight"),
                                           (dict(rate="bits"), "rate")])
def test_bad_options_name_their_field(kw, param):
    with pytest.raises(InputError) as err:
        ManoeuvreOptions(**kw)
    assert err.value.param == param


def test_the_spread_is_the_own_posterior_s_on_a_simulated_flight():
    """Measured as the project measures it: the own-pattern posterior of models/own_posterior.py
    (the solver's gauge-constrained covariance, scaled to the noise) gives the same spreads."""
    from rplearn.data.sync import SyncOptions, synchronise
    from rplearn.data.tables import link_samples
    from rplearn.sim import simulate

    sim = simulate("smoke", seed=4)
    ds = synchronise(sim.pose_log, sim.signal_log, SyncOptions()).dataset
    s = link_samples(ds[ds["unit"].str.startswith("learn")], nodes=NODES)
    normal = NormalEquations(SPEC.basis(), 2).add(s.directions, s.tx_index, s.rx_index, s.joint_gain_db)
    opts = replace(_options(), noise_std_db=4.2)
    ours = pattern_spreads(normal, SPEC, NODES, opts)
    own = own_pattern_posterior(normal, ModelSpec("sh", 2).basis(), NODES,
                                OwnPrior(opts.penalty_weight, 1.0, opts.power, SPEC.ridge_weight, EQUAL_MEAN, None), 4.2**2, None)
    p = SPEC.basis().n_coef
    for k, (node, m) in enumerate(zip(NODES, target_metrics(SPEC.basis(), NODES, opts))):
        theirs = float(np.sqrt(np.sum(m * own.covariance[k * p:(k + 1) * p, k * p:(k + 1) * p])))
        assert ours[node] == pytest.approx(theirs, rel=1e-6)
    assert all(0 < v < 3.0 for v in ours.values())


def test_the_greedy_plan_lowers_the_spread_at_every_step_and_keeps_to_its_budget():
    steps = greedy_plan(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, 120.0, 1.0, _options())
    assert steps and steps[-1].end_s <= 120.0
    worst = [max(s.spread_db.values()) for s in steps]
    assert all(b < a for a, b in zip(worst, worst[1:]))
    assert all(b.end_s > a.end_s for a, b in zip(steps, steps[1:]))
    with pytest.raises(InputError) as err:
        greedy_plan(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, 0.0, 1.0, _options())
    assert err.value.param == "budget_s"


def test_the_predicted_spread_is_what_flying_the_manoeuvre_in_the_simulator_gives():
    """The top-ranked manoeuvre, flown in the simulator (wind, tracking errors, pose noise, packet
    loss) and synchronised as real logs: the measured spread after it is the predicted one."""
    from rplearn.data.sync import synchronise
    from rplearn.data.tables import link_samples
    from rplearn.plan.campaign import Campaign
    from rplearn.sim import simulate
    from rplearn.sim.presets import make_preset

    config = make_preset("smoke")
    config = replace(config, radio=replace(config.radio, link_offsets_db=(), dropouts=0))
    start = simulate(config, seed=6)
    poses = start.pose_log[start.pose_log["t"] <= 8.0]
    s = link_samples(synchronise(poses, start.signal_log[start.signal_log["t"] <= 8.0]).dataset, nodes=NODES)
    normal = NormalEquations(SPEC.basis(), 2).add(s.directions, s.tx_index, s.rx_index, s.joint_gain_db)
    rate = config.radio.packet_rate_hz * (1.0 - config.radio.loss_probability)
    opts = replace(_options(), noise_std_db=start.noise_std_db, packet_rate_hz=rate,
                   candidates=replace(_options().candidates, library=False))
    best = rank_manoeuvres(normal, SPEC, NODES, poses, opts)[0]
    flown = simulate(replace(config, campaign=Campaign((best.candidate.unit,), gap_s=0.0)), seed=7)
    m = link_samples(synchronise(flown.pose_log, flown.signal_log).dataset, nodes=NODES)
    normal.add(m.directions, m.tx_index, m.rx_index, m.joint_gain_db)
    measured = pattern_spreads(normal, SPEC, NODES, opts)
    for node in NODES:
        assert measured[node] == pytest.approx(best.spread_after_db[node], rel=0.1), (best.name, measured, best.spread_after_db)
        assert measured[node] < best.spread_before_db[node]


def test_a_floor_gives_no_credit_below_it():
    normal = NormalEquations(SPEC.basis(), 2)
    plain = rank_manoeuvres(normal, SPEC, NODES, POSES, _options(rate="spread"))
    before = max(plain[0].spread_before_db.values())
    floor = before - 0.05
    floored = rank_manoeuvres(normal, SPEC, NODES, POSES, _options(rate="spread", floor_db=floor))
    assert plain[0].reduction_db_per_s > 0.05 / plain[0].duration_s
    for r in floored:  # no manoeuvre is credited with more than bringing the spread down to the floor
        assert r.reduction_db_per_s * r.duration_s <= 0.05 + 1e-9
    assert max(r.reduction_db_per_s * r.duration_s for r in floored) == pytest.approx(0.05)
    # a floor every node is below already rewards nothing: the candidates are ranked without it
    # (they all scored 0 and came in an arbitrary order)
    above = rank_manoeuvres(normal, SPEC, NODES, POSES, _options(rate="spread", floor_db=10.0))
    assert [r.name for r in above] == [r.name for r in plain]
    assert [r.reduction_db_per_s for r in above] == [r.reduction_db_per_s for r in plain]
    with pytest.raises(InputError) as err:
        ManoeuvreOptions(floor_db=-1.0)
    assert err.value.param == "floor_db"


def test_a_steady_tilt_shifts_the_peer_s_elevation_and_spares_a_fixed_node():
    """A drone leaning 12 deg toward its peer sees it 12 deg off its body plane whatever its
    heading (its body z axis is held by the thrust while it turns); the features of a node that
    stands on the ground are those of the level hover."""
    unit = ManoeuvreUnit(nodes=("B", "A"), kind="yaw", anchor_enu_m=(5.0, 0.0, 20.0), start_enu_m=(-5.0, 0.0, 20.0),
                         turn_deg=360.0)
    lean = (9.80665 * np.tan(np.radians(12.0)), 0.0, 0.0)
    level = manoeuvre_rows(unit, NODES, SPEC.basis(), 4.0)
    tilted = manoeuvre_rows(unit, NODES, SPEC.basis(), 4.0, (lean, ()))
    spared = manoeuvre_rows(unit, NODES, SPEC.basis(), 4.0, (lean, ("A",)))
    p = SPEC.basis().n_coef
    assert not np.allclose(level[:, :p], tilted[:, :p]) and np.allclose(level[:, :p], spared[:, :p])  # A, the turning mover
    from rplearn.analysis.manoeuvre_rows import rows_and_ends as _rows_and_ends

    el_a = np.degrees(_rows_and_ends(unit, NODES, SPEC.basis(), 4.0, (lean, ()))[1][1][2])  # A's end of the link
    assert np.abs(el_a) == pytest.approx(np.full(el_a.size, 12.0), abs=0.01)
    assert np.abs(np.degrees(_rows_and_ends(unit, NODES, SPEC.basis(), 4.0)[1][1][2])).max() < 0.01
    with pytest.raises(InputError) as err:
        ManoeuvreOptions(steady_accel_enu_m_s2=(12.0, 0.0, 0.0))
    assert err.value.param == "steady_accel_enu_m_s2"


def test_ranking_by_information_orders_by_the_inverse_square_spread_s_growth_per_second():
    normal = NormalEquations(SPEC.basis(), 2)
    by_spread = rank_manoeuvres(normal, SPEC, NODES, POSES, _options(rate="spread", prefixes=1))
    by_info = rank_manoeuvres(normal, SPEC, NODES, POSES, _options(prefixes=1))  # the default rate, whole manoeuvres
    assert all(r.score_per_s == r.reduction_db_per_s for r in by_spread)
    for r in by_info:  # the nodes' RMS spread, before and after, as 1/s^2 per second of flight
        b, a = (float(np.sqrt(np.mean(np.square(list(d.values()))))) for d in (r.spread_before_db, r.spread_after_db))
        assert r.score_per_s == pytest.approx((1 / a**2 - 1 / b**2) / r.duration_s, rel=1e-9)
    scores = [r.score_per_s for r in by_info]
    assert scores == sorted(scores, reverse=True)
    assert sorted(r.name for r in by_info) == sorted(r.name for r in by_spread)
    # the same spreads: a longer manoeuvre weighs less against a short one by its spread's
    # reduction per second than by its information per second
    yaw1 = next(r for r in by_info if r.name == "yaw turn of A")
    yaw2 = next(r for r in by_info if r.name == "yaw turn of A by 720 deg")
    assert yaw2.score_per_s / yaw1.score_per_s > yaw2.reduction_db_per_s / yaw1.reduction_db_per_s


def test_a_long_manoeuvre_is_ranked_by_its_best_prefix_and_flown_only_to_it():
    """With ``prefixes``, a candidate's first quarters count too: its score is at least the whole
    manoeuvre's, the repeated second lap of a 720-deg turn is cut, and the cut candidate's
    predicted effect is that of its own unit scored whole (the rows it flies are the prefix's)."""
    from rplearn.analysis.manoeuvres import _score, start_posterior
    from rplearn.plan.prefix import PrefixUnit

    opts = _options(prefixes=1)
    normal = NormalEquations(SPEC.basis(), 2)
    whole = {r.name: r for r in rank_manoeuvres(normal, SPEC, NODES, POSES, opts)}
    cut = rank_manoeuvres(normal, SPEC, NODES, POSES, replace(opts, prefixes=4))
    assert [r.score_per_s for r in cut] == sorted((r.score_per_s for r in cut), reverse=True)
    prefixed = [r for r in cut if isinstance(r.candidate.unit, PrefixUnit)]
    assert prefixed and len(cut) == len(whole)
    for r in cut:
        name = r.name.split(", its first ")[0]
        assert r.score_per_s >= whole[name].score_per_s * (1 - 1e-12)
        assert (r.score_per_s > whole[name].score_per_s) == isinstance(r.candidate.unit, PrefixUnit)
    yaw2 = next(r for r in cut if r.name.startswith("yaw turn of A by 720 deg"))
    assert isinstance(yaw2.candidate.unit, PrefixUnit) and yaw2.duration_s < whole["yaw turn of A by 720 deg"].duration_s
    post = start_posterior(normal, SPEC, list(NODES), opts)
    for r in prefixed[:3]:
        again, (rows, _) = _score(post, r.candidate, list(NODES), SPEC.basis(), opts)  # its unit, whole
        assert again.duration_s == pytest.approx(r.duration_s)
        assert again.spread_after_db == pytest.approx(r.spread_after_db, rel=1e-9)
    with pytest.raises(InputError) as err:
        ManoeuvreOptions(prefixes=0)
    assert err.value.param == "prefixes"


def test_a_greedy_plan_of_prefixes_starts_each_step_where_the_last_one_was_cut():
    """A ground station and a drone: the plan's cut steps hand the next step the poses at their
    cut (position and heading of every node the next unit flies), and the plan's clock adds
    each step's lead and flown time (a prefix: its cut, not its whole unit's duration): the
    poses are followed along the units flown, not taken from the candidates' ``ends``."""
    from rplearn.plan.prefix import PrefixUnit

    poses = {"D": ((20.0, 0.0, 10.0), 180.0), "G": ((0.0, 0.0, 1.5), 0.0)}
    weight = prior_penalty_weight(SPEC.basis(), 3.0, 4.0, SPEC.ridge_weight)
    opts = ManoeuvreOptions(noise_std_db=4.0, penalty_weight=weight, target_points=256,
                            candidates=CandidateOptions(fixed_nodes=("G",), library=False), prefixes=4)
    steps = greedy_plan(NormalEquations(SPEC.basis(), 2), SPEC, ("D", "G"), poses, 60.0, 1.0, opts)
    assert any(isinstance(s.manoeuvre.candidate.unit, PrefixUnit) for s in steps)
    state, t = dict(poses), 0.0
    for s in steps:
        cand = s.manoeuvre.candidate
        start = cand.unit.evaluate(np.array([0.0]))
        for j, node in enumerate(cand.unit.nodes):
            assert start.position_enu_m[0, j] == pytest.approx(state[node][0], abs=1e-9), (s.manoeuvre.name, node)
            turn = np.angle(np.exp(1j * (start.yaw_rad[0, j] - np.radians(state[node][1]))))
            assert abs(turn) < 1e-9, (s.manoeuvre.name, node)
        if isinstance(cand.unit, PrefixUnit):
            assert cand.unit.cut_s < cand.unit.unit.duration_s and cand.unit.brake_s > 0.0  # cut on the move
            assert cand.unit.duration_s == cand.unit.cut_s + cand.unit.brake_s  # the plan's clock pays the braking
        t += cand.lead_s + cand.unit.duration_s
        assert s.end_s == pytest.approx(t)
        end = cand.unit.evaluate(np.array([cand.unit.duration_s]))  # where the unit flown leaves its nodes
        for j, node in enumerate(cand.unit.nodes):
            if node in cand.ends:
                assert cand.ends[node][0] == pytest.approx(tuple(end.position_enu_m[0, j]), abs=1e-9), (s.manoeuvre.name, node)
            state[node] = (tuple(end.position_enu_m[0, j]), float(np.degrees(end.yaw_rad[0, j])))
