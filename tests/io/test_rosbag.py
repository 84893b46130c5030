"""ROS bags with defects: every message recorded twice."""

from __future__ import annotations

import pandas as pd
import pytest
from flightfiles import FREQUENCY_HZ, POSE_TOPICS, RSSI_MSG, RSSI_MSGDEF, RSSI_TOPICS, TX_POWER_DBM, write_bag

from rplearn.io import ReaderOptions, inspect_logs, read_logs
from rplearn.io.inspect import file_damage
from rplearn.io.rosbag import RosbagOptions, read_rosbag


def _read(path):
    return read_rosbag(path, POSE_TOPICS, RSSI_TOPICS, rssi_field="rssi_dbm", tx_power_dbm=TX_POWER_DBM,
                       frequency_hz=FREQUENCY_HZ, options=RosbagOptions(msg_definitions={RSSI_MSG: RSSI_MSGDEF}))


@pytest.mark.parametrize("kind", ["ros1", "mcap"])
def test_a_bag_with_every_message_twice_reads_as_once_and_says_so(tmp_path, flight, kind):
    pose, sig = flight
    pose, sig = pose.iloc[::7], sig.iloc[::7]
    once = write_bag(tmp_path / ("once.bag" if kind == "ros1" else "once"), pose, sig, kind)
    twice = write_bag(tmp_path / ("twice.bag" if kind == "ros1" else "twice"), pose, sig, kind, copies=2)
    (l1, m1), (l2, m2) = _read(once), _read(twice)
    pd.testing.assert_frame_equal(l1.pose, l2.pose)
    pd.testing.assert_frame_equal(l1.signal, l2.signal)
    assert m1["repeated_messages"] == 0 and m2["repeated_messages"] == len(pose) + len(sig)
    assert m2["topics"] == m1["topics"]
    assert sum(m2["repeated_by_topic"].values()) == m2["repeated_messages"]
    assert any("part of the log is in the file twice" in line for line in file_damage(str(twice), m2))


def test_a_doubled_bag_is_said_by_inspect(tmp_path, flight):
    pose, sig = flight
    twice = write_bag(tmp_path / "twice.bag", pose.iloc[::9], sig.iloc[::9], "ros1", copies=2)
    options = ReaderOptions(pose_topics=POSE_TOPICS, rssi_topics=RSSI_TOPICS, rssi_field="rssi_dbm",
                            tx_power_dbm=TX_POWER_DBM, frequency_hz=FREQUENCY_HZ,
                            msg_definitions={RSSI_MSG: RSSI_MSGDEF})
    _, meta = read_logs(twice, options)
    assert meta["files"][0]["repeated_messages"] > 0
    problems = inspect_logs(twice, options).problems
    assert any("twice.bag" in p and "repeat an earlier one exactly" in p for p in problems)


@pytest.mark.parametrize("fraction", [0.5, 0.999])
def test_a_cut_ros1_bag_is_said_to_be_cut(tmp_path, flight, fraction):
    from rplearn.errors import LogFormatError
    from rplearn.io.rosbag import ros1_index_pos

    pose, sig = flight
    whole = write_bag(tmp_path / "whole.bag", pose.iloc[::7], sig.iloc[::7], "ros1")
    data = whole.read_bytes()
    index_at = ros1_index_pos(whole)
    assert index_at is not None and len(data) // 2 < index_at < len(data)
    cut = tmp_path / "cut.bag"
    cut.write_bytes(data[:int(len(data) * fraction)])
    # was "cannot open bag (AnyReaderError: Bag index looks damaged: ...)"
    want = (rf"cut.bag: the bag is cut off at byte {int(len(data) * fraction):,} before its index" if fraction < 0.9
            else rf"cut.bag: the bag's index \(from byte {index_at:,} of .*cut off or damaged")
    with pytest.raises(LogFormatError, match=want):
        _read(cut)
