"""Headings that maximise links: the yaw of one or both ends of a link (rplearn orient)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from rplearn.core.geometry import direction_in_body, quat_wxyz_from_yaw
from rplearn.errors import InputError
from rplearn.models.patterns import PatternSet

Progress = Callable[[str], None]


@dataclass(frozen=True)
class OrientationResult:
    """Headings that maximise a link and the predicted joint gain there."""

    tx_yaw_deg: float
    rx_yaw_deg: float
    gain_db: float
    baseline_gain_db: float


def best_yaw(
    model: PatternSet,
    tx_node: str,
    rx_node: str,
    tx_position_xyz: Sequence[float],
    rx_position_xyz: Sequence[float],
    turn: str = "tx",
    tx_yaw_deg: float = 0.0,
    rx_yaw_deg: float = 0.0,
    step_deg: float = 1.0,
) -> OrientationResult:
    """Heading(s) of level drones at given ENU positions that maximise the predicted joint gain.

    Parameters
    ----------
    turn : {"tx", "rx", "both"}
        Which drone may turn; the other keeps its given yaw (ENU, ccw from east) [deg].
    """
    if turn not in ("tx", "rx", "both"):
        raise InputError(f"turn must be 'tx', 'rx' or 'both', got {turn!r}")
    if not (0 < step_deg <= 90):
        raise InputError(f"step_deg must be in (0, 90], got {step_deg}")
    grid = np.arange(-180.0, 180.0, step_deg)
    tx_p = np.asarray(tx_position_xyz, float)
    rx_p = np.asarray(rx_position_xyz, float)

    def gains(yaw_deg: np.ndarray, own: np.ndarray, other: np.ndarray, node: str) -> np.ndarray:
        q = quat_wxyz_from_yaw(np.radians(yaw_deg))
        az, el = direction_in_body(np.broadcast_to(own, (yaw_deg.size, 3)), q, np.broadcast_to(other, (yaw_deg.size, 3)))
        return model.evaluate(node, az, el)

    g_tx = gains(grid, tx_p, rx_p, tx_node) if turn in ("tx", "both") else gains(np.array([tx_yaw_deg]), tx_p, rx_p, tx_node)
    g_rx = gains(grid, rx_p, tx_p, rx_node) if turn in ("rx", "both") else gains(np.array([rx_yaw_deg]), rx_p, tx_p, rx_node)
    base = float(gains(np.array([tx_yaw_deg]), tx_p, rx_p, tx_node)[0] + gains(np.array([rx_yaw_deg]), rx_p, tx_p, rx_node)[0])
    i_tx = int(np.argmax(g_tx))
    i_rx = int(np.argmax(g_rx))
    best_tx = float(grid[i_tx]) if turn in ("tx", "both") else float(tx_yaw_deg)
    best_rx = float(grid[i_rx]) if turn in ("rx", "both") else float(rx_yaw_deg)
    return OrientationResult(best_tx, best_rx, float(g_tx[i_tx] + g_rx[i_rx]), base)
