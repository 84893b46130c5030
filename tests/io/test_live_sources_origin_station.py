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
