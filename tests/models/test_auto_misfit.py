"""The automatic fit's pattern spreads (issues 24 item 4-5, 27 item 3, 28 item 1): the error the
model cannot represent, from the grouped cross-validation, is added to each node's spread
everywhere (0 when the model represents the truth), and where the flight never looked the
spread is the measured gains' (not the smoothing's)."""

from __future__ import annotations

import numpy as np
import pytest
from test_calibration import flights_with_their_own_errors
from test_flight_spread import flights_with_levels

from rplearn.core.geometry import Directions
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.sh import SphericalHarmonics
from rplearn.data.tables import LinkSamples
from rplearn.models.auto import fit_auto
from rplearn.models.auto_spread import held_out_misfit_var, misfit_covariance, unseen_spread_cap_db


@pytest.mark.parametrize("seed", [4, 5, 6, 7])
def test_no_misfit_when_the_model_represents_the_truth(seed):
    """A true SH-3 pair, white noise, flights alike (or differing only by their levels): the
    held-out error is the posterior's; the misfit is ~0 (measured 0-0.05 dB per node)."""
    fitted, sel = fit_auto(flights_with_their_own_errors(5, seed=seed, unit_error_db=0.0))
    assert fitted.model.training["misfit_std_db"] < 0.1, fitted.model.training["misfit_std_db"]
    levels, _ = flights_with_levels(8, seed, 3.0)
    assert fit_auto(levels)[0].model.training["misfit_std_db"] < 0.1


def test_a_pattern_the_order_cannot_hold_adds_its_misfit_everywhere():
    """Truth: an SH-3 pair plus fine structure (SH-4..12 terms, 1.5 dB RMS); each learning
    flight sees one band of elevation: the smooth fit chosen cannot hold the fine structure,
    its held-out bands show it, the fit states it as a misfit, and every prediction's spread
    holds it (the joint gain: both ends' halves)."""
    rng = np.random.default_rng(11)
    fine, coarse = SphericalHarmonics(12), SphericalHarmonics(3)
    c_coarse = rng.normal(0.0, 3.0, (2, coarse.n_coef))
    c_fine = rng.normal(0.0, 1.5 / np.sqrt(fine.n_coef / (4 * np.pi)), (2, fine.n_coef))
    c_fine[:, :coarse.n_coef] = 0.0
    units = {}
    for u, el0 in enumerate((-0.5, -0.3, 0.3, 0.5)):
        n = 900
        az, el = rng.uniform(-np.pi, np.pi, (2, n)), np.clip(el0 + rng.normal(0.0, 0.05, (2, n)), -1.5, 1.5)
        tx = rng.integers(0, 2, n)
        g = sum(np.einsum("nc,nc->n", c[i], b.design(az[k], el[k]))
                for c, b in ((c_coarse, coarse), (c_fine, fine)) for k, i in ((0, tx), (1, 1 - tx)))
        y = g + rng.normal(0.0, 1.0, n)
        units[f"u{u}"] = LinkSamples(Directions(az[0], el[0], az[1], el[1]), tx, 1 - tx, ("A", "B"), y, np.full(n, 30.0))
    fitted, sel = fit_auto(units)
    misfit = fitted.model.training["misfit_std_db"]
    assert sel.held_out_excess_db2 > 0 and misfit > 0.3, (misfit, sel.held_out_excess_db2, fitted.spec.label)
    probe = units["u0"]
    with_misfit = fitted.model.predict_gain_std(probe, new_flight=False)
    pat = fitted.model.n_pattern_columns
    fitted.model.covariance = fitted.model.covariance.copy()
    fitted.model.covariance[:pat, :pat] -= misfit_covariance(fitted.model.basis, 2, misfit**2)
    bare = fitted.model.predict_gain_std(probe, new_flight=False)
    np.testing.assert_allclose(with_misfit**2 - bare**2, 2 * misfit**2, rtol=1e-6)


def test_the_misfit_is_the_held_out_excess_beyond_the_stated_variance():
    basis = SphericalHarmonics(2)
    rng = np.random.default_rng(0)
    n = 200
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), rng.uniform(-1, 1, (2, n))
    normal = NormalEquations(basis, 2).add(Directions(az[0], el[0], az[1], el[1]), np.zeros(n, int), np.ones(n, int),
                                           rng.normal(0, 1, n))
    cov = np.eye(normal.n_columns) * 1e-3
    stated = float(np.sum(cov * normal.gram)) / n
    assert held_out_misfit_var(stated + 0.5, cov, normal) == pytest.approx(0.5)
    assert held_out_misfit_var(stated / 2, cov, normal) == 0.0 and held_out_misfit_var(1.0, None, normal) == 0.0
    # per node: the same variance at every direction (the addition theorem)
    d = basis.design(az[0], el[0])
    var = np.einsum("nc,cd,nd->n", d, misfit_covariance(basis, 2, 0.7)[:basis.n_coef, :basis.n_coef], d)
    np.testing.assert_allclose(var, 0.7, rtol=1e-9)
    assert unseen_spread_cap_db(normal, basis) > 0


def test_where_unseen_the_spread_is_the_measured_gains_even_when_the_smoothing_implies_less():
    """Flights alike (no inflation: the cross-validated smoothing implies a small spread): the
    spread stated where the flight never looked is the measured gains' spread, not below it
    (within 0.1%: the cap here is computed without the fit's gauge)."""
    units, _ = flights_with_levels(6, 2, 0.5)
    fitted, _ = fit_auto(units)
    training = fitted.model.training
    total = NormalEquations(fitted.model.basis, 2)
    for s in units.values():
        total.add(s.directions, s.tx_index, s.rx_index, s.joint_gain_db)
    cap = unseen_spread_cap_db(total, fitted.model.basis)
    assert training["prior_std_source"].startswith("the spread of the measured gains")
    assert all(v == pytest.approx(cap, rel=1e-3) for v in training["prior_std_db"].values()), (training["prior_std_db"], cap)
