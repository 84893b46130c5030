"""The large-system path of the solver (issue 13, item 1): Cholesky instead of the KKT inverse,
an estimated spectrum instead of a full eigendecomposition; the same solution."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core import solver
from rplearn.core.bases import make_basis
from rplearn.core.geometry import Directions
from rplearn.core.normal_equations import NormalEquations


def _statistics(n_nodes, order, links=None, n=30000, seed=1):
    rng = np.random.default_rng(seed)
    basis = make_basis("sh", order)
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), rng.uniform(-1.5, 1.5, (2, n))
    if links:
        pick = rng.integers(0, len(links), n)
        tx = np.array([links[i][0] for i in pick])
        rx = np.array([links[i][1] for i in pick])
    else:
        tx = rng.integers(0, n_nodes, n)
        rx = (tx + rng.integers(1, n_nodes, n)) % n_nodes
    y = rng.normal(size=n) + np.sin(el[0])
    return NormalEquations(basis, n_nodes).add(Directions(az[0], el[0], az[1], el[1]), tx, rx, y)


@pytest.mark.parametrize("n_nodes,order,gauge,links", [
    (2, 8, "equal-mean", None),
    (3, 6, "equal-mean", None),  # a triangle: no gauge
    (2, 6, {"node": "1", "mean_gain_dbi": 2.0}, None),  # a stated level: the constraint's value is not 0
    (4, 5, "equal-mean", [(0, 1), (2, 3)]),  # two bipartite components, two gauges
])
def test_large_path_gives_the_small_paths_solution(monkeypatch, n_nodes, order, gauge, links):
    normal = _statistics(n_nodes, order, links)
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 10**9)
    small = solver.solve(normal, gauge=gauge)
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 0)
    large = solver.solve(normal, gauge=gauge)
    np.testing.assert_allclose(large.coef, small.coef, atol=1e-10)
    np.testing.assert_allclose(large.covariance, small.covariance, atol=1e-10 * np.abs(small.covariance).max())
    assert large.report.rank == small.report.rank
    assert large.report.expected_null_dim == small.report.expected_null_dim
    assert large.report.condition_number == pytest.approx(small.report.condition_number, rel=0.03)


def test_spectrum_estimate_finds_free_directions_beyond_the_gauge():
    """Two nodes, every sample at one elevation: far more free directions than the one gauge."""
    rng = np.random.default_rng(2)
    basis = make_basis("sh", 5)
    n = 5000
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = np.zeros((2, n))
    normal = NormalEquations(basis, 2).add(Directions(az[0], el[0], az[1], el[1]), np.zeros(n, int), np.ones(n, int),
                                           rng.normal(size=n))
    exact = solver.spectrum_report(normal.gram)
    null = solver.null_directions(basis, 2, solver.link_components(2, normal.link_counts), normal.n_columns)
    sv, rank, cond = solver.spectrum_estimate(normal.gram, null)
    assert rank == exact[1] < normal.n_columns - 1
    assert cond == float("inf")
