"""The coverage map (issue 30) finds the k-d tree's nearest grid point and chord."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.coverage import COVERAGE_GRID_POINTS, _grid_tree, _query, coverage_at, coverage_grid
from rplearn.core.coverage_map import nearest_grid_point
from rplearn.core.geometry import unit_vector
from rplearn.errors import InputError


@pytest.mark.parametrize("n_points", [COVERAGE_GRID_POINTS, 500])
def test_the_map_finds_the_trees_nearest_point_everywhere(n_points):
    rng = np.random.default_rng(7)
    az = np.r_[rng.uniform(-np.pi, np.pi, 200_000), rng.uniform(-np.pi, np.pi, 20_000), [np.pi, -np.pi, 0.0, 2.0, -3.0]]
    el = np.r_[np.arcsin(rng.uniform(-1, 1, 200_000)), np.pi / 2 - rng.uniform(0, 0.05, 20_000),
               [0.0, 0.0, np.pi / 2, -np.pi / 2, -np.pi / 2 + 1e-12]]
    chord, idx = nearest_grid_point(n_points, az, el)
    want_chord, want_idx = _query(_grid_tree(n_points), unit_vector(az, el))
    assert np.array_equal(idx, want_idx)
    assert np.array_equal(chord, np.asarray(want_chord))


def test_coverage_reads_the_same_and_refuses_nan():
    rng = np.random.default_rng(1)
    grid = coverage_grid(rng.uniform(-1, 1, 500), rng.uniform(-0.5, 0.5, 500))
    az, el = rng.uniform(-np.pi, np.pi, 1000), np.arcsin(rng.uniform(-1, 1, 1000))
    chord, idx = _query(_grid_tree(grid.size), unit_vector(az, el))
    want = grid[idx] + np.degrees(2.0 * np.arcsin(np.clip(np.asarray(chord) / 2.0, 0.0, 1.0)))
    assert np.array_equal(coverage_at(grid, az, el), want)
    assert coverage_at(grid, 0.3, np.pi / 2 + 0.2).shape == (1,)  # beyond the pole: the tree answers
    with pytest.raises(InputError, match="1 query direction"):
        coverage_at(grid, np.array([0.0, np.nan]), np.array([0.0, 0.0]))
