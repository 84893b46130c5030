"""The single-precision Cholesky factor with refined solves (rplearn.core.refined) and its use
by ConstrainedFactor: double-precision answers, and the float64 factor where single precision
cannot deliver them."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core import refined, spectrum
from rplearn.core.refined import RefinedCholesky, scaled_double, scaled_single


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
    factor = spectrum.ConstrainedFactor.refined(g, added, scale, none)
    b = np.random.default_rng(4).standard_normal(200)
    reference = spectrum.ConstrainedFactor.of(scaled_double(g, scale, added), none, scale=scale)
    if factor is None:
        factor = spectrum.ConstrainedFactor.of(scaled_double(g, scale, added), none, scale=scale)
    x = factor.solve_a(b)
    assert factor.kind == "dense"
    np.testing.assert_allclose(x, reference.solve_a(b), rtol=1e-12)


def test_a_solve_that_does_not_converge_switches_to_float64(monkeypatch):
    g = _gram(120, 1e2)
    added = np.full(120, 0.5)
    scale = 1.0 / np.sqrt(np.diag(g) + added)
    monkeypatch.setattr(refined, "MAX_STEPS", 0)  # no corrections allowed: float32 never suffices
    factor = spectrum.ConstrainedFactor.refined(g, added, scale, np.zeros((0, 120)))
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
    factor = spectrum.ConstrainedFactor.refined(g, added, scale, cmat)
    dense = spectrum.ConstrainedFactor.of(scaled_double(g, scale, added), cmat, scale=scale)
    np.testing.assert_allclose(factor.inverse(), dense.inverse(), rtol=1e-9, atol=1e-12 * np.abs(dense.inverse()).max())
