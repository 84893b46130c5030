"""A swarm's links, a block of times at a time, on the grid of every (time, drone, drone) (issue 30).

Each drone's gain toward each other drone is evaluated once per time: the direction of ``b``
in ``a``'s body frame, ``R_a^T (p_b - p_a)``, is the transmitter end of link ``a -> b`` and the
receiver end of link ``b -> a`` (the receiver end of ``a -> b`` is ``R_b^T (p_a - p_b)``,
the same numbers bit for bit, since ``fl(x - y) = -fl(y - x)``). So the joint gain of
``a -> b`` is ``G[a, b] + G[b, a]`` on a ``(times, drones, drones)`` grid, with no per-link
gather of poses or rotations and half the pattern evaluations of a per-link computation. The
links are then the grid's off-diagonal entries where both drones have a pose, in the order
of time, then transmitter, then receiver, written straight into the columns of the links
table (node columns as categorical codes of the smallest integer type).

The connectivity is computed from the same grid, a larger block of times at a time
(:func:`rplearn.analysis.swarm_connectivity.connectivity_of_weights`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn.analysis.swarm_connectivity import connectivity_of_weights, connectivity_table
from rplearn.analysis.swarm_geometry import pose_rotations
from rplearn.core.geometry import Directions
from rplearn.core.link import far_field_limit_m, free_space_path_loss_db
from rplearn.data.tables import LinkSamples
from rplearn.models.patterns import PatternSet
from rplearn.models.predict import end_coverage_deg

#: Grid cells (time x drone x drone) predicted at once: bounds the geometry and features in memory ...
LINK_BLOCK_ROWS = 50_000
#: ... and at least this many, else at most the links over :data:`CONNECTIVITY_SHARE` (small swarms: the
#: block's arrays stay small beside the table).
LINK_BLOCK_MIN_ROWS = 20_000
#: Grid cells whose connectivity is computed at once (a few arrays of this many values) ...
SWARM_CONNECTIVITY_VALUES = 1_000_000
#: ... and at most the links over this number (a few arrays of them stay small beside the table).
CONNECTIVITY_SHARE = 64
#: ... but at least this many (fewer blocks: Prim's steps cost the same on few times as on many).
CONNECTIVITY_MIN_VALUES = 100_000


@dataclass(frozen=True)
class Radio:
    """Every drone's radio in a swarm prediction: transmit power [dBm], carrier [Hz], and the
    RSSI a link needs to be up [dBm]."""

    tx_power_dbm: float
    frequency_hz: float
    min_rssi_dbm: float


@dataclass(frozen=True)
class SwarmPoses:
    """The drones' poses at the prediction times.

    Attributes
    ----------
    position_m : ndarray, shape (drones, times, 3)
        ENU positions [m] (anything where absent).
    quat_wxyz : ndarray, shape (drones, times, 4)
        FLU -> ENU attitudes (anything where absent).
    present : ndarray of bool, shape (times, drones)
        Whether each drone has a pose.
    t_s : ndarray
        The times [s].
    drones : sequence of str
        Drone names, sorted.
    """

    position_m: np.ndarray
    quat_wxyz: np.ndarray
    present: np.ndarray
    t_s: np.ndarray
    drones: Sequence[str]


def code_dtype(n_categories: int) -> type:
    """The integer type pandas keeps categorical codes of ``n_categories`` in (no copy)."""
    for dtype in (np.int8, np.int16, np.int32):
        if n_categories < np.iinfo(dtype).max:
            return dtype
    return np.int64


def _off_diagonal(grid: np.ndarray) -> np.ndarray:
    """View ``(m, n - 1, n)`` of the off-diagonal entries of a C-contiguous ``(m, n, n)`` grid,
    in row-major order (entry ``[t, i, j]`` with ``j`` skipping ``i``)."""
    m, n, _ = grid.shape
    # rows of n * n - 1 = (n - 1)(n + 1) entries, each contiguous: reshape gives a view
    # (numpy's reshape(copy=False), which would say so, needs numpy 2.1)
    view = grid.reshape(m, n * n)[:, 1:].reshape(m, n - 1, n + 1)
    if not np.may_share_memory(view, grid):
        raise AssertionError("off-diagonal cells: reshape copied the grid")
    return view[:, :, :n]


class _Cells:
    """Which grid cells of a block are links: every off-diagonal cell (``mask`` None), or the
    off-diagonal cells whose two drones both have a pose."""

    def __init__(self, present: np.ndarray) -> None:
        m, n = present.shape
        self.shape = (m, n, n)
        self.mask: np.ndarray | None = None
        if not present.all():
            self.mask = present[:, :, None] & present[:, None, :] & ~np.eye(n, dtype=bool)
        self.size = m * n * (n - 1) if self.mask is None else int(np.count_nonzero(self.mask))

    def take(self, grid: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """The links' values of a ``(m, n, n)`` grid (or a broadcast of it), in link order."""
        out = np.empty(self.size, grid.dtype) if out is None else out
        if self.mask is None:
            m, n, _ = self.shape
            links = out.reshape(m, n * (n - 1))
            if grid.shape[1:] == (1, 1):  # one value a time
                links[...] = grid.reshape(-1, 1)
            elif grid.shape[0] == 1:  # the same links every time: one time's, repeated
                links[...] = _off_diagonal(np.ascontiguousarray(np.broadcast_to(grid, (1, n, n)))).reshape(1, -1)
            else:
                np.copyto(out.reshape(m, n - 1, n), _off_diagonal(np.ascontiguousarray(np.broadcast_to(grid, self.shape))))
        else:
            out[...] = np.broadcast_to(grid, self.shape)[self.mask]
        return out

    def put(self, grid: np.ndarray, values: np.ndarray) -> None:
        """Write the links' ``values`` into their cells of ``grid``."""
        if self.mask is None:
            m, n, _ = self.shape
            _off_diagonal(grid)[...] = values.reshape(m, n - 1, n)
        else:
            grid[self.mask] = values


