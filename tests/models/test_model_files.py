"""Model files written before the restructuring still load and predict identically.

``tests/fixtures/models_v1`` holds an SH-5 and a mean model written by ``rplearn fit``, a dataset
of poses, and the predictions ``rplearn predict`` wrote for it with each model then.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from model_file_checks import assert_predicts_as_stored, stored_samples

from rplearn.models.base import Model, model_frequency_hz
from rplearn.models.load import load_model

DATA = Path(__file__).resolve().parents[1] / "fixtures" / "models_v1"


@pytest.fixture(scope="module")
def samples():
    return stored_samples(DATA)


@pytest.mark.parametrize(
    "model_file, predictions, kind, label",
    [("sh5.json", "pred_sh5.csv", "patterns", "SH-5"), ("mean.json", "pred_mean.csv", "mean", "M")],
)
def test_v1_model_files_predict_as_before(samples, model_file, predictions, kind, label):
    model = load_model(DATA / model_file)
    assert isinstance(model, Model)
    assert (model.kind, model.label, model.nodes) == (kind, label, ("A", "B"))
    assert_predicts_as_stored(model, samples, DATA / predictions)


def test_model_frequency():
    sh5 = load_model(DATA / "sh5.json")
    mean = load_model(DATA / "mean.json")
    assert sh5.frequency_hz == pytest.approx(2.412e9) and mean.frequency_hz is None
    assert model_frequency_hz(sh5) == sh5.frequency_hz and model_frequency_hz(mean, 5.8e9) == 5.8e9
    from rplearn.errors import InputError

    with pytest.raises(InputError, match="frequency_hz") as info:
        model_frequency_hz(mean)
    assert info.value.param == "frequency_hz"
    with pytest.raises(InputError, match="positive"):
        model_frequency_hz(sh5, -1.0)


@pytest.mark.parametrize("name, kind, label", [("sh-3", "patterns", "SH-3"), ("m", "mean", "M"), ("nn-5", "knn", "NN-5")])
def test_every_model_kind_implements_the_protocol(samples, tmp_path, name, kind, label):
    from rplearn.models.fit import fit_model
    from rplearn.models.spec import ModelSpec

    model = fit_model(samples, ModelSpec.parse(name)).model
    assert isinstance(model, Model)
    assert (model.kind, model.label, model.nodes) == (kind, label, ("A", "B"))
    assert model.frequency_hz == pytest.approx(2.412e9)  # recorded from the samples by every kind
    assert model.n_params > 0 and model.training["n_samples"] == len(samples)
    assert (model.predict_gain_std(samples) is None) == (kind != "patterns")
    model.save(tmp_path / "m.json")
    back = load_model(tmp_path / "m.json")
    assert back.to_dict()["label"] == label and back.frequency_hz == model.frequency_hz
    np.testing.assert_array_equal(back.predict_gain(samples), model.predict_gain(samples))
