"""rplearn.io.live_sources.CsvTail with a static ground station at the ENU origin (0, 0, 0), the natural
frame for a table whose positions are measured from the station: ``sync`` on the whole file keeps every
row of it, so a live session should hand the station's poses out as they come and match its links from
the first poll (found by review45: the pre-fix zero hold keeps them back for HOLD_S of table time, and
the signal rows of its links are dropped as unknown_node meanwhile)."""

from __future__ import annotations

from pathlib import Path

from rplearn.data.live_sync import LiveMatcher
from rplearn.io.live_sources import CsvTail
from rplearn.io.options import ReaderOptions


def _write(pose: Path, signal: Path, start_s: float) -> None:
    """10 s at 10 Hz: station B still at the origin, vehicle A flying east, A -> B readings."""
    with pose.open("a") as fp, signal.open("a") as fs:
        for k in range(100):
            t = start_s + 0.1 * k
            fp.write(f"{t:.2f},B,0,0,0,1,0,0,0\n{t + 0.05:.2f},A,{10 + t:g},5,20,1,0,0,0\n")
            fs.write(f"{t + 0.07:.3f},A,B,{-60 - 0.01 * k:.2f},20,433000000\n")


def test_a_station_at_the_origin_is_handed_out_and_matched_from_the_first_poll(tmp_path):
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text("t,node,x,y,z,qw,qx,qy,qz\n")
    signal.write_text("t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n")
    tail = CsvTail(str(pose), str(signal), ReaderOptions(nan_policy="drop"))
    matcher = LiveMatcher()
    _write(pose, signal, 0.0)
    got = tail.poll()
    assert set(got.poses["node"]) == {"A", "B"}  # was: only A (B held back)
    matcher.add_poses(got.poses)
    matcher.add_signals(got.signals)
    result = matcher.match()
    assert result.summary.dropped["unknown_node"] == 0  # was: 99 (every settled row of the link)
    assert len(result.dataset) > 90


def test_a_station_at_the_origin_logging_its_attitude_is_held_and_its_links_rows_wait_for_it(tmp_path):
    """A station at the origin whose attitude varies (sensor noise: not one pose) is held back as a logger's start
    at the zero position may be, HOLD_S of table time; the rows of its links wait in the matcher for its poses,
    and the session ends with the rows sync matches from the finished files (was: 1,198 of 1,798 rows dropped
    as unknown_node, the station held)."""
    import numpy as np
    import pandas as pd

    from rplearn.data.live_sync import HOLD_S
    from rplearn.data.sync import synchronise
    from rplearn.io import read_logs

    rng = np.random.default_rng(4)
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text("t,node,x,y,z,qw,qx,qy,qz\n")
    signal.write_text("t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n")
    options = ReaderOptions(nan_policy="drop")
    tail, matcher, got = CsvTail(str(pose), str(signal), options), LiveMatcher(), []
    seconds = int(HOLD_S) + 30
    for s in range(seconds):  # a poll a second
        with pose.open("a") as fp, signal.open("a") as fs:
            for k in range(10):
                t = s + 0.1 * k
                yaw = 0.02 * rng.standard_normal()
                fp.write(f"{t:.2f},G,0,0,0,{np.cos(yaw / 2):.9f},0,0,{np.sin(yaw / 2):.9f}\n"
                         f"{t + 0.05:.2f},A,{10 + 2 * t:g},5,20,1,0,0,0\n")
                fs.write(f"{t + 0.07:.3f},A,G,{-60 - 0.01 * k:.2f},20,433000000\n"
                         f"{t + 0.08:.3f},G,A,{-61 - 0.01 * k:.2f},20,433000000\n")
        polled = tail.poll(final=s == seconds - 1)
        matcher.add_poses(polled.poses)
        matcher.add_signals(polled.signals)
        got.append(matcher.match(final=s == seconds - 1).dataset)
    live = pd.concat(got, ignore_index=True).sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    logs, _ = read_logs([str(pose), str(signal)], options)
    whole = synchronise(logs.pose, logs.signal)
    expected = whole.dataset.sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    assert matcher.summary.dropped["unknown_node"] == 0 and len(live) == len(expected) == 2 * 10 * seconds - 2  # the last two: after the last pose
    num = [c for c in expected.columns if c not in ("tx", "rx")]
    np.testing.assert_allclose(live[num].to_numpy(float), expected[num].to_numpy(float), rtol=0, atol=1e-9)
    assert matcher.summary.dropped == whole.summary.dropped
