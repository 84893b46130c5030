"""Learning workflows on datasets without trajectory units (a telemetry log) and with models the
data cannot identify."""

from __future__ import annotations

import pytest

from rplearn.errors import InputError
from rplearn.workflows.learning import learn_and_report, sweep_dataset


@pytest.fixture(scope="module")
def no_units(tmp_path_factory):
    from rplearn.sim.flight import simulate

    path = tmp_path_factory.mktemp("nounits") / "flight.parquet"
    simulate("smoke", seed=2).matched_truth.drop(columns=["unit"]).to_parquet(path)
    return str(path)


def test_report_cuts_a_flight_by_time_and_goes_on_without_a_model_it_cannot_learn(no_units, tmp_path):
    out = learn_and_report(no_units, ["m", "nn-100000", "sh-3"], str(tmp_path / "rep"))
    assert [r.model for r in out.rows] == ["M", "SH-3"]
    assert out.test_units == ["test[5/5]"] and len(out.learn_units) == 4
    assert "has no 'unit' column" in out.notes[0]
    assert out.notes[1].startswith("NN-100000 not learned:") and "100000" in out.notes[1]
    html = (tmp_path / "rep" / "report.html").read_text(encoding="utf-8")
    assert "NN-100000 not learned" in html and "Notes" in html
    # the labels the note names can be chosen by hand
    again = learn_and_report(no_units, ["m"], str(tmp_path / "rep2"), test_units=["flight[1/5]"])
    assert again.test_units == ["flight[1/5]"] and "test[5/5]" in again.learn_units


def test_report_fails_whole_when_no_model_can_be_learned(no_units, tmp_path):
    with pytest.raises(InputError, match="none of the models could be learned") as err:
        learn_and_report(no_units, ["nn-100000"], str(tmp_path / "rep"))
    assert "no 'unit' column" not in str(err.value) and err.value.param == "models"
    assert not (tmp_path / "rep").exists()


def test_sweep_says_how_it_split_a_flight_without_units(no_units):
    result = sweep_dataset(no_units, "sh", [2, 3])
    assert result.orders == [2, 3] and len(result.notes) == 1 and "stretches of time" in result.notes[0]


@pytest.mark.parametrize("baseline", ["m", "nn-5"])
def test_a_baseline_with_an_environment_term_is_refused_once_by_fit_model(no_units, baseline, monkeypatch):
    """The one check that baselines learn no environment term is fit_model's: fit_dataset passes
    the terms on and says the same (issue 25: it was checked twice)."""
    from rplearn.core.environment import PathLoss
    from rplearn.models import fit as fit_module
    from rplearn.models.spec import ModelSpec
    from rplearn.workflows.learning import fit_dataset

    calls = []
    real = fit_module.fit_model
    monkeypatch.setattr("rplearn.workflows.learning.fit_model", lambda *a, **k: (calls.append(k), real(*a, **k))[1])
    with pytest.raises(InputError, match="learn no environment term") as err:
        fit_dataset(no_units, ModelSpec.parse(baseline), path_loss=PathLoss("log-distance"))
    assert err.value.param == "path_loss" and calls and calls[0]["path_loss"].kind == "log-distance"
    with pytest.raises(InputError, match="learn no environment term"):
        real(*_samples(no_units), ModelSpec.parse(baseline), path_loss=PathLoss("two-ray"))
    assert fit_dataset(no_units, ModelSpec.parse(baseline)).fitted.model.kind != "patterns"  # free space: learned


def _samples(path):
    import pandas as pd

    from rplearn.data.units import samples_of

    return (samples_of(pd.read_parquet(path)),)
