"""Swarm links: every ordered pair over time, connectivity and its bottleneck."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.analysis.swarm import SwarmOptions, predict_swarm
from rplearn.core.bases import SphericalHarmonics
from rplearn.core.geometry import quat_wxyz_from_yaw
from rplearn.errors import InputError
from rplearn.models.patterns import PatternSet
from rplearn.models.training import TrainingSummary


def _model(rng):
    b = SphericalHarmonics(4)
    coef = rng.normal(0, 1.5, (2, b.n_coef))
    cov = np.diag(np.full(2 * b.n_coef, 0.01))
    return PatternSet(basis=b, nodes=("A", "B"), coef=coef, covariance=cov, training=TrainingSummary(frequency_hz=2.4e9, rmse_db=4.0))


def _formation(n_t=121):
    """Four drones 20 m up: A, B, C hover in a line 30 m apart; D flies away from C along +x."""
    t = np.arange(n_t, dtype=float)  # 1 Hz, 120 s
    rows = []
    fixed = {"A": (0.0, 0.0), "B": (30.0, 0.0), "C": (60.0, 0.0)}
    for node, (x, y) in fixed.items():
        for ti in t:
            rows.append((ti, node, x, y, 20.0, *quat_wxyz_from_yaw(np.radians(90.0))))
    for ti in t:  # D leaves C at 20 m/s: from 90 m to 2490 m
        rows.append((ti, "D", 90.0 + 20.0 * ti, 0.0, 20.0, *quat_wxyz_from_yaw(np.radians(-90.0))))
    return pd.DataFrame(rows, columns=["t", "node", "x", "y", "z", "qw", "qx", "qy", "qz"])


def test_links_equal_single_link_predictions_and_connectivity_is_consistent():
    rng = np.random.default_rng(0)
    model = _model(rng)
    poses = _formation()
    res = predict_swarm(model, poses, 0.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, min_rssi_dbm=-90.0))
    assert len(res.links) == 121 * 12 and len(res.connectivity) == 121
    # every row equals the one-link prediction of the same poses
    for tx, rx in [("A", "B"), ("D", "C"), ("C", "A")]:
        sel = res.links[(res.links["tx"] == tx) & (res.links["rx"] == rx)]
        p_tx = poses[poses["node"] == tx][["x", "y", "z"]].to_numpy()
        q_tx = poses[poses["node"] == tx][["qw", "qx", "qy", "qz"]].to_numpy()
        p_rx = poses[poses["node"] == rx][["x", "y", "z"]].to_numpy()
        q_rx = poses[poses["node"] == rx][["qw", "qx", "qy", "qz"]].to_numpy()
        one = model.predict_for_poses(res.pattern_of[tx], res.pattern_of[rx], p_tx, q_tx, p_rx, q_rx, 0.0, 2.4e9)
        np.testing.assert_allclose(sel["rssi_pred_dbm"].to_numpy(), one["rssi_dbm"], atol=1e-9)
        assert (sel["rssi_pred_std_db"] > 4.0).all()  # training residual included
    c = res.connectivity
    # D flies away: the swarm is connected at first, then D drops out for good
    assert c["connected"].iloc[0] and not c["connected"].iloc[-1]
    first_down = int(np.argmax(~c["connected"].to_numpy()))
    assert not c["connected"].iloc[first_down:].any()
    # the bottleneck decides connectivity at this threshold and at any other
    np.testing.assert_array_equal(c["connected"], c["bottleneck_rssi_dbm"] >= -90.0)
    assert set(c.loc[~c["connected"], "n_components"]) == {2}
    for threshold in (-60.0, -75.0, -100.0):
        other = predict_swarm(model, poses, 0.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, min_rssi_dbm=threshold))
        np.testing.assert_array_equal(other.connectivity["connected"], c["bottleneck_rssi_dbm"] >= threshold)
    # the bottleneck of the last time is D's best link, to C (the nearest drone) both ways
    last = res.links[res.links["t"] == 120.0].set_index(["tx", "rx"])["rssi_pred_dbm"]
    expected = max(min(last[("D", n)], last[(n, "D")]) for n in "ABC")
    assert c["bottleneck_rssi_dbm"].iloc[-1] == pytest.approx(expected)
    assert "weakest moment" in res.summary() and "D (B)" in res.summary()


def test_times_gaps_and_errors():
    rng = np.random.default_rng(1)
    model = _model(rng)
    poses = _formation(31)
    at = predict_swarm(model, poses, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, times_s=[2.5, 10.0]))
    assert sorted(at.links["t"].unique()) == [2.5, 10.0]
    # a gap in D's log: D is absent there, the others are not
    gappy = poses[~((poses["node"] == "D") & poses["t"].between(10, 20))]
    res = predict_swarm(model, gappy, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, max_gap_s=2.0))
    c = res.connectivity.set_index("t")
    assert c.loc[15.0, "n_drones"] == 3 and c.loc[5.0, "n_drones"] == 4
    # while D has no pose the swarm's connectivity is unknown: not connected, no bottleneck
    assert c.loc[15.0, "missing"] == "D" and not c.loc[15.0, "connected"] and np.isnan(c.loc[15.0, "bottleneck_rssi_dbm"])
    assert c.loc[5.0, "connected"] and "connectivity unknown" in res.summary()
    # requested times outside every log still get a row
    outside = predict_swarm(model, poses, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, times_s=[5.0, 500.0]))
    assert list(outside.connectivity["t"]) == [5.0, 500.0] and outside.connectivity["n_missing"].iloc[1] == 4
    # a sparse waypoint plan (one pose every 5 s) is known at its waypoints
    sparse = poses[poses["t"] % 5 == 0]
    way = predict_swarm(model, sparse, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, times_s=[0.0, 5.0, 10.0]))
    assert (way.connectivity["n_drones"] == 4).all()
    assert any("D 11" in n for n in res.notes)  # times 10..20 lie inside the 9..21 s gap
    with pytest.raises(InputError, match=r"drone C has no learned pattern.*\(pattern_of C=NODE\)") as info:
        predict_swarm(model, poses, 20.0)
    assert info.value.param == "pattern_of"  # the command line names its flag
    with pytest.raises(InputError, match="pattern_of names drone"):
        predict_swarm(model, poses, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B", "E": "A"}))
    with pytest.raises(InputError, match="pattern_of C=Z: Z is not a learned node"):
        predict_swarm(model, poses, 20.0, SwarmOptions(pattern_of={"C": "Z", "D": "B"}))
    with pytest.raises(InputError, match="max_gap_s") as info:
        predict_swarm(model, poses, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, max_gap_s=-1.0))
    assert info.value.param == "max_gap_s"
    with pytest.raises(InputError, match="at least 2 drones"):
        predict_swarm(model, poses[poses["node"] == "A"], 20.0)
    bare = PatternSet(basis=model.basis, nodes=model.nodes, coef=model.coef)
    with pytest.raises(InputError, match="frequency"):
        predict_swarm(bare, poses, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}))
    # too close for the far field: no prediction, counted
    close = poses.copy()
    close.loc[close["node"] == "B", "x"] = 0.1
    res = predict_swarm(model, close, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, frequency_hz=2.4e9))
    ab = res.links[(res.links["tx"] == "A") & (res.links["rx"] == "B")]
    assert ab["rssi_pred_dbm"].isna().all() and ab["near_field"].all() and ab["up"].all()
    assert any("far field" in n for n in res.notes)
    # only near-field pairs: every link is up, the bottleneck is unbounded, the summary still works
    two = close[close["node"].isin(["A", "B"])]
    only = predict_swarm(model, two, 20.0, SwarmOptions(frequency_hz=2.4e9))
    assert only.connectivity["connected"].all() and np.isinf(only.connectivity["bottleneck_rssi_dbm"]).all()
    assert "connected at" in only.summary()


def test_headings_improve_the_bottleneck_and_agree_with_the_links():
    from rplearn.analysis.headings import SwarmHeadingOptions, YawOptions, best_swarm_headings, best_yaw

    rng = np.random.default_rng(2)
    model = _model(rng)
    pos = {"A": [0, 0, 20], "B": [40, 0, 20], "C": [20, 30, 25], "D": [60, 40, 20]}
    res = best_swarm_headings(model, pos, 20.0, SwarmHeadingOptions(pattern_of={"C": "A", "D": "B"},
                                                                    start_yaw_deg={"A": 30.0}, fixed=["B"], step_deg=5))
    assert res.bottleneck_dbm >= res.start_bottleneck_dbm
    assert res.yaw_deg["B"] == 0.0 and res.start_yaw_deg["A"] == 30.0
    # the chosen yaws, flown as a (static) pose log, give the same bottleneck through predict_swarm
    rows = [(0.0, d, *p, *quat_wxyz_from_yaw(np.radians(res.yaw_deg[d]))) for d, p in pos.items()]
    poses = pd.DataFrame(rows, columns=["t", "node", "x", "y", "z", "qw", "qx", "qy", "qz"])
    links = predict_swarm(model, poses, 20.0, SwarmOptions(pattern_of={"C": "A", "D": "B"}, times_s=[0.0]))
    assert links.connectivity["bottleneck_rssi_dbm"].iloc[0] == pytest.approx(res.bottleneck_dbm, abs=1e-9)
    # two drones: the pair's optimum, the same as the single-link search on the same grid
    two = best_swarm_headings(model, {"A": [0, 0, 20], "B": [30, 10, 25]}, 20.0, SwarmHeadingOptions(step_deg=1.0))
    single = best_yaw(model, "A", "B", [0, 0, 20], [30, 10, 25], turn="both", options=YawOptions(step_deg=1.0))
    assert two.yaw_deg == {"A": single.tx_yaw_deg, "B": single.rx_yaw_deg}
    with pytest.raises(InputError, match="fixed names unknown"):
        best_swarm_headings(model, pos, 20.0, SwarmHeadingOptions(pattern_of={"C": "A", "D": "B"}, fixed=["Z"]))


def test_three_drone_headings_are_the_grid_optimum():
    """Brute force over every yaw combination on a 30 deg grid, gains from the one-link predictor."""
    import itertools

    from rplearn.analysis.headings import SwarmHeadingOptions, best_swarm_headings

    rng = np.random.default_rng(7)
    model = _model(rng)
    grid = np.arange(-180.0, 180.0, 30.0)
    ya, yb = np.meshgrid(grid, grid, indexing="ij")
    for trial in range(5):
        pos = {d: np.array([*rng.uniform(-40, 40, 2), rng.uniform(15, 30)]) for d in "ABC"}
        pattern = {"A": "A", "B": "B", "C": "A"}
        res = best_swarm_headings(model, pos, 20.0, SwarmHeadingOptions(pattern_of={"C": "A"}, step_deg=30.0))
        table = {}
        for a, b in (("A", "B"), ("A", "C"), ("B", "C")):
            qa = quat_wxyz_from_yaw(np.radians(ya.ravel()))
            qb = quat_wxyz_from_yaw(np.radians(yb.ravel()))
            n = qa.shape[0]
            pa, pb = np.tile(pos[a], (n, 1)), np.tile(pos[b], (n, 1))
            ab = model.predict_for_poses(pattern[a], pattern[b], pa, qa, pb, qb, 20.0, 2.4e9)["rssi_dbm"]
            ba = model.predict_for_poses(pattern[b], pattern[a], pb, qb, pa, qa, 20.0, 2.4e9)["rssi_dbm"]
            table[(a, b)] = np.minimum(ab, ba).reshape(grid.size, grid.size)
        best = -np.inf
        for i, j, k in itertools.product(range(grid.size), repeat=3):
            w = sorted([table[("A", "B")][i, j], table[("A", "C")][i, k], table[("B", "C")][j, k]])
            best = max(best, w[1])  # a triangle's spanning tree: its two strongest edges
        assert res.bottleneck_dbm == pytest.approx(best, abs=1e-9), trial


def test_headings_never_worse_than_off_grid_current_yaws():
    from rplearn.analysis.headings import SwarmHeadingOptions, best_swarm_headings

    rng = np.random.default_rng(3)
    model = _model(rng)
    pos = {"A": [0, 0, 20], "B": [30, 5, 22], "C": [10, 25, 18]}
    # take the fine-grid optimum as the "current" yaws, then search a coarse grid that misses them
    fine = best_swarm_headings(model, pos, 20.0, SwarmHeadingOptions(pattern_of={"C": "A"}, step_deg=5.0))
    coarse = best_swarm_headings(model, pos, 20.0, SwarmHeadingOptions(pattern_of={"C": "A"}, step_deg=45.0,
                                                                       start_yaw_deg=fine.yaw_deg))
    assert coarse.bottleneck_dbm >= fine.bottleneck_dbm - 1e-9
    assert coarse.bottleneck_dbm >= coarse.start_bottleneck_dbm
