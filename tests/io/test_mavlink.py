"""ArduPilot / MAVLink readers (rplearn.io.mavlink): real tlogs and DataFlash, and a round trip
through pymavlink's encoder."""

from __future__ import annotations

import shutil
import struct
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from flightfiles import simulated_dataflash
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from rplearn.core.geometry import rotate_body_to_world
from rplearn.errors import LogFormatError, RplearnError
from rplearn.io._mavlink_records import merge_copied_boots
from rplearn.io.inspect import file_damage
from rplearn.io.mavlink import MavlinkOptions, dataflash_cut_off_at, read_mavlink, sik_rssi_to_dbm

DATA = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot"
TLOG_1 = DATA / "mavlink-log_2013-10-13_16-58-51.tlog"
TLOG_2 = DATA / "mavlink-log_2013-10-13_18-31-24.tlog"
BIN = DATA / "pymavlink_test.BIN"


def test_folder_carries_licenses_and_provenance():
    names = {p.name for p in DATA.iterdir()}
    assert {"LICENSE-code-lever-mavlink-log.txt", "COPYING-pymavlink", "PROVENANCE.md"} <= names


# ------------------------------------------------------------------------------ real tlogs


@pytest.fixture(scope="module")
def real_tlog():
    """``path`` -> what :func:`read_mavlink` makes of a real tlog at 20 dBm and 915 MHz, each read
    once for the module's tests of it (they only read the result)."""
    read: dict[Path, tuple] = {}

    def of(path: Path) -> tuple:
        if path not in read:
            read[path] = read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6)
        return read[path]

    return of


@pytest.mark.parametrize(
    "path, attitude, positions, radio, link_lost, heartbeat, gps",
    [(TLOG_1, 2743, 974, 570, 57, 1082, 650), (TLOG_2, 1977, 702, 1114, 695, 1529, 473)],
)
def test_real_tlog_counts_match_pymavlink(real_tlog, path, attitude, positions, radio, link_lost, heartbeat, gps):
    logs, meta = real_tlog(path)
    assert meta["format"] == "tlog"
    assert meta["messages"] == {"ATTITUDE": attitude, "GLOBAL_POSITION_INT": positions, "RADIO": radio,
                                "HEARTBEAT": heartbeat, "GPS_RAW_INT": gps}
    # every ATTITUDE is a pose row or a counted drop
    vehicle = logs.pose[logs.pose["node"] == "sys1"]
    assert len(vehicle) == meta["rows"]
    assert len(vehicle) + sum(meta["dropped"].values()) == attitude
    assert sum(meta["dropped"].values()) < 0.01 * attitude
    # every RADIO message gives one row per direction; a link-lost one an outage row per direction
    # (counted, rssi_dbm NaN): the received rows are as before outages were kept
    s = meta["signal"]
    assert s["link_lost"] == link_lost
    received = logs.signal[~logs.signal["outage"]]
    links = received.groupby(["tx", "rx"]).size().to_dict()
    assert links == {("sys1", "gcs"): radio - link_lost, ("gcs", "sys1"): radio - link_lost}
    assert s["rows_vehicle_to_station"] == s["rows_station_to_vehicle"] == radio - link_lost
    lost = logs.signal[logs.signal["outage"]]
    assert lost.groupby(["tx", "rx"]).size().to_dict() == {("sys1", "gcs"): link_lost, ("gcs", "sys1"): link_lost}
    assert s["outage_vehicle_to_station"] == s["outage_station_to_vehicle"] == link_lost
    assert lost["rssi_dbm"].isna().all() and received["rssi_dbm"].notna().all()
    # the ground station: one static row at the first fix, said so
    station = logs.pose[logs.pose["node"] == "gcs"]
    assert len(station) == 1
    assert "first position fix" in meta["station_note"]
    assert np.allclose(station[["x", "y", "z"]].to_numpy(), 0.0, atol=1e-6)
    assert meta["station_geodetic"][0] == pytest.approx(41.185, abs=0.01)
    assert meta["station_geodetic"][1] == pytest.approx(-96.010, abs=0.01)


@pytest.mark.parametrize("path, top", [(TLOG_1, 100.8), (TLOG_2, 150.9)])
def test_real_tlog_poses_are_plausible(real_tlog, path, top):
    logs, _ = real_tlog(path)
    pose = logs.pose
    q = pose[["qw", "qx", "qy", "qz"]].to_numpy()
    assert np.isfinite(q).all()
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-9)
    z = pose["z"].to_numpy()
    # relative altitude (PROVENANCE.md) within a few metres: the station sits at the first fix
    assert -10.0 < z.min() < 1.0 and top - 10.0 < z.max() < top + 10.0
    assert np.hypot(pose["x"], pose["y"]).max() < 1000.0
    # poses and signal share the ground station's UNIX clock (2013-10-13)
    for t in (pose["t"], logs.signal["t"]):
        assert 1381701000 < t.min() and t.max() < 1381709000
    assert pose.groupby("node")["t"].apply(lambda s: s.is_monotonic_increasing).all()
    # SiK units -> dBm: every value is raw / 1.9 - 127 for a raw value in 1..254 (outage rows: no value)
    raw = (logs.signal.loc[~logs.signal["outage"], "rssi_dbm"].to_numpy() + 127.0) * 1.9
    np.testing.assert_allclose(raw, np.round(raw), atol=1e-9)
    assert raw.min() >= 1 and raw.max() <= 254


def test_real_tlog_link_lost_rows_follow_the_vehicle_stream(real_tlog):
    logs, _ = real_tlog(TLOG_1)
    last_pose = logs.pose.loc[logs.pose["node"] == "sys1", "t"].max()
    # the 57 link-lost messages (outage rows) came after the vehicle's last message: the received
    # packets end within seconds of it (the radio holds its remote statistics until the link times out)
    received, lost = logs.signal[~logs.signal["outage"]], logs.signal[logs.signal["outage"]]
    assert received["t"].max() < last_pose + 5.0
    assert received["t"].max() > last_pose - 5.0
    assert len(lost) == 2 * 57 and lost["t"].min() > last_pose + 2.0


