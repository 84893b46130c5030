"""The posterior the next-best manoeuvre ranking reads, and its rank-k update by a manoeuvre.

The pattern covariance is ``Sigma = sigma^2 A^-1 + D D^T``: the white-noise posterior
(``A = X^T X + P`` in the units of ``X^T X``) and the part an error drifting over seconds
leaves (:mod:`rplearn.core.lsq.block_sums`: ``s_c^2 A^-1 C A^-1``, ``C = sum_b v_b v_b^T`` over
time blocks), kept as a factor ``D = (s_c / sigma^2) Sigma_w C^1/2`` (``Sigma_w = sigma^2
A^-1``); without a drifting error ``D`` has no columns and the posterior is the white one.

A manoeuvre adds the feature rows ``F`` (``weight`` packets each). Its white part is the
Woodbury update ``Sigma_w' = Sigma_w - B^T S^-1 B`` (``B = F Sigma_w``; more rows than columns
first compressed to the triangular factor of ``F^T F``). Its drifting part keeps the old blocks'
columns, mapped through the new ``A'^-1`` (``D' = D - B^T S^-1 F D``), and appends one column per
time block of the manoeuvre (``correlation rows`` consecutive rows): ``(s_c / sigma^2)
Sigma_w' u_j`` with ``u_j = weight * sum of the block's rows``. Each node's spread is
``sqrt(sum(M_k * Sigma_kk))``, from the diagonal blocks only.

The pattern misfit a fixed order cannot represent (:mod:`rplearn.analysis.manoeuvre_cells`:
an offset per node and direction cell, of variance ``s_m^2``) enters the same factor: the
flight's cells ``s_m A^-1 V`` (:meth:`ManoeuvrePosterior.with_misfit`), and a manoeuvre's own cells
(``weight`` times its rows summed per node and cell) appended like its time blocks.
"""

from __future__ import annotations

import numpy as np

from rplearn.analysis.manoeuvre_cells import cell_sums
from rplearn.core.lsq.products import spd_inverse
from rplearn.errors import InputError

#: Per link end of a manoeuvre's rows: (node index per row, az [rad], el [rad]); None: not given.
Ends = tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...] | None


def psd_factor(matrix: np.ndarray, rtol: float = 1e-12) -> np.ndarray:
    """``F`` with ``F F^T = matrix`` (symmetric positive semi-definite), columns of the
    eigenvalues above ``rtol`` times the largest only; a matrix with a NaN or infinite entry
    raises :class:`~rplearn.errors.InputError`."""
    if not np.isfinite(matrix).all():
        raise InputError(f"matrix: a {matrix.shape[0]}x{matrix.shape[-1]} covariance to factor has NaN or infinite "
                         "entries (statistics with a non-finite value)", param="matrix")
    sym = 0.5 * (matrix + matrix.T)
    try:
        values, vectors = np.linalg.eigh(sym)
    except np.linalg.LinAlgError:
        # LAPACK's eigensolver can fail to converge on a finite matrix; the SVD then gives the singular
        # values, which are the eigenvalues for a PSD matrix (for an indefinite one their absolute
        # values: a negative eigenvalue is then kept as positive)
        vectors, values, _ = np.linalg.svd(sym)
        values, vectors = values[::-1], vectors[:, ::-1]
    top = float(values[-1]) if values.size else 0.0
    keep = values > rtol * max(top, 0.0) if top > 0 else np.zeros(values.size, bool)
    return np.asarray(vectors[:, keep] * np.sqrt(values[keep]), np.float64)


