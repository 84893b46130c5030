"""LiveMatcher: rows matched as they arrive give what sync gives on the whole logs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.live_sync import DUPLICATE_MEMORY_S, LiveMatcher
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.errors import InputError
from rplearn.sim import simulate


@pytest.fixture(scope="module")
def logs() -> tuple[pd.DataFrame, pd.DataFrame]:
    r = simulate("smoke", seed=0)
    signal = r.signal_log.drop(columns=["unit"])
    # a row logged twice in batches far apart, and a station logged once
    signal = pd.concat([signal, signal.iloc[[10]]], ignore_index=True)
    return r.pose_log, signal


def _live(pose: pd.DataFrame, signal: pd.DataFrame, batch_s: float, held_node: str | None = None,
          until_s: float = -np.inf) -> tuple[pd.DataFrame, LiveMatcher]:
    """The logs fed to a matcher in batches of ``batch_s``, as they arrive; with ``held_node``, its poses
    before ``until_s`` held back (a source holding a node's start) and handed out with the batch that reaches it."""
    m = LiveMatcher()
    out = []
    edges = np.arange(pose["t"].min(), pose["t"].max() + batch_s, batch_s)
    for a, b in zip(edges[:-1], edges[1:]):
        held = (pose["node"] == held_node) & (pose["t"] < until_s)
        rows = pose[(pose["t"] >= a) & (pose["t"] < b) & ~held]
        m.add_poses(pd.concat([pose[held], rows]) if a <= until_s < b else rows)  # the held rows, all at once
        m.add_signals(signal[(signal["t"] >= a) & (signal["t"] < b)])
        out.append(m.match().dataset)
    m.add_signals(signal[signal["t"] >= edges[-1]])
    out.append(m.match(final=True).dataset)
    return pd.concat([o for o in out if len(o)], ignore_index=True), m


@pytest.mark.parametrize("batch_s", [0.5, 3.0])
def test_matching_as_rows_arrive_gives_syncs_rows_and_counts(logs, batch_s):
    pose, signal = logs
    whole = synchronise(pose, signal)
    live, m = _live(pose, signal, batch_s)
    expected = whole.dataset.sort_values("t", kind="stable").reset_index(drop=True)
    assert len(live) == len(expected) > 2000
    num = [c for c in expected.columns if c not in ("tx", "rx")]
    np.testing.assert_allclose(live[num].to_numpy(float), expected[num].to_numpy(float), rtol=0, atol=1e-9)
    assert (live["tx"].astype(str).to_numpy() == expected["tx"].astype(str).to_numpy()).all()
    assert m.summary.dropped == whole.summary.dropped
    assert m.summary.dropped["duplicate"] == 1
    assert m.pending_rows == 0


def test_a_row_waits_until_every_moving_node_has_a_pose_after_it(logs):
    pose, signal = logs
    m = LiveMatcher()
    m.add_poses(pose[pose["t"] < 5.0])
    m.add_signals(signal[signal["t"] < 6.0])
    got = m.match().dataset
    assert len(got) and got["t"].max() <= m.settled_s() < 5.0
    assert m.pending_rows == int(((signal["t"] > m.settled_s()) & (signal["t"] < 6.0)).sum())


def test_the_pose_rows_kept_stay_bounded_as_the_flight_goes_on(logs):
    pose, signal = logs
    _, m = _live(pose, signal, 1.0)
    assert len(m._poses) < len(pose) / 20


def test_whole_log_options_are_refused():
    with pytest.raises(InputError, match="airborne"):
        LiveMatcher(SyncOptions(airborne=True))


def test_signal_rows_that_lag_the_poses_still_find_their_poses(logs):
    """A robot's signal file written after its pose file (a poll between the two writes): each
    batch's signal rows arrive one poll after its poses, yet match as ``sync`` matches them
    (the poses are kept back to where the signal stream has reached)."""
    pose, signal = logs
    whole = synchronise(pose, signal)
    m, out = LiveMatcher(), []
    edges = np.arange(pose["t"].min(), pose["t"].max() + 0.5, 0.5)
    late = signal.iloc[:0]
    for a, b in zip(edges[:-1], edges[1:]):
        m.add_poses(pose[(pose["t"] >= a) & (pose["t"] < b)])
        m.add_signals(late)
        out.append(m.match().dataset)
        late = signal[(signal["t"] >= a) & (signal["t"] < b)]
    m.add_signals(pd.concat([late, signal[signal["t"] >= edges[-1]]]))
    out.append(m.match(final=True).dataset)
    live = pd.concat([o for o in out if len(o)], ignore_index=True)
    assert len(live) == len(whole.dataset) and m.summary.dropped == whole.summary.dropped


def test_the_duplicate_hashes_kept_stay_bounded_and_a_copy_sent_again_later_is_still_found(logs):
    """A row sent again 5 s later (a later batch) is a duplicate, as ``sync`` says; the hashes
    kept are those of the last :data:`DUPLICATE_MEMORY_S` or so, not of every row."""
    pose, signal = logs
    row = signal.iloc[[len(signal) // 2]]
    again = float(row["t"].iloc[0]) + 5.0
    whole = synchronise(pose, pd.concat([signal, row], ignore_index=True))
    m = LiveMatcher()
    edges = np.arange(pose["t"].min(), pose["t"].max() + 1.0, 1.0)
    for a, b in zip(edges[:-1], edges[1:]):
        m.add_poses(pose[(pose["t"] >= a) & (pose["t"] < b)])
        m.add_signals(signal[(signal["t"] >= a) & (signal["t"] < b)])
        if a <= again < b:
            m.add_signals(row)  # arrives with a later batch, its time already matched
        m.match()
    m.add_signals(signal[signal["t"] >= edges[-1]])
    m.match(final=True)
    assert m.summary.dropped == whole.summary.dropped and m.summary.dropped["duplicate"] == 2
    span_s = float(signal["t"].max() - signal["t"].min())
    per_s = len(signal) / span_s
    assert span_s > 2 * DUPLICATE_MEMORY_S
    assert len(m._seen) < (DUPLICATE_MEMORY_S + 5.0) * per_s < 0.6 * len(signal)


def _still_ends_and_a_mover(pose: pd.DataFrame) -> pd.DataFrame:
    """A and B held at their first pose for the whole flight, C flying A's track: the A-B
    link's poses are kept whole, while C's moving poses make the hashes be forgotten."""
    held = []
    for node in ("A", "B"):
        group = pose[pose["node"] == node].copy()
        cols = [c for c in group.columns if c not in ("t", "node")]
        group[cols] = group[cols].iloc[0].to_numpy()
        held.append(group)
    mover = pose[pose["node"] == "A"].assign(node="C")
    return pd.concat([*held, mover], ignore_index=True).sort_values("t", kind="stable").reset_index(drop=True)


@pytest.mark.parametrize("still", [True, False], ids=["still_ends", "moving_ends"])
def test_a_copy_sent_again_after_the_hashes_are_forgotten_is_dropped_as_late_not_learned(logs, still):
    """A row sent again 40 s late (> DUPLICATE_MEMORY_S): ``sync`` drops it as ``duplicate``;
    live matching no longer knows its hash, so drops it as ``late`` and learns sync's rows."""
    pose, signal = logs
    signal = signal.iloc[:-1]  # without the fixture's own copy
    pose = _still_ends_and_a_mover(pose) if still else pose
    row = signal.iloc[[len(signal) // 4]]
    again = float(row["t"].iloc[0]) + DUPLICATE_MEMORY_S + 10.0
    assert again < float(signal["t"].max()) - 1.0
    whole = synchronise(pose, pd.concat([signal, row], ignore_index=True))
    m, out = LiveMatcher(), []
    edges = np.arange(pose["t"].min(), pose["t"].max() + 1.0, 1.0)
    for a, b in zip(edges[:-1], edges[1:]):
        m.add_poses(pose[(pose["t"] >= a) & (pose["t"] < b)])
        m.add_signals(signal[(signal["t"] >= a) & (signal["t"] < b)])
        if a <= again < b:
            m.add_signals(row)
        out.append(m.match().dataset)
    m.add_signals(signal[signal["t"] >= edges[-1]])
    out.append(m.match(final=True).dataset)
    live = pd.concat([o for o in out if len(o)], ignore_index=True)
    expected = whole.dataset.sort_values("t", kind="stable").reset_index(drop=True)
    assert whole.summary.dropped["duplicate"] == 1 and len(live) == len(expected) > 2000
    np.testing.assert_allclose(live["t"].to_numpy(float), expected["t"].to_numpy(float), rtol=0, atol=1e-9)
    assert m.summary.dropped["late"] == 1 and m.summary.dropped["duplicate"] == 0
    assert {**m.summary.dropped, "late": 0, "duplicate": 1} == whole.summary.dropped
    assert m.summary.n_in == whole.summary.n_in and m.summary.n_out == whole.summary.n_out


@pytest.mark.parametrize("until_s", [12.0, 45.0])
def test_rows_of_a_node_whose_first_poses_are_held_wait_for_them(logs, until_s):
    # a source holding a node's first poses (CsvTail: a logger's start at the zero position, up to HOLD_S):
    # the rows of its links wait for them and are matched as sync matches them (was: 458 and 1,524 of 2,659
    # dropped as unknown_node)
    pose, signal = logs
    node = "B"
    assert pose.loc[pose["node"] == node, "t"].min() < until_s < pose["t"].max()
    whole = synchronise(pose, signal)
    live, m = _live(pose, signal, 1.0, node, until_s)
    expected = whole.dataset.sort_values(["t", "tx", "rx"], kind="stable").reset_index(drop=True)
    live = live.sort_values(["t", "tx", "rx"], kind="stable").reset_index(drop=True)
    assert len(live) == len(expected)
    num = [c for c in expected.columns if c not in ("tx", "rx")]
    np.testing.assert_allclose(live[num].to_numpy(float), expected[num].to_numpy(float), rtol=0, atol=1e-9)
    assert m.summary.dropped == whole.summary.dropped and m.summary.dropped["unknown_node"] == 0
    assert m.pending_rows == 0 and m.waiting_rows == 0


def _rows_to_a_ghost(logs) -> tuple[LiveMatcher, pd.DataFrame]:
    """A matcher given the first 10 s of poses and signals and 50 rows to a node Z that never logs a pose, matched;
    returns it and those rows."""
    pose, signal = logs
    ghost = signal.iloc[:50].assign(rx="Z")
    m = LiveMatcher()
    m.add_poses(pose[pose["t"] < 10.0])
    m.add_signals(pd.concat([signal[signal["t"] < 10.0], ghost], ignore_index=True))
    m.match()
    return m, ghost


def test_rows_naming_a_node_that_never_logs_wait_no_longer_than_the_hold(logs):
    # a link to a node without poses: its rows wait HOLD_S of pose time, then are dropped as unknown_node
    from rplearn.data.live_sync import HOLD_S

    pose, _ = logs
    m, ghost = _rows_to_a_ghost(logs)
    assert m.waiting_rows == 50 and m.summary.dropped["unknown_node"] == 0
    m.add_poses(pose[(pose["t"] >= 10.0) & (pose["t"] < ghost["t"].max() + HOLD_S + 1.0)])
    m.match()
    assert m.waiting_rows == 0 and m.summary.dropped["unknown_node"] == 50


def test_rows_waiting_for_a_nodes_poses_are_bounded_in_number(logs, monkeypatch):
    # at most WAIT_ROWS signal rows wait (the oldest go first, counted as unknown_node); the bound counts
    # signal rows, not the source's held pose rows (review46: one limit for both dropped rows of a busy link)
    import rplearn.data.live_sync as live_sync

    monkeypatch.setattr(live_sync, "WAIT_ROWS", 20)
    m, _ = _rows_to_a_ghost(logs)
    assert m.waiting_rows == 20 and m.summary.dropped["unknown_node"] == 30
    assert m.waiting_nodes == frozenset({"Z"})


def test_a_pose_time_repeated_in_a_later_batch_is_refused_as_sync_refuses_it():
    """The kept pose rows and a new batch are merged without checking again what each passed;
    a node's time given twice across batches is still refused, with ``sync``'s message."""
    from rplearn.data.live_sync import LiveMatcher
    from rplearn.data.tables import validate_pose_log

    rows = pd.DataFrame({"t": [0.0, 1.0, 2.0], "node": ["A", "A", "B"], "x": 0.0, "y": 0.0, "z": 1.0,
                         "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    m = LiveMatcher()
    m.add_poses(rows.iloc[:2])
    with pytest.raises(InputError) as got:
        m.add_poses(rows.iloc[1:])
    with pytest.raises(InputError) as expected:
        validate_pose_log(pd.concat([rows.iloc[:2], rows.iloc[1:]]), "pose log")
    assert str(got.value) == str(expected.value)
