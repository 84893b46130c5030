"""The large-system path of the solver (issue 13, item 1): Cholesky instead of the KKT inverse,
an estimated spectrum instead of a full eigendecomposition; the same solution."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import make_basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq import solver, solver_large
from rplearn.core.lsq.normal_equations import NormalEquations


@pytest.fixture(autouse=True, params=["float64", "refined"])
def factor_precision(request, monkeypatch):
    """Every test runs with the float64 factor and with the single-precision factor and refined
    solves (which large dense systems use, :data:`rplearn.core.lsq.solver_large.REFINED_COLUMNS`)."""
    monkeypatch.setattr(solver_large, "REFINED_COLUMNS", 0 if request.param == "refined" else 10**9)
    return request.param


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


def test_large_path_with_link_offsets_and_a_penalty_gives_the_small_paths_solution(monkeypatch):
    """Shared columns (one offset per two-way link) are unridged and scaled for the report; a
    smoothness penalty takes the estimate without the factor: both as the KKT path."""
    from rplearn.core.lsq.selection import penalty_vector

    normal = _statistics(3, 6, n=20000).with_shared(_statistics(3, 6, n=20000).two_way_links())
    penalty = penalty_vector(normal.basis, 3, 1e-3, 1e3)
    for pen in (None, penalty):
        monkeypatch.setattr(solver, "LARGE_COLUMNS", 10**9)
        small = solver.solve(normal, penalty=pen)
        monkeypatch.setattr(solver, "LARGE_COLUMNS", 0)
        large = solver.solve(normal, penalty=pen)
        np.testing.assert_allclose(large.coef, small.coef, atol=1e-10)
        np.testing.assert_allclose(large.shared_coef, small.shared_coef, atol=1e-10)
        np.testing.assert_allclose(large.shared_unexplained, small.shared_unexplained, atol=1e-10)
        np.testing.assert_allclose(large.covariance, small.covariance, atol=1e-10 * np.abs(small.covariance).max())
        assert large.report.rank == small.report.rank
        assert large.report.condition_number == pytest.approx(small.report.condition_number, rel=0.03)


def test_the_large_covariance_is_formed_only_when_read(monkeypatch):
    normal = _statistics(2, 8)
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 0)
    sol = solver.solve(normal)
    assert sol.covariance_matrix is None and sol.covariance_fn is not None
    cov = sol.covariance
    assert cov.shape == (normal.n_columns, normal.n_columns)
    assert sol.covariance_matrix is cov and sol.covariance_fn is None and sol.covariance is cov


@pytest.mark.parametrize("shape, kind", [("ring", "banded"), ("star", "sparse"), ("ring+offsets", "sparse")])
def test_a_swarm_whose_drones_link_to_few_others_is_factorised_sparse_with_the_same_solution(shape, kind, monkeypatch):
    """24 drones on a ring, each linked to its two neighbours: a band once the nodes are
    reordered; 12 drones around a hub (a star), or the ring with link offset columns
    (full rows): a general sparse factor. The solution, covariance and rank equal the exact
    path's either way."""
    from rplearn.core.lsq import factor
    from rplearn.core.lsq.node_blocks import NodeBlocks

    if shape == "star":
        links = [(0, k) for k in range(1, 12)] + [(k, 0) for k in range(1, 12)]
        normal = _statistics(12, 4, links, n=20000)
    else:
        links = [(k, (k + 1) % 24) for k in range(24)] + [((k + 1) % 24, k) for k in range(24)]
        normal = _statistics(24, 4, links, n=20000)
        if shape == "ring+offsets":  # one offset column per link: full rows, no band
            normal = normal.with_shared(normal.two_way_links())
    assert NodeBlocks.of(normal.n_nodes, normal.basis.n_coef, normal.link_counts).fraction <= factor.SPARSE_BLOCK_FRACTION
    made = []
    real = factor.ConstrainedFactor.__init__
    monkeypatch.setattr(factor.ConstrainedFactor, "__init__",
                        lambda self, *a: (real(self, *a), made.append(self.kind))[0])
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 10**9)
    small = solver.solve(normal)
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 0)
    large = solver.solve(normal)
    assert made == [kind]  # sparse layouts are never refined
    np.testing.assert_allclose(large.coef, small.coef, atol=1e-10)
    np.testing.assert_allclose(large.covariance, small.covariance, atol=1e-10 * np.abs(small.covariance).max())
    assert large.report.rank == small.report.rank
    assert large.report.condition_number == pytest.approx(small.report.condition_number, rel=0.03)


def test_free_directions_beyond_the_gauge_are_decided_by_the_ridge_with_a_warning_as_on_the_kkt_path(monkeypatch):
    """A node seen at one elevation only: rank-deficient, but the ridge makes the system solvable;
    the large path solves and warns like the small one (found by review: it used to refuse)."""
    rng = np.random.default_rng(3)
    basis = make_basis("sh", 4)
    n = 6000
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = rng.uniform(-1.5, 1.5, (2, n))
    tx = rng.integers(0, 4, n)
    rx = (tx + 1 + rng.integers(0, 3, n)) % 4
    el[0, tx == 0] = 0.3
    el[1, rx == 0] = 0.3
    normal = NormalEquations(basis, 4).add(Directions(az[0], el[0], az[1], el[1]), tx, rx, rng.normal(size=n))
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 10**9)
    small = solver.solve(normal)
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 0)
    large = solver.solve(normal)
    assert large.report.rank == small.report.rank < normal.n_columns - large.report.expected_null_dim
    assert any("not identified" in w for w in large.report.warnings)
    np.testing.assert_allclose(large.coef, small.coef, atol=1e-8)


@pytest.mark.parametrize("n, rows", [(7, 3), (300, 256), (5, 256)])
def test_symmetric_from_lower_mirrors_the_lower_triangle(n, rows):
    from rplearn.core.lsq.factor import symmetric_from_lower

    x = np.random.default_rng(n).standard_normal((n, n))
    low = np.tril(x)
    expected = low + np.tril(x, -1).T
    for layout in ("C", "F"):
        got = symmetric_from_lower(np.array(x, order=layout), rows=rows)
        np.testing.assert_array_equal(got, expected)


def test_the_large_covariance_is_exactly_symmetric(monkeypatch):
    normal = _statistics(3, 6)
    monkeypatch.setattr(solver, "LARGE_COLUMNS", 0)
    cov = solver.solve(normal).covariance
    assert np.array_equal(cov, cov.T) and np.all(np.diag(cov) > 0)