# ------------------------------------------------------------------------------ DataFlash


def test_dataflash_counts_and_cut_off_record():
    logs, meta = read_mavlink(BIN, tx_power_dbm=20.0, frequency_hz=433e6)
    assert meta["format"] == "dataflash"
    assert meta["messages"]["ATT"] == 24 and meta["messages"]["POS"] == 23 and meta["messages"]["RAD"] == 1
    vehicle = logs.pose[logs.pose["node"] == "sys1"]
    assert len(vehicle) + sum(meta["dropped"].values()) == 24
    assert meta["cut_off_at_byte"] == 65512 and meta["cut_off_record"] == "AHR2"
    assert meta["corrupt_bytes"] == 0
    assert "ORGN" in meta["station_note"]
    # RAD is logged from the air radio: RSSI = vehicle receiving, RemRSSI = station receiving
    sig = logs.signal.set_index(["tx", "rx"])
    assert sig.loc[("gcs", "sys1"), "rssi_dbm"] == pytest.approx(111 / 1.9 - 127)
    assert sig.loc[("sys1", "gcs"), "rssi_dbm"] == pytest.approx(115 / 1.9 - 127)
    assert sig["t"].iloc[0] == pytest.approx(82.570082)
    assert vehicle["t"].between(81.7, 82.8).all()
    # sitting still on the ground at CMAC, within a metre of home
    assert np.abs(vehicle[["x", "y", "z"]].to_numpy()).max() < 1.0


def test_dataflash_corrupt_bytes_are_counted(tmp_path):
    data = BIN.read_bytes()
    junk = tmp_path / "junk.bin"
    junk.write_bytes(data[:89 * 3] + b"\x00garbage" + data[89 * 3:])  # between two FMT records
    assert dataflash_cut_off_at(junk) == (65512 + 8, "AHR2", 8)
    _, meta = read_mavlink(junk, tx_power_dbm=20.0, frequency_hz=433e6)
    assert meta["corrupt_bytes"] == 8 and meta["messages"]["ATT"] == 24


# ------------------------------------------------- a log in the file twice, corrupt frames, a first record cut


def _read(path):
    return read_mavlink(path, tx_power_dbm=20.0, frequency_hz=433e6)


def test_a_tlog_in_the_file_twice_reads_as_once_and_says_so(tmp_path):
    twice = tmp_path / "twice.tlog"
    twice.write_bytes(TLOG_2.read_bytes() * 2)  # concatenated with itself
    (once, m1), (doubled, m2) = _read(TLOG_2), _read(twice)
    pd.testing.assert_frame_equal(once.pose, doubled.pose)
    pd.testing.assert_frame_equal(once.signal, doubled.signal)
    assert m1["repeated_messages"] == 0 and m2["repeated_messages"] == sum(m1["messages"].values())
    assert m2["reboots"] == 0 and m2["dropped"] == m1["dropped"] and m2["messages"] == m1["messages"]
    assert m2["radio_senders"] == m1["radio_senders"] == {"51/68": 1114}  # review 38: was 2,228 doubled
    assert any("part of the log is in the file twice" in line for line in file_damage(str(twice), m2))


def test_a_dataflash_log_in_the_file_twice_is_not_a_reboot_and_a_second_flight(tmp_path):
    once_path = simulated_dataflash(tmp_path / "once.bin")
    twice = tmp_path / "twice.bin"
    twice.write_bytes(once_path.read_bytes() * 2)  # its TimeUS steps back: read before as a reboot
    (once, m1), (doubled, m2) = _read(once_path), _read(twice)
    pd.testing.assert_frame_equal(once.pose, doubled.pose)
    pd.testing.assert_frame_equal(once.signal, doubled.signal)
    assert m2["reboots"] == 0 and m2["repeated_messages"] > 0 and m1["repeated_messages"] == 0
    assert any("part of the log is in the file twice" in line for line in file_damage(str(twice), m2))


def test_a_real_reboot_is_not_merged_for_a_few_equal_records():
    # boot 1 repeats one record of boot 0 by chance (ORGN at the same TimeUS): still a reboot
    att = [(1.0, 0.1, 0.2, 0.3, 0), (2.0, 0.1, 0.2, 0.3, 0), (1.0, 0.5, 0.2, 0.3, 1), (2.0, 0.6, 0.2, 0.3, 1)]
    tables = {"ATT": list(att), "ORGN": [(1.5, 0), (1.5, 1)]}
    boot_t = [(1.0, 0), (1.5, 0), (2.0, 0), (1.0, 1), (1.5, 1), (2.0, 1)]
    assert merge_copied_boots(tables, boot_t) == 0
    assert tables["ATT"] == att and [b for _, b in boot_t] == [0, 0, 0, 1, 1, 1]
    # boots 0, 1 (a reboot), then both again: 2 is boot 0 again, 3 boot 1
    att4 = att + [(r[0], *r[1:4], r[4] + 2) for r in att]
    tables = {"ATT": list(att4)}
    boot_t = [(r[0], r[4]) for r in att4]
    assert merge_copied_boots(tables, boot_t) == 4
    assert tables["ATT"] == att and [b for _, b in boot_t] == [0, 0, 1, 1, 0, 0, 1, 1]


