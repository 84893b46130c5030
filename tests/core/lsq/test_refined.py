"""The single-precision Cholesky factor with refined solves (rplearn.core.lsq.refined) and its use
by ConstrainedFactor: double-precision answers, and the float64 factor where single precision
cannot deliver them."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.lsq import factor as factor_module
from rplearn.core.lsq import refined, spectrum
from rplearn.core.lsq.refined import RefinedCholesky, scaled_double, scaled_single
from rplearn.errors import NotPositiveDefinite


def _gram(n, cond, seed=0):
    """A symmetric positive definite matrix of ``n`` columns whose unit-diagonal form has a
    condition number of about ``cond``, with a wide spread of diagonal values."""
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    lam = np.geomspace(1.0, 1.0 / cond, n)
    g = (q * lam) @ q.T
    d = np.geomspace(1.0, 1e4, n)[rng.permutation(n)]
    return g * np.sqrt(d)[:, None] * np.sqrt(d)[None, :]


def test_the_scaled_copies_are_the_scaled_matrix_and_its_norm():
    g = _gram(150, 1e3)
    added = np.linspace(0.0, 2.0, 150)
    scale = 1.0 / np.sqrt(np.diag(g) + added)
    exact = scale[:, None] * (g + np.diag(added)) * scale[None, :]
    single, norm = scaled_single(g, scale, added)
    assert single.dtype == np.float32
    np.testing.assert_allclose(single, exact, rtol=1e-6, atol=1e-7)
    assert norm == pytest.approx(np.abs(exact).sum(axis=1).max(), rel=1e-12)
    np.testing.assert_allclose(scaled_double(g, scale, added), exact, rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("cond", [10.0, 1e4])
def test_refined_solves_reach_double_precision(cond):
    g = _gram(300, cond)
    added = np.full(300, 1e-3)
    scale = 1.0 / np.sqrt(np.diag(g) + added)
    a = scale[:, None] * (g + np.diag(added)) * scale[None, :]
    factor = RefinedCholesky.of(g, scale, added)
    assert factor is not None
    b = np.random.default_rng(1).standard_normal((300, 3))
    exact = np.linalg.solve(a, b)
    single = factor.approximate(b)
    x = factor.solve(b)
    # float32 alone is off by far more than the refined answer
    assert np.abs(single - exact).max() > 1e3 * np.abs(x - exact).max()
    # a backward-stable float64 answer: forward error within cond * eps
    assert np.abs(x - exact).max() <= 50 * cond * np.finfo(float).eps * np.abs(exact).max()
    assert 1 <= factor.steps[-1] <= 4


@pytest.mark.parametrize("cond", [1e8, 1e9])
def test_an_ill_conditioned_matrix_is_left_to_the_float64_factor(cond):
    """Condition beyond 1 / eps32: the single-precision factorisation fails (None: the solver
    then factorises in float64) or its solves cannot converge and the factor turns float64;
    either way the answer is float64's."""
    g = _gram(200, cond, seed=3)
    added = np.zeros(200)
    scale = 1.0 / np.sqrt(np.diag(g))
    none = np.zeros((0, 200))
    factor = factor_module.ConstrainedFactor.refined(g, added, scale, none)
    b = np.random.default_rng(4).standard_normal(200)
    reference = factor_module.ConstrainedFactor.of(scaled_double(g, scale, added), none, scale=scale)
    if factor is None:
        factor = factor_module.ConstrainedFactor.of(scaled_double(g, scale, added), none, scale=scale)
    x = factor.solve_a(b)
    assert factor.kind == "dense"
    np.testing.assert_allclose(x, reference.solve_a(b), rtol=1e-12)


def test_a_solve_that_does_not_converge_switches_to_float64(monkeypatch):
    g = _gram(120, 1e2)
    added = np.full(120, 0.5)
    scale = 1.0 / np.sqrt(np.diag(g) + added)
    monkeypatch.setattr(refined, "MAX_STEPS", 0)  # no corrections allowed: float32 never suffices
    factor = factor_module.ConstrainedFactor.refined(g, added, scale, np.zeros((0, 120)))
    assert factor.kind == "refined"
    b = np.random.default_rng(5).standard_normal(120)
    x = factor.solve_a(b)
    assert factor.kind == "dense"
    np.testing.assert_allclose(x, np.linalg.solve(g + np.diag(added), b), rtol=1e-10)


def test_the_inverse_of_a_refined_factor_is_float64s():
    g = _gram(100, 1e3, seed=6)
    added = np.full(100, 0.1)
    scale = 1.0 / np.sqrt(np.diag(g) + added)
    cmat = np.zeros((1, 100))
    cmat[0, :50] = 1.0
    factor = factor_module.ConstrainedFactor.refined(g, added, scale, cmat)
    dense = factor_module.ConstrainedFactor.of(scaled_double(g, scale, added), cmat, scale=scale)
    np.testing.assert_allclose(factor.inverse(), dense.inverse(), rtol=1e-9, atol=1e-12 * np.abs(dense.inverse()).max())


