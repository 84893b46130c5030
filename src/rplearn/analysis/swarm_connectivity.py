"""A swarm's connectivity over many times at once, from its pair weights (issue 30).

Per time: the drones with a pose, the pairs up both ways, the groups and the bottleneck (the
weakest edge of a maximum spanning tree of the weights ``min(RSSI a->b, RSSI b->a)``; see
:mod:`rplearn.analysis.swarm`), from a ``(times, drones, drones)`` array of directed RSSI.
Prim's algorithm runs on every time of a block at once (:func:`maximum_spanning_edges`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd


def connectivity_of_weights(
    rssi_dbm: np.ndarray, present: np.ndarray, times_s: np.ndarray, drones: Sequence[str], min_rssi_dbm: float,
) -> dict[str, np.ndarray]:
    """Columns of :func:`rplearn.analysis.swarm.connectivity_over_time` for the times of one
    block (:func:`connectivity_table` joins the blocks' into the table).

    Parameters
    ----------
    rssi_dbm : ndarray, shape (times, drones, drones)
        RSSI of every link ``[t, tx, rx]`` [dBm]: NaN where the link is not predicted (the
        diagonal, a drone without a pose), +inf where the pair is closer than the far field.
    present : ndarray of bool, shape (times, drones)
        Drones in at least one link at each time.
    times_s : ndarray
        The block's times [s].
    drones : sequence of str
        Drone names, in index order.
    min_rssi_dbm : float
        RSSI a link needs in each direction to be up [dBm].
    """
    n, m = len(drones), times_s.size
    names = np.asarray(list(drones), dtype=object)
    iu, ju = np.triu_indices(n, 1)
    w = np.fmin(rssi_dbm, rssi_dbm.transpose(0, 2, 1))  # a pair's weight: its weaker direction (NaN: unknown)
    pairs_up = np.sum(w[:, iu, ju] >= min_rssi_dbm, axis=1)
    np.copyto(w, -np.inf, where=np.isnan(w))
    edge_w, edge_a, edge_b = maximum_spanning_edges(w)
    del w
    n_missing = n - present.sum(axis=1)
    n_groups = n - np.sum(edge_w >= min_rssi_dbm, axis=1)
    spans = (n_missing == 0) & ~np.any(np.isneginf(edge_w), axis=1)
    rows = np.arange(m)
    weakest = np.argmin(edge_w, axis=1)
    a = np.minimum(edge_a[rows, weakest], edge_b[rows, weakest])
    b = np.maximum(edge_a[rows, weakest], edge_b[rows, weakest])
    missing = np.full(m, "", dtype=object)
    for r in np.flatnonzero(n_missing):
        missing[r] = ",".join(str(d) for d, p in zip(drones, present[r]) if not p)
    return {
        "t": times_s, "n_drones": present.sum(axis=1).astype(int), "n_missing": n_missing.astype(int),
        "missing": missing, "n_pairs_up": pairs_up.astype(int), "n_components": (n_groups - n_missing).astype(int),
        "connected": (n_missing == 0) & (n_groups == 1),
        "bottleneck_rssi_dbm": np.where(spans, edge_w[rows, weakest], np.nan).astype(float),
        "bottleneck_pair": np.where(spans, names[a] + "-" + names[b], ""),
    }


def connectivity_table(parts: Sequence[dict[str, np.ndarray]]) -> pd.DataFrame:
    """The connectivity table of the blocks' columns (:func:`connectivity_of_weights`), in order."""
    return pd.DataFrame({name: np.concatenate([part[name] for part in parts]) for name in parts[0]})


def maximum_spanning_edges(weights: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Maximum spanning trees of many complete graphs at once (Prim's algorithm, vectorised
    over the first axis).

    Parameters
    ----------
    weights : ndarray, shape (m, n, n)
        Symmetric pair weights; ``-inf`` for a pair with no edge, ``+inf`` for one stronger
        than any.

    Returns
    -------
    edge_w, edge_a, edge_b : ndarray, shape (m, n - 1)
        Each tree's edges in the order Prim adds them: weight and the two nodes. A graph that
        is not connected gets ``-inf`` edges (its spanning forest, joined arbitrarily).
    """
    m, n, _ = weights.shape
    rows = np.arange(m)
    in_tree = np.zeros((m, n), bool)
    in_tree[:, 0] = True
    best = weights[:, 0, :].copy()
    parent = np.zeros((m, n), np.intp)
    edge_w = np.full((m, max(n - 1, 0)), np.inf)
    edge_a = np.zeros((m, max(n - 1, 0)), np.intp)
    edge_b = np.zeros((m, max(n - 1, 0)), np.intp)
    for step in range(n - 1):
        cand = np.where(in_tree, -np.inf, best)
        j = np.argmax(cand, axis=1)
        stuck = np.isneginf(cand[rows, j])  # nothing reachable: take any node not yet in the tree
        j = np.where(stuck, np.argmax(~in_tree, axis=1), j)
        edge_w[:, step] = np.where(stuck, -np.inf, best[rows, j])
        edge_a[:, step] = parent[rows, j]
        edge_b[:, step] = j
        in_tree[rows, j] = True
        row = weights[rows, j, :]
        better = row > best
        best = np.where(better, row, best)
        parent = np.where(better, j[:, None], parent)
    return edge_w, edge_a, edge_b


__all__ = ["connectivity_of_weights", "connectivity_table", "maximum_spanning_edges"]
