"""Flight-to-flight level spread (issue 24, item 4 and acceptance 4): each flight's own level is
told apart from the pattern by grouped cross-validation, reported, stored in the model and
added to the spread of a new flight's predictions; every spread ``fit`` prints is one a user can
act on."""

from __future__ import annotations

import numpy as np
import pytest
from simulated_flights import auto_fit
from test_auto import campaign

from rplearn.core.geometry import Directions
from rplearn.core.sh import SphericalHarmonics
from rplearn.data.tables import LinkSamples
from rplearn.io.files import read_dataset
from rplearn.models import load_model
from rplearn.models.auto import fit_auto
from rplearn.models.predict import UNCOVERED_DEG, predict_dataset
from rplearn.sim.presets import CAMPAIGN_FLIGHTS, CAMPAIGN_LEVEL_STD_DB


def flights_with_levels(n_units, seed, level_db, noise_db=1.0, n=300):
    """Units of one smooth SH-3 pair of patterns, each unit shifted by its own level."""
    rng = np.random.default_rng(seed)
    basis = SphericalHarmonics(3)
    coef = rng.normal(0.0, 3.0, (2, basis.n_coef))
    levels = rng.normal(0.0, level_db, n_units)
    units = {}
    for u in range(n_units):
        az, el = rng.uniform(-np.pi, np.pi, (2, n)), np.arcsin(rng.uniform(-1, 1, (2, n)))
        tx = rng.integers(0, 2, n)
        g = (np.einsum("nc,nc->n", coef[tx], basis.design(az[0], el[0]))
             + np.einsum("nc,nc->n", coef[1 - tx], basis.design(az[1], el[1])))
        y = g + levels[u] + rng.normal(0.0, noise_db, n)
        units[f"u{u}"] = LinkSamples(Directions(az[0], el[0], az[1], el[1]), tx, 1 - tx, ("A", "B"), y, np.full(n, 30.0))
    return units, levels


@pytest.mark.parametrize("seed", range(6))
def test_levels_alone_are_a_between_flight_spread_not_an_inflation(seed):
    """Flights that differ only by their levels: the spread is found between flights (within 30%
    of the levels' realised spread; measured within 2%) and the variance inflation stays small
    (1.0-2.5 over these seeds; before, the levels went into the inflation: x7-x37)."""
    units, levels = flights_with_levels(8, seed, 3.0)
    fitted, sel = fit_auto(units)
    truth = float(np.std(levels, ddof=1))
    assert 0.7 * truth <= sel.flight_level_std_db <= 1.3 * truth, (sel.flight_level_std_db, truth)
    assert 1.0 <= sel.variance_inflation < 3.0, sel.variance_inflation
    training = fitted.model.training
    assert training["flight_level_std_db"] == pytest.approx(sel.flight_level_std_db)
    assert training["noise_std_db"] == pytest.approx(1.0, rel=0.1)  # the noise, not the levels
    assert training["rmse_db"] > 1.3  # the training residual still holds the levels
    # a new flight's level: the between-flight spread and the uncertainty of the learned mean level
    assert sel.flight_level_std_db < training["new_flight_level_std_db"] < 1.1 * sel.flight_level_std_db


def test_flights_at_one_level_have_no_level_spread():
    units, _ = flights_with_levels(6, 7, 0.0)
    _, sel = fit_auto(units)
    assert sel.flight_level_std_db < 0.1, sel.flight_level_std_db


