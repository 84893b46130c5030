"""Where each node's posterior is widest (rplearn.analysis.manoeuvre_aimed) and the ranking's aimed candidates."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from test_manoeuvres import NODES, POSES, SPEC  # the same small problem as the ranking's tests
from test_manoeuvres import _options as _ranking_options

from rplearn.analysis.manoeuvre_aimed import AIM_SEPARATION_DEG, pointwise_variances, target_directions, widest_directions
from rplearn.analysis.manoeuvre_posterior import ManoeuvrePosterior
from rplearn.analysis.manoeuvres import manoeuvre_rows, rank_manoeuvres, target_metrics
from rplearn.core.geometry import great_circle_angle
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.errors import InputError
from rplearn.plan.manoeuvres import ManoeuvreUnit


def _options(**kw):
    return _ranking_options(target_points=512, **kw)


def _after_a_level_turn(opts):
    """The prior's posterior after A turned a full circle in front of B at the same height."""
    basis = SPEC.basis()
    prior = np.full(2 * basis.n_coef, float(SPEC.ridge_weight)) + float(opts.penalty_weight) * np.tile(basis.roughness(opts.power), 2)
    post = ManoeuvrePosterior(np.diag(prior) / opts.noise_std_db**2, target_metrics(basis, NODES, opts), opts.noise_std_db**2)
    post = post.with_drift(0.5**2, None, 20)
    unit = ManoeuvreUnit(nodes=("B", "A"), kind="yaw", anchor_enu_m=POSES["B"][0], start_enu_m=POSES["A"][0])
    post.update(manoeuvre_rows(unit, NODES, basis, opts.sample_rate_hz), 2.0 * opts.packet_rate_hz / opts.sample_rate_hz)
    return post


def test_the_pointwise_variances_average_to_the_squared_spread():
    opts = _options()
    post = _after_a_level_turn(opts)
    dirs = target_directions(NODES, opts.target_points, opts.target_el_deg, None)
    var = pointwise_variances(post, SPEC.basis(), dirs)
    assert np.allclose([v.mean() for v in var], post.spreads() ** 2, rtol=1e-9)
    assert post.drift.shape[1] > 0  # the drifting part is counted too


def test_after_a_level_turn_a_node_s_widest_directions_are_off_its_equator_and_apart():
    opts = _options()
    post = _after_a_level_turn(opts)
    dirs = target_directions(NODES, opts.target_points, opts.target_el_deg, None)
    aims = widest_directions(post, SPEC.basis(), NODES, dirs, 3)
    var = pointwise_variances(post, SPEC.basis(), dirs)[0]
    assert len(aims["A"]) == 3 and float(np.max(var)) > 2.0 * float(np.min(var))
    (az0, el0) = aims["A"][0]
    assert abs(np.degrees(el0)) > 30.0  # the turn taught the ring at el 0
    k = int(np.argmin(great_circle_angle(dirs[0][0], dirs[0][1], az0, el0)))
    assert var[k] == pytest.approx(float(np.max(var)))
    for i, a in enumerate(aims["A"]):
        for b in aims["A"][:i]:
            assert np.degrees(great_circle_angle(a[0], a[1], b[0], b[1])) >= AIM_SEPARATION_DEG - 1e-9


def test_the_ranking_offers_aimed_candidates_only_when_asked():
    normal = NormalEquations(SPEC.basis(), 2)
    plain = rank_manoeuvres(normal, SPEC, NODES, POSES, _options())
    aimed = rank_manoeuvres(normal, SPEC, NODES, POSES, _options(aimed=2))
    assert not any("aimed at" in r.name for r in plain)
    extra = [r for r in aimed if "aimed at" in r.name]
    assert extra and len(aimed) == len(plain) + len(extra)
    assert {r.name.split("aimed at ")[1][0] for r in extra} == {"A", "B"}
    rates = [r.score_per_s for r in aimed]
    assert rates == sorted(rates, reverse=True)
    with pytest.raises(InputError) as err:
        replace(_options(), aimed=1.5)
    assert err.value.param == "aimed"