def test_a_copied_boot_drops_only_the_copies_not_distinct_records_that_read_alike():
    # review 38: boot 0 holds two ORGN records at one TimeUS (type 0 and 1: rows (t, boot) alike);
    # boot 1 is boot 0 again. Both records stay, only the 2 + 2 copies go (was: 3 dropped, one
    # of boot 0's own ORGN records with them)
    att = [(1.0, 0.1, 0.2, 0.3, 0), (2.0, 0.1, 0.2, 0.3, 0)]
    orgn = [(1.5, 0), (1.5, 0)]
    tables = {"ATT": att + [(*r[:-1], 1) for r in att], "ORGN": orgn + [(1.5, 1), (1.5, 1)]}
    boot_t = [(1.0, 0), (1.5, 0), (1.5, 0), (2.0, 0), (1.0, 1), (1.5, 1), (1.5, 1), (2.0, 1)]
    assert merge_copied_boots(tables, boot_t) == 4
    assert tables == {"ATT": att, "ORGN": orgn}
    # a real reboot (boot 1) between boot 0 and its copy (boot 2): boot 1's own alike records stay
    tables = {"ATT": att + [(5.0, 0.9, 0.2, 0.3, 1)] + [(*r[:-1], 2) for r in att],
              "ORGN": orgn + [(0.5, 1), (0.5, 1)] + [(1.5, 2), (1.5, 2)]}
    boot_t = [(r[0], r[-1]) for k in ("ATT", "ORGN") for r in tables[k]]
    assert merge_copied_boots(tables, boot_t) == 4
    assert tables["ORGN"] == orgn + [(0.5, 1), (0.5, 1)]


def test_a_dataflash_log_in_the_file_twice_counts_its_messages_once(tmp_path):
    once_path = simulated_dataflash(tmp_path / "once.bin")
    twice = tmp_path / "twice.bin"
    twice.write_bytes(once_path.read_bytes() * 2)
    (_, m1), (_, m2) = _read(once_path), _read(twice)
    assert m1["messages"]["ORGN"] == 2  # an EKF origin and a home, at one TimeUS
    assert m2["messages"] == m1["messages"]  # was ORGN 1: the home's record taken for a copy
    # each message of the copy once: those counted, and its one ARM record (was one ORGN more)
    assert m2["repeated_messages"] == sum(m1["messages"].values()) + 1


def test_a_dataflash_log_after_a_partial_copy_of_itself_is_read_once(tmp_path):
    # review 38: a download cut at 30 % then the whole log, in one file: the whole log repeats
    # all of the partial copy but only 30 % of it is repeats, so it read as a reboot and a
    # second flight (9,118 pose rows for 7,027; 3,474 signal rows for 2,658)
    once_path = simulated_dataflash(tmp_path / "once.bin")
    data = once_path.read_bytes()
    cut = data.index(b"\xa3\x95", int(len(data) * 0.3))  # a record's start
    resumed = tmp_path / "resumed.bin"
    resumed.write_bytes(data[:cut] + data)
    (once, _), (read, meta) = _read(once_path), _read(resumed)
    pd.testing.assert_frame_equal(once.pose, read.pose)
    pd.testing.assert_frame_equal(once.signal, read.signal)
    assert meta["reboots"] == 0 and meta["repeated_messages"] > 0


