"""A manoeuvre's feature rows for the next-best manoeuvre ranking, one unit or many at once.

Each row is ``phi(d_tx)`` on the transmitter's block plus ``phi(d_rx)`` on the receiver's, the
link directions of the unit's references sampled at the ranking's rate, the drones tilted into
their reference acceleration (plus a steady wind's drag, never for the nodes standing on the
ground). :func:`rows_and_ends` computes them for one unit; :func:`batch_rows_and_ends` for many,
their samples stacked so that the attitudes and link directions are a few calls on long arrays
instead of many on short ones: the same element-wise operations on each sample, so the same
numbers (``tests/analysis/test_manoeuvre_rows.py`` compares the two); the basis features stay one
call per unit (a matrix product, whose rounding may depend on the number of samples).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from rplearn.core.basis_base import Basis
from rplearn.core.geometry import attitude_from_thrust, link_directions
from rplearn.errors import InputError
from rplearn.plan.trajectory import G_M_S2

#: The steady extra thrust [m/s^2] (ENU) and the nodes it spares; None: a level hover.
Steady = tuple[tuple[float, float, float], tuple[str, ...]] | None
#: Per link end of a unit's rows: (node index per row, az [rad], el [rad]).
LinkEnds = tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...]
#: Samples stacked per batch of :func:`batch_rows_and_ends` (bounds its temporary arrays).
BATCH_SAMPLES = 16384


def manoeuvre_rows(unit: Any, nodes: Sequence[str], basis: Basis, rate_hz: float, steady: Steady = None) -> np.ndarray:
    """Feature rows (pattern columns of ``nodes``) of both link directions along a unit's references.

    The drones tilt into their reference acceleration plus ``steady[0]`` (a wind's drag,
    :attr:`~rplearn.analysis.manoeuvres.ManoeuvreOptions.steady_accel_enu_m_s2`; never the nodes
    of ``steady[1]``, which stand on the ground; None: no wind); each row is
    ``phi(d_tx) on tx's block + phi(d_rx) on rx's block``.
    """
    return rows_and_ends(unit, nodes, basis, rate_hz, steady)[0]


def _end_indices(unit: Any, index: dict[str, int]) -> tuple[list[str], tuple[int, int]]:
    ends = [str(v) for v in unit.nodes]
    missing = [e for e in ends if e not in index]
    if missing:
        raise InputError(f"manoeuvre {unit.label}: node(s) {', '.join(missing)} not in the statistics' nodes", param="nodes")
    return ends, (index[ends[0]], index[ends[1]])


def _thrust_extra(ends: list[str], steady: Steady) -> list[np.ndarray]:
    """Per end of the unit, what its thrust carries beyond its reference acceleration [m/s^2]."""
    extra = [np.array([0.0, 0.0, G_M_S2]) for _ in ends]
    if steady is not None:
        extra = [e + (0.0 if node in steady[1] else np.asarray(steady[0], np.float64)) for e, node in zip(extra, ends)]
    return extra


def _assemble(f0: np.ndarray, f1: np.ndarray, az_el: tuple[np.ndarray, ...], ks: tuple[int, int],
              n_nodes: int) -> tuple[np.ndarray, LinkEnds]:
    """One unit's rows and link ends from its samples' features at both ends."""
    n, p = f0.shape
    rows = np.zeros((n, n_nodes * p))
    k0, k1 = ks
    rows[:, k0 * p:(k0 + 1) * p] += f0
    rows[:, k1 * p:(k1 + 1) * p] += f1
    # the other direction (1 -> 0) has the same two directions: the same row, so weight twice
    az_tx, el_tx, az_rx, el_rx = az_el
    return rows, ((np.full(n, k0, np.intp), az_tx, el_tx), (np.full(n, k1, np.intp), az_rx, el_rx))


def rows_and_ends(unit: Any, nodes: Sequence[str], basis: Basis, rate_hz: float,
                  steady: Steady = None) -> tuple[np.ndarray, LinkEnds]:
    """:func:`manoeuvre_rows` and, per link end, (node index per row, az, el) [rad]."""
    ref = unit.sample(rate_hz)
    index = {node: k for k, node in enumerate(nodes)}
    ends, ks = _end_indices(unit, index)
    extra = _thrust_extra(ends, steady)
    quats = [attitude_from_thrust(ref.accel_enu_m_s2[:, j, :] + extra[j], ref.yaw_rad[:, j]) for j in (0, 1)]
    d = link_directions(ref.position_enu_m[:, 0, :], quats[0], ref.position_enu_m[:, 1, :], quats[1])
    f0, f1 = basis.design(d.az_tx, d.el_tx), basis.design(d.az_rx, d.el_rx)
    return _assemble(f0, f1, (d.az_tx, d.el_tx, d.az_rx, d.el_rx), ks, len(nodes))


def batch_rows_and_ends(units: Sequence[Any], nodes: Sequence[str], basis: Basis, rate_hz: float,
                        steady: Steady = None) -> Iterator[tuple[np.ndarray, LinkEnds]]:
    """:func:`rows_and_ends` of each unit, in order: the samples of up to :data:`BATCH_SAMPLES`
    at a time stacked through the attitudes and link directions (the same per-sample
    operations). A unit naming a node not in ``nodes`` raises as :func:`rows_and_ends` does,
    before any of its batch is yielded."""
    index = {node: k for k, node in enumerate(nodes)}
    batch: list[tuple[Any, tuple[int, int], list[np.ndarray]]] = []
    size = 0
    for unit in units:
        ref = unit.sample(rate_hz)
        ends, ks = _end_indices(unit, index)
        extra = _thrust_extra(ends, steady)
        parts = [ref.accel_enu_m_s2[:, j, :] + extra[j] for j in (0, 1)]
        parts += [ref.yaw_rad[:, 0], ref.yaw_rad[:, 1], ref.position_enu_m[:, 0, :], ref.position_enu_m[:, 1, :]]
        batch.append((unit, ks, parts))
        size += ref.t_s.size
        if size >= BATCH_SAMPLES:
            yield from _batch(batch, basis, len(nodes))
            batch, size = [], 0
    if batch:
        yield from _batch(batch, basis, len(nodes))


def known_rows_and_ends(units: Sequence[Any], nodes: Sequence[str], basis: Basis, rate_hz: float, steady: Steady,
                        known: dict[Any, tuple[np.ndarray, LinkEnds]]) -> list[tuple[np.ndarray, LinkEnds]]:
    """:func:`batch_rows_and_ends` of ``units``, those equal to a unit of the previous call taken
    from ``known`` (the same unit, nodes, basis, rate and lean: the same rows), which is then
    replaced by this call's (a greedy plan's next step from where a turn in place left the same
    poses offers the same units). Units that cannot be hashed are always computed."""
    keys = [_key(u) for u in units]
    todo = [u for u, k in zip(units, keys) if k is None or k not in known]
    fresh = iter(batch_rows_and_ends(todo, nodes, basis, rate_hz, steady))
    out = [next(fresh) if k is None or k not in known else known[k] for k in keys]
    known.clear()
    known.update((k, g) for k, g in zip(keys, out) if k is not None)
    return out


def _key(unit: Any) -> Any:
    try:
        hash(unit)
    except TypeError:
        return None
    return unit


def _batch(batch: list[tuple[Any, tuple[int, int], list[np.ndarray]]], basis: Basis,
           n_nodes: int) -> Iterator[tuple[np.ndarray, LinkEnds]]:
    thrust0, thrust1, yaw0, yaw1, pos0, pos1 = (np.concatenate([b[2][i] for b in batch]) for i in range(6))
    quats = [attitude_from_thrust(thrust0, yaw0), attitude_from_thrust(thrust1, yaw1)]
    d = link_directions(pos0, quats[0], pos1, quats[1])
    start = 0
    for _, ks, parts in batch:
        cut = slice(start, start + parts[2].size)
        start = cut.stop
        az_tx, el_tx, az_rx, el_rx = (np.array(v[cut]) for v in (d.az_tx, d.el_tx, d.az_rx, d.el_rx))
        # the features per unit: their matrix product's rounding may depend on the number of samples
        f0, f1 = basis.design(az_tx, el_tx), basis.design(az_rx, el_rx)
        yield _assemble(f0, f1, (az_tx, el_tx, az_rx, el_rx), ks, n_nodes)


__all__ = ["BATCH_SAMPLES", "LinkEnds", "Steady", "batch_rows_and_ends", "known_rows_and_ends", "manoeuvre_rows", "rows_and_ends"]
