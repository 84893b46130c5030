"""Connectivity of a swarm over time, every time at once (issue 13, item 2): the same rows as
one scipy spanning tree and component count per time."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from rplearn.analysis.swarm import connectivity_over_time, maximum_spanning_edges, spanning_bottleneck


def _links(rng, n, times, absent_share, near_share):
    drones = [f"d{i:02d}" for i in range(n)]
    rows = []
    for t in times:
        present = rng.random(n) >= absent_share
        for a in range(n):
            for b in range(n):
                if a != b and present[a] and present[b]:
                    rows.append((t, drones[a], drones[b], rng.normal(-75.0, 8.0), rng.random() < near_share))
    links = pd.DataFrame(rows, columns=["t", "tx", "rx", "rssi_pred_dbm", "near_field"])
    return drones, links.sort_values(["t", "tx", "rx"], kind="stable", ignore_index=True)


def _one_time(links, t, drones, threshold):
    """The definition, one time at a time (scipy's graph routines)."""
    n = len(drones)
    part = links[links["t"] == t]
    rssi = np.full((n, n), np.nan)
    idx = {d: i for i, d in enumerate(drones)}
    for tx, rx, v, near in zip(part["tx"], part["rx"], part["rssi_pred_dbm"], part["near_field"]):
        rssi[idx[tx], idx[rx]] = np.inf if near else v
    iu, ju = np.triu_indices(n, 1)
    w = np.fmin(rssi, rssi.T)[iu, ju]
    up = w >= threshold
    groups = connected_components(csr_matrix((np.ones(int(up.sum())), (iu[up], ju[up])), shape=(n, n)), directed=False)[0]
    present = set(part["tx"]) | set(part["rx"])
    missing = [d for d in drones if d not in present]
    bottleneck = (float("nan"), "") if missing else spanning_bottleneck(w, iu, ju, n, drones)
    return int(up.sum()), int(groups - len(missing)), bottleneck


@pytest.mark.parametrize("n,absent,near", [(2, 0.0, 0.0), (3, 0.1, 0.05), (7, 0.05, 0.02), (16, 0.0, 0.01), (16, 0.03, 0.0)])
def test_every_time_at_once_equals_one_time_at_a_time(n, absent, near):
    rng = np.random.default_rng(n)
    times = np.arange(60) * 0.5
    drones, links = _links(rng, n, times, absent, near)
    got = connectivity_over_time(links, times, drones, -80.0)
    assert len(got) == times.size
    for row in got.itertuples():
        pairs_up, components, (bottleneck, pair) = _one_time(links, row.t, drones, -80.0)
        assert row.n_pairs_up == pairs_up and row.n_components == components
        assert row.connected == (row.n_missing == 0 and components == 1)
        if np.isnan(bottleneck):
            assert np.isnan(row.bottleneck_rssi_dbm) and row.bottleneck_pair == ""
        else:
            # spanning_bottleneck maps weights to costs and back: equal to its rounding (1e-10 dB)
            assert row.bottleneck_rssi_dbm == pytest.approx(bottleneck, abs=1e-6) and row.bottleneck_pair == pair


def test_maximum_spanning_edges_of_disconnected_and_near_field_graphs():
    w = np.full((2, 4, 4), -np.inf)
    w[0, 0, 1] = w[0, 1, 0] = -70.0
    w[0, 2, 3] = w[0, 3, 2] = -60.0  # two groups: one edge -inf
    w[1] = np.inf  # every pair near field
    edge_w, _, _ = maximum_spanning_edges(w)
    assert np.sum(np.isneginf(edge_w[0])) == 1 and sorted(edge_w[0][np.isfinite(edge_w[0])]) == [-70.0, -60.0]
    assert np.all(np.isposinf(edge_w[1]))
