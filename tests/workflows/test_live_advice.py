"""rplearn.workflows.live_advice: the live session's next-best manoeuvres are
:func:`rplearn.analysis.manoeuvres.rank_manoeuvres` on the session's own statistics."""

from __future__ import annotations

import math

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
    refit, not one every 5 s; the tests read the last)."""
    r = simulate("smoke", seed=0)
    calls = []
    advisor = ManoeuvreAdvisor(every_s=0.0)

    def hook(stats, fitted, latest):
        rows = advisor(stats, fitted, latest)
        calls.append((stats, fitted, latest, rows))
        return rows

    options = LiveOptions(spec=ModelSpec.parse("sh", order=6), refit_s=40.0, manoeuvres=hook)
    path = str(tmp_path_factory.mktemp("live") / "m.json")
    outcome = replay_session(r.pose_log, r.signal_log.drop(columns=["unit"]), path, options)
    return outcome, calls


def test_the_session_shows_the_rankers_best_three(session):
    outcome, calls = session
    assert len(calls) == 2, "the hook was not called at both refits"
    stats, fitted, latest, rows = calls[-1]
    ranked = rank_manoeuvres(stats, fitted.spec, list(fitted.model.nodes), latest,
                             ManoeuvreOptions(noise_std_db=float(fitted.model.training.noise_std_db
                                                                  or fitted.model.training.rmse_db)))
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
