"""Sources of rows that are still being written: a CSV tail, the replay's checks."""

from __future__ import annotations

import pytest

from rplearn.errors import InputError
from rplearn.io.live_sources import CsvTail, replay_tlog

POSE_HEAD = "t,node,x,y,z,qw,qx,qy,qz\n"
SIGNAL_HEAD = "t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n"


def test_a_tail_gives_each_complete_line_once_and_waits_for_a_half_written_one(tmp_path):
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    tail = CsvTail(str(pose), str(signal))
    assert tail.poll().received == 0  # the files do not exist yet
    pose.write_text(POSE_HEAD + "0.0,A,0,0,10,1,0,0,0\n0.1,A,1,0,10,1,0,0,0\n0.2,A,2,0")
    signal.write_text(SIGNAL_HEAD + "0.05,A,B,-60,20,2.4e9\n")
    got = tail.poll()
    assert list(got.poses["t"]) == [0.0, 0.1] and list(got.signals["rssi_dbm"]) == [-60.0]
    assert str(got.poses["node"].iloc[0]) == "A" and str(got.signals["rx"].iloc[0]) == "B"
    with pose.open("a") as fh:
        fh.write(",10,1,0,0,0\n")
    again = tail.poll()
    assert list(again.poses["t"]) == [0.2] and again.signals.empty
    assert tail.poll().received == 0


def test_a_corrupt_appended_row_names_the_file(tmp_path):
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text(POSE_HEAD + "0.0,A,0,0,10,1,0,0,0\n")
    signal.write_text(SIGNAL_HEAD + 'x,"A\n')
    with pytest.raises(Exception, match="signal.csv"):
        CsvTail(str(pose), str(signal)).poll()


@pytest.mark.parametrize(("address", "speed", "match"), [("127.0.0.1:1", 0.0, "speed"), ("nohost", 1.0, "HOST:PORT")])
def test_the_replay_refuses_a_bad_speed_or_address(tmp_path, address, speed, match):
    with pytest.raises(InputError, match=match):
        replay_tlog(str(tmp_path / "x.tlog"), address, speed)
