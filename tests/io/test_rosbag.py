"""ROS bags with defects: every message recorded twice, a ROS 1 bag cut off or never closed."""

from __future__ import annotations

import io
from pathlib import Path

import pandas as pd
import pytest
from flightfiles import FREQUENCY_HZ, POSE_TOPICS, RSSI_MSG, RSSI_MSGDEF, RSSI_TOPICS, TX_POWER_DBM, write_bag

from rplearn.errors import LogFormatError
from rplearn.io import ReaderOptions, inspect_logs, read_logs
from rplearn.io.inspect import file_damage
from rplearn.io.rosbag import RosbagOptions, read_rosbag, ros1_index_pos


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


REAL_BAG = Path(__file__).resolve().parents[1] / "fixtures" / "ros1-bag" / "test2.bag"
ODOM = {"/jackal_velocity_controller/odom": "jackal"}


def _chunk_starts(path):
    from rosbags.rosbag1 import Reader

    with Reader(path) as r:
        return sorted(c.pos for c in r.chunk_infos)


@pytest.mark.parametrize("where", ["just_after_header", "mid_chunk_header", "at_chunk", "mid_chunk",
                                   "mid_last_chunk", "in_index"])
def test_a_cut_real_ros1_bag_reads_the_messages_before_the_cut(tmp_path, where):
    # was refused: "the bag is cut off at byte N before its index ... `rosbag reindex`"
    data = REAL_BAG.read_bytes()
    starts = _chunk_starts(REAL_BAG)  # 5 bz2 chunks
    index_at = ros1_index_pos(REAL_BAG)
    at = {"just_after_header": starts[0] + 12, "mid_chunk_header": starts[1] + 30, "at_chunk": starts[2],
          "mid_chunk": (starts[2] + starts[3]) // 2, "mid_last_chunk": starts[4] + 1000,
          "in_index": index_at + 40}[where]
    cut = tmp_path / "cut.bag"
    cut.write_bytes(data[:at])
    whole, _ = read_rosbag(REAL_BAG, ODOM)
    if where == "just_after_header":
        with pytest.raises(LogFormatError, match=rf"cut.bag: the bag is cut off or damaged at byte {starts[0]:,} "
                                                 r"\(the header of the first record after the bag header\) before any whole message"):
            read_rosbag(cut, ODOM)
        return
    logs, meta = read_rosbag(cut, ODOM)
    n = len(logs.pose)
    assert 0 < n <= len(whole.pose)
    pd.testing.assert_frame_equal(logs.pose, whole.pose.iloc[:n].reset_index(drop=True))
    whole_chunks = sum(s < at for s in starts) - (where in ("mid_chunk_header", "mid_chunk", "mid_last_chunk"))
    assert meta["cut_off_at_byte"] == (starts[whole_chunks] if whole_chunks < len(starts) else index_at)
    assert meta["records_read"] > n and meta["unindexed"] is False
    assert n == (len(whole.pose) if where == "in_index" else meta["topics"]["/jackal_velocity_controller/odom"])
    line = file_damage(str(cut), meta)
    assert len(line) == 1 and f"cut off inside the message at byte {meta['cut_off_at_byte']:,}" in line[0]
    assert f"the {meta['records_read']:,} complete record(s) before it were read" in line[0]