class ManoeuvrePosterior:
    """The pattern posterior's covariance and the per-node spread read from it (module docstring).

    Parameters
    ----------
    precision : ndarray
        ``A / sigma^2`` over the pattern columns.
    metrics : list of ndarray
        Per node, the second moment of the mean-removed design over its target directions.
    noise_var : float
        ``sigma^2`` [dB^2].
    """

    def __init__(self, precision: np.ndarray, metrics: list[np.ndarray], noise_var: float) -> None:
        self.noise_var = noise_var
        self.metrics = metrics
        self.p = metrics[0].shape[0]
        self.cov = spd_inverse(precision)
        self.drift = np.zeros((self.cov.shape[0], 0))
        self.drift_scale = 0.0
        self.block_rows = 0
        self.misfit_scale = 0.0
        self.grid: np.ndarray | None = None

    def with_drift(self, correlated_var: float, cross: np.ndarray | None, block_rows: int) -> ManoeuvrePosterior:
        """Add the drifting error: block-offset variance ``s_c^2`` [dB^2], the blocks' ``C`` so
        far (None: none yet) and the feature rows per time block of a manoeuvre."""
        if correlated_var > 0:
            self.drift_scale = float(np.sqrt(correlated_var)) / self.noise_var
            self.block_rows = max(int(block_rows), 1)
            if cross is not None and np.any(cross):
                self.drift = np.hstack([self.drift, self.drift_scale * (self.cov @ psd_factor(cross))])
                if self.drift.shape[1] > self.drift.shape[0]:
                    self.drift = psd_factor(self.drift @ self.drift.T)
        return self

    def with_prior_excess(self, excess: float, prior_diag: np.ndarray) -> ManoeuvrePosterior:
        """Add ``sigma^2 * excess * A^-1 P A^-1``: the prior's variance taken ``1 + excess`` times
        what the penalty ``P`` (diagonal, units of ``X^T X``) and the noise imply, the noise part
        left as it is (the fit keeps its penalty; the error it leaves where the data are thin is
        the larger prior's)."""
        if excess > 0:
            cols = (float(np.sqrt(excess)) / float(np.sqrt(self.noise_var))) * (self.cov * np.sqrt(np.asarray(prior_diag, np.float64))[None, :])
            self.drift = np.hstack([self.drift, cols])
            if self.drift.shape[1] > self.drift.shape[0]:
                self.drift = psd_factor(self.drift @ self.drift.T)
        return self

    def with_misfit(self, misfit_var: float, cells: np.ndarray | None, grid: np.ndarray) -> ManoeuvrePosterior:
        """Add the misfit fixed per direction cell: its variance ``s_m^2`` [dB^2] per node and
        cell, the flight's cell sums ``V`` so far (None: none yet) and the cells' grid."""
        if misfit_var > 0:
            self.misfit_scale = float(np.sqrt(misfit_var)) / self.noise_var
            self.grid = grid
            if cells is not None and cells.shape[1]:
                self.drift = np.hstack([self.drift, self.misfit_scale * (self.cov @ cells)])
                if self.drift.shape[1] > self.drift.shape[0]:
                    self.drift = psd_factor(self.drift @ self.drift.T)
        return self

    def _node_vars(self, cov: np.ndarray, drift: np.ndarray) -> np.ndarray:
        p = self.p
        out = []
        for k, m in enumerate(self.metrics):
            var = float(np.sum(m * cov[k * p:(k + 1) * p, k * p:(k + 1) * p]))
            if drift.shape[1]:
                g = drift[k * p:(k + 1) * p]
                var += float(np.sum((m @ g) * g))
            out.append(var)
        return np.array(out)

    def spreads(self, cov: np.ndarray | None = None) -> np.ndarray:
        """Each node's spread now (``cov``: of that white covariance instead, no drift)."""
        if cov is not None:
            return np.sqrt(np.maximum(self._node_vars(cov, np.zeros((cov.shape[0], 0))), 0.0))
        return np.sqrt(np.maximum(self._node_vars(self.cov, self.drift), 0.0))

    def _woodbury(self, rows: np.ndarray, weight: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(F, B, S^-1 B)`` of the update ``Sigma' = Sigma - B^T S^-1 B`` with ``B = F Sigma``; more
        rows than columns are first compressed to the triangular factor of ``F^T F`` (same update)."""
        if rows.shape[0] > rows.shape[1]:
            rows = np.asarray(np.linalg.qr(rows, mode="r"), np.float64)
        b = rows @ self.cov
        s = b @ rows.T + np.eye(rows.shape[0]) * (self.noise_var / weight)
        return rows, b, np.linalg.solve(s, b)

    def _drift_after(self, rows: np.ndarray, weight: float, parts: tuple[np.ndarray, np.ndarray, np.ndarray],
                     ends: Ends = None) -> np.ndarray:
        """``D'`` after the update (module docstring); ``rows`` uncompressed, ``parts`` of
        :meth:`_woodbury`, ``ends`` the rows' (node index, az, el) of each link end (for the misfit)."""
        cols = []
        if self.drift_scale > 0:
            starts = np.arange(0, rows.shape[0], self.block_rows)
            cols.append(self.drift_scale * (weight * np.add.reduceat(rows, starts, axis=0).T))  # (columns, blocks)
        if self.misfit_scale > 0 and ends is not None and self.grid is not None:
            cols.append(self.misfit_scale * cell_sums(rows, ends, self.grid, weight))
        if not cols and not self.drift.shape[1]:
            return self.drift
        small, b, sb = parts
        old = self.drift - sb.T @ (small @ self.drift) if self.drift.shape[1] else self.drift
        if not cols:
            return old
        u = np.hstack(cols)
        return np.hstack([old, self.cov @ u - sb.T @ (b @ u)])

    def updated(self, rows: np.ndarray, weight: float) -> np.ndarray:
        """The white covariance after ``weight`` packets per feature row ``rows`` (rank-k update)."""
        if rows.shape[0] == 0:
            return self.cov
        _, b, sb = self._woodbury(rows, weight)
        return self.cov - b.T @ sb

    def update(self, rows: np.ndarray, weight: float, ends: Ends = None) -> None:
        """Take the manoeuvre's rows into the posterior (white part, drift and misfit)."""
        if rows.shape[0] == 0:
            return
        parts = self._woodbury(rows, weight)
        drift = self._drift_after(rows, weight, parts, ends)
        self.cov = self.cov - parts[1].T @ parts[2]
        if drift.shape[1] > drift.shape[0]:  # keep it at most square: the same D D^T
            drift = psd_factor(drift @ drift.T)
        self.drift = drift

    def spreads_after(self, rows: np.ndarray, weight: float, ends: Ends = None) -> np.ndarray:
        """:meth:`spreads` after the update, from its diagonal blocks only."""
        if rows.shape[0] == 0:
            return self.spreads()
        parts = self._woodbury(rows, weight)
        _, b, sb = parts
        drift = self._drift_after(rows, weight, parts, ends)
        p = self.p
        var = []
        for k, m in enumerate(self.metrics):
            blk = slice(k * p, (k + 1) * p)
            v = float(np.sum(m * self.cov[blk, blk])) - float(np.sum((sb[:, blk] @ m) * b[:, blk]))
            if drift.shape[1]:
                g = drift[blk]
                v += float(np.sum((m @ g) * g))
            var.append(v)
        return np.sqrt(np.maximum(var, 0.0))


__all__ = ["ManoeuvrePosterior", "psd_factor"]
