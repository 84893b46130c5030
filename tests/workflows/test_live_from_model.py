"""``rplearn live --from-model``: a young session ranks the next-best manoeuvres with an earlier
flight's noise, smoothing and drift (issue 27, item 3), its own once it has learned as many
samples as that fit; its fitted model is the same as without; the refusals are one line."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from simulated_flights import synced

from rplearn.analysis.manoeuvres import rank_manoeuvres
from rplearn.errors import InputError
from rplearn.models import ModelSpec, load_model
from rplearn.models.options import FitOptions
from rplearn.sim import simulate
from rplearn.workflows.calibration_plan import options_from_model
from rplearn.workflows.learning import fit_dataset
from rplearn.workflows.live import LiveOptions, _capped_note, replay_session
from rplearn.workflows.live_advice import ManoeuvreAdvisor, earlier_fit, live_advisor, ranking_options


@pytest.fixture(scope="module")
def earlier(tmp_path_factory):
    """``rplearn fit --order auto`` of an earlier flight (smoke preset, seed 5) written to a file."""
    path = str(tmp_path_factory.mktemp("earlier") / "earlier.json")
    fit_dataset(str(synced("smoke", 5).folder / "m.parquet"), ModelSpec.parse("sh"), options=FitOptions(auto=True), output=path)
    return path


@pytest.fixture(scope="module")
def sessions(earlier, tmp_path_factory):
    """The first 12 s of another flight (smoke, seed 0) learned live twice: ranked with the earlier
    model's hyper-parameters, and without a ranking: 4 s of log a poll, refitted (and ranked) at 12 s
    and at the end, so the given session's model is refitted after a ranking (was: a poll a second,
    a refit every 6 s, three rankings of ~165 candidates)."""
    r = simulate("smoke", seed=0)
    poses, signals = r.pose_log, r.signal_log.drop(columns=["unit"])
    advisor = live_advisor(every_s=0.0, from_model=earlier)
    calls = []

    def hook(stats, fitted, latest):
        rows = advisor(stats, fitted, latest)
        calls.append((stats, fitted, latest, rows))
        return rows

    d = tmp_path_factory.mktemp("live")
    given = replay_session(poses, signals, str(d / "given.json"),
                           LiveOptions(refit_s=12.0, duration_s=12.0, manoeuvres=hook, rank_beside=False), batch_s=4.0)
    plain = replay_session(poses, signals, str(d / "plain.json"), LiveOptions(refit_s=12.0, duration_s=12.0), batch_s=4.0)
    return advisor, calls, given, plain


def test_a_young_session_ranks_with_the_earlier_models_hyper_parameters(earlier, sessions):
    advisor, calls, _, _ = sessions
    t = load_model(earlier).training
    assert advisor.earlier is not None and advisor.earlier.n_samples == t.n_samples
    assert calls, "no ranking"
    stats, fitted, latest, rows = calls[-1]
    assert stats.n_samples < t.n_samples  # young: fewer samples than the earlier fit learned from
    expected = options_from_model(earlier, advisor.options, fitted.spec)
    assert expected.noise_std_db == pytest.approx(t.noise_std_db * np.sqrt(t.variance_inflation))
    assert expected.penalty_weight == t.planning_penalty_weight and expected.correlated_std_db == t.drift_std_db
    used = ranking_options(advisor.options, stats, fitted, advisor.earlier)
    for name in ("noise_std_db", "penalty_weight", "power", "correlated_std_db", "misfit_std_db", "prior_variance_factor"):
        assert getattr(used, name) == pytest.approx(getattr(expected, name)), name
    ranked = rank_manoeuvres(stats, fitted.spec, list(fitted.model.nodes), latest, expected, stats.blocks)
    assert [r[0] for r in rows] == [r.name for r in ranked]
    # not the session's own hyper-parameters: those rank otherwise
    own = ranking_options(advisor.options, stats, fitted)
    assert (own.noise_std_db, own.penalty_weight, own.correlated_std_db) != (used.noise_std_db, used.penalty_weight,
                                                                           used.correlated_std_db)
    # the view says so while the fit is at the search's largest smoothing
    assert "earlier.json's noise, smoothing and drift meanwhile" in _capped_note(advisor)


def test_the_sessions_own_take_over_from_as_many_samples_as_the_earlier_fit(sessions):
    advisor, calls, _, _ = sessions
    stats, fitted, _, _ = calls[-1]
    grown = replace(advisor.earlier, n_samples=stats.n_samples)  # the session has learned as many as that fit
    assert ranking_options(advisor.options, stats, fitted, grown) == ranking_options(advisor.options, stats, fitted)
    assert ranking_options(advisor.options, stats, fitted, replace(grown, n_samples=stats.n_samples + 1)) != \
        ranking_options(advisor.options, stats, fitted)
    assert f"until the session has learned {advisor.earlier.n_samples} samples" in advisor.earlier.text()
    # once it has, the view no longer says the earlier model's figures rank a capped fit
    grown_advisor = ManoeuvreAdvisor(advisor.options, 0.0, grown)
    grown_advisor(stats, fitted, calls[-1][2])
    assert not grown_advisor.young and "earlier.json" not in _capped_note(grown_advisor)


def test_the_sessions_model_is_learned_as_without_it(sessions):
    _, _, given, plain = sessions
    a, b = given.fitted.model, plain.fitted.model
    assert a.label == b.label and np.array_equal(a.coef, b.coef)
    assert np.array_equal(load_model(given.output).coef, load_model(plain.output).coef)


def _saved(model, path, **changes):
    out = load_model(model)
    out.training = out.training.replace(**changes)
    out.save(str(path))
    return str(path)


def test_each_refusal_is_one_line_naming_the_model_file(earlier, tmp_path):
    fixed = str(tmp_path / "sh4.json")
    fit_dataset(str(synced("smoke", 5).folder / "m.parquet"), ModelSpec("sh", 4), output=fixed)
    cases = [
        (str(tmp_path / "missing.json"), {}, "missing.json: no such"),
        (fixed, {}, "sh4.json is a fixed-order fit (SH-4)"),
        (_saved(earlier, tmp_path / "no_drift.json", drift_std_db=None), {}, "has no training.drift_std_db"),
        (_saved(earlier, tmp_path / "no_weight.json", planning_penalty_weight=None), {}, "has no training.planning_penalty_weight"),
        (_saved(earlier, tmp_path / "with_prior.json", prior={"A": "ref.json"}), {}, "was fitted with priors"),
        (earlier, {"spec": ModelSpec.parse("bg")}, "the session learns bg"),
        (_saved(earlier, tmp_path / "weight_big.json", planning_penalty_weight=1e300), {},
         "training.planning_penalty_weight is 1e+300"),
        (_saved(earlier, tmp_path / "at_cap.json", smoothing=1e6), {}, "training.smoothing is 1e+06, the largest"),
    ]
    for model, kw, text in cases:
        with pytest.raises(InputError) as err:
            earlier_fit(model, kw.get("spec"))
        message = str(err.value)
        assert err.value.param == "from_model" and message.startswith("from_model: ") and "\n" not in message
        assert text in message, (text, message)
        assert "--drift" not in message and "--noise" not in message and "--prior-std" not in message  # live has none
    assert ManoeuvreAdvisor().earlier is None


def test_each_earlier_fit_of_other_nodes_or_band_is_refused_when_the_session_says_them(earlier, tmp_path):
    """--nodes and a MAVLink --frequency are known before the session: refused then, one line naming the file and field."""
    cases = [
        ({"nodes": ("A", "gcs")}, "learned the nodes A, B (its model's nodes), the session learns A, gcs: gcs not among them"),
        ({"frequency_hz": 433e6}, "learned at 2.412 GHz (training.frequency_hz), the session's rows are at 433 MHz"),
        ({}, None),
        ({"nodes": ("A",), "frequency_hz": 2.45e9}, None),  # a subset of its nodes, the same band
    ]
    for kw, text in cases:
        if text is None:
            assert earlier_fit(earlier, None, **kw).nodes == ("A", "B")
            continue
        with pytest.raises(InputError) as err:
            earlier_fit(earlier, None, **kw)
        assert err.value.param == "from_model" and text in str(err.value) and "\n" not in str(err.value)


def test_a_session_of_other_nodes_or_band_ranks_with_its_own(sessions):
    """Learned only once rows arrive: the advisor ranks with the session's own hyper-parameters and says why
    (was: the earlier model's, of other antennas or another band, silently)."""
    advisor, calls, _, _ = sessions
    stats, fitted, latest, _ = calls[-1]
    assert advisor.mismatch(fitted) is None
    own = ManoeuvreAdvisor(advisor.options, 0.0)(stats, fitted, latest)  # the session's own ranking, once
    for changed, text in ((replace(advisor.earlier, nodes=("X", "Y")), "the session learns A, B: A, B not among them"),
                          (replace(advisor.earlier, frequency_hz=433e6), "learned at 433 MHz (training.frequency_hz)")):
        other = ManoeuvreAdvisor(advisor.options, 0.0, changed)
        why = other.mismatch(fitted)
        assert why is not None and text in why and why.startswith(changed.path)
        assert other(stats, fitted, latest) == own
        assert not other.young and changed.path not in _capped_note(other)
