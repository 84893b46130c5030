"""rplearn.workflows.live_advice: the live session's next-best manoeuvres are
:func:`rplearn.analysis.manoeuvres.rank_manoeuvres` on the session's own statistics."""

from __future__ import annotations

import copy
import math
from dataclasses import replace

import pytest

from rplearn.analysis.manoeuvres import ManoeuvreOptions, rank_manoeuvres
from rplearn.errors import InputError
from rplearn.models.spec import ModelSpec
from rplearn.sim import simulate
from rplearn.workflows.live import LiveOptions, replay_session
from rplearn.workflows.live_advice import ManoeuvreAdvisor, live_advisor


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """A fixed-order SH-6 session on the smoke flight (75 s), with an advisor that ranks at every
    refit (every 40 s: two rankings of some 300 candidates each, at 40 s and after the last
    refit, not one every 5 s; the tests read the last). Replayed 5 s of log at a time (a batch a
    second made 75 polls; what is learned and when it is refitted are the same)."""
    r = simulate("smoke", seed=0)
    calls = []
    advisor = ManoeuvreAdvisor(every_s=0.0)

    def hook(stats, fitted, latest):
        rows = advisor(stats, fitted, latest)
        calls.append((stats, fitted, latest, rows))
        return rows

    options = LiveOptions(spec=ModelSpec.parse("sh", order=6), refit_s=40.0, manoeuvres=hook)
    path = str(tmp_path_factory.mktemp("live") / "m.json")
    outcome = replay_session(r.pose_log, r.signal_log.drop(columns=["unit"]), path, options, batch_s=5.0)
    return outcome, calls


def test_the_session_shows_the_rankers_best_three(session):
    outcome, calls = session
    assert len(calls) == 2, "the hook was not called at both refits"
    stats, fitted, latest, rows = calls[-1]
    training = fitted.model.training
    noise = float(training.noise_std_db or training.rmse_db) * math.sqrt(training.variance_inflation or 1.0)
    ranked = rank_manoeuvres(stats, fitted.spec, list(fitted.model.nodes), latest, ManoeuvreOptions(noise_std_db=noise))
    assert [r[0] for r in rows] == [r.name for r in ranked]  # best first: the largest reduction per second
    assert outcome.status.manoeuvres == rows[:3]
    for name, duration_s, spread_db in rows[:3]:
        assert duration_s > 0 and math.isfinite(spread_db) and spread_db > 0
    before = max(ranked[0].spread_before_db.values())
    assert rows[0][2] < before  # the best manoeuvre lowers the worst node's spread


def test_between_rankings_the_last_one_is_shown(session):
    _, calls = session
    stats, fitted, latest, _ = calls[-1]
    advisor = ManoeuvreAdvisor(every_s=3600.0)
    first = advisor(stats, fitted, latest)
    assert advisor(stats, fitted, latest) is first


def test_the_cli_advisor_holds_the_station_still_and_checks_its_period():
    advisor = live_advisor(("gcs",), 10.0, 2.0)
    assert advisor.options.candidates.fixed_nodes == ("gcs",) and advisor.options.floor_db == 2.0
    with pytest.raises(InputError, match="every_s"):
        ManoeuvreAdvisor(every_s=float("nan"))


@pytest.fixture(scope="module")
def capped_refit(tmp_path_factory):
    """The first refit of a live session on the ground preset (2 s, 300 samples): ``--order auto``
    takes SH-2 at the search's largest smoothing."""
    r = simulate("ground", seed=0)
    calls = []

    def hook(stats, fitted, latest):
        calls.append((stats, fitted, latest))
        return []

    path = str(tmp_path_factory.mktemp("live") / "m.json")
    replay_session(r.pose_log, r.signal_log.drop(columns=["unit"]), path,
                   LiveOptions(refit_s=2.0, duration_s=2.5, manoeuvres=hook, rank_beside=False))
    return calls[0]