def test_corrupt_mavlink_frames_are_counted_and_said(tmp_path):
    data = bytearray(TLOG_2.read_bytes())
    at = data.index(b"\xfe", len(data) // 2)
    data[at + 8] ^= 0xFF  # a payload byte: the frame's checksum no longer holds
    bad = tmp_path / "flipped.tlog"
    bad.write_bytes(bytes(data))
    (_, whole), (_, meta) = _read(TLOG_2), _read(bad)
    assert whole["corrupt_stretches"] == 0 and whole["corrupt_bytes"] == 0
    # one stretch: that record's 8-byte time and its MAVLink 1 frame (6 + payload + 2 bytes)
    assert meta["corrupt_stretches"] == 1 and meta["corrupt_bytes"] == 8 + 6 + data[at + 1] + 2
    assert whole["records_read"] - 1 <= meta["records_read"] <= whole["records_read"]  # of the kinds read
    assert any("1 corrupt stretch(es) of MAVLink data" in line for line in file_damage(str(bad), meta))
    from rplearn.io import inspect_logs

    assert any("corrupt stretch(es) of MAVLink data" in p for p in inspect_logs([bad]).problems)


def test_a_damaged_frame_length_is_one_corrupt_stretch_of_several_frames(tmp_path):
    # was "corrupt_frames": 1 (pymavlink's one BAD_DATA) for the 8 frames the bad length swallowed
    src = TLOG_2.read_bytes()
    at = src.index(b"\xfe", len(src) // 2)
    data = bytearray(src)
    data[at + 1] ^= 0xFF  # the length byte
    other = data.index(b"\xfe", len(data) // 2 + 5000)
    data[other + 8] ^= 0xFF  # and a checksum failure further on
    bad = tmp_path / "length.tlog"
    bad.write_bytes(bytes(data))
    (_, whole), (_, meta) = _read(TLOG_2), _read(bad)
    lost = whole["records_read"] - meta["records_read"]
    assert lost > 2 and meta["corrupt_stretches"] == 2
    assert meta["corrupt_bytes"] > 8 + 6 + src[at + 1] + 2 + 8 + 6 + src[other + 1] + 2
    assert "corrupt_frames" not in meta
@pytest.mark.parametrize("size", [16, 20, 24])
def test_a_tlog_cut_inside_its_first_record_is_refused_naming_it(tmp_path, size):
    cut = tmp_path / "cut.tlog"
    cut.write_bytes(TLOG_2.read_bytes()[:size])
    with pytest.raises(LogFormatError, match=rf"cut.tlog: the file ends inside its first record \({size} byte"):
        _read(cut)


def test_dataflash_cut_off_detection(tmp_path):
    whole = tmp_path / "whole.bin"
    whole.write_bytes(BIN.read_bytes()[:65512])
    assert dataflash_cut_off_at(whole) == (None, None, 0)
    assert dataflash_cut_off_at(BIN) == (65512, "AHR2", 0)
    _, meta = read_mavlink(whole, tx_power_dbm=20.0, frequency_hz=433e6)
    assert meta["cut_off_at_byte"] is None
    _, cut_meta = read_mavlink(BIN, tx_power_dbm=20.0, frequency_hz=433e6)
    assert cut_meta["records_read"] == meta["records_read"] > 0  # the cut record is not counted
    said = file_damage(str(BIN), cut_meta)
    assert any(f"the {meta['records_read']:,} complete record(s) before it were read" in line for line in said)
    assert not any("cut off" in n for n in cut_meta["notes"])  # said once, by file_damage (was twice in sync)


# ------------------------------------------------------------------------------ round trip

T0 = 1_700_000_000.0


def _write_tlog(path, *, radio=True, home=None, yaw=np.pi / 2, pitch=0.0, roll=0.0, lost=0, censored=False,
                boot_ms=True):
    """A tlog written with pymavlink's encoder: 5 s of ATTITUDE (10 Hz) and GLOBAL_POSITION_INT
    (5 Hz) moving east, a gimbal's ATTITUDE (same system, component 154, 1 Hz), RADIO_STATUS
    from the ground radio at 2 Hz (with ``censored``, one remrssi = 0 while the vehicle
    streams), then ``lost`` radio messages with remrssi = 0 after the vehicle stops."""
    vehicle = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    gimbal = mavlink2.MAVLink(None, srcSystem=1, srcComponent=154)
    radio_mav = mavlink2.MAVLink(None, srcSystem=51, srcComponent=68)
    packets = []
    boot_offset = T0 - 100.0  # time_boot_ms 100 000 at T0
    if home is not None:
        lat, lon, alt = home
        packets.append((T0 - 0.5, vehicle, vehicle.home_position_encode(
            int(lat * 1e7), int(lon * 1e7), int(alt * 1e3), 0, 0, 0, [1, 0, 0, 0], 0, 0, 0)))
    for k in range(51):
        t = T0 + 0.1 * k
        packets.append((t + 0.03, vehicle, vehicle.attitude_encode(
            int(round((t - boot_offset) * 1e3)) if boot_ms else 0, roll, pitch, yaw, 0, 0, 0)))
        if k % 10 == 5:
            packets.append((t + 0.04, gimbal, gimbal.attitude_encode(
                int(round((t - boot_offset) * 1e3)), 0.5, -0.5, 2.0, 0, 0, 0)))
        if k % 2 == 0:
            east = 2.0 * (t - T0)  # m
            packets.append((t + 0.03, vehicle, vehicle.global_position_int_encode(
                int(round((t - boot_offset) * 1e3)), int(round(47.0 * 1e7)),
                int(round((8.0 + east / (111_320 * np.cos(np.radians(47.0)))) * 1e7)),
                510_000, 10_000, 0, 0, 0, 0)))
    if radio:
        for k in range(10):
            remrssi = 0 if censored and k == 4 else 95
            packets.append((T0 + 0.25 + 0.5 * k, radio_mav,
                            radio_mav.radio_status_encode(190, remrssi, 100, 30, 28, 0, 0)))
        for k in range(lost):
            packets.append((T0 + 10.0 + k, radio_mav, radio_mav.radio_status_encode(40, 0, 100, 30, 0, 0, 0)))
    packets.sort(key=lambda p: p[0])
    with open(path, "wb") as fh:
        for t, mav, msg in packets:
            fh.write(struct.pack(">Q", int(round(t * 1e6))) + msg.pack(mav))
    return path


def test_round_trip_attitude_position_and_dbm(tmp_path):
    path = _write_tlog(tmp_path / "flight.tlog", home=(47.0, 8.0, 500.0), lost=3)
    logs, meta = read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6)
    assert meta["messages"] == {"HOME_POSITION": 1, "ATTITUDE": 56, "GLOBAL_POSITION_INT": 26, "RADIO_STATUS": 13}
    assert (meta["system_id"], meta["component_id"]) == (1, 1)  # the gimbal's 5 ATTITUDE ignored
    assert "HOME_POSITION" in meta["station_note"]
    vehicle = logs.pose[logs.pose["node"] == "sys1"]
    assert len(vehicle) == 51 and sum(meta["dropped"].values()) == 0
    # NED yaw 90 deg = facing east = the ENU/FLU identity
    q = vehicle[["qw", "qx", "qy", "qz"]].to_numpy()
    np.testing.assert_allclose(q, np.tile([1.0, 0.0, 0.0, 0.0], (51, 1)), atol=1e-6)
    # 10 m above home, moving east at 2 m/s from home; times back on the receive clock
    np.testing.assert_allclose(vehicle["z"], 10.0, atol=0.01)
    np.testing.assert_allclose(vehicle["x"], 2.0 * (vehicle["t"] - T0 - 0.03), atol=0.05)
    np.testing.assert_allclose(vehicle["y"], 0.0, atol=0.05)
    np.testing.assert_allclose(vehicle["t"].to_numpy(), T0 + 0.03 + 0.1 * np.arange(51), atol=1e-3)
    # SiK units -> dBm exactly; the ground radio's rssi is the station receiving
    sig = logs.signal[~logs.signal["outage"]]
    up = sig[(sig["tx"] == "sys1") & (sig["rx"] == "gcs")]
    down = sig[(sig["tx"] == "gcs") & (sig["rx"] == "sys1")]
    assert len(up) == len(down) == 10
    assert (up["rssi_dbm"] == 190 / 1.9 - 127).all() and (down["rssi_dbm"] == 95 / 1.9 - 127).all()
    assert up["rssi_dbm"].iloc[0] == pytest.approx(-27.0) and down["rssi_dbm"].iloc[0] == pytest.approx(-77.0)
    assert (sig["tx_power_dbm"] == 20.0).all() and (sig["frequency_hz"] == 915e6).all()
    assert meta["signal"]["link_lost"] == 3
    # the 3 link-lost messages: one outage row per direction each, no RSSI
    lost = logs.signal[logs.signal["outage"]]
    assert len(lost) == 6 and lost["rssi_dbm"].isna().all()


@pytest.mark.parametrize(
    "roll, pitch, body_axis, world_z",
    [(0.0, np.radians(30), [1, 0, 0], 0.5),    # NED pitch up: the nose (FLU x) rises
     (np.radians(30), 0.0, [0, 1, 0], 0.5)],   # NED roll right: the left wing (FLU y) rises
)
def test_round_trip_tilts(tmp_path, roll, pitch, body_axis, world_z):
    path = _write_tlog(tmp_path / "tilt.tlog", roll=roll, pitch=pitch, yaw=0.0)
    logs, _ = read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6, vehicle="drone",
                           options=MavlinkOptions(station_geodetic=(47.0, 8.0, 505.0)))
    q = logs.pose.loc[logs.pose["node"] == "drone", ["qw", "qx", "qy", "qz"]].to_numpy()[0]
    v = rotate_body_to_world(q, np.array(body_axis, float))
    assert v[2] == pytest.approx(world_z, abs=1e-6)
    # yaw 0 NED = facing north: the level part of the nose points north (ENU +y)
    if pitch:
        assert v[1] == pytest.approx(np.cos(pitch), abs=1e-6)
    station = logs.pose[logs.pose["node"] == "gcs"]
    assert station["z"].iloc[0] == pytest.approx(0.0, abs=1e-6)  # the station is the origin
    assert logs.pose.loc[logs.pose["node"] == "drone", "z"].iloc[0] == pytest.approx(5.0, abs=0.01)


def test_zero_while_streaming_drops_that_direction_only(tmp_path):
    path = _write_tlog(tmp_path / "censored.tlog", censored=True)
    logs, meta = read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6)
    assert meta["signal"]["link_lost"] == 0
    assert meta["signal"]["zero_station_to_vehicle"] == 1 and meta["signal"]["rows_station_to_vehicle"] == 9
    assert meta["signal"]["rows_vehicle_to_station"] == 10
    assert len(logs.signal) == 19
    assert "first position fix" in meta["station_note"]


