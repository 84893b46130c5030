"""The look-ahead ranking: the best candidates by rate ordered again by their estimated time to the target spread."""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest
from test_manoeuvres import NODES, POSES, SPEC, _options  # the same small problem as the ranking's tests

from rplearn.analysis.manoeuvre_lookahead import information_deficit, information_rate, reach_fraction, time_to_target_s
from rplearn.analysis.manoeuvres import ManoeuvreOptions, greedy_plan, rank_manoeuvres
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.errors import InputError


def test_the_deficit_is_the_missing_inverse_square_and_a_candidate_reaching_the_target_stops_where_it_does():
    assert information_deficit(2.0, 2.0) == 0.0 and information_deficit(1.5, 2.0) == 0.0
    assert information_deficit(4.0, 2.0) == pytest.approx(1 / 4 - 1 / 16)
    assert information_rate(4.0, 2.0, 10.0) == pytest.approx((1 / 4 - 1 / 16) / 10.0)
    assert time_to_target_s(12.0, 0.0, 0.0) == 12.0
    assert time_to_target_s(12.0, 0.1, 0.01) == pytest.approx(22.0)
    assert time_to_target_s(12.0, 0.1, 0.0) == float("inf")
    # the slower node sets the fraction: B reaches the target only at the end, A about a sixth of the way
    assert reach_fraction(np.array([3.0, 2.5]), np.array([1.0, 2.0]), 2.0) == pytest.approx(1.0)
    assert reach_fraction(np.array([3.0, 2.5]), np.array([1.0, 1.0]), 2.0) == pytest.approx((1 / 4 - 1 / 9) / (1 - 1 / 9))
    assert reach_fraction(np.array([1.5, 1.8]), np.array([1.4, 1.7]), 2.0) == 0.0  # already there
    assert reach_fraction(np.array([3.0, 2.5]), np.array([1.0, 2.2]), 2.0) == float("inf")  # B left above it


def test_the_best_few_by_rate_are_reordered_by_their_time_to_the_target_and_the_rest_kept():
    normal = NormalEquations(SPEC.basis(), 2)
    opts = _options(floor_db=1.6)
    by_rate = rank_manoeuvres(normal, SPEC, NODES, POSES, opts)
    ahead = rank_manoeuvres(normal, SPEC, NODES, POSES, replace(opts, lookahead=3))
    assert all(r.time_to_target_s is None for r in by_rate)
    head, rest = ahead[:3], ahead[3:]
    assert sorted(r.name for r in head) == sorted(r.name for r in by_rate[:3])
    assert [r.name for r in rest] == [r.name for r in by_rate[3:]] and all(r.time_to_target_s is None for r in rest)
    times = [r.time_to_target_s for r in head]
    assert times == sorted(times)
    # the estimate of each: its time, then the deficit it leaves over the best rate from where it ends
    from rplearn.analysis.manoeuvres import _aggregate, packet_weight, scored_candidates, start_posterior

    post = start_posterior(normal, SPEC, list(NODES), opts)
    scored = {r.name: rows for r, rows in scored_candidates(post, dict(POSES), list(NODES), SPEC.basis(), opts)}
    for r in head:
        after = copy.copy(post)
        after.update(scored[r.name][0], packet_weight(opts), scored[r.name][1])
        assert _aggregate(after.spreads(), opts) == pytest.approx(_aggregate(np.array(list(r.spread_after_db.values())), opts))
        deficit = information_deficit(_aggregate(after.spreads(), opts), 1.6)
        if deficit == 0.0:  # it reaches the target: at the fraction of its own time where it does
            frac = reach_fraction(np.array(list(r.spread_before_db.values())), np.array(list(r.spread_after_db.values())), 1.6)
            assert 0.0 < frac <= 1.0
            assert r.time_to_target_s == pytest.approx(r.candidate.lead_s + frac * (r.duration_s - r.candidate.lead_s), rel=1e-6)
            continue
        nxt = scored_candidates(after, {**POSES, **r.candidate.ends}, list(NODES), SPEC.basis(), opts)
        best = max(information_rate(_aggregate(np.array(list(n.spread_before_db.values())), opts),
                                    _aggregate(np.array(list(n.spread_after_db.values())), opts), n.duration_s) for n, _ in nxt)
        assert r.time_to_target_s == pytest.approx(time_to_target_s(r.duration_s, deficit, best), rel=1e-9)
        assert r.time_to_target_s > r.duration_s
    # without a target there is no time to it: the rate alone
    assert [r.name for r in rank_manoeuvres(normal, SPEC, NODES, POSES, _options(lookahead=3))] == \
        [r.name for r in rank_manoeuvres(normal, SPEC, NODES, POSES, _options())]
    with pytest.raises(InputError) as err:
        ManoeuvreOptions(lookahead=-1)
    assert err.value.param == "lookahead"


def test_the_greedy_plan_looks_ahead_at_every_step():
    """Each step of a look-ahead plan is the candidate with the shortest estimated time to the
    target among the best few by rate from where the last step ended; the plan reaches the
    target, and its last step reaches it within its own time."""
    opts = _options(lookahead=3)
    steps = greedy_plan(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, 400.0, 1.6, opts)
    assert steps and max(steps[-1].spread_db.values()) <= 1.6
    assert all(s.manoeuvre.time_to_target_s is not None for s in steps)
    assert 0.0 < steps[-1].manoeuvre.time_to_target_s <= steps[-1].manoeuvre.duration_s
    plain = greedy_plan(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, 400.0, 1.6, replace(opts, lookahead=0))
    assert all(s.manoeuvre.time_to_target_s is None for s in plain)