@pytest.mark.parametrize("fraction", [0.2, 0.5, 0.77, 0.999])
def test_a_cut_written_ros1_bag_reads_a_prefix_of_each_topic(tmp_path, flight, fraction):
    pose, sig = flight
    whole = write_bag(tmp_path / "whole.bag", pose.iloc[::7], sig.iloc[::7], "ros1")  # uncompressed chunks
    data = whole.read_bytes()
    cut = tmp_path / "cut.bag"
    cut.write_bytes(data[:int(len(data) * fraction)])
    (lw, mw), (lc, mc) = _read(whole), _read(cut)
    assert mc["cut_off_at_byte"] is not None and mc["cut_off_at_byte"] <= int(len(data) * fraction)
    assert sum(mc["topics"].values()) == mc["records_read"]
    lost = sum(mw["topics"].values()) - mc["records_read"]
    assert (lost > 0) if fraction < 0.9 else (lost == 0)  # 0.999: a cut in the index after the one chunk
    for node, got in lc.pose.groupby("node"):
        want = lw.pose[lw.pose["node"] == node]
        pd.testing.assert_frame_equal(got.reset_index(drop=True), want.iloc[:len(got)].reset_index(drop=True))
    for (tx, rx), got in lc.signal.groupby(["tx", "rx"]):
        want = lw.signal[(lw.signal["tx"] == tx) & (lw.signal["rx"] == rx)]
        pd.testing.assert_frame_equal(got.reset_index(drop=True), want.iloc[:len(got)].reset_index(drop=True))


def test_a_ros1_bag_never_closed_by_its_recorder_is_read_record_by_record(tmp_path):
    data = bytearray(REAL_BAG.read_bytes())
    field = data.index(b"index_pos=") + len(b"index_pos=")
    data[field:field + 8] = bytes(8)  # what `rosbag record` leaves until it closes the bag
    open_bag = tmp_path / "open.bag"
    open_bag.write_bytes(bytes(data))
    (whole, mw), (logs, meta) = read_rosbag(REAL_BAG, ODOM), read_rosbag(open_bag, ODOM)
    pd.testing.assert_frame_equal(logs.pose, whole.pose)
    assert meta["unindexed"] is True and meta["cut_off_at_byte"] is None and meta["records_read"] == 3061 + 3060
    assert mw["unindexed"] is False and mw["records_read"] is None
    assert any("the bag has no index" in line for line in file_damage(str(open_bag), meta))


@pytest.mark.parametrize("tail", ["junk", "bag"])
def test_bytes_after_a_ros1_bags_index_are_said(tmp_path, tail):
    # was silent: the index reader never looks past the index
    data = REAL_BAG.read_bytes()
    extra = data if tail == "bag" else bytes(range(256)) * 7
    longer = tmp_path / "longer.bag"
    longer.write_bytes(data + extra)
    (whole, mw), (logs, meta) = read_rosbag(REAL_BAG, ODOM), read_rosbag(longer, ODOM)
    pd.testing.assert_frame_equal(logs.pose, whole.pose)
    assert mw["trailing_bytes"] == 0 and meta["trailing_bytes"] == len(extra)
    assert meta["trailing_bag"] is (tail == "bag")
    (line,) = file_damage(str(longer), meta)
    assert f"{len(extra):,} byte(s) after the bag's index were not read" in line
    assert ("another bag begins there" in line) is (tail == "bag")


def test_inspect_says_a_cut_ros1_bag(tmp_path):
    cut = tmp_path / "cut.bag"
    cut.write_bytes(REAL_BAG.read_bytes()[:400_000])
    problems = inspect_logs(cut, ReaderOptions(pose_topics=ODOM)).problems
    assert any(p.startswith(f"{cut}: the file is cut off inside the message at byte") and "complete record(s)" in p
               for p in problems), problems


class _NoWholeRead(io.FileIO):
    """A bag file that refuses to be read whole into memory."""

    def read(self, size=-1):
        if size is None or size < 0:
            raise AssertionError("the whole bag read into memory")
        return super().read(size)


def test_a_cut_ros1_bag_is_scanned_without_reading_it_whole_into_memory(tmp_path):
    from rplearn.io._ros1_scan import scan_ros1

    cut = tmp_path / "cut.bag"
    data = REAL_BAG.read_bytes()
    cut.write_bytes(data[:len(data) // 2])
    with _NoWholeRead(cut, "r") as fh:
        mapped = scan_ros1(fh, None)
    in_memory = scan_ros1(io.BytesIO(data[:len(data) // 2]), None)
    assert mapped.messages_read == in_memory.messages_read > 0
    assert mapped.cut_off_at_byte == in_memory.cut_off_at_byte is not None
    assert list(mapped.chunks) == list(in_memory.chunks)
