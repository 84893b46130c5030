"""rplearn.models.auto_prior: with a reference prior the automatic fit searches the order of the
deviation from it, keeps the prior's own degrees above the chosen order, and lets the held-out
units choose between that and the prior cut to the chosen order (issue 28)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import fibonacci_grid_nodes, make_basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection_result import Selection
from rplearn.models import ModelSpec
from rplearn.models.auto import fit_from_statistics
from rplearn.models.auto_prior import PRIOR_TAPER_RESOLUTION, deviation_problem, kept_within_noise
from rplearn.models.options import FitOptions
from rplearn.models.patterns import PatternSet

BIG = 12  # largest candidate order: statistics at SH-12
NODES = ("A", "B")


def _truth(seed: int) -> np.ndarray:
    """Two patterns of SH-12 whose degrees decay slowly (fine structure above SH-4)."""
    rng = np.random.default_rng(seed)
    degrees = make_basis("sh", BIG).degrees
    return rng.normal(size=(2, degrees.size)) * 4.0 / (1.0 + degrees)


def _units(truth: np.ndarray, seed: int = 0) -> dict[str, NormalEquations]:
    """Three flights that see each antenna only in a band 10-40 deg below its horizon, at three
    headings; 1 dB of noise."""
    basis = make_basis("sh", BIG)
    rng = np.random.default_rng(seed)
    out = {}
    for u, centre in enumerate((-1.0, 0.0, 1.0)):
        n = 6000
        az = centre + rng.uniform(-0.6, 0.6, (2, n))
        el = np.radians(rng.uniform(-40.0, -10.0, (2, n)))
        tx = rng.integers(0, 2, n)
        rx = 1 - tx
        d = Directions(az[0], el[0], az[1], el[1])
        ft, fr = basis.design(d.az_tx, d.el_tx), basis.design(d.az_rx, d.el_rx)
        y = np.einsum("ij,ij->i", ft, truth[tx]) + np.einsum("ij,ij->i", fr, truth[rx]) - 60.0 + rng.normal(size=n)
        out[f"u{u}"] = NormalEquations(basis, 2).add(d, tx, rx, y)
    return out


def _prior(coef: np.ndarray) -> PatternSet:
    return PatternSet(basis=make_basis("sh", BIG), nodes=NODES, coef=np.asarray(coef, np.float64))


def _fit(units, prior: np.ndarray, orders, std: float | None = 1.0):
    options = FitOptions(auto=True, priors={n: _prior(prior) for n in NODES}, prior_std_db=std)
    return fit_from_statistics(units, ModelSpec("sh", BIG), list(orders), NODES, options)


def _unseen_rms(model: PatternSet, truth: np.ndarray) -> float:
    """RMS [dB] of each node's shape error (sphere means dropped) above its horizon, never flown."""
    az, el = fibonacci_grid_nodes(2000)
    up = el > np.radians(10.0)
    basis = make_basis("sh", BIG)
    errors = []
    for k, n in enumerate(NODES):
        got = model.evaluate(n, az[up], el[up])
        want = basis.design(az[up], el[up]) @ truth[k]
        errors.append((got - got.mean()) - (want - want.mean()))
    return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))


@pytest.fixture(scope="module")
def exact_case():
    """A prior 0.02 dB per coefficient from a truth of SH-12 (no structure above the largest
    order, so nothing rings: the taper of the kept prior switched off)."""
    import rplearn.models.auto_prior as auto_prior

    truth = _truth(1)
    units = _units(truth)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(auto_prior, "PRIOR_TAPER_RESOLUTION", 0.0)
        return truth, units, _fit(units, truth + np.random.default_rng(5).normal(size=truth.shape) * 0.02, range(2, BIG + 1))