def test_the_level_spread_is_stored_and_added_to_a_new_flights_spread(tmp_path):
    units, _ = flights_with_levels(8, 3, 3.0)
    model = fit_auto(units)[0].model
    model.save(tmp_path / "m.json")
    loaded = load_model(tmp_path / "m.json")
    level = loaded.new_flight_level_std_db
    assert level == pytest.approx(model.training["new_flight_level_std_db"]) and level > 1.0
    probe = units["u0"]
    with_level, bare = loaded.predict_gain_std(probe), loaded.predict_gain_std(probe, new_flight=False)
    np.testing.assert_allclose(with_level**2, bare**2 + level**2, rtol=1e-9)
    loaded.training = loaded.training.replace(new_flight_level_std_db=None)  # an older model file: no level spread
    np.testing.assert_allclose(loaded.predict_gain_std(probe), bare, rtol=0, atol=0)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_new_flight_of_a_campaign_is_covered_inside_and_outside(tmp_path_factory, seed):
    """Acceptance 4: the `campaign` preset (9 learning and 6 held-out flights whose levels
    differ by 3 dB RMS): 90% intervals ``gain +- 1.645 * rssi_pred_std_db`` (predict_dataset:
    the coefficients' and the new flight's level spread, and the noise) cover 85-95% of the
    held-out samples, apart inside and outside the learned directions (measured on seeds 0-5:
    88-93% inside, 88-93% outside); the between-flight spread is within 30% of the learning
    flights' realised RMS (3 dB; measured 2.5-3.6 dB).

    The held-out flights are pooled: one flight's coverage is one draw of its level (a flight
    at the common level is covered ~96%, one 7 dB off ~55%, under an honest spread)."""
    d, sim, per_unit, _, _ = campaign(tmp_path_factory, "campaign", seed)
    assert len(per_unit) == CAMPAIGN_FLIGHTS[0] >= 8
    fitted, sel = auto_fit("campaign", seed)  # fit_auto(per_unit), once per process
    learned = np.array([sim.unit_levels_db[u] for u in per_unit])
    truth = float(np.sqrt(np.mean((learned - learned.mean()) ** 2)))
    assert truth == pytest.approx(CAMPAIGN_LEVEL_STD_DB)
    assert 0.7 * truth <= sel.flight_level_std_db <= 1.3 * truth, (sel.flight_level_std_db, truth)
    df = read_dataset(str(d / "m.parquet"))
    test = df[df["unit"].str.startswith("test")].reset_index(drop=True)
    table = predict_dataset(fitted.model, test).table
    error = table["rssi_dbm"] - table["rssi_pred_dbm"]  # the joint gain's error (same path loss)
    hit = (np.abs(error) <= 1.645 * table["rssi_pred_std_db"]).to_numpy()
    covered = (np.fmax(table["tx_coverage_deg"], table["rx_coverage_deg"]) <= UNCOVERED_DEG).to_numpy()
    assert covered.sum() > 1000 and (~covered).sum() > 1000, (covered.sum(), (~covered).sum())
    for name, part in (("covered", hit[covered]), ("uncovered", hit[~covered])):
        assert 0.85 <= part.mean() <= 0.95, (name, part.mean(), part.size)
    # the spreads fit prints are a few dB, not tens
    training = fitted.model.training
    assert all(v < 10.0 for v in training["prior_std_db"].values()), training["prior_std_db"]
    assert training["variance_inflation"] < 10.0


@pytest.mark.parametrize("seed,error_db", [(3, 2.0), (4, 4.0)])
def test_the_unseen_spread_is_capped_by_the_measured_gains_spread(seed, error_db):
    """Flights with their own smooth errors inflate the within-flight variance ~x50; the spread
    the smoothing then implies where the flight never looked is capped at the measured joint
    gains' spread (what the data allow; 4.4 and 7.4 dB here)."""
    from test_calibration import flights_with_their_own_errors

    units = flights_with_their_own_errors(8, seed=seed, unit_error_db=error_db, n=400)
    y = np.concatenate([u.joint_gain_db for u in units.values()])
    fitted, sel = fit_auto(units)
    training = fitted.model.training
    assert sel.variance_inflation > 10 and training["prior_std_source"].startswith("the spread of the measured gains")
    spread = training["prior_std_db"]
    assert all(0.8 * y.std() < v <= y.std() for v in spread.values()), (spread, y.std())