def _block_poses(poses: SwarmPoses, s0: int, s1: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``(m, n, 3)`` [m] (0 where absent) and rotations ``(m, n, 9)`` (body -> ENU, row by
    row; the identity where absent) of the times ``s0:s1``."""
    present = poses.present[s0:s1]
    position = np.where(present.T[..., None], poses.position_m[:, s0:s1], 0.0).transpose(1, 0, 2)
    n, m = present.shape[1], s1 - s0
    rotation = pose_rotations(poses.quat_wxyz[:, s0:s1], present).reshape(n, m, 9).transpose(1, 0, 2)
    return position, rotation


def _grid_directions(position: np.ndarray, rot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Azimuth and elevation [rad] of every drone ``j`` in every drone ``i``'s body frame, and
    the distance [m], on a ``(m, n, n)`` grid from positions ``(m, n, 3)`` and rotations ``(m, n, 9)``
    (the same arithmetic as :func:`rplearn.analysis.swarm_geometry.pair_directions`)."""
    dx, dy, dz = (position[:, None, :, c] - position[:, :, None, c] for c in range(3))
    r = [rot[:, :, c, None] for c in range(9)]
    bx = dx * r[0] + dy * r[3] + dz * r[6]
    by = dx * r[1] + dy * r[4] + dz * r[7]
    bz = dx * r[2] + dy * r[5] + dz * r[8]
    az = np.arctan2(by, bx)
    az[az == -np.pi] = np.pi
    el = np.arctan2(bz, np.hypot(bx, by))
    dx *= dx
    dy *= dy
    dz *= dz
    dx += dz  # the order numpy's einsum sums three squares in (the distances of earlier releases, bit for bit)
    dx += dy
    return az, el, np.sqrt(dx, out=dx)


def _grid_gains(model: PatternSet, az: np.ndarray, el: np.ndarray, node_of: np.ndarray) -> np.ndarray:
    """Gain [dBi] of drone ``i``'s pattern (model node ``node_of[i]``) toward cell ``[t, i, j]``."""
    gain = np.empty(az.shape)
    for k in np.unique(node_of):
        rows = np.flatnonzero(node_of == k)
        if rows.size == node_of.size:
            gain[...] = model.basis.evaluate(model.coef[k], az, el).reshape(az.shape)
        else:
            part = model.basis.evaluate(model.coef[k], az[:, rows], el[:, rows])
            gain[:, rows] = part.reshape(az.shape[0], rows.size, az.shape[2])
    return gain


def predict_links(
    model: PatternSet, poses: SwarmPoses, pattern_of: dict[str, str], radio: Radio,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The links and connectivity tables of :class:`rplearn.analysis.swarm.SwarmPrediction`.

    Memory holds the links table and one block's work, not copies of the table.
    """
    drones, t, present = list(poses.drones), poses.t_s, poses.present
    n = len(drones)
    n_present = present.sum(axis=1)
    total = int(np.sum(n_present * (n_present - 1)))
    node_of = np.array([model.node_index(pattern_of[x]) for x in drones], np.intp)
    used = sorted(set(pattern_of.values()))  # categories of the pattern columns
    pattern_code: np.ndarray = np.array([used.index(pattern_of[x]) for x in drones], code_dtype(len(used)))
    drone_code: np.ndarray = np.arange(n, dtype=code_dtype(n))
    columns = _LinkColumns(model, total, n, len(used))
    limit_m = float(far_field_limit_m(radio.frequency_hz))
    link_step = max(1, min(LINK_BLOCK_ROWS, max(LINK_BLOCK_MIN_ROWS, total // CONNECTIVITY_SHARE)) // (n * n))
    # the connectivity's few (times, n, n) arrays stay small beside the table
    conn_cells = min(SWARM_CONNECTIVITY_VALUES, max(CONNECTIVITY_MIN_VALUES, total // CONNECTIVITY_SHARE))
    conn_step = link_step * max(1, conn_cells // (n * n * link_step))
    parts = []
    for c0 in range(0, t.size, conn_step):
        c1 = min(t.size, c0 + conn_step)
        rssi_grid = np.full((c1 - c0, n, n), np.nan)
        for s0 in range(c0, c1, link_step):
            s1 = min(c1, s0 + link_step)
            cells = _Cells(present[s0:s1])
            position, rotation = _block_poses(poses, s0, s1)
            az, el, dist = _grid_directions(position, rotation)
            gain = _grid_gains(model, az, el, node_of)
            rows = columns.rows(cells.size)
            block = {
                "t": t[s0:s1, None, None], "tx": drone_code[None, :, None], "rx": drone_code[None, None, :],
                "tx_pattern": pattern_code[None, :, None], "rx_pattern": pattern_code[None, None, :], "distance_m": dist,
            }
            for name, grid in block.items():
                cells.take(grid, columns[name][rows])
            g = cells.take(gain, columns["gain_pred_db"][rows])
            g += cells.take(gain.transpose(0, 2, 1))  # the receiver end: drone j toward i
            samples = None
            if columns.needs_samples:
                samples = _samples(model, cells, (az, el), position[:, :, 2], node_of, columns["distance_m"][rows],
                                   radio.frequency_hz)
            if samples is not None and columns.environment:
                g += model.environment_db(samples)
            columns.finish(rows, samples, radio, limit_m)
            rssi = np.where(columns["near_field"][rows], np.inf, columns["rssi_pred_dbm"][rows])
            cells.put(rssi_grid[s0 - c0:s1 - c0], rssi)
            del position, rotation, az, el, dist, gain, g, samples, rssi  # before the next block's are made
        seen = present[c0:c1] & (n_present[c0:c1, None] >= 2)  # a drone in at least one link
        parts.append(connectivity_of_weights(rssi_grid, seen, t[c0:c1], drones, radio.min_rssi_dbm))
        del rssi_grid
    return columns.frame(drones, used), connectivity_table(parts)


def _samples(model: PatternSet, cells: _Cells, angles: tuple[np.ndarray, np.ndarray], z: np.ndarray,
             node_of: np.ndarray, d: np.ndarray, frequency_hz: float) -> LinkSamples:
    """The block's links as :class:`LinkSamples` (for the spreads, the coverage, the environment):
    ``angles`` the grid's azimuth and elevation [rad], ``z`` the heights [m], ``d`` the distances [m]."""
    az, el = angles
    back = (0, 2, 1)
    directions = Directions(cells.take(az), cells.take(el), cells.take(az.transpose(back)), cells.take(el.transpose(back)))
    heights = model.path_loss.kind == "two-ray"  # the only term that reads them
    return LinkSamples(directions, cells.take(node_of[None, :, None]), cells.take(node_of[None, None, :]), model.nodes,
                       np.broadcast_to(np.nan, d.shape), d, np.broadcast_to(float(frequency_hz), d.shape),
                       tx_z_m=cells.take(z[:, :, None]) if heights else None,
                       rx_z_m=cells.take(z[:, None, :]) if heights else None)


class _LinkColumns:
    """The columns of the links table, filled a block of links at a time."""

    def __init__(self, model: PatternSet, total: int, n_drones: int, n_patterns: int) -> None:
        self.model = model
        self.environment = model.path_loss.kind != "free" or bool(model.shared_names)
        self.coverage = bool(model.training.coverage_deg)
        self.needs_samples = model.covariance is not None or self.environment or self.coverage
        # one packet's noise about its flight's level (an automatic fit over flights), else the training
        # residual, as predict_dataset reads it
        noise = model.training.noise_std_db if model.training.noise_std_db is not None else model.training.rmse_db
        self.residual_db = float(noise if noise is not None else np.nan)
        drone, pattern = code_dtype(n_drones), code_dtype(n_patterns)
        names: list[tuple[str, Any]] = [("t", np.float64), ("tx", drone), ("rx", drone), ("tx_pattern", pattern),
                                        ("rx_pattern", pattern), ("distance_m", np.float64),
                                        ("gain_pred_db", np.float64), ("rssi_pred_dbm", np.float64)]
        if model.covariance is not None:
            names += [("gain_pred_std_db", np.float64), ("rssi_pred_std_db", np.float64)]
        if self.coverage:
            names += [("tx_coverage_deg", np.float64), ("rx_coverage_deg", np.float64)]
        names += [("near_field", bool), ("up", bool)]
        self.columns = {name: np.empty(total, dtype) for name, dtype in names}
        self.offset = 0

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def rows(self, size: int) -> slice:
        """The next ``size`` rows."""
        rows = slice(self.offset, self.offset + size)
        self.offset += size
        return rows

    def finish(self, rows: slice, samples: LinkSamples | None, radio: Radio, limit_m: float) -> None:
        """The received power, spreads, coverage and ``up`` of ``rows`` from their distance and gain."""
        c = self.columns
        d, gain = c["distance_m"][rows], c["gain_pred_db"][rows]
        near = np.less_equal(d, limit_m, out=c["near_field"][rows])
        loss = free_space_path_loss_db(np.where(near, 1.0, d), radio.frequency_hz)
        c["rssi_pred_dbm"][rows] = np.where(near, np.nan, radio.tx_power_dbm + gain - loss)
        rssi = c["rssi_pred_dbm"][rows]
        if samples is not None:
            std = self.model.predict_gain_std(samples)
            if std is not None:
                c["gain_pred_std_db"][rows] = std
                c["rssi_pred_std_db"][rows] = np.sqrt(std**2 + self.residual_db**2)
            ends = end_coverage_deg(self.model, samples) if self.coverage else None
            if ends is not None:  # how far each end looks from where its pattern was learned [deg]
                c["tx_coverage_deg"][rows], c["rx_coverage_deg"][rows] = ends
        np.greater_equal(rssi, radio.min_rssi_dbm, out=c["up"][rows])
        c["up"][rows] |= near

    def frame(self, drones: Sequence[str], used: Sequence[str]) -> pd.DataFrame:
        """The links table: categorical node columns (codes into the names, no string per row)."""
        frame: dict[str, Any] = dict(self.columns)
        for name, categories in (("tx", drones), ("rx", drones), ("tx_pattern", used), ("rx_pattern", used)):
            frame[name] = pd.Categorical.from_codes(frame[name], dtype=pd.CategoricalDtype(list(categories)))
        self.columns = {}
        return pd.DataFrame(frame, copy=False)


__all__ = ["Radio", "SwarmPoses", "code_dtype", "predict_links"]
