"""Direction-cell sums: pattern structure a fixed-order fit cannot represent, in the manoeuvre posterior.

A pattern fit of a fixed order learns each node's gain up to that order; the rest of the true
pattern (narrow lobes of screws, cables and guards, the fine structure of a sharp beam) is a
*misfit* that stays where it is: looking at a direction again does not average it out, as it
does the fading. Where a flight looks at few directions many times, the fit takes the misfit
it sees there for pattern and carries it to the directions around (aliasing); a flight that
spreads the same packets over many directions averages it out. The white-noise posterior sees
only the packet count and so prefers the first.

The model here: each node's misfit is an offset ``r_{k,c}`` per *direction cell* ``c`` (the
points of a Fibonacci grid of :data:`CELLS_PER_COEF` times the basis's coefficients per node,
every direction in the cell of its nearest point: cells about the size of the finest structure
the basis resolves), independent between cells and nodes, of variance ``s_m^2``. A sample of
link ``{a, b}`` carries ``r_{a, c_a} + r_{b, c_b}``. The penalised estimate ``beta = A^-1 X^T y``
then has the extra covariance ``s_m^2 A^-1 V V^T A^-1`` with ``V`` the features summed per
(node, cell): the columns :class:`DirectionCells` keeps (memory fixed: one row per node and
cell). A manoeuvre adds its own cells' sums (:mod:`rplearn.analysis.manoeuvre_posterior`);
they are taken as new cells (a manoeuvre that looks again at directions seen earlier is
credited as if its misfit there were fresh: a lower bound on the misfit's share, never above
the white part's credit).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.core.bases import fibonacci_grid_nodes
from rplearn.core.basis_base import Basis
from rplearn.errors import InputError

#: Direction cells per basis coefficient of a node (the misfit's correlation scale).
CELLS_PER_COEF = 2
_CHUNK = 8192


@check_types
def cell_grid(n_coef: int) -> np.ndarray:
    """Unit vectors (ENU-like body frame, shape ``(n_cells, 3)``) of the cells' centres for a
    basis of ``n_coef`` coefficients per node."""
    if int(n_coef) < 1:
        raise InputError(f"n_coef: expected at least 1, got {n_coef!r}", param="n_coef")
    az, el = fibonacci_grid_nodes(max(CELLS_PER_COEF * int(n_coef), 16))
    return np.column_stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])


def cell_index(az_rad: Any, el_rad: Any, grid: np.ndarray) -> np.ndarray:
    """The cell (nearest grid point) of each direction."""
    az, el = np.asarray(az_rad, np.float64).ravel(), np.asarray(el_rad, np.float64).ravel()
    u = np.column_stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    out = np.empty(u.shape[0], np.intp)
    for s in range(0, u.shape[0], _CHUNK):
        out[s:s + _CHUNK] = np.argmax(u[s:s + _CHUNK] @ grid.T, axis=1)
    return out


def cell_sums(rows: np.ndarray, ends: tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...], grid: np.ndarray,
              weight: float = 1.0) -> np.ndarray:
    """``weight`` times the rows summed per (node, cell) of each end, as columns ``(P, cells hit)``.

    ``ends``: per link end ``(node index per row, az, el)``; a row goes into the cell of each end.
    """
    n_cells = grid.shape[0]
    keys = np.concatenate([idx * n_cells + cell_index(az, el, grid) for idx, az, el in ends])
    both = np.concatenate([rows] * len(ends))
    uniq, inv = np.unique(keys, return_inverse=True)
    out = np.zeros((uniq.size, rows.shape[1]))
    np.add.at(out, inv, both)
    return np.asarray(weight * out.T, np.float64)


@check_types
class DirectionCells:
    """The features of a flight's samples summed per node and direction cell (module docstring).

    Parameters
    ----------
    basis : Basis
        The basis of the statistics followed (pattern columns first, one block per node).
    n_nodes : int
        Nodes of the statistics.
    """

    def __init__(self, basis: Basis, n_nodes: int) -> None:
        if int(n_nodes) < 2:
            raise InputError(f"n_nodes: expected 2 or more, got {n_nodes!r}", param="n_nodes")
        self.basis = basis
        self.n_nodes = int(n_nodes)
        self.grid = cell_grid(basis.n_coef)
        p = basis.n_coef
        self.sums = np.zeros((self.n_nodes * self.grid.shape[0], self.n_nodes * p))
        self.n_samples = 0

    def add(self, directions: Any, tx_index: Any, rx_index: Any) -> DirectionCells:
        """Take samples: their link directions (``az_tx, el_tx, az_rx, el_rx`` [rad]) and node indices."""
        ti, ri = np.asarray(tx_index, np.intp).ravel(), np.asarray(rx_index, np.intp).ravel()
        d = directions
        if ti.size != np.asarray(d.az_tx).size or ri.size != ti.size:
            raise InputError("directions, tx_index and rx_index: expected one entry per sample", param="directions")
        if ti.size and (min(ti.min(), ri.min()) < 0 or max(ti.max(), ri.max()) >= self.n_nodes):
            raise InputError(f"tx_index/rx_index: expected node indices below {self.n_nodes}", param="tx_index")
        p, n_cells = self.basis.n_coef, self.grid.shape[0]
        for s in range(0, ti.size, _CHUNK):
            sl = slice(s, s + _CHUNK)
            t, r = ti[sl], ri[sl]
            rows = np.zeros((t.size, self.n_nodes * p))
            ft = self.basis.design(np.asarray(d.az_tx)[sl], np.asarray(d.el_tx)[sl])
            fr = self.basis.design(np.asarray(d.az_rx)[sl], np.asarray(d.el_rx)[sl])
            for k in range(self.n_nodes):
                rows[t == k, k * p:(k + 1) * p] += ft[t == k]
                rows[r == k, k * p:(k + 1) * p] += fr[r == k]
            for idx, az, el in ((t, np.asarray(d.az_tx)[sl], np.asarray(d.el_tx)[sl]),
                                (r, np.asarray(d.az_rx)[sl], np.asarray(d.el_rx)[sl])):
                np.add.at(self.sums, idx * n_cells + cell_index(az, el, self.grid), rows)
        self.n_samples += int(ti.size)
        return self

    def factor(self) -> np.ndarray:
        """``V``: the visited cells' feature sums as columns, shape ``(n_nodes * n_coef, cells)``."""
        hit = np.any(self.sums != 0.0, axis=1)
        return np.asarray(self.sums[hit].T, np.float64)


__all__ = ["DirectionCells", "cell_grid"]
