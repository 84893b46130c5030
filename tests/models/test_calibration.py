"""Calibration of the predictive spread (issue 11, acceptance 3): 90% intervals
``prediction +- 1.645 sqrt(gain_std^2 + rmse^2)`` of an automatic fit cover 85-95% of held-out
samples, inside and outside the covered directions."""

from __future__ import annotations

import numpy as np
import pytest
from simulated_flights import auto_fit, synced
from test_prior import ground_case

from rplearn.models.auto import fit_auto
from rplearn.models.options import FitOptions
from rplearn.models.predict import UNCOVERED_DEG, end_coverage_deg


def interval_hits(model, test):
    """Per held-out sample: inside its 90% interval, and whether both ends are covered."""
    g = model.predict_gain(test)
    half = 1.645 * np.sqrt(model.predict_gain_std(test) ** 2 + model.training["rmse_db"] ** 2)
    tx, rx = end_coverage_deg(model, test)
    return np.abs(test.joint_gain_db - g) <= half, np.fmax(tx, rx) <= UNCOVERED_DEG


@pytest.mark.slow
def test_ground_with_a_prior_is_calibrated_inside_and_outside(tmp_path):
    per_unit, _, test, prior = ground_case(tmp_path, 0)
    fitted, _ = fit_auto(per_unit, options=FitOptions(auto=True, priors={n: prior for n in prior.nodes}))
    hit, covered = interval_hits(fitted.model, test)
    assert covered.sum() > 100 and (~covered).sum() > 100
    for name, part in (("all", hit), ("covered", hit[covered]), ("uncovered", hit[~covered])):
        assert 0.85 <= part.mean() <= 0.95, (name, part.mean(), part.size)


@pytest.mark.slow
def test_paper_is_calibrated_inside_and_outside_the_flown_directions():
    """On `paper` the test flight strays beyond 10 deg of the learning directions for under 1%
    of its samples, in one stretch of flight (12 to 176 samples a seed): one stretch is one
    draw of the pattern's error there, so the uncovered samples of six independent campaigns
    are pooled; the covered ones are checked campaign by campaign."""
    pooled = []
    for seed in range(6):
        test = synced("paper", seed, ("A", "B")).test  # held-out samples; no files read: none copied
        fitted, _ = auto_fit("paper", seed, ("A", "B"))  # fit_auto of the learning units, once per process
        hit, covered = interval_hits(fitted.model, test)
        assert 0.85 <= hit.mean() <= 0.95 and 0.85 <= hit[covered].mean() <= 0.95, (seed, hit.mean(), hit[covered].mean())
        pooled.append(hit[~covered])
    outside = np.concatenate(pooled)
    assert outside.size > 300 and 0.85 <= outside.mean() <= 0.95, (outside.size, outside.mean())


def flights_with_their_own_errors(n_units, seed, unit_error_db=1.0, noise_db=1.0, n=1500):
    """Units of one smooth SH-3 pair of patterns, each unit with its own smooth SH-2 error
    (another day, another altitude) on top of independent noise."""
    from rplearn.core.geometry import Directions
    from rplearn.core.sh import SphericalHarmonics
    from rplearn.data.tables import LinkSamples

    rng = np.random.default_rng(seed)
    truth, wobble = SphericalHarmonics(3), SphericalHarmonics(2)
    coef = rng.normal(0.0, 3.0, (2, truth.n_coef))
    units = {}
    for u in range(n_units):
        bias = rng.normal(0.0, unit_error_db / np.sqrt(wobble.n_coef / (4 * np.pi)), (2, wobble.n_coef))
        az, el = rng.uniform(-np.pi, np.pi, (2, n)), np.arcsin(rng.uniform(-1, 1, (2, n)))
        tx = rng.integers(0, 2, n)
        rx = 1 - tx
        g = sum(np.einsum("nc,nc->n", c[i], b.design(az[k], el[k]))
                for c, b in ((coef, truth), (bias, wobble)) for k, i in ((0, tx), (1, rx)))
        y = g + rng.normal(0.0, noise_db, n)
        units[f"u{u}"] = LinkSamples(Directions(az[0], el[0], az[1], el[1]), tx, rx, ("A", "B"), y, np.full(n, 30.0))
    return units


