"""Nearest point of a coverage grid from a precomputed map of the sphere (issue 30).

A model's coverage is stored on a Fibonacci grid (:data:`rplearn.core.coverage.COVERAGE_GRID_POINTS`
points); reading it at a direction means finding the grid point nearest to it. A k-d tree
query per direction cost 3.5 us (a million directions: 3.5 s, eight times the pattern's own
evaluation there). Here the sphere is cut once into 1 x 1 degree cells of elevation and
azimuth, and each cell keeps the few grid points that can be nearest to any direction in it;
a query then compares the direction with its cell's candidates only (vectorised, no tree).

The candidates are complete by construction, not by sampling: for a cell with centre ``c``
whose every point lies within ``r`` of ``c``, and ``g_c`` the grid point nearest ``c``, the
grid point nearest any direction ``q`` of the cell lies within ``|q g_c| <= r + |c g_c|`` of
``q``, hence within ``2 r + |c g_c|`` of ``c``; every grid point within that angle of ``c``
is a candidate. ``r`` is bounded by half the cell's height plus half its width along its
widest parallel (a path along a meridian and a parallel is no shorter than the great circle).
The distance compared is the same squared chord a k-d tree compares, so the nearest point and
its chord are the tree's (a tie between two equidistant grid points aside).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from pykdtree.kdtree import KDTree

from rplearn.core.bases import fibonacci_grid_nodes
from rplearn.core.geometry import unit_vector

#: Cells per degree of elevation and of azimuth.
_CELLS_PER_DEG = 1
#: Directions compared at once (bounds the (directions, candidates) scratch arrays).
_QUERY_CHUNK = 16_384
#: Margin added to every bound [rad] (rounding of the angles).
_MARGIN_RAD = 1e-9


@lru_cache(maxsize=4)
def _cell_candidates(n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """The grid's coordinates by axis, shape (3, n_points + 1) (a far dummy point last), and
    per cell its candidates, shape (cells, width) (the dummy's index where a cell has fewer
    than the widest)."""
    az, el = fibonacci_grid_nodes(n_points)
    points = np.ascontiguousarray(unit_vector(az, el))
    tree = KDTree(points)
    n_el, n_az = 180 * _CELLS_PER_DEG, 360 * _CELLS_PER_DEG
    step = np.radians(1.0 / _CELLS_PER_DEG)
    el_lo = -np.pi / 2 + step * np.arange(n_el)
    el_mid = el_lo + step / 2
    az_mid = -np.pi + step * (np.arange(n_az) + 0.5)
    # widest parallel of each band: the one nearest the equator
    widest_cos = np.cos(np.minimum(np.abs(el_lo), np.abs(el_lo + step)) * (np.sign(el_lo) * np.sign(el_lo + step) > 0))
    radius = step / 2 + (step / 2) * widest_cos + _MARGIN_RAD  # per band: every point of a cell within it of its centre
    centres = np.ascontiguousarray(unit_vector(np.tile(az_mid, n_el), np.repeat(el_mid, n_az)))
    to_nearest, _ = tree.query(centres, k=1)
    nearest_rad = 2.0 * np.arcsin(np.clip(np.asarray(to_nearest) / 2.0, 0.0, 1.0))
    reach = np.minimum(2.0 * np.repeat(radius, n_az) + nearest_rad + _MARGIN_RAD, np.pi)
    bound = 2.0 * np.sin(reach / 2.0) * (1.0 + 1e-12)  # as a chord
    k = 16
    while True:
        dist, idx = tree.query(centres, k=k, distance_upper_bound=float(bound.max()))
        inside = np.asarray(dist) <= bound[:, None]
        if not inside[:, -1].any() or k >= n_points:  # no cell has more candidates than k
            break
        k = min(2 * k, n_points)
    width = int(inside.sum(axis=1).max())
    dummy = n_points
    cand = np.where(inside, idx, dummy)[:, :max(width, 1)].astype(np.int32)
    with_dummy = np.vstack([points, np.full((1, 3), 1e3)])
    # small tables that stay in the cache: coordinates by axis, candidates as 16-bit indices
    small = np.int16 if n_points < 2**15 else np.int32
    return np.ascontiguousarray(with_dummy.T), cand.astype(small)


def nearest_grid_point(n_points: int, az_rad: np.ndarray, el_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Chord to, and index of, the grid point nearest each direction.

    Parameters
    ----------
    n_points : int
        Points of the Fibonacci grid (:func:`rplearn.core.bases.fibonacci_grid_nodes`).
    az_rad, el_rad : ndarray
        Finite directions [rad], flattened; elevations in [-pi/2, pi/2].
    """
    coords, cand = _cell_candidates(int(n_points))
    az = np.asarray(az_rad, np.float64).ravel()
    el = np.asarray(el_rad, np.float64).ravel()
    q = unit_vector(az, el)
    per_deg = np.degrees(1.0) * _CELLS_PER_DEG
    n_el, n_az = 180 * _CELLS_PER_DEG, 360 * _CELLS_PER_DEG
    row = np.clip(np.floor((el + np.pi / 2) * per_deg), 0, n_el - 1).astype(np.intp)
    col = np.floor((np.mod(az + np.pi, 2 * np.pi)) * per_deg).astype(np.intp) % n_az
    cell = row * n_az + col
    chord = np.empty(az.size)
    index = np.empty(az.size, np.intp)
    for s in range(0, az.size, _QUERY_CHUNK):
        e = min(az.size, s + _QUERY_CHUNK)
        c = cand[cell[s:e]].astype(np.intp)
        d2 = np.subtract(q[s:e, 0, None], coords[0][c]) ** 2  # the squared chord, summed as a k-d tree does
        d2 += np.subtract(q[s:e, 1, None], coords[1][c]) ** 2
        d2 += np.subtract(q[s:e, 2, None], coords[2][c]) ** 2
        best = np.argmin(d2, axis=1)
        rows = np.arange(e - s)
        index[s:e] = c[rows, best]
        chord[s:e] = np.sqrt(d2[rows, best])
    return chord, index


__all__ = ["nearest_grid_point"]
