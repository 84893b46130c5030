"""Level-free fits (issue 24, item 3; acceptance 3): with uncalibrated power the level of the RSSI
values is arbitrary, so adding a constant to every one of them must shift every prediction by
exactly that constant and change nothing else (the chosen order and smoothing, the spreads,
the coverage), for every model kind. The regularisation shrinks toward the data's own level
(:mod:`rplearn.core.lsq.level`), never toward 0 dB nor toward a prior's absolute dBi."""

from __future__ import annotations

import dataclasses
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rplearn.core.environment import PathLoss
from rplearn.core.lsq.level import constant_coefficients
from rplearn.data.tables import LinkSamples
from rplearn.data.units import samples_of, split_units
from rplearn.errors import InputError
from rplearn.io.files import read_dataset
from rplearn.io.reference import read_reference_pattern
from rplearn.models import ModelSpec
from rplearn.models.auto import fit_auto
from rplearn.models.fit import fit_model
from rplearn.models.options import FitOptions
from rplearn.models.reference import reference_model
from rplearn.models.robust import fit_huber
from rplearn.plan.campaign import Campaign
from rplearn.plan.trajectory import TrajectoryUnit
from rplearn.sim import imperfect_reference, simulate
from rplearn.sim.presets import make_preset
from rplearn.workflows.logs import sync_logs

SHIFTS = st.floats(min_value=-100.0, max_value=100.0, allow_nan=False)
#: few examples, each a handful of small fits: the whole file runs in well under a minute
PROPERTY = settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def small_flight():
    """The smoke preset's two drones (their link offsets included) in three short learning
    loops at 3, 8 and 20 m (so that a log-distance exponent is identifiable and the
    cross-validation has three units) and one testing loop at 6 m."""
    smoke = make_preset("smoke")
    opts = dict(height_m=14.0, n_loops=1, speed_m_s=3.0, accel_m_s2=3.0, yaw_rate_deg_s=90.0)
    units = tuple(TrajectoryUnit(nodes=("A", "B"), psi0_deg=psi, distance_m=dist, role=role, label=label, **opts)
                  for label, psi, dist, role in (("learn_3m", 0.0, 3.0, "learning"), ("learn_8m", 0.0, 8.0, "learning"),
                                                 ("learn_20m", 0.0, 20.0, "learning"), ("test_6m", 90.0, 6.0, "testing")))
    return replace(smoke, name="level", campaign=Campaign(units, gap_s=5.0))


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    d = tmp_path_factory.mktemp("level")
    sim = simulate(small_flight(), seed=3, out_dir=str(d / "f"))
    sync_logs([str(d / "f" / "pose_log.parquet")], [str(d / "f" / "signal_log.parquet")], str(d / "m.parquet"))
    df = read_dataset(str(d / "m.parquet"))
    learn, test = split_units(df, None, None)
    nodes = sorted(set(df["tx"]) | set(df["rx"]))
    refs = {}
    for n in nodes:  # the true pattern with a 2 dB RMS smooth error, mounted 10 degrees off
        imperfect_reference(sim.ground_truth, n, 2.0, 10.0, seed=3).to_csv(d / f"ref_{n}.csv", index=False)
        refs[n] = read_reference_pattern(d / f"ref_{n}.csv")
    per_unit = {u: samples_of(df, [u], "d", nodes=nodes) for u in learn}
    return (per_unit, samples_of(df, learn, "d", nodes=nodes), samples_of(df, test, "d", nodes=nodes), reference_model(refs),
            df.assign(rssi_scale="relative"))


def shifted(samples: LinkSamples, shift_db: float) -> LinkSamples:
    """``shift_db`` added to every RSSI value, hence to every observed joint gain."""
    return dataclasses.replace(samples, joint_gain_db=np.asarray(samples.joint_gain_db, np.float64) + shift_db)


def fits(flight, shift_db):
    """Every model kind, learned from the flight with ``shift_db`` added to every RSSI value."""
    per_unit, learn, _, prior, _ = flight
    units = {u: shifted(s, shift_db) for u, s in per_unit.items()}
    learn = shifted(learn, shift_db)
    auto, sel = fit_auto(units)
    logd, sel_logd = fit_auto(units, options=FitOptions(auto=True, path_loss=PathLoss("log-distance")))
    with_prior, sel_prior = fit_auto(units, options=FitOptions(auto=True, priors={n: prior for n in learn.nodes}))
    huber, robust = fit_huber(learn, ModelSpec("sh", 5))
    return {
        "mean": (fit_model(learn, ModelSpec("mean")).model, None),
        "k-NN": (fit_model(learn, ModelSpec("knn", 50)).model, None),
        "fixed SH-6": (fit_model(learn, ModelSpec("sh", 6)).model, None),
        "P-5": (fit_model(learn, ModelSpec("poly", 5)).model, None),
        "auto": (auto.model, sel),
        "auto, log-distance": (logd.model, sel_logd),
        "auto, prior": (with_prior.model, sel_prior),
        "huber SH-5": (huber.model, robust),
    }


@pytest.fixture(scope="module")
def unshifted(flight):
    return fits(flight, 0.0)