def test_without_boot_times_the_receive_clock_is_used(tmp_path):
    path = _write_tlog(tmp_path / "noboot.tlog", boot_ms=False)
    logs, meta = read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6)
    t = logs.pose.loc[logs.pose["node"] == "sys1", "t"].to_numpy()
    np.testing.assert_allclose(t, T0 + 0.03 + 0.1 * np.arange(51), atol=1e-5)
    assert meta["clock_offset_s"] is None and "time_boot_ms" not in meta["time_reference"]


def test_sik_formula():
    np.testing.assert_allclose(sik_rssi_to_dbm([0, 19, 190, 254]), [-127.0, -117.0, -27.0, 254 / 1.9 - 127])


# ------------------------------------------------------------------------------ errors


def test_tlog_without_radio_is_a_one_line_error(tmp_path):
    path = _write_tlog(tmp_path / "noradio.tlog", radio=False)
    with pytest.raises(LogFormatError) as exc:
        read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6)
    msg = str(exc.value)
    assert "\n" not in msg and str(path) in msg and "RADIO_STATUS" in msg and "RADIO (id 166)" in msg


def test_tlog_without_attitude_is_a_one_line_error(tmp_path):
    path = tmp_path / "radio_only.tlog"
    mav = mavlink2.MAVLink(None, srcSystem=51, srcComponent=68)
    path.write_bytes(struct.pack(">Q", int(T0 * 1e6)) + mav.radio_status_encode(100, 100, 100, 30, 30, 0, 0).pack(mav))
    with pytest.raises(LogFormatError, match=r"no ATTITUDE messages") as exc:
        read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6)
    assert "\n" not in str(exc.value) and str(path) in str(exc.value)


def test_bad_arguments(tmp_path):
    with pytest.raises(RplearnError, match="no such file"):
        read_mavlink(tmp_path / "missing.tlog", tx_power_dbm=20.0, frequency_hz=915e6)
    path = shutil.copy(TLOG_1, tmp_path / "a.tlog")
    with pytest.raises(RplearnError) as exc:
        read_mavlink(path, tx_power_dbm=20.0, frequency_hz=-1.0)
    assert exc.value.param == "frequency_hz"
    with pytest.raises(RplearnError) as exc:
        read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6, options=MavlinkOptions(system_id=7))
    assert exc.value.param == "system_id"
    for bad in ({"frequency_hz": 915.0}, {"tx_power_dbm": 1e6}, {"station": ""}):
        args = {"tx_power_dbm": 20.0, "frequency_hz": 915e6, **bad}
        with pytest.raises(RplearnError) as exc:
            read_mavlink(BIN, **args)
        assert exc.value.param == next(iter(bad)) and "\n" not in str(exc.value)
    for bad in ({"station_geodetic": (41.0, -96.0)}, {"origin_geodetic": (100.0, 0.0, 0.0)}, {"system_id": 300},
                {"station_heading_deg": "east"}, {"max_gap_s": 0.0}, {"stream_timeout_s": float("nan")}):
        with pytest.raises(RplearnError) as exc:
            MavlinkOptions(**bad)
        assert exc.value.param == next(iter(bad)) and "\n" not in str(exc.value)


# ------------------------------------------------------------------------------ dispatch