def test_a_fit_at_the_largest_smoothing_is_ranked_under_the_nominal_prior(capped_refit):
    from rplearn.analysis.manoeuvre_prior import NOMINAL_PRIOR_STD_DB, prior_penalty_weight
    from rplearn.core.lsq.selection import at_smoothing_cap
    from rplearn.plan.manoeuvres import CandidateOptions
    from rplearn.workflows.live_advice import ranking_options

    stats, fitted, latest = capped_refit
    assert at_smoothing_cap(fitted.spec.smoothing)
    noise = ranking_options(ManoeuvreOptions(), stats, fitted).noise_std_db
    base = ManoeuvreOptions(candidates=CandidateOptions(fixed_nodes=("G",)))
    nodes = list(fitted.model.nodes)
    # under the fit's own posterior every candidate scores alike: its order is arbitrary
    own = rank_manoeuvres(stats, fitted.spec, nodes, latest, replace(base, noise_std_db=noise), stats.blocks)
    after = [max(r.spread_after_db.values()) for r in own]
    assert max(after) - min(after) < 1e-4 and max(own[0].spread_before_db.values()) < 0.01
    # the advisor ranks under the smoothness prior trajectory --optimize plans with, and the candidates differ
    rows = ManoeuvreAdvisor(base, every_s=0.0)(stats, fitted, latest)
    weight = prior_penalty_weight(stats.basis, NOMINAL_PRIOR_STD_DB, noise, float(fitted.spec.ridge_weight), base.power)
    nominal = rank_manoeuvres(stats, fitted.spec, nodes, latest, replace(base, noise_std_db=noise, penalty_weight=weight),
                              stats.blocks)
    assert [r[0] for r in rows] == [r.name for r in nominal]
    assert ranking_options(base, stats, fitted).penalty_weight == weight
    after = [r[2] for r in rows]
    assert max(after) - min(after) > 0.1
    assert 3.0 < max(nominal[0].spread_before_db.values()) <= NOMINAL_PRIOR_STD_DB + 0.1
    # a penalty the caller gives is kept
    assert ranking_options(replace(base, penalty_weight=1.0), stats, fitted).penalty_weight == 1.0


def test_a_fit_below_the_cap_is_ranked_under_its_own_smoothing(session):
    from rplearn.workflows.live_advice import ranking_options

    _, calls = session
    stats, fitted, _, _ = calls[-1]
    options = ranking_options(ManoeuvreOptions(), stats, fitted)
    assert options.penalty_weight is None
    # the noise the model's covariance is read with: the fit's, times its variance inflation
    training = fitted.model.training
    assert options.noise_std_db == pytest.approx(float(training.noise_std_db) * math.sqrt(training.variance_inflation or 1.0))
    inflated = copy.copy(fitted.model)
    inflated.training = training.replace(variance_inflation=4.0)
    options = ranking_options(ManoeuvreOptions(), stats, replace(fitted, model=inflated))
    assert options.noise_std_db == pytest.approx(2.0 * float(training.noise_std_db))


def test_the_view_says_a_capped_fit_is_ranked_under_the_nominal_prior():
    from rplearn.workflows.live import _capped_note

    assert "manoeuvres are ranked under a 6-dB smoothness prior meanwhile" in _capped_note(live_advisor())
    assert "smoothness prior" not in _capped_note(lambda *a: [])  # another hook ranks as it will
    assert _capped_note(None).startswith("not known yet: the fit took the largest smoothing")


def test_the_capped_note_names_the_nominal_prior_only_when_the_advisor_ranks_under_it():
    # an advisor given its own penalty weight keeps it (ranking_options): the note must not claim the 6-dB prior
    from rplearn.workflows.live import _capped_note

    assert "6-dB smoothness prior" in _capped_note(ManoeuvreAdvisor(ManoeuvreOptions()))
    assert "prior" not in _capped_note(ManoeuvreAdvisor(ManoeuvreOptions(penalty_weight=1.0)))
    assert "prior" not in _capped_note(lambda *a: [])
