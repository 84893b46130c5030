"""A node with one pose row so far, in live matching: a node logged once (a station) holds still, as
``sync`` holds a one-row log, but a node whose log has just started must not be held at its first pose
(audit48: the rows waiting for a drone whose poses start at 15 s were all matched at its first pose
once it came, 299 of 300 learned where sync matches 149), nor a moving node trimmed to its last pose
row (the rows after it are ``out_of_span``)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.live_sync import LiveMatcher
from rplearn.data.sync import synchronise


def _node(name: str, t: np.ndarray, radius_m: float) -> pd.DataFrame:
    a = 2 * np.pi * t / 20.0
    yaw = 3 * a
    return pd.DataFrame({"t": t, "node": name, "x": radius_m * np.cos(a), "y": radius_m * np.sin(a), "z": 20.0 + 0 * t,
                         "qw": np.cos(yaw / 2), "qx": 0.0, "qy": 0.0, "qz": np.sin(yaw / 2)})


def _logs(d_rows: slice, station: bool = False) -> tuple[pd.DataFrame, pd.DataFrame]:
    """A circling, D circling (``d_rows`` of its 10 Hz poses), packets A -> D every 0.1 s for 30 s; with
    ``station``, G logged once at t = 0 and packets A -> G too."""
    t = np.arange(300) * 0.1
    parts = [_node("A", t, 40.0), _node("D", t, 30.0).iloc[d_rows]]
    rng = np.random.default_rng(1)
    sig = [pd.DataFrame({"t": t + 0.05, "tx": "A", "rx": "D", "rssi_dbm": -60 + rng.normal(0, 2, 300),
                         "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})]
    if station:
        parts.append(_node("G", np.array([0.0]), 0.0))
        sig.append(sig[0].assign(t=t + 0.07, rx="G"))
    pose = pd.concat(parts, ignore_index=True).sort_values("t", kind="stable")
    return pose, pd.concat(sig, ignore_index=True).sort_values("t", kind="stable")


def _edges(batch_s: float) -> np.ndarray:
    """Batch edges [s] of log time: ``batch_s`` apart in the first second and from 14 to 16 s (where a
    node's log starts or ends, so that it has one pose row so far; and the station's first rows), a
    second apart elsewhere (each batch re-matches what is waiting: fewer batches, a faster test)."""
    fine = np.concatenate([np.arange(0.0, 1.0, batch_s), np.arange(14.0, 16.0, batch_s)])
    return np.unique(np.round(np.concatenate([fine, np.arange(0.0, 32.0, 1.0)]), 6))


def _live(pose: pd.DataFrame, sig: pd.DataFrame, batch_s: float) -> tuple[int, dict, list[int]]:
    """Matched rows, drops and rows matched per batch, fed by the batches of :func:`_edges`."""
    m, per_batch, edges = LiveMatcher(), [], _edges(batch_s)
    kp = np.searchsorted(edges, pose["t"].to_numpy() + 1e-6, side="right") - 1
    ks = np.searchsorted(edges, sig["t"].to_numpy() + 1e-6, side="right") - 1
    for k in range(edges.size - 1):
        m.add_poses(pose[kp == k])
        m.add_signals(sig[ks == k])
        per_batch.append(len(m.match().dataset))
    per_batch.append(len(m.match(final=True).dataset))
    return sum(per_batch), {r: n for r, n in m.summary.dropped.items() if n}, per_batch


@pytest.mark.parametrize("batch_s", [0.1, 1.0])
@pytest.mark.parametrize("d_rows", [slice(150, None), slice(0, 150)], ids=["starts_late", "ends_early"])
def test_a_node_with_one_pose_row_so_far_is_not_held_at_it(d_rows, batch_s):
    pose, sig = _logs(d_rows)
    ref = synchronise(pose, sig)
    n, dropped, _ = _live(pose, sig, batch_s)
    assert (n, dropped) == (ref.summary.n_out, {r: k for r, k in ref.summary.dropped.items() if k})
    assert n == 149 and dropped == {"out_of_span": 151}


def test_a_station_logged_once_holds_still_and_its_rows_are_matched_in_flight():
    """G's one row at t = 0: its links' rows are matched as the flight goes (not all at the end), as sync does."""
    pose, sig = _logs(slice(None), station=True)
    ref = synchronise(pose, sig)
    n, dropped, per_batch = _live(pose, sig, 0.1)
    assert (n, dropped) == (ref.summary.n_out, {r: k for r, k in ref.summary.dropped.items() if k})
    assert sum(per_batch[:-1]) >= n - 4  # matched in flight: the last few wait for the poses after them
