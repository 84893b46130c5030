"""rplearn.models.predict: predictions for a dataset of poses, their spreads, frequency checks."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.core.gauge import Gauge
from rplearn.data.tables import validate_matched
from rplearn.errors import InputError
from rplearn.models.load import load_model
from rplearn.models.predict import distinct_labels, frequency_mismatch, predict_dataset
from rplearn.models.spec import ModelSpec, check_fit_options

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "models_v1"


@pytest.fixture(scope="module")
def poses() -> pd.DataFrame:
    return validate_matched(pd.read_csv(FIXTURES / "poses.csv", dtype={"tx": str, "rx": str, "unit": str}), "poses.csv")


def test_predict_dataset_adds_gain_power_and_both_spreads(poses):
    model = load_model(FIXTURES / "sh5.json")
    pred = predict_dataset(model, poses, "poses.csv")
    expected = pd.read_csv(FIXTURES / "pred_sh5.csv")
    for col in ("gain_pred_db", "rssi_pred_dbm", "gain_pred_std_db", "rssi_pred_std_db"):
        np.testing.assert_allclose(pred.table[col], expected[col], rtol=0, atol=1e-9)
    # one packet's spread adds the training residual to the coefficients' standard error
    np.testing.assert_allclose(
        pred.table["rssi_pred_std_db"] ** 2, pred.table["gain_pred_std_db"] ** 2 + model.training["rmse_db"] ** 2
    )
    measured = poses["rssi_dbm"].to_numpy() - pred.table["rssi_pred_dbm"].to_numpy()
    assert pred.n_measured == len(poses) and pred.rmse_db == pytest.approx(np.sqrt(np.mean(measured**2)))
    assert pred.mismatch is None and "RMSE against the 150 measured" in pred.summary("p.csv")


def test_baselines_give_no_spread_and_unmeasured_rows_no_rmse(poses):
    blind = poses.drop(columns=["rssi_dbm"])
    pred = predict_dataset(load_model(FIXTURES / "mean.json"), blind, "poses.csv")
    assert "gain_pred_std_db" not in pred.table and pred.n_measured == 0 and np.isnan(pred.rmse_db)
    assert "RMSE" not in pred.summary("p.csv")


def test_frequency_mismatch_counts_rows_beyond_five_percent():
    model = load_model(FIXTURES / "sh5.json")
    assert frequency_mismatch(model, [model.frequency_hz * 1.04]) is None
    found = frequency_mismatch(model, [model.frequency_hz, 5.8e9, 5.8e9])
    assert found.n_rows == 2 and found.median_hz == 5.8e9
    assert "5.800 GHz" in found.describe("d.csv", "m.json")


def test_distinct_labels_add_the_name_only_where_labels_repeat():
    assert distinct_labels(["SH-3", "SH-3", "M"], ["a.json", "b.json", "m.json"]) == ["SH-3 (a.json)", "SH-3 (b.json)", "M"]


@pytest.mark.parametrize(
    "model, options, param",
    [
        ("knn", {"ridge": 5.0}, "ridge"),
        ("mean", {"order": 7}, "order"),
        ("sh", {"sigma_rad2": 3.0}, "sigma_rad2"),
        ("sh-10", {"order": 5}, "order"),
    ],
)
def test_fit_options_a_model_would_ignore_are_refused(model, options, param):
    spec = ModelSpec.parse(model, order=options.get("order"))
    with pytest.raises(InputError) as err:
        check_fit_options(spec, model=model, **options)
    assert err.value.param == param


def test_fit_options_that_fit_pass_and_gauges_are_explicit():
    check_fit_options(ModelSpec.parse("bg", order=7), order=7, sigma_rad2=0.4, grid="fibonacci")
    assert Gauge().to_dict() == "equal-mean" and Gauge("A").to_dict() == {"node": "A", "mean_gain_dbi": 0.0}
