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
          shift_s: dict[str, float] | None = None, poll_s: float = 1.0) -> tuple[int, dict, int]:
    """Matched rows, drops and rows matched before the end of the stream, fed ``poll_s`` of common-clock
    time a poll (each log's rows arrive when their time on the common clock has come: ``shift_s`` per
    node and ``"signal"``)."""
    shift_s = shift_s or {}
    m, n = LiveMatcher(options), 0
    common_p = pose["t"].to_numpy() + pose["node"].map(lambda v: shift_s.get(v, 0.0)).to_numpy(np.float64)
    common_s = sig["t"].to_numpy() + shift_s.get("signal", 0.0)
    kp, ks = np.floor(common_p / poll_s), np.floor(common_s / poll_s)
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
