"""A ROS 1 bag with a flipped byte inside a chunk: the damaged chunk is named (number, byte,
compression), its lost messages counted, and the other chunks read (they were refused whole,
with no word of where)."""

from __future__ import annotations

from pathlib import Path

from flightfiles import FREQUENCY_HZ, POSE_TOPICS, RSSI_MSG, RSSI_MSGDEF, RSSI_TOPICS, TX_POWER_DBM, write_bag

from rplearn.io.damage import file_damage
from rplearn.io.rosbag import RosbagOptions, read_rosbag, ros1_index_pos

REAL_BAG = Path(__file__).resolve().parents[1] / "fixtures" / "ros1-bag" / "test2.bag"
ODOM = {"/jackal_velocity_controller/odom": "j"}
ODOM_MESSAGES = 3060  # of the real bag (tests/io/test_rosbag.py reads them all)
CHUNK_2_AT = 124_853  # the second bz2 chunk record of the real bag (its data start 48 bytes later)


def _flipped(tmp_path: Path, data: bytes, at: int, name: str = "flipped.bag") -> Path:
    bad = bytearray(data)
    bad[at] ^= 0xFF
    out = tmp_path / name
    out.write_bytes(bytes(bad))
    return out


def test_a_flipped_byte_in_a_bz2_chunk_loses_that_chunk_only_and_says_where(tmp_path):
    bad = _flipped(tmp_path, REAL_BAG.read_bytes(), CHUNK_2_AT + 48 + 5000)
    logs, meta = read_rosbag(bad, ODOM)
    [d] = meta["damaged_chunks"]
    assert (d["chunk"], d["at_byte"], d["compression"]) == (2, CHUNK_2_AT, "bz2")
    assert d["what"] == "its data do not decompress" and meta["damaged_chunk_messages"] == d["lost_messages"] > 0
    assert len(logs.pose) + d["lost_messages"] == ODOM_MESSAGES
    [line] = file_damage(str(bad), meta)
    assert line.startswith(f"{bad}: chunk 2 of the bag (at byte 124,853, bz2) is damaged (its data do not decompress")
    assert f"its {d['lost_messages']:,} message(s) of the topics read are lost" in line


def test_an_unindexed_bag_reads_on_past_a_damaged_chunk(tmp_path):
    data = bytearray(REAL_BAG.read_bytes())
    field = data.index(b"index_pos=") + len(b"index_pos=")
    data[field:field + 8] = bytes(8)  # never closed: read record by record
    open_bag = tmp_path / "open.bag"
    open_bag.write_bytes(bytes(data))
    intact, _ = read_rosbag(open_bag, ODOM)
    logs, meta = read_rosbag(_flipped(tmp_path, bytes(data), CHUNK_2_AT + 48 + 5000), ODOM)
    [d] = meta["damaged_chunks"]
    assert (d["chunk"], d["at_byte"], d["lost_messages"]) == (2, CHUNK_2_AT, None)
    assert meta["cut_off_at_byte"] is None and len(intact.pose) > len(logs.pose) > len(intact.pose) * 0.6
    assert logs.pose["t"].max() == intact.pose["t"].max()  # the chunks after the damaged one were read
    assert any("chunk 2 of the bag (at byte 124,853, bz2) is damaged" in s for s in file_damage("open.bag", meta))


def test_a_flipped_record_in_an_uncompressed_chunk_loses_that_message(tmp_path, flight):
    pose, sig = flight
    good = write_bag(tmp_path / "good.bag", pose.iloc[::7], sig.iloc[::7], "ros1")
    options = RosbagOptions(msg_definitions={RSSI_MSG: RSSI_MSGDEF})

    def read(path: Path):
        return read_rosbag(path, POSE_TOPICS, RSSI_TOPICS, rssi_field="rssi_dbm", tx_power_dbm=TX_POWER_DBM,
                           frequency_hz=FREQUENCY_HZ, options=options)

    data = good.read_bytes()
    ops = [i for i in range(len(data)) if data.startswith(b"op=\x02", i)]
    (_, mw), (_, mb) = read(good), read(_flipped(tmp_path, data, ops[len(ops) // 2] + 3))  # a message record's op
    [d] = mb["damaged_chunks"]
    assert d["what"] == "a damaged record" and d["lost_messages"] == 1 and d["compression"] == "none"
    assert sum(mb["topics"].values()) == sum(mw["topics"].values()) - 1


def test_a_flipped_byte_in_the_index_reads_the_bag_record_by_record_and_says_where(tmp_path):
    """Was refused whole ("cannot open bag (ValueError: 249 is not a valid RecordType)"), naming no byte."""
    data = REAL_BAG.read_bytes()
    index_at = data.index(b"op=\x06", ros1_index_pos(REAL_BAG))  # a chunk info record of the index
    bad = _flipped(tmp_path, data, index_at + 3)  # its op: a record of no bag kind
    logs, meta = read_rosbag(bad, ODOM)
    assert len(logs.pose) == ODOM_MESSAGES and meta["damaged_chunks"] == []
    d = meta["damaged_index"]
    assert d["at_byte"] is not None and ros1_index_pos(REAL_BAG) <= d["at_byte"] < index_at
    assert "a record of no bag kind" in d["what"]
    assert any(f"at byte {d['at_byte']:,}" in line for line in file_damage(str(bad), meta))


def test_a_damaged_index_is_said_as_such_not_as_a_cut_off_file(tmp_path):
    """Was said as "the file is cut off inside the message at byte ... (a log that ends early: power
    loss ...)", though every message was read record by record."""
    data = REAL_BAG.read_bytes()
    index_pos = ros1_index_pos(REAL_BAG)
    bad = _flipped(tmp_path, data, data.index(b"op=\x06", index_pos) + 3)
    logs, meta = read_rosbag(bad, ODOM)
    assert meta["cut_off_at_byte"] is None and meta["cut_off_record"] is None and len(logs.pose) == ODOM_MESSAGES
    [line] = file_damage(str(bad), meta)
    assert line.startswith(f"{bad}: the bag's index (from byte {index_pos:,}) is damaged at byte ")
    assert f"read record by record from the start ({meta['records_read']:,} message record(s) read)" in line
    assert "no message was lost" in line and "cut off" not in line