def _swarm_statistics(n_nodes=6, order=5, n=20000, seed=0):
    from rplearn.core.bases import make_basis
    from rplearn.core.geometry import Directions
    from rplearn.core.lsq.normal_equations import NormalEquations

    rng = np.random.default_rng(seed)
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), rng.uniform(-1.2, 1.2, (2, n))
    tx = rng.integers(0, n_nodes, n)
    rx = (tx + rng.integers(1, n_nodes, n)) % n_nodes
    y = rng.normal(size=n) + np.sin(el[0])
    return NormalEquations(make_basis("sh", order), n_nodes), (Directions(az[0], el[0], az[1], el[1]), tx, rx, y)


@pytest.fixture
def refined_everywhere(monkeypatch):
    from rplearn.core.lsq import solver, solver_large

    monkeypatch.setattr(solver, "LARGE_COLUMNS", 0)
    monkeypatch.setattr(solver_large, "REFINED_COLUMNS", 0)


def test_a_solution_keeps_its_gram_when_samples_are_added_later(refined_everywhere):
    """The refined factor reads the Gram for its lazy covariance: adding samples to the normal
    equations afterwards must not change an earlier solution's covariance (found by review:
    it was off by 54%)."""
    import copy

    from rplearn.core.lsq import solver

    normal, (d, tx, rx, y) = _swarm_statistics()
    normal.add(d, tx, rx, y)
    before = copy.deepcopy(normal)
    first = solver.solve(normal)
    assert not normal.gram.flags.writeable  # kept by the solution
    more_normal, (d2, tx2, rx2, y2) = _swarm_statistics(seed=1)
    normal.add(d2, tx2, rx2, y2)  # works on a copy
    assert normal.gram.flags.writeable and normal.n_samples == 2 * before.n_samples
    expected = solver.solve(before).covariance
    np.testing.assert_allclose(first.covariance, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
    both = copy.deepcopy(before)
    both.add(d2, tx2, rx2, y2)
    np.testing.assert_array_equal(normal.gram, both.gram)


def test_float64_trouble_after_single_precision_leaves_the_decision_to_the_kkt_path(refined_everywhere, monkeypatch):
    """When the refined solves give up and the float64 factor fails too, the large path gives
    way to the KKT path (as a failed float64 factor always did) instead of raising."""
    from rplearn.core.lsq import solver

    normal, (d, tx, rx, y) = _swarm_statistics()
    normal.add(d, tx, rx, y)
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 10**9)
    small = solver.solve(normal)
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 0)
    monkeypatch.setattr(refined, "MAX_STEPS", 0)

    def fail(self):
        raise NotPositiveDefinite("forced")

    monkeypatch.setattr(factor_module.ConstrainedFactor, "_to_double", fail)
    large = solver.solve(normal)
    assert large.covariance_fn is None  # the KKT path's eager covariance
    np.testing.assert_allclose(large.coef, small.coef, atol=1e-12)


def test_a_matrix_without_a_ridge_is_never_refined():
    """Only positive semi-definite (no ridge): single precision might factorise it where float64
    refuses; the float64 factor decides (found by review: a ValueError escaped)."""
    rng = np.random.default_rng(4)
    b = rng.standard_normal((40, 39))
    g = b @ b.T  # exactly singular
    scale = 1.0 / np.sqrt(np.diag(g))
    cmat = np.zeros((1, 40))
    cmat[0, :20] = 1.0
    for added in (np.zeros(40), np.r_[np.ones(39), 0.0]):
        with_refined = factor_module.ConstrainedFactor.of_gram(g, added, scale, cmat, None, refined=True)
        without = factor_module.ConstrainedFactor.of_gram(g, added, scale, cmat, None, refined=False)
        assert (with_refined is None) == (without is None)
        assert with_refined is None or with_refined.kind == "dense"


@pytest.mark.parametrize("low, zeros", [(1e-4, 0), (1e2, 3)])
def test_the_spectrum_through_a_regularised_factor_is_not_masked_by_the_ridge(low, zeros):
    """Eigenvalues far below the ridge look alike through ``(G + ridge)^-1``: the estimate of an
    exact condition number of 1e5 was 1.1e4. Now within 3% (and exact zeros found), with the
    float64 and the refined factor alike."""
    n = 400
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    lam = np.r_[np.geomspace(1e6, low, n - zeros), np.zeros(zeros)]
    g = (q * lam) @ q.T
    g = 0.5 * (g + g.T)
    added = np.ones(n)
    scale = 1.0 / np.sqrt(np.diag(g) + added)
    none, null = np.zeros((0, n)), np.zeros((n, 0))
    for factor in (factor_module.ConstrainedFactor.of(scaled_double(g, scale, added), none, scale=scale),
                   factor_module.ConstrainedFactor.refined(g, added, scale, none)):
        sv, rank, cond = spectrum.spectrum_from_factor(g, null, factor, np.ones(n), ridge=1.0)
        assert rank == n - zeros
        assert cond == pytest.approx(np.sqrt(1e6 / low), rel=0.03) if not zeros else cond == float("inf")