def test_the_spread_is_inflated_to_what_held_out_flights_show():
    """Each flight has its own smooth error, which no fit from other flights can know: with the
    inflation learned from grouped cross-validation, 90% intervals of a new flight cover about
    90% of it; with the bare posterior (inflation 1) far fewer."""
    units = flights_with_their_own_errors(16, seed=3, unit_error_db=2.0)
    new = [units.pop(f"u{k}") for k in range(6, 16)]
    fitted, sel = fit_auto(units)
    kappa = fitted.model.training["variance_inflation"]
    assert kappa == sel.variance_inflation > 3, kappa
    hit = np.concatenate([interval_hits(fitted.model, s)[0] for s in new])
    fitted.model.covariance = fitted.model.covariance / kappa
    bare = np.concatenate([interval_hits(fitted.model, s)[0] for s in new])
    assert 0.85 <= hit.mean() <= 0.95 and bare.mean() < 0.85, (hit.mean(), bare.mean())


def test_flights_that_agree_are_not_inflated_much():
    units = flights_with_their_own_errors(5, seed=4, unit_error_db=0.0)
    fitted, sel = fit_auto(units)
    assert 1.0 <= sel.variance_inflation < 1.6, sel.variance_inflation  # 1.0-1.58 over seeds 4-9


def test_far_from_the_data_the_spread_is_the_reported_prior_spread(tmp_path):
    """Where no learning direction comes near, the spread of a link's gain is that of the prior
    (the reported ``prior_std_db`` of both ends), with and without a reference prior."""
    from rplearn.core.geometry import Directions
    from rplearn.data.tables import LinkSamples

    per_unit, learn, _, prior = ground_case(tmp_path, 3)
    far = Directions(np.full(50, np.pi), np.full(50, 1.2), np.full(50, np.pi), np.full(50, 1.2))
    for with_prior in ({}, {n: prior for n in prior.nodes}):
        model = fit_auto(per_unit, options=FitOptions(auto=True, priors=with_prior))[0].model
        spread = model.training["prior_std_db"]
        samples = LinkSamples(far, np.zeros(50, int), np.ones(50, int), learn.nodes, np.zeros(50), np.full(50, 40.0))
        expected = np.hypot(spread[learn.nodes[0]], spread[learn.nodes[1]])
        got = np.median(model.predict_gain_std(samples))
        assert 0.8 * expected <= got <= 1.3 * expected, (got, expected, with_prior is not None)


def test_the_prior_spread_is_finite_without_smoothing_and_stated_only_for_all_nodes():
    from rplearn.core.sh import SphericalHarmonics
    from rplearn.errors import InputError
    from rplearn.models.auto_spread import prior_std_db

    basis = SphericalHarmonics(4)
    plain = prior_std_db(basis, ["A", "B"], np.ones(2 * basis.n_coef), 4.0, power=2.0)  # smoothing 0: the ridge alone
    # noise variance over the ridge (1), summed over the 24 non-constant harmonics, averaged on the sphere
    from rplearn.core.bases import fibonacci_grid_nodes

    az, el = fibonacci_grid_nodes(20_000)
    squares = basis.design(az, el) ** 2
    assert plain["A"] == pytest.approx(np.sqrt(4.0 * np.mean(squares[:, 1:].sum(axis=1))), rel=0.01)
    assert np.isfinite(plain["B"])
    units = flights_with_their_own_errors(3, seed=5)
    from rplearn.models.reference import reference_model  # noqa: F401  (a prior of one node)

    one_prior = fit_auto(units)[0].model
    with pytest.raises(InputError, match="node.s. B have no prior"):
        fit_auto(units, options=FitOptions(auto=True, priors={"A": one_prior}, prior_std_db=10.0))
    with pytest.raises(InputError, match="positive number"):
        FitOptions(auto=True, priors={"A": one_prior, "B": one_prior}, prior_std_db=float("nan"))
    stated = fit_auto(units, options=FitOptions(auto=True, priors={"A": one_prior, "B": one_prior}, prior_std_db=6.0))[0].model.training
    assert stated["prior_std_db"]["A"] == pytest.approx(6.0, rel=1e-6) and stated["prior_std_source"] == "stated"