def test_formats_are_detected(tmp_path):
    from rplearn.io import detect_format

    text_log = tmp_path / "00000001.log"
    text_log.write_text("FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns\n")
    renamed = tmp_path / "flight.dat"
    renamed.write_bytes(BIN.read_bytes()[:1000])
    for path in (TLOG_1, BIN, text_log, renamed):
        assert detect_format(path) == "mavlink"


def test_read_logs_reads_a_tlog_with_reader_options():
    from rplearn.io import ReaderOptions, read_logs

    options = ReaderOptions(tx_power_dbm={"copter": 20.0, "base": 17.0}, frequency_hz=433e6,
                            nodes={str(TLOG_1): "copter"}, station="base",
                            station_geodetic=(41.1857, -96.0105, 304.0))
    logs, meta = read_logs([TLOG_1], options)
    assert set(logs.pose["node"]) == {"copter", "base"}
    assert set(map(tuple, logs.signal[["tx", "rx"]].drop_duplicates().to_numpy())) == {
        ("copter", "base"), ("base", "copter")}
    assert logs.signal.groupby("tx")["tx_power_dbm"].first().to_dict() == {"copter": 20.0, "base": 17.0}
    assert meta["origin_geodetic"] == (41.1857, -96.0105, 304.0)
    f = meta["files"][0]
    assert f["kind"] == "pose+signal" and f["format"] == "tlog"
    assert f["station_note"] == "station position given (ReaderOptions.station_geodetic)"
    base = logs.pose[logs.pose["node"] == "base"]
    np.testing.assert_allclose(base[["x", "y", "z"]].to_numpy(), 0.0, atol=1e-6)


def test_read_logs_names_the_missing_options():
    from rplearn.io import ReaderOptions, read_logs

    with pytest.raises(RplearnError) as exc:
        read_logs([TLOG_1], ReaderOptions(frequency_hz=915e6))
    assert exc.value.param == "tx_power_dbm" and "\n" not in str(exc.value)
    assert str(TLOG_1) in str(exc.value)
    with pytest.raises(RplearnError) as exc:
        ReaderOptions(station_geodetic=(95.0, 0.0, 0.0))
    assert exc.value.param == "station_geodetic"


def test_inspect_reports_station_link_lost_and_cut_off():
    from rplearn.io import inspect_logs

    report = inspect_logs([TLOG_2])
    f = report.files[0]
    assert f["error"] is None and f["format"] == "tlog"
    assert any("first position fix" in n for n in f["notes"])
    assert any("695 radio message(s)" in n for n in f["notes"])
    assert {lk.tx for lk in report.links} == {"sys1", "gcs"}
    text = inspect_logs([BIN]).to_text()
    assert "cut off inside the message at byte 65,512 (AHR2)" in text


def test_cli_sync_of_a_tlog(tmp_path):
    from flightfiles import rplearn_here

    from rplearn.io.files import read_table

    out = tmp_path / "m.parquet"
    proc = rplearn_here(["sync", "--poses", str(TLOG_1), "--signals", str(TLOG_1), "--tx-power", "20",
                         "--frequency", "915e6", "--link", "all", "--max-gap", "1.0", "-o", str(out)])
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "station placed at the vehicle's first position fix" in proc.stdout
    assert "57 radio message(s)" in proc.stdout
    matched = read_table(str(out))
    assert set(zip(matched["tx"], matched["rx"])) == {("sys1", "gcs"), ("gcs", "sys1")}
    assert 900 < len(matched) <= 1026


def test_cli_station_flags(tmp_path):
    """--station LAT,LON,ALT places the ground station (said so), --station-node names it; a
    malformed position is a one-line error naming the flag."""
    import os
    import subprocess
    import sys

    from rplearn.io.files import read_table

    rplearn = os.path.join(os.path.dirname(sys.executable), "rplearn")
    out = tmp_path / "m.parquet"
    base = [rplearn, "sync", "--poses", str(TLOG_1), "--signals", str(TLOG_1), "--tx-power", "20",
            "--frequency", "915e6", "--link", "all", "--max-gap", "1.0", "-o", str(out)]
    from flightfiles import rplearn_here

    proc = rplearn_here(base[1:] + ["--station", "41.1855,-96.0105,330", "--station-node", "base"])  # in this process
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "station position given (--station LAT,LON,ALT)" in proc.stdout  # the flag, not the option's field
    assert "station_geodetic" not in proc.stdout + proc.stderr
    matched = read_table(str(out))
    assert set(zip(matched["tx"], matched["rx"])) == {("sys1", "base"), ("base", "sys1")}
    far = rplearn_here(base[1:] + ["--station", "41.1855,-96.0105,1e308"])  # an altitude no place has: the flag's fault
    assert far.returncode == 1
    assert far.stderr.strip().startswith("error: --station: altitude 1e+308 m is outside"), far.stderr
    bad = subprocess.run(base + ["--station", "41.1855,-96.0105"], check=False, capture_output=True, text=True,
                         timeout=300)
    assert bad.returncode != 0 and "--station" in bad.stderr and "LAT,LON,ALT" in bad.stderr
    assert "Traceback" not in bad.stderr


