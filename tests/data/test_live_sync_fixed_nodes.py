"""Live matching against ``sync`` of the whole logs on a simulated ground-station flight (``sim`` preset
``ground``, its first pass) whose station G is logged as identical rows, and with clock offsets.

A station logged with identical rows holds still over its log's span (``sync``), so a row after its last
row so far is matched once its next row comes: live matching had matched such rows at once against the
span logged so far, ``out_of_span`` (review49: 51 of 200 matched where sync matched 200 on a station
logged at 0, 5 and 20 s; at 1 Hz pose logging, a station logged half a second after the drone lost almost
every row).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.live_sync import LiveMatcher
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.sim import simulate

PASS_S = 85.0  # the ground preset's first pass (the next begins after a 60 s gap)


@pytest.fixture(scope="module")
def ground() -> tuple[pd.DataFrame, pd.DataFrame]:
    r = simulate("ground", seed=0)
    pose, sig = r.pose_log, r.signal_log.drop(columns=["unit"])
    return pose[pose["t"] < PASS_S].reset_index(drop=True), sig[sig["t"] < PASS_S].reset_index(drop=True)


def _station_rows(pose: pd.DataFrame, times_s) -> pd.DataFrame:
    """G's poses replaced by identical rows of its first pose at ``times_s``, as a station logging its surveyed
    pose when something changes (or at a steady rate) writes them."""
    g = pose[pose["node"] == "G"].iloc[[0]]
    rows = pd.concat([g] * len(times_s), ignore_index=True).assign(t=np.asarray(times_s, np.float64))
    return pd.concat([pose[pose["node"] != "G"], rows], ignore_index=True).sort_values("t", kind="stable")


def _live(pose: pd.DataFrame, sig: pd.DataFrame, options: SyncOptions | None = None,
          common_p: pd.Series | None = None, common_s: pd.Series | None = None) -> tuple[int, dict, int]:
    """Matched rows, drops and rows matched before the end of the stream, fed a second of common-clock
    time a poll: each log's rows arrive when their time on the common clock (``common_p``, ``common_s``;
    default their own) has come."""
    m, n = LiveMatcher(options), 0
    kp = np.floor((pose["t"] if common_p is None else common_p).to_numpy(np.float64))
    ks = np.floor((sig["t"] if common_s is None else common_s).to_numpy(np.float64))
    for k in range(int(max(kp.max(), ks.max())) + 1):
        m.add_poses(pose[kp == k])
        m.add_signals(sig[ks == k])
        n += len(m.match().dataset)
    in_flight = n
    n += len(m.match(final=True).dataset)
    return n, {r: v for r, v in m.summary.dropped.items() if v}, in_flight


def _sync(pose: pd.DataFrame, sig: pd.DataFrame, options: SyncOptions | None = None) -> tuple[int, dict]:
    ref = synchronise(pose, sig, options)
    return ref.summary.n_out, {r: v for r, v in ref.summary.dropped.items() if v}


@pytest.mark.parametrize("times_s", [[0.0, 5.0, 20.0, 80.0], [0.0, 0.5, 70.0, 75.0], list(np.arange(0.5, PASS_S, 1.0))],
                         ids=["on_change", "at_start_and_much_later", "1Hz_after_the_drone"])
def test_a_station_of_identical_rows_is_matched_as_sync_matches_it(ground, times_s):
    pose, sig = ground
    pose = _station_rows(pose, times_s)
    n, dropped, in_flight = _live(pose, sig)
    ref = _sync(pose, sig)
    assert (n, dropped) == ref
    span = (sig["t"] > times_s[0]) & (sig["t"] < times_s[-1])
    assert ref[0] > 0.95 * span.sum()  # the station's span is matched
    assert in_flight > 0.95 * ref[0]  # as the flight goes, not held to the end


def test_one_hertz_pose_logging_of_the_drone_and_the_station(ground):
    """A flight whose drone and station are logged once a second (``max_gap_s`` 1.5 s), the station 0.2 s
    into each second, the drone 0.9 s: live matching had matched 168 rows where sync matched 5950 of 6000."""
    pose, sig = ground
    d = pose[pose["node"] == "D"]
    d = d.iloc[np.unique(np.searchsorted(d["t"].to_numpy(), np.arange(0.9, PASS_S, 1.0)))]
    pose = _station_rows(pd.concat([d, pose[pose["node"] == "G"]]), np.arange(0.2, PASS_S, 1.0))
    options = SyncOptions(max_gap_s=1.5)
    n, dropped, in_flight = _live(pose, sig, options)
    ref = _sync(pose, sig, options)
    assert (n, dropped) == ref
    assert ref[0] > 0.95 * len(sig) and in_flight > 0.95 * ref[0]


@pytest.mark.parametrize("pose_offsets_s, signal_offset_s", [({"D": 0.0, "G": 300.0}, 210.0),
                                                              ({"D": -300.0, "G": -300.0}, -210.0),
                                                              ({"D": 0.0, "G": 300.0}, {"D": 210.0, "G": -45.0})],
                         ids=["0_300_210", "minus_300_minus_210", "per_receiver"])
def test_rows_are_settled_on_the_common_clock_after_the_offsets(ground, pose_offsets_s, signal_offset_s):
    """Each log on its own clock (an offset is what puts it on the common clock), its rows arriving when their
    common time has come: live matching compared the logs' own times, holding every row to the end (or
    matching rows before the poses after them had come, ``out_of_span``), where sync matched them."""
    pose, sig = ground
    pose = pose.assign(t=pose["t"] - pose["node"].map(pose_offsets_s))
    sig_offset = sig["rx"].map(signal_offset_s) if isinstance(signal_offset_s, dict) else signal_offset_s
    sig = sig.assign(t=sig["t"] - sig_offset)
    options = SyncOptions(clock_offsets_s=pose_offsets_s, signal_clock_offset_s=signal_offset_s)
    ref = _sync(pose, sig, options)
    n, dropped, in_flight = _live(pose, sig, options, common_s=sig["t"] + sig_offset,
                                  common_p=pose["t"] + pose["node"].map(pose_offsets_s))
    assert (n, dropped) == ref
    assert ref[0] > 0.95 * len(sig) and in_flight > 0.95 * ref[0]
