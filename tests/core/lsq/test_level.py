"""rplearn.core.lsq.level: the level a regularised solve shrinks toward is the data's own, so a
constant added to every observation shifts every prediction by it, on the small (KKT) and the
large (Cholesky, single precision refined) paths, under every gauge (issue 24, item 3)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import make_basis
from rplearn.core.gauge import Gauge
from rplearn.core.geometry import Directions
from rplearn.core.lsq import solver, solver_large
from rplearn.core.lsq.level import constant_coefficients, pattern_shape, shrink_target
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection import penalty_scale, penalty_vector


def _samples(n_nodes, links=None, n=6000, seed=1):
    rng = np.random.default_rng(seed)
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), np.arcsin(rng.uniform(-0.9, 0.9, (2, n)))
    if links:
        pick = rng.integers(0, len(links), n)
        tx, rx = np.array([links[i][0] for i in pick]), np.array([links[i][1] for i in pick])
    else:
        tx = rng.integers(0, n_nodes, n)
        rx = (tx + rng.integers(1, n_nodes, n)) % n_nodes
    y = rng.normal(size=n) + 3.0 * np.sin(el[0]) - 40.0
    return Directions(az[0], el[0], az[1], el[1]), tx, rx, y


def _joint(basis, coef, d, tx, rx):
    """Joint gain every sample's link predicts."""
    ft, fr = basis.design(d.az_tx, d.el_tx), basis.design(d.az_rx, d.el_rx)
    return np.einsum("ij,ij->i", ft, coef[tx]) + np.einsum("ij,ij->i", fr, coef[rx])


@pytest.mark.parametrize("path", ["small", "large", "large-refined"])
@pytest.mark.parametrize("n_nodes,gauge,links", [
    (2, "equal-mean", None),
    (3, "equal-mean", None),  # a triangle: the level of each node is identified, no gauge
    (2, {"node": "1", "mean_gain_dbi": 2.0}, None),  # a stated level
    (4, "equal-mean", [(0, 1), (2, 3)]),  # two bipartite components
])
@pytest.mark.parametrize("with_prior", [False, True])
def test_a_constant_added_to_every_observation_only_shifts_the_predictions(monkeypatch, path, n_nodes, gauge, links,
                                                                              with_prior):
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 10**9 if path == "small" else 0)
    monkeypatch.setattr(solver_large, "REFINED_COLUMNS", 0 if path == "large-refined" else 10**9)
    basis = make_basis("sh", 5)
    d, tx, rx, y = _samples(n_nodes, links)
    prior = np.random.default_rng(3).normal(0.0, 3.0, n_nodes * basis.n_coef) + 20.0 if with_prior else None
    sols = []
    for shift in (0.0, 87.5, -60.0):
        normal = NormalEquations(basis, n_nodes).add(d, tx, rx, y + shift)
        penalty = penalty_vector(basis, n_nodes, 1e-2, penalty_scale(normal.gram), 0.0 if with_prior else 2.0)
        sols.append(solver.solve(normal, gauge=gauge, ridge=50.0, penalty=penalty, penalty_target=prior))
    base = _joint(basis, sols[0].coef, d, tx, rx)
    for shift, sol in zip((87.5, -60.0), sols[1:]):
        np.testing.assert_allclose(_joint(basis, sol.coef, d, tx, rx) - shift, base, rtol=0, atol=1e-6)
        np.testing.assert_allclose(sol.covariance, sols[0].covariance, rtol=1e-6, atol=1e-12)
        assert sol.report.rmse_db == pytest.approx(sols[0].report.rmse_db, rel=1e-6)
        if isinstance(gauge, dict):  # the stated level is kept
            np.testing.assert_allclose(sol.coef[1] @ basis.sphere_mean, 2.0, atol=1e-9)


def test_the_constant_function_is_one_everywhere():
    rng = np.random.default_rng(0)
    az, el = rng.uniform(-np.pi, np.pi, 50), np.arcsin(rng.uniform(-1, 1, 50))
    for kind, order, tol in (("sh", 4, 1e-12), ("poly", 3, 1e-12), ("bg", 7, 1e-2)):  # BG: only approximately
        basis = make_basis(kind, order)
        np.testing.assert_allclose(basis.evaluate(constant_coefficients(basis), az, el), 1.0, atol=tol)


def test_the_target_is_the_prior_shape_plus_the_least_squares_constants():
    """Each node's constant is the least-squares fit to what the prior's shape leaves of the
    data (from the statistics alone), and a given gauge holds."""
    basis = make_basis("sh", 3)
    p = basis.n_coef
    d, _, _, y = _samples(3, n=400, seed=4)
    tx = np.zeros(400, int)
    rx = np.array([1, 2] * 200)  # node 0 to 1 and 2, 1 and 2 never linked: bipartite
    prior = np.random.default_rng(0).normal(0.0, 2.0, 3 * p)
    normal = NormalEquations(basis, 3).add(d, tx, rx, y)
    shape = pattern_shape(prior, basis, 3)
    np.testing.assert_allclose(shape.reshape(3, p) @ basis.sphere_mean, 0.0, atol=1e-12)
    components = solver.link_components(3, normal.link_counts.keys())
    cmat, cval, _ = solver._gauge_constraints(basis, 3, ["0", "1", "2"], components, Gauge("0", 1.5))
    target = shrink_target(normal.gram, normal.rhs, basis, 3, prior, (cmat, cval), components)
    level = (target - shape).reshape(3, p)
    np.testing.assert_allclose(level[:, 1:], 0.0, atol=1e-12)  # only the constants
    k = level[:, 0] / np.sqrt(4.0 * np.pi)  # Y_00 = 1 / sqrt(4 pi)
    assert k[0] == pytest.approx(1.5)  # the gauge's stated level
    residual = y - _joint(basis, shape.reshape(3, p), d, tx, rx) - (k[tx] + k[rx])
    for node in (1, 2):  # least squares for the constants the gauge leaves free
        assert residual[rx == node].mean() == pytest.approx(0.0, abs=1e-9)