def test_a_text_dataflash_log_reads_as_its_binary(tmp_path):
    """The text form of a DataFlash log (``.log``: ``NAME, v1, v2...`` lines, as ground stations
    export it), written here from the real binary log, gives the same poses and link."""
    import pandas as pd
    from pymavlink import DFReader

    reader = DFReader.DFReader_binary(str(BIN))
    lines = []
    while (msg := reader.recv_msg()) is not None:
        if msg.get_type() == "FMT":
            lines.append(f"FMT, {msg.Type}, {msg.Length}, {msg.Name}, {msg.Format}, {msg.Columns}")
            continue
        values = [getattr(msg, c) for c in msg.get_fieldnames()]
        lines.append(", ".join([msg.get_type(), *(v.decode(errors="replace") if isinstance(v, bytes) else repr(v)
                                                   if isinstance(v, float) else str(v) for v in values)]))
    text = tmp_path / "flight.log"
    text.write_text("\n".join(lines) + "\n")
    binary_logs, binary = read_mavlink(BIN, tx_power_dbm=20.0, frequency_hz=433e6)
    text_logs, meta = read_mavlink(text, tx_power_dbm=20.0, frequency_hz=433e6)
    assert meta["format"] == "dataflash" and meta["messages"] == binary["messages"]
    pd.testing.assert_frame_equal(text_logs.pose, binary_logs.pose, check_exact=False, atol=1e-6)
    pd.testing.assert_frame_equal(text_logs.signal.drop(columns=["rssi_raw"], errors="ignore"),
                                  binary_logs.signal.drop(columns=["rssi_raw"], errors="ignore"), check_exact=False, atol=1e-9)
    assert meta["station_geodetic"] == pytest.approx(binary["station_geodetic"], abs=1e-7)


def test_fixes_without_a_3d_fix_are_excluded(tmp_path):
    """GPS_RAW_INT.fix_type < 3 until T0 + 2 s: the positions before are not learned from."""
    path = _write_tlog(tmp_path / "nofix.tlog", home=(47.0, 8.0, 500.0))
    vehicle = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    extra = b"".join(struct.pack(">Q", int(round(t * 1e6))) + vehicle.gps_raw_int_encode(
        0, fix, 470000000, 80000000, 510000, 100, 100, 0, 0, 8).pack(vehicle)
        for t, fix in ((T0 - 1.0, 1), (T0 + 2.0, 3)))
    path.write_bytes(path.read_bytes() + extra)  # the reader orders messages by time
    logs, meta = read_mavlink(path, tx_power_dbm=20.0, frequency_hz=915e6)
    (period,) = meta["excluded_periods"]
    assert period["reason"] == "before_valid_position" and "GPS fix below 3-D" in period["detail"]
    assert period["to_t"] == pytest.approx(T0 + 2.03, abs=1e-3)  # the first fix after the 3-D fix
    vehicle_rows = logs.pose[logs.pose["node"] == "sys1"]
    assert vehicle_rows["t"].min() >= period["to_t"] and meta["dropped"]["before_valid_position"] == 20
    assert len(vehicle_rows) + sum(meta["dropped"].values()) == 51
    assert (logs.signal["t"] > period["to_t"]).all() and meta["signal"]["before_valid_position"] == 2 * 4