def test_an_exact_prior_is_kept_above_the_chosen_order(exact_case):
    truth, _, (fitted, choice) = exact_case
    model = fitted.model
    kept = model.training.extra["prior_kept"]
    assert kept["kept"] and kept["model_order"] == BIG and choice.order < BIG, kept
    assert model.basis == make_basis("sh", BIG) and model.covariance is not None
    assert model.covariance.shape == (2 * model.basis.n_coef + len(model.shared_names),) * 2
    # the degrees above the chosen order are the prior's (untapered here), exactly
    p = make_basis("sh", choice.order).n_coef
    prior = truth + np.random.default_rng(5).normal(size=truth.shape) * 0.02
    assert np.array_equal(model.coef[:, p:], prior[:, p:])
    # where the flights never looked the pattern is the truth's, within the prior's error
    assert _unseen_rms(model, truth) < 0.3, _unseen_rms(model, truth)
    # and the spread stated there is the prior's (stated 1 dB), all degrees together
    assert model.training.prior_std_source == "stated"
    assert all(v == pytest.approx(1.0, rel=1e-6) for v in model.training.prior_std_db.values())


def test_a_prior_cut_to_the_chosen_order_loses_the_unseen_structure(exact_case):
    """The same prior cut to the chosen order (what the fit did before): far worse where the
    flights never looked, which no held-out unit can see."""
    truth, units, (fitted, choice) = exact_case
    basis = make_basis("sh", choice.order)
    cut = np.zeros_like(truth)
    cut[:, :basis.n_coef] = fitted.model.coef[:, :basis.n_coef]
    assert _unseen_rms(_prior(cut), truth) > 3 * _unseen_rms(fitted.model, truth)


def test_at_the_largest_order_alone_kept_and_cut_are_one_model(monkeypatch):
    """Untapered, the deviation's search at one order, the largest, is the previous search (the
    same penalised least squares): same choice, predictions within 1e-9 dB."""
    truth = _truth(2)
    units = _units(truth, 1)
    prior = truth.copy()
    prior[:, 16:] = 0.0  # a prior of SH-4 (zero above): kept or cut, the same at SH-12
    import rplearn.models.auto_prior as auto_prior

    monkeypatch.setattr(auto_prior, "PRIOR_TAPER_RESOLUTION", 0.0)
    fitted, choice = _fit(units, prior, [BIG], std=None)
    old = auto_prior.MAX_KEPT_COLUMNS
    try:
        auto_prior.MAX_KEPT_COLUMNS = 0  # the prior cut: the search of before
        plain, plain_choice = _fit(units, prior, [BIG], std=None)
    finally:
        auto_prior.MAX_KEPT_COLUMNS = old
    assert (choice.order, choice.smoothing) == (plain_choice.order, plain_choice.smoothing)
    assert abs(choice.rmse_db - plain_choice.rmse_db) < 1e-9
    az, el = fibonacci_grid_nodes(500)
    for n in NODES:
        assert np.max(np.abs(fitted.model.evaluate(n, az, el) - plain.model.evaluate(n, az, el))) < 1e-9


def test_a_prior_whose_fine_structure_is_wrong_where_the_flights_looked_is_cut():
    """A prior right in its low degrees but with other fine structure: the held-out units see
    the kept prior's misfit and choose the prior cut to the chosen order."""
    truth = _truth(3)
    units = _units(truth, 2)
    wrong = truth.copy()
    wrong[:, 25:] = _truth(4)[:, 25:] * 2.0
    fitted, choice = _fit(units, wrong, range(2, BIG + 1))
    kept = fitted.model.training.extra["prior_kept"]
    assert not kept["kept"] and kept["kept_rmse_db"] > kept["cut_rmse_db"], kept
    assert fitted.model.basis == make_basis("sh", choice.order)


