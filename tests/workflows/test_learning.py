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