def test_a_flipped_record_header_in_a_dataflash_log_is_counted_and_said(tmp_path):
    once_path = simulated_dataflash(tmp_path / "once.bin")
    data = bytearray(once_path.read_bytes())
    at = data.index(b"\xa3\x95", len(data) // 2)
    data[at] ^= 0x5A  # the record's header damaged: its record cannot be found
    bad = tmp_path / "flipped.bin"
    bad.write_bytes(bytes(data))
    (_, m_bad), (_, m_once) = _read(bad), _read(once_path)
    assert m_bad["corrupt_bytes"] > 0 and m_once["corrupt_bytes"] == 0
    assert m_bad["records_read"] == m_once["records_read"] - 1
    assert any("corrupt byte(s) between DataFlash records were skipped" in line for line in file_damage(str(bad), m_bad))


def _dataflash_records(data: bytes) -> list[tuple[int, int]]:
    """(start, type) of each record of a DataFlash log, from its FMT records' lengths."""
    lengths, at, out = {128: 89}, 0, []
    while at + 3 <= len(data) and data[at:at + 2] == b"\xa3\x95":
        kind = data[at + 2]
        if kind == 128:
            lengths[data[at + 3]] = data[at + 4]
        out.append((at, kind))
        at += lengths[kind]
    assert at == len(data)
    return out


@pytest.mark.parametrize("records", [1, 3, "under_1s"])
def test_a_copy_of_the_last_records_appended_is_read_once(tmp_path, records):
    # was: a tail copy shorter than 1 s stepped back less than a reboot, so it was no copy and
    # its rows reached sync as duplicates; the reader now counts the repeated messages
    once_path = simulated_dataflash(tmp_path / "once.bin")
    data = once_path.read_bytes()
    (once, m1) = _read(once_path)
    starts = _dataflash_records(data)
    if records == "under_1s":
        t_end = float(once.pose["t"].max())
        att = [s for s, k in starts if k == data[starts[-1][0] + 2]]  # records of the last one's kind
        start = att[-min(len(att), 8)]  # 8 records of one kind: well under 1 s at the log's rates
    else:
        start = starts[-records][0]
    tail = tmp_path / "tail.bin"
    tail.write_bytes(data + data[start:])
    read, meta = _read(tail)
    pd.testing.assert_frame_equal(once.pose, read.pose)
    pd.testing.assert_frame_equal(once.signal, read.signal)
    assert meta["reboots"] == 0 and meta["messages"] == m1["messages"]
    # the last records again right after themselves: records written twice (close copies, looked for among the
    # records read last: rplearn.io._dataflash_records), each read once and counted
    appended = sum(1 for at, _ in starts if at >= start)  # all of types the reader reads
    assert meta["close_copies"] == appended and meta["repeated_messages"] == 0
    assert any("a short stretch of the log written again" in line for line in file_damage(str(tail), meta))
    if records == "under_1s":
        assert t_end - float(once.pose["t"].iloc[-1]) < 1.0


def test_a_small_step_back_is_a_copy_only_when_its_records_repeat():
    att = [(1.0, 0.1, 0.2, 0.3, 0), (2.0, 0.1, 0.2, 0.3, 0), (2.5, 0.4, 0.2, 0.3, 0)]
    # stretch 1 (time back 0.5 s) repeats one record: a one-record tail copy
    tables = {"ATT": att + [(2.5, 0.4, 0.2, 0.3, 1)]}
    boot_t = [(r[0], r[-1]) for r in tables["ATT"]]
    assert merge_copied_boots(tables, boot_t, frozenset({1})) == 1
    assert tables["ATT"] == att and [b for _, b in boot_t] == [0, 0, 0, 0]
    # stretch 1 steps back 0.5 s with its own records: out of time order, still boot 0, none dropped
    other = [(2.2, 0.9, 0.2, 0.3, 1), (2.6, 0.9, 0.2, 0.3, 1)]
    tables = {"ATT": att + other}
    boot_t = [(r[0], r[-1]) for r in tables["ATT"]]
    assert merge_copied_boots(tables, boot_t, frozenset({1})) == 0
    assert len(tables["ATT"]) == 5 and [b for _, b in boot_t] == [0] * 5
    # a reboot (a big step back, not minor) repeating one record by chance stays a reboot
    tables = {"ATT": att + [(2.5, 0.4, 0.2, 0.3, 1), (3.0, 0.7, 0.2, 0.3, 1)]}
    boot_t = [(r[0], r[-1]) for r in tables["ATT"]]
    assert merge_copied_boots(tables, boot_t) == 0 and [b for _, b in boot_t] == [0, 0, 0, 1, 1]


def test_a_log_is_read_as_a_file_whatever_its_path_and_name(tmp_path, monkeypatch):
    """pymavlink's ``mavlink_connection`` runs a path holding ``/bin/`` as a program, opens a
    socket for one starting ``tcp:``, and reads anything not ending ``.bin`` as a ``.tlog``: a
    log under a ``bin`` folder (an SD card's files are all executable), named ``tcp:...``, or a
    DataFlash log named ``.tlog`` reads as the log it is."""
    import os

    part = tmp_path / "part.tlog"
    part.write_bytes(TLOG_1.read_bytes()[:150_000])  # a quarter of the flight: every kind of message it needs
    whole_logs, whole = _read(part)
    (tmp_path / "bin").mkdir()
    under_bin = tmp_path / "bin" / "flight.tlog"
    shutil.copy(part, under_bin)
    os.chmod(under_bin, 0o755)
    monkeypatch.chdir(tmp_path)
    shutil.copy(part, tmp_path / "tcp:flight.tlog")
    for path in (under_bin, "tcp:flight.tlog"):
        logs, meta = _read(path)
        assert meta["records_read"] == whole["records_read"]
        pd.testing.assert_frame_equal(logs.pose, whole_logs.pose)
    shutil.copy(BIN, tmp_path / "dataflash.tlog")
    (bin_logs, binary), (logs, meta) = _read(BIN), _read(tmp_path / "dataflash.tlog")
    assert meta["format"] == "dataflash" and meta["messages"] == binary["messages"]
    pd.testing.assert_frame_equal(logs.pose, bin_logs.pose)


def test_a_tlog_cut_inside_the_first_message_of_its_type_reads_up_to_the_cut(tmp_path):
    """The real log cut inside its first STATUSTEXT (at byte 216,220, a third of the way): the
    messages before the cut are read and the cut said (pymavlink's memory-mapped reader, indexing
    the file first, failed inside itself and the whole log was refused)."""
    cut = tmp_path / "cut.tlog"
    cut.write_bytes(TLOG_1.read_bytes()[:216_250])
    logs, meta = _read(cut)
    assert meta["cut_off_at_byte"] == 216_220 and meta["cut_off_record"] == "STATUSTEXT"
    assert len(logs.pose) > 900 and len(logs.signal) > 200
    assert any("cut off inside the message at byte 216,220 (STATUSTEXT)" in line for line in file_damage(str(cut), meta))


def test_a_corrupt_position_record_refuses_the_log_in_a_line_naming_the_file(tmp_path):
    """One POS record of the real DataFlash log with an altitude of 7e12 m (a flipped byte), or
    every one (a unit error): the log is refused in one line naming the file (it named none).
    (Leaving a few such records out is not done: the growing-log reader, rplearn.io.tlog_tail,
    would have to leave out the same ones in every window.)"""
    from pymavlink import DFReader

    data = bytearray(BIN.read_bytes())
    pos_type = next(f.type for f in DFReader.DFReader_binary(str(BIN)).formats.values()
                    if f.name == "POS")  # format QLLfff: TimeUS, Lat, Lng, Alt...
    head, starts = b"\xa3\x95" + bytes([pos_type]), []
    at = data.find(head)
    while at >= 0:
        if data[at + 31:at + 33] == b"\xa3\x95":  # a whole 31-byte record follows
            starts.append(at)
        at = data.find(head, at + 1)
    data[starts[10] + 19:starts[10] + 23] = struct.pack("<f", 7e12)
    bad = tmp_path / "alt.bin"
    bad.write_bytes(bytes(data))
    with pytest.raises(RplearnError, match=rf"^{bad}: .*altitude \[m\] 7e\+12") as info:
        _read(bad)
    assert "\n" not in str(info.value)
    everywhere = bytearray(data)  # every fix impossible (a unit error): refused, naming the file
    for s in starts:
        everywhere[s + 19:s + 23] = struct.pack("<f", 7e12)
    bad.write_bytes(bytes(everywhere))
    with pytest.raises(RplearnError, match=rf"^{bad}: .*altitude \[m\] 7e\+12"):
        _read(bad)


def test_a_log_without_link_loss_says_no_outage_events(tmp_path):
    # was: "0 radio message(s) with a zero RSSI while the vehicle was silent (link lost): kept as outage events"
    meta = _read(simulated_dataflash(tmp_path / "f.bin"))[1]
    assert meta["signal"]["link_lost"] == 0
    assert not [n for n in meta["notes"] if "zero RSSI while the vehicle was silent" in n]
