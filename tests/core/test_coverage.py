"""rplearn.core.coverage: the angle to the nearest learning direction, the covered fraction of
the sphere, and the coverage grid a model stores (issue 11, item 3)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import fibonacci_grid_nodes
from rplearn.core.coverage import coverage_at, coverage_grid, covered_fraction, nearest_angle_deg
from rplearn.core.geometry import great_circle_angle


def random_directions(rng, n):
    return rng.uniform(-np.pi, np.pi, n), np.arcsin(rng.uniform(-1, 1, n))


def test_nearest_angle_equals_brute_force():
    rng = np.random.default_rng(0)
    la, le = random_directions(rng, 300)
    qa, qe = random_directions(rng, 50)
    brute = np.degrees([great_circle_angle(a, e, la, le).min() for a, e in zip(qa, qe)])
    np.testing.assert_allclose(nearest_angle_deg(qa, qe, la, le), brute, atol=1e-6)


def test_covered_fraction_of_a_cap():
    az, el = fibonacci_grid_nodes(20_000)
    cap = el > np.radians(60.0)  # a cap of 30 deg radius: (1 - cos 30) / 2 = 6.7% of the sphere
    f = covered_fraction(az[cap], el[cap], within_deg=2.0)
    assert f == pytest.approx((1 - np.cos(np.radians(32.0))) / 2, abs=0.005)


def test_a_grid_accumulates_chunk_by_chunk_and_bounds_the_true_angle():
    rng = np.random.default_rng(1)
    la, le = random_directions(rng, 400)
    whole = coverage_grid(la, le)
    chunked = coverage_grid(la[200:], le[200:], coverage_grid(la[:200], le[:200]))
    np.testing.assert_allclose(chunked, whole)
    qa, qe = random_directions(rng, 500)
    exact = nearest_angle_deg(qa, qe, la, le)
    bound = coverage_at(whole, qa, qe)
    assert np.all(bound >= exact - 1.2) and np.all(bound <= exact + 3.0)  # within the grid spacing


def test_non_finite_directions_are_refused():
    import numpy as np
    import pytest

    from rplearn.core.coverage import coverage_at, coverage_grid, nearest_angle_deg
    from rplearn.errors import InputError

    with pytest.raises(InputError, match="1 query direction"):
        nearest_angle_deg([0.0, np.nan], [0.0, 0.0], [0.1], [0.2])
    with pytest.raises(InputError, match="1 learning direction"):
        nearest_angle_deg([0.0], [0.0], [0.1, np.nan], [0.2, 0.0])
    with pytest.raises(InputError):
        coverage_grid(np.array([np.nan, 0.1]), np.array([0.0, 0.2]))
    grid = coverage_grid(np.array([0.1]), np.array([0.2]))
    with pytest.raises(InputError):
        coverage_at(grid, [np.nan], [0.0])


def test_the_grid_is_the_angle_to_the_nearest_occupied_cell_by_brute_force():
    """The stored grid: each direction is replaced by its nearest grid point (its cell), and each
    grid point gets the angle to the nearest such point; occupied points are at exactly 0."""
    from rplearn.core.coverage import COVERAGE_GRID_POINTS

    rng = np.random.default_rng(7)
    az = np.concatenate([rng.normal(0.3, 0.4, 150), rng.uniform(-np.pi, np.pi, 50)])
    el = np.concatenate([rng.uniform(-0.4, 0.2, 150), np.arcsin(rng.uniform(-1, 1, 50))])
    gaz, gel = fibonacci_grid_nodes(COVERAGE_GRID_POINTS)
    g = np.stack([np.cos(gel) * np.cos(gaz), np.cos(gel) * np.sin(gaz), np.sin(gel)], axis=1)
    q = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=1)
    cells = np.unique(np.argmin(((q[:, None, :] - g[None, :, :]) ** 2).sum(axis=2), axis=1))
    brute = np.degrees(np.min(np.arccos(np.clip(g @ g[cells].T, -1.0, 1.0)), axis=1))
    grid = coverage_grid(az, el)
    assert np.all(grid[cells] == 0.0) and np.count_nonzero(grid == 0.0) == cells.size
    np.testing.assert_allclose(grid, brute, atol=1e-5)
