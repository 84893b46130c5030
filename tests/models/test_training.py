"""The typed training summary, and model files written before it was typed.

``tests/fixtures/models_main`` holds an automatic SH fit (order and smoothing chosen, link
offsets, spreads, coverage grids, decoupling certificate) and a mean model, written by
``rplearn fit`` at commit 3b94a97 (before :class:`TrainingSummary`), a dataset of poses (every
10th row of the smoke preset, seed 5) and the predictions ``rplearn predict`` wrote for it
with each model then.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from model_file_checks import assert_predicts_as_stored, stored_samples

from rplearn.errors import InputError
from rplearn.models.load import load_model
from rplearn.models.training import TrainingSummary

DATA = Path(__file__).resolve().parents[1] / "fixtures" / "models_main"


@pytest.fixture(scope="module")
def samples():
    return stored_samples(DATA)


def _stored_training(name: str) -> dict:
    return json.loads((DATA / name).read_text())["model"]["training"]


@pytest.mark.parametrize("model_file, predictions", [("auto.json", "pred_auto.csv"), ("mean.json", "pred_mean.csv")])
def test_model_files_of_main_load_typed_and_predict_identically(samples, model_file, predictions):
    model = load_model(DATA / model_file)
    assert isinstance(model.training, TrainingSummary)
    assert_predicts_as_stored(model, samples, DATA / predictions)
    # every entry read into a typed field (none left over), and written back as it was
    stored = _stored_training(model_file)
    assert model.training.extra == {}
    assert model.training.to_dict() == stored


def test_typed_fields_of_an_automatic_fit():
    t = load_model(DATA / "auto.json").training
    stored = _stored_training("auto.json")
    assert (t.rank, t.n_columns, t.n_samples) == (stored["rank"], stored["n_columns"], stored["n_samples"])
    assert t.selection["order"] == 4 and t.smoothing == pytest.approx(stored["smoothing"])
    assert set(t.prior_std_db) == {"A", "B"} and set(t.coverage_deg) == {"A", "B"}
    assert isinstance(t.gauges, tuple) and t.gauges[0]["rule"] == "equal-mean"
    assert [o["tx"] + o["rx"] for o in t.link_offsets_db] == ["AB", "BA"]
    assert "summary" in t.decoupling
    # the former dictionary reads still work (the README's example reads training["rank"])
    assert t["rank"] == t.rank and t.get("ltd_s") == t.ltd_s and "selection" in t and "reference" not in t
    with pytest.raises(KeyError):
        t["reference"]


def test_unknown_entries_are_kept_and_a_summary_is_frozen():
    t = TrainingSummary.from_dict({"rank": 3, "from_the_future": {"x": 1}, "warnings": ["w"]})
    assert t.rank == 3 and t.warnings == ("w",) and t.extra == {"from_the_future": {"x": 1}}
    assert t.to_dict() == {"rank": 3, "warnings": ["w"], "from_the_future": {"x": 1}}
    later = t.replace(ltd_s=0.5, also_new=2)
    assert later.ltd_s == 0.5 and later.extra == {"from_the_future": {"x": 1}, "also_new": 2} and t.ltd_s is None
    with pytest.raises(AttributeError):
        t.rank = 4  # type: ignore[misc]
    with pytest.raises(TypeError):
        t["rank"] = 4  # type: ignore[index]
    assert TrainingSummary.from_dict(t) is t and TrainingSummary.from_dict(None) == TrainingSummary()
    assert TrainingSummary.from_dict(t.to_dict()) == t


def test_a_training_entry_that_is_not_an_object_is_refused():
    with pytest.raises(InputError, match="training") as info:
        TrainingSummary.from_dict(["rank", 3])  # type: ignore[arg-type]
    assert info.value.param == "training"


def test_save_and_load_keep_the_summary(tmp_path, samples):
    model = load_model(DATA / "auto.json")
    model.save(tmp_path / "again.json")
    again = load_model(tmp_path / "again.json")
    assert again.training == model.training
    np.testing.assert_allclose(again.predict_gain(samples), model.predict_gain(samples), rtol=0, atol=0)