@PROPERTY
@given(shift_db=SHIFTS)
def test_a_constant_added_to_every_rssi_shifts_every_prediction_and_changes_nothing_else(flight, unshifted, shift_db):
    test = flight[2]
    for name, (model, extra) in fits(flight, shift_db).items():
        ref, ref_extra = unshifted[name]
        np.testing.assert_allclose(model.predict_gain(test) - shift_db, ref.predict_gain(test), rtol=0, atol=1e-6,
                                   err_msg=name)
        std = model.predict_gain_std(test)
        if std is None:  # the baselines give no spread
            assert ref.predict_gain_std(test) is None, name
            continue
        np.testing.assert_allclose(std, ref.predict_gain_std(test), rtol=1e-6, atol=1e-9, err_msg=name)
        t, r = model.training, ref.training
        assert t["coverage_deg"] == r["coverage_deg"], name
        assert t["rmse_db"] == pytest.approx(r["rmse_db"], rel=1e-6), name
        # the channel's terms (path-loss exponent, link offsets) and their spreads do not move with the level
        assert model.shared_names == ref.shared_names, name
        np.testing.assert_allclose(model.shared_coef, ref.shared_coef, rtol=0, atol=1e-6, err_msg=name)
        for row, ref_row in zip(t.get("link_offsets_db", []), r.get("link_offsets_db", [])):
            assert row["se_db"] == pytest.approx(ref_row["se_db"], rel=1e-6), name
        if "exponent" in r["path_loss"]:
            assert t["path_loss"]["exponent_se"] == pytest.approx(r["path_loss"]["exponent_se"], rel=1e-6), name
        if name.startswith("auto"):
            assert (extra.order, extra.smoothing) == (ref_extra.order, ref_extra.smoothing), name
            assert extra.variance_inflation == pytest.approx(ref_extra.variance_inflation, rel=1e-6), name
            np.testing.assert_allclose([p.rmse_db for p in extra.curve], [p.rmse_db for p in ref_extra.curve],
                                       rtol=1e-6, err_msg=name)
            for node, spread in r["prior_std_db"].items():
                assert t["prior_std_db"][node] == pytest.approx(spread, rel=1e-6), (name, node)
        if name.startswith("huber"):
            assert extra.scale_db == pytest.approx(ref_extra.scale_db, rel=1e-6)
            assert np.array_equal(extra.downweighted, ref_extra.downweighted) and extra.iterations == ref_extra.iterations


def test_a_gaussian_grid_represents_a_constant_only_approximately(flight):
    """BG cannot represent a constant exactly (nor can its unregularised least squares follow a
    shift exactly): the shift holds to 1e-3 dB at BG-7 over 100 dB."""
    _, learn, test, _, _ = flight
    base = fit_model(learn, ModelSpec("bg", 7)).model.predict_gain(test)
    for shift_db in (-100.0, 100.0):
        got = fit_model(shifted(learn, shift_db), ModelSpec("bg", 7)).model.predict_gain(test) - shift_db
        np.testing.assert_allclose(got, base, rtol=0, atol=1e-3)


def test_a_prior_fixes_the_shape_and_the_data_the_level(flight):
    """The prior's absolute level is not imposed: a prior moved by 30 dBi gives the same fit."""
    per_unit, _, test, prior, _ = flight
    fitted, sel = fit_auto(per_unit, options=FitOptions(auto=True, priors={n: prior for n in prior.nodes}))
    raised = dataclasses.replace(prior, coef=np.asarray(prior.coef) + 30.0 * constant_coefficients(prior.basis))
    fitted_raised, sel_raised = fit_auto(per_unit, options=FitOptions(auto=True, priors={n: raised for n in prior.nodes}))
    assert (sel.order, sel.smoothing) == (sel_raised.order, sel_raised.smoothing)
    np.testing.assert_allclose(fitted_raised.model.predict_gain(test), fitted.model.predict_gain(test), atol=1e-6)


def test_a_prior_level_is_imposed_only_when_asked(flight):
    """``prior_level="prior"`` (calibrated power, a trusted reference) shrinks toward the
    prior's absolute dBi: a prior moved by 30 dBi then moves the fit; anything else is refused."""
    per_unit, _, test, prior, _ = flight
    raised = dataclasses.replace(prior, coef=np.asarray(prior.coef) + 30.0 * constant_coefficients(prior.basis))
    kept = fit_auto(per_unit, options=FitOptions(auto=True, priors={n: prior for n in prior.nodes}, prior_level="prior"))[0].model.predict_gain(test)
    moved = fit_auto(per_unit, options=FitOptions(auto=True, priors={n: raised for n in prior.nodes}, prior_level="prior"))[0].model.predict_gain(test)
    assert np.mean(moved - kept) > 0.1
    with pytest.raises(InputError, match="prior level"):
        FitOptions(auto=True, priors={n: prior for n in prior.nodes}, prior_level="absolute")


def test_a_streamed_fit_is_level_free(flight):
    """``fit`` on a big file (statistics a chunk at a time): the same shift, through the table's
    ``rssi_dbm`` (uncalibrated: ``rssi_scale`` relative; shifts off the readers' integer sentinels)."""
    from rplearn.models.streamed import fit_patterns_streamed

    _, _, test, _, df = flight
    nodes = list(test.nodes)
    learn = df[~df["unit"].astype(str).str.startswith("test")]
    base = fit_patterns_streamed([learn.iloc[:1000], learn.iloc[1000:]], ModelSpec("sh", 6), nodes).patterns
    for shift_db in (-77.25, 55.5):
        moved = learn.assign(rssi_dbm=learn["rssi_dbm"] + shift_db)
        fit = fit_patterns_streamed([moved.iloc[:1000], moved.iloc[1000:]], ModelSpec("sh", 6), nodes).patterns
        np.testing.assert_allclose(fit.predict_gain(test) - shift_db, base.predict_gain(test), rtol=0, atol=1e-6)
        np.testing.assert_allclose(fit.predict_gain_std(test), base.predict_gain_std(test), rtol=1e-6)
