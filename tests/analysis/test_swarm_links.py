"""A swarm's links from the (time, drone, drone) grid (issue 30) equal the per-link computation."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.analysis import swarm_links
from rplearn.analysis.swarm import SwarmOptions, connectivity_over_time, predict_swarm
from rplearn.analysis.swarm_geometry import pair_directions, pose_rotations
from rplearn.analysis.swarm_links import Radio, SwarmPoses, _Cells, code_dtype, predict_links
from rplearn.core.bases import SphericalHarmonics
from rplearn.core.link import free_space_path_loss_db
from rplearn.data.tables import LinkSamples
from rplearn.models.patterns import PatternSet
from rplearn.models.training import TrainingSummary


def _model(rng, covariance=True):
    b = SphericalHarmonics(5)
    a = rng.normal(0, 0.05, (3 * b.n_coef, 3 * b.n_coef))
    return PatternSet(basis=b, nodes=("A", "B", "C"), coef=rng.normal(0, 2.0, (3, b.n_coef)),
                      covariance=a @ a.T if covariance else None,
                      training=TrainingSummary(frequency_hz=2.4e9, rmse_db=3.0))


def _poses(rng, n=6, m=9, absent=0.2):
    position = rng.normal(0, 40, (n, m, 3))
    position[..., 2] = np.abs(position[..., 2]) + 10
    position[1, :, :] = position[0, :, :] + 0.05  # drone 1 inside drone 0's near field
    quat = rng.normal(size=(n, m, 4))
    present = rng.uniform(size=(m, n)) >= absent
    present[0] = True  # one time with every drone
    position[~present.T] = np.nan  # absent poses may be NaN
    quat[~present.T] = np.nan
    return SwarmPoses(position, quat, present, np.arange(m) * 0.5, tuple(f"d{i}" for i in range(n)))


@pytest.mark.parametrize("covariance", [False, True])
def test_grid_links_equal_the_per_link_computation(covariance):
    rng = np.random.default_rng(4)
    model = _model(rng, covariance)
    poses = _poses(rng)
    pattern_of = {d: "ABC"[i % 3] if i != 4 else "A" for i, d in enumerate(poses.drones)}
    links, _ = predict_links(model, poses, pattern_of, Radio(20.0, 2.4e9, -70.0))
    # per link, as predict_swarm computed it before issue 30
    n, m = len(poses.drones), poses.t_s.size
    k, a, b = np.nonzero(poses.present[:, :, None] & poses.present[:, None, :] & ~np.eye(n, dtype=bool))
    delta = poses.position_m[b, k] - poses.position_m[a, k]
    node = np.array([model.node_index(pattern_of[d]) for d in poses.drones])
    d = np.sqrt(np.einsum("ij,ij->i", delta, delta))
    samples = LinkSamples(pair_directions(pose_rotations(poses.quat_wxyz, poses.present), m, k, a, b, delta), node[a],
                          node[b], model.nodes, np.full(d.size, np.nan), d, np.full(d.size, 2.4e9))
    gain = model.predict_gain(samples)
    near = d <= 0.25
    rssi = np.where(near, np.nan, 20.0 + gain - free_space_path_loss_db(np.where(near, 1.0, d), 2.4e9))
    np.testing.assert_array_equal(links["t"], poses.t_s[k])
    np.testing.assert_array_equal(links["tx"].cat.codes, a)
    np.testing.assert_array_equal(links["rx"].cat.codes, b)
    assert list(links["tx"].cat.categories) == list(poses.drones)
    np.testing.assert_array_equal(links["tx_pattern"].astype(str), [pattern_of[poses.drones[i]] for i in a])
    np.testing.assert_array_equal(links["distance_m"], d)  # bit for bit
    np.testing.assert_allclose(links["gain_pred_db"], gain, rtol=0, atol=1e-12)
    np.testing.assert_allclose(links["rssi_pred_dbm"], rssi, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(links["near_field"], near)
    assert near.any() and not near.all()
    if covariance:
        np.testing.assert_allclose(links["gain_pred_std_db"], model.predict_gain_std(samples), rtol=0, atol=1e-12)
    else:
        assert "gain_pred_std_db" not in links


def test_connectivity_in_blocks_equals_the_one_from_the_links(monkeypatch):
    monkeypatch.setattr(swarm_links, "LINK_BLOCK_ROWS", 2 * 36)  # two times a link block
    monkeypatch.setattr(swarm_links, "SWARM_CONNECTIVITY_VALUES", 5 * 36)  # four times a connectivity block
    rng = np.random.default_rng(7)
    model = _model(rng, covariance=False)
    poses = _poses(rng, m=23, absent=0.15)
    pattern_of = {d: "AB"[i % 2] for i, d in enumerate(poses.drones)}
    links, connectivity = predict_links(model, poses, pattern_of, Radio(20.0, 2.4e9, -62.0))
    again = connectivity_over_time(links, poses.t_s, poses.drones, -62.0)
    pd.testing.assert_frame_equal(connectivity, again)
    assert connectivity["n_missing"].gt(0).any() and connectivity["n_pairs_up"].gt(0).any()


def test_cells_take_the_links_in_order_and_put_them_back():
    rng = np.random.default_rng(1)
    for present in (np.ones((3, 5), bool), rng.uniform(size=(3, 5)) < 0.6):
        cells = _Cells(present)
        grid = rng.normal(size=(3, 5, 5))
        k, a, b = np.nonzero(present[:, :, None] & present[:, None, :] & ~np.eye(5, dtype=bool))
        np.testing.assert_array_equal(cells.take(grid), grid[k, a, b])
        np.testing.assert_array_equal(cells.take(np.arange(5)[None, :, None]), a)  # a broadcast grid
        np.testing.assert_array_equal(cells.take(np.arange(5)[None, None, :]), b)
        np.testing.assert_array_equal(cells.take(np.arange(3.0)[:, None, None]), k)  # one value a time
        back = np.full((3, 5, 5), np.nan)
        cells.put(back, grid[k, a, b])
        np.testing.assert_array_equal(back[k, a, b], grid[k, a, b])
        assert np.isnan(back).sum() == back.size - k.size


@pytest.mark.parametrize("n", [2, 126, 127, 128, 40_000])
def test_node_codes_are_kept_by_pandas_without_a_copy(n):
    codes = np.zeros(3, code_dtype(n))
    cat = pd.Categorical.from_codes(codes, dtype=pd.CategoricalDtype([f"c{i}" for i in range(n)]))
    assert np.shares_memory(cat.codes, codes)


def test_predict_swarm_names_the_node_columns_as_before():
    rng = np.random.default_rng(2)
    model = _model(rng)
    t = np.arange(5.0)
    rows = [(ti, d, 30.0 * i, 5.0 * ti, 20.0, 1.0, 0.0, 0.0, 0.0) for i, d in enumerate("PQR") for ti in t]
    log = pd.DataFrame(rows, columns=["t", "node", "x", "y", "z", "qw", "qx", "qy", "qz"])
    res = predict_swarm(model, log, 20.0, SwarmOptions(pattern_of={"P": "A", "Q": "C", "R": "A"}))
    assert list(res.links.columns[:5]) == ["t", "tx", "rx", "tx_pattern", "rx_pattern"]
    assert res.links["tx"].astype(str).tolist()[:2] == ["P", "P"] and res.links["rx"].astype(str).tolist()[:2] == ["Q", "R"]
    assert list(res.links["tx_pattern"].cat.categories) == ["A", "C"]
    assert len(res.links) == 5 * 6 and res.connectivity["connected"].dtype == bool