def test_kept_within_noise_follows_the_ties_rule():
    def point(rmse):
        return Selection("grouped-cv", 4, 1e-3, rmse)

    sse = np.array([100.0, 110.0, 90.0])
    assert kept_within_noise(point(1.0), point(1.0), sse, sse, 300)  # as good
    assert not kept_within_noise(point(1.004), point(1.0), sse * 1.008, sse, 300)  # 0.8% worse in every unit: seen
    assert not kept_within_noise(point(1.05), point(1.0), sse * 1.1, sse, 300)  # 10% worse
    noisy = sse + np.array([2.0, -2.5, 2.6])  # 0.7% worse on average, but it varies: within 2 standard errors
    assert kept_within_noise(point(1.005), point(1.0), noisy, sse, 300)
    two = np.array([100.0, 100.0])  # two units: the fraction alone
    assert kept_within_noise(point(1.004), point(1.0), two, two, 200)
    assert not kept_within_noise(point(1.006), point(1.0), two, two, 200)


def test_the_kept_prior_is_tapered_against_ringing():
    """The shape the deviation is searched from: each degree ``l`` of the prior's shape times
    ``exp(-l (l + 1) sigma^2 / 2)``, ``sigma`` a quarter of the largest order's resolution (3 deg
    at SH-15); the prior's level is the target of the deviation with ``prior_level="prior"``."""
    truth = _truth(1)
    units = _units(truth)
    total = NormalEquations(make_basis("sh", BIG), 2)
    for st in units.values():
        total.merge(st)
    problem = deviation_problem(units, total, truth.ravel(), "prior")
    degrees = make_basis("sh", BIG).degrees
    sigma = PRIOR_TAPER_RESOLUTION * np.pi / BIG
    want = truth * np.exp(-0.5 * degrees * (degrees + 1.0) * sigma**2)
    want[:, 0] = 0.0  # the shape: each node's sphere mean dropped
    assert np.allclose(problem.shape.reshape(2, -1), want, rtol=1e-12, atol=1e-12)
    assert problem.target is not None and np.allclose(problem.target.reshape(2, -1)[:, 1:], 0.0)
    assert np.allclose(problem.target.reshape(2, -1)[:, 0], truth[:, 0])
    assert deviation_problem(units, total, truth.ravel(), "data").target is None


def test_the_kept_model_names_its_order_whatever_the_order_of_the_candidates(monkeypatch):
    import rplearn.models.auto_prior as auto_prior

    monkeypatch.setattr(auto_prior, "PRIOR_TAPER_RESOLUTION", 0.0)
    truth = _truth(1)
    units = _units(truth)
    prior = truth + np.random.default_rng(5).normal(size=truth.shape) * 0.02
    fitted, _ = _fit(units, prior, [BIG, 4, 6, 8])
    kept = fitted.model.training.extra["prior_kept"]
    assert kept["kept"] and fitted.model.basis == make_basis("sh", BIG), kept
    assert kept["model_order"] == BIG and fitted.spec.order == BIG, (kept, fitted.spec)


def test_the_kept_prior_target_holds_the_tapered_shape_at_the_priors_levels(monkeypatch):
    """The misfit that sets a kept prior's unseen spread is that of the prior the model keeps:
    the tapered shape at each node's own level (review 37: it was the untapered prior's)."""
    from rplearn.core.lsq.level import pattern_shape
    from rplearn.models.auto_prior import kept_prior_target

    basis = make_basis("sh", BIG)
    truth = _truth(2)
    units = _units(truth)
    total = NormalEquations(basis, 2)
    for st in units.values():
        total.merge(st)
    prior = (truth + 3.0).ravel()
    problem = deviation_problem(units, total, prior, "data")
    kept = kept_prior_target(prior, problem.shape, basis, 2)
    assert np.allclose(pattern_shape(kept, basis, 2), problem.shape, atol=1e-12)
    assert np.allclose(kept - pattern_shape(kept, basis, 2), prior - pattern_shape(prior, basis, 2), atol=1e-12)
    assert not np.allclose(kept, prior)  # the taper moved the high degrees
    monkeypatch.setattr("rplearn.models.auto_prior.PRIOR_TAPER_RESOLUTION", 0.0)
    untapered = deviation_problem(units, total, prior, "data")
    assert np.allclose(kept_prior_target(prior, untapered.shape, basis, 2), prior, atol=1e-12)
