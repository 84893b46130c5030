"""The continuous optimal design over candidate manoeuvres and the ranking at the anticipated end (issue 27, item 3)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rplearn.analysis import manoeuvres as mv
from rplearn.analysis.manoeuvre_bound import design_bound
from rplearn.analysis.manoeuvre_design import (
    BETA,
    SUPPORT_FRACTION,
    DesignProblem,
    criterion,
    criterion_gradient,
    design_order,
    design_problem,
    end_gradient_scores,
    node_variances,
    optimal_design,
    scored_design,
)
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.errors import InputError
from rplearn.models.spec import ModelSpec
from rplearn.plan.manoeuvres import CandidateOptions

SPEC = ModelSpec("sh", 4)
NODES = ["A", "B"]
POSES = {"A": ((-5.0, 0.0, 20.0), 0.0), "B": ((5.0, 0.0, 20.0), 0.0)}


def _two_directions(rate_a: float, rate_b: float, prior: float = 0.5, target_db: float = 1.0) -> DesignProblem:
    """Two nodes of one column each; candidate i teaches only node i, at ``rate`` per second."""
    info = np.zeros((2, 2, 2))
    info[0, 0, 0], info[1, 1, 1] = rate_a, rate_b
    return DesignProblem(np.eye(2) * prior, np.zeros((2, 2)), [np.eye(1), np.eye(1)], info, np.zeros_like(info),
                         np.array([10.0, 10.0]), np.array([0.0, 0.0]), target_db**2)


def test_two_candidates_one_direction_each_give_the_optimum_by_hand():
    """Node k's variance is 1 / (prior + rate_k t_k): each needs t_k = (1/T^2 - prior) / rate_k."""
    for target_db in (1.0, 0.5):
        problem = _two_directions(2.0, 0.5, target_db=target_db)
        need = 1.0 / target_db**2 - 0.5
        design = optimal_design(problem)
        assert design.times_s == pytest.approx([need / 2.0, need / 0.5], rel=6e-2)  # the smooth max trades a little
        # the smooth maximum is never above the largest variance (at most log(2) / BETA below it)
        assert design.total_s == pytest.approx(need / 2.0 + need / 0.5, rel=np.log(2.0) / BETA)
        assert design.spreads_db == pytest.approx([target_db, target_db], rel=2e-2)
        # the white-noise problem is convex: the gap certifies that no smaller total reaches it
        assert 0.8 * design.total_s <= design.certified_s <= need / 2.0 + need / 0.5


def test_a_target_already_met_needs_no_flight_and_an_unreachable_one_none():
    assert optimal_design(_two_directions(2.0, 0.5, target_db=2.0)).total_s == 0.0
    problem = _two_directions(2.0, 0.0)  # node B can never be taught
    assert optimal_design(problem, max_total_s=1e4).total_s == float("inf")


def test_the_gradient_is_the_criterion_s_derivative():
    problem = _two_directions(2.0, 0.5)
    t = np.array([0.3, 1.1])
    _, grad = criterion_gradient(problem, t)
    for i in range(2):
        e = np.zeros(2)
        e[i] = 1e-6
        assert grad[i] == pytest.approx((criterion(problem, t + e) - criterion(problem, t - e)) / 2e-6, rel=1e-4)


def _options(**kw):
    weight = mv.prior_penalty_weight(SPEC.basis(), 3.0, 4.0, SPEC.ridge_weight)
    cands = CandidateOptions(elevations_deg=(-30.0, 0.0, 30.0), library_loops=(1,))
    return mv.ManoeuvreOptions(noise_std_db=4.0, packet_rate_hz=20.0, penalty_weight=weight, candidates=cands, **kw)


def _scored(opts):
    post = mv.start_posterior(NormalEquations(SPEC.basis(), 2), SPEC, NODES, opts)
    return post, mv.scored_candidates(post, mv.latest_poses(POSES, NODES), NODES, SPEC.basis(), opts)


def test_a_candidate_flown_whole_gives_the_rank_k_update_s_spreads_with_the_drift():
    opts = _options(correlated_std_db=1.0)
    post, scored = _scored(opts)
    rows = [r for _, (r, _) in scored]
    problem = design_problem(post, rows, [c.candidate.unit.duration_s for c, _ in scored],
                             [c.candidate.lead_s for c, _ in scored], mv.packet_weight(opts), 2.0)
    assert np.any(problem.drift_information)
    for i in (0, len(scored) // 2, len(scored) - 1):
        t = np.zeros(len(scored))
        t[i] = scored[i][0].candidate.unit.duration_s
        after = post.spreads_after(scored[i][1][0], mv.packet_weight(opts), scored[i][1][1])
        assert np.sqrt(node_variances(problem, t)) == pytest.approx(after, rel=1e-9)
    white = design_problem(post, rows, [1.0] * len(rows), [0.0] * len(rows), mv.packet_weight(opts), 2.0, drift=False)
    assert not np.any(white.drift_information) and not np.any(white.drift_middle)


def test_the_bound_is_below_the_greedy_plan_s_time_and_its_design_reaches_the_target():
    opts = _options()
    bound = design_bound(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, 1.5, opts)
    plan = mv.greedy_plan(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, 600.0, 1.5, opts)
    assert max(plan[-1].spread_db.values()) <= 1.5
    assert 0.0 < bound.design.total_s < plan[-1].end_s
    assert np.all(bound.design.spreads_db <= 1.5 * (1 + 1e-3)) and np.max(bound.design.spreads_db) > 1.49
    assert bound.support() and bound.support()[0][1] >= bound.support()[-1][1]
    assert bound.spreads_now_db["A"] > 1.5


def test_the_end_ranking_orders_by_the_gradient_at_the_anticipated_final_posterior():
    opts = _options(floor_db=1.5)
    post, scored = _scored(opts)
    problem, design = scored_design(post, scored, mv.packet_weight(opts), 1.5, max_iter=mv.DESIGN_STEPS)
    scores = end_gradient_scores(problem, design)
    ranked = mv.rank_manoeuvres(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, replace(opts, design="end"))
    names = [r.name for r, _ in scored]
    assert [r.name for r in ranked] == [names[k] for k in np.argsort(-scores, kind="stable")]
    rate = mv.rank_manoeuvres(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, opts)
    assert [r.name for r in ranked] != [r.name for r in rate]  # it is another order than the rate's
    with pytest.raises(InputError) as err:
        replace(opts, design="final")
    assert err.value.param == "design"


def test_the_support_ranking_puts_what_the_optimal_design_flies_first_in_rate_order():
    opts = _options(floor_db=1.5)
    post, scored = _scored(opts)
    problem, design = scored_design(post, scored, mv.packet_weight(opts), 1.5, max_iter=mv.DESIGN_STEPS)
    share = design.times_s / problem.durations_s
    wanted = {r.name for (r, _), f in zip(scored, share) if f >= SUPPORT_FRACTION * np.max(share)}
    assert 0 < len(wanted) < len(scored)
    ranked = [r.name for r in mv.rank_manoeuvres(NormalEquations(SPEC.basis(), 2), SPEC, NODES, POSES, replace(opts, design="support"))]
    assert set(ranked[:len(wanted)]) == wanted
    rate = [r.name for r, _ in scored]
    assert ranked[:len(wanted)] == [n for n in rate if n in wanted]
    assert ranked[len(wanted):] == [n for n in rate if n not in wanted]
    with pytest.raises(InputError):
        design_order(post, scored, mv.packet_weight(opts), 1.5, "first")
