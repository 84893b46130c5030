"""The ranking's feature rows computed in batches: the same as one unit at a time, unit by unit."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rplearn.analysis import manoeuvre_rows as mr
from rplearn.analysis import manoeuvres as mv
from rplearn.errors import InputError
from rplearn.models.spec import ModelSpec
from rplearn.plan.manoeuvres import CandidateOptions, candidate_manoeuvres

SPEC = ModelSpec("sh", 4)
NODES = ["A", "B"]
POSES = {"A": ((-5.0, 0.0, 20.0), 0.0), "B": ((5.0, 0.0, 20.0), 40.0)}
LEAN = ((1.5, -0.5, 0.0), ("A",))


def _options(**kw):
    cands = CandidateOptions(elevations_deg=(-30.0, 0.0, 30.0), library_loops=(1,))
    return mv.ManoeuvreOptions(noise_std_db=4.0, packet_rate_hz=20.0, candidates=cands, correlated_std_db=1.0, **kw)


def _units():
    units = [c.unit for c in candidate_manoeuvres(mv.latest_poses(POSES, NODES), _options().candidates)]
    sizes = {u.sample(4.0).t_s.size for u in units}
    assert len(units) > 10 and len(sizes) > 3  # units of different lengths, so a shifted cut shows
    return units


@pytest.mark.parametrize("batch", [50, 400, mr.BATCH_SAMPLES])
@pytest.mark.parametrize("steady", [None, LEAN])
def test_batched_rows_equal_each_unit_s_own(monkeypatch, batch, steady):
    monkeypatch.setattr(mr, "BATCH_SAMPLES", batch)  # batches ending inside and between units
    units = _units()
    got = list(mr.batch_rows_and_ends(units, NODES, SPEC.basis(), 4.0, steady))
    assert len(got) == len(units)
    for unit, (rows, ends) in zip(units, got):
        ref_rows, ref_ends = mr.rows_and_ends(unit, NODES, SPEC.basis(), 4.0, steady)
        assert np.array_equal(rows, ref_rows), unit.label  # to the bit
        for end, ref_end in zip(ends, ref_ends, strict=True):
            assert all(np.array_equal(a, b) for a, b in zip(end, ref_end, strict=True)), unit.label


def test_a_unit_naming_another_node_is_refused_in_a_batch():
    units = _units()
    units[3] = replace(units[3], nodes=("A", "C"))
    with pytest.raises(InputError, match="node\\(s\\) C not in the statistics' nodes"):
        list(mr.batch_rows_and_ends(units, NODES, SPEC.basis(), 4.0))


@pytest.mark.parametrize("prefixes", [1, 3])
def test_batched_ranking_equals_scoring_each_candidate_alone(prefixes):
    """scored_candidates (rows in batches, the spreads before once) against a straightforward
    reference: each candidate scored on its own with its own rows."""
    from rplearn.analysis.manoeuvres import _score
    from rplearn.core.lsq.normal_equations import NormalEquations

    opts = replace(_options(prefixes=prefixes), steady_accel_enu_m_s2=(1.5, -0.5, 0.0))
    normal = NormalEquations(SPEC.basis(), 2)
    post = mv.start_posterior(normal, SPEC, NODES, opts)
    state = mv.latest_poses(POSES, NODES)
    got = mv.scored_candidates(post, state, NODES, SPEC.basis(), opts)
    ref = sorted((_score(post, c, NODES, SPEC.basis(), opts) for c in candidate_manoeuvres(state, opts.candidates)),
                 key=lambda s: -s[0].score_per_s)
    assert [r.name for r, _ in got] == [r.name for r, _ in ref]
    for (r, (rows, _)), (r0, (rows0, _)) in zip(got, ref, strict=True):
        assert (r.score_per_s, r.reduction_db_per_s, r.spread_after_db) == (r0.score_per_s, r0.reduction_db_per_s, r0.spread_after_db)
        assert np.array_equal(rows, rows0)


def test_known_rows_are_reused_for_equal_units_and_replaced_each_call():
    units = _units()
    known: dict = {}
    first = mr.known_rows_and_ends(units[:6], NODES, SPEC.basis(), 4.0, None, known)
    assert list(known) == units[:6]
    second = mr.known_rows_and_ends(units[3:9], NODES, SPEC.basis(), 4.0, None, known)
    assert all(a is b for a, b in zip(first[3:6], second[:3]))  # the same arrays, not computed again
    assert list(known) == units[3:9]  # only the last call's
    for unit, (rows, _) in zip(units[3:9], second):
        assert np.array_equal(rows, mr.rows_and_ends(unit, NODES, SPEC.basis(), 4.0)[0])


def test_greedy_plan_with_the_last_step_s_rows_equals_computing_them_each_step(monkeypatch):
    from rplearn.core.lsq.normal_equations import NormalEquations

    opts, poses, hits = _options(), {"A": ((-5.0, 0.0, 20.0), 0.0), "B": ((5.0, 0.0, 20.0), 0.0)}, []
    real = mr.known_rows_and_ends

    def counted(units, nodes, basis, rate_hz, steady, known):
        hits.append(sum(u in known for u in units))
        return real(units, nodes, basis, rate_hz, steady, known)

    monkeypatch.setattr(mv, "known_rows_and_ends", counted)
    plan = mv.greedy_plan(NormalEquations(SPEC.basis(), 2), SPEC, NODES, poses, 300.0, 1.5, opts)
    assert max(hits) > 0  # a step offered units of the step before

    def fresh_each_step(units, nodes, basis, rate_hz, steady, known):
        return list(mr.batch_rows_and_ends(units, nodes, basis, rate_hz, steady))

    monkeypatch.setattr(mv, "known_rows_and_ends", fresh_each_step)
    again = mv.greedy_plan(NormalEquations(SPEC.basis(), 2), SPEC, NODES, poses, 300.0, 1.5, opts)
    assert len(plan) >= 3 and [s.manoeuvre.name for s in plan] == [s.manoeuvre.name for s in again]
    assert [(s.end_s, s.spread_db, s.manoeuvre.score_per_s) for s in plan] == [(s.end_s, s.spread_db, s.manoeuvre.score_per_s) for s in again]
