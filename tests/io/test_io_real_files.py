"""Acceptance 2: real third-party files (tests/fixtures, copied with their licenses)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from rplearn.io import ReaderOptions, detect_format, read_logs
from rplearn.io.pcap import read_pcap, read_radiotap_frames
from rplearn.io.rosbag import read_rosbag
from rplearn.io.ulog import read_ulog, read_ulogs

DATA = Path(__file__).resolve().parents[1] / "fixtures"
ULOGS = sorted((DATA / "px4-ulog").glob("*.ulg"))
PCAPS = sorted((DATA / "radiotap-pcap").glob("*.pcap"))
BAG = DATA / "ros1-bag" / "test2.bag"


def test_data_folders_carry_license_and_provenance():
    for folder in ("px4-ulog", "radiotap-pcap", "ros1-bag"):
        names = {p.name for p in (DATA / folder).iterdir()}
        assert any(n.startswith("LICENSE") for n in names), folder
        assert "PROVENANCE" in names, folder


# ---------------------------------------------------------------------------------- ULog


def _raw(path, topic):
    from pyulog import ULog

    u = ULog(str(path), [topic])
    return [d for d in u.data_list if d.name == topic and d.multi_id == 0][0].data


def _raw_utc_offset_us(path):
    g = _raw(path, "vehicle_gps_position")
    ok = g["time_utc_usec"] > 0
    return np.median(g["time_utc_usec"][ok].astype(np.int64) - g["timestamp"][ok].astype(np.int64))


def _matrix(q):
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


@pytest.mark.parametrize("path", ULOGS, ids=lambda p: p.name)
def test_ulog_positions_are_raw_ned_converted_to_enu(path):
    pose, meta = read_ulog(path, "px4", timebase="position")
    raw = _raw(path, "vehicle_local_position")
    t_raw = raw["timestamp"].astype(np.int64)
    offset = _raw_utc_offset_us(path)
    assert meta["time_reference"] == "utc" and abs(meta["utc_offset_us"] - offset) <= 0.5
    offset = meta["utc_offset_us"]
    assert len(pose) >= len(np.unique(t_raw)) - meta["dropped"]["out_of_span"] - 2
    for i in (0, len(pose) // 2, len(pose) - 1):
        row = pose.iloc[i]
        j = int(np.flatnonzero((t_raw + offset) * 1e-6 == row["t"])[0])
        # documented conversion: ENU = (y_ned, x_ned, -z_ned)
        assert row["x"] == pytest.approx(float(raw["y"][j]), abs=1e-9)
        assert row["y"] == pytest.approx(float(raw["x"][j]), abs=1e-9)
        assert row["z"] == pytest.approx(-float(raw["z"][j]), abs=1e-9)


@pytest.mark.parametrize("path", ULOGS, ids=lambda p: p.name)
def test_ulog_attitudes_are_raw_frd_ned_converted_to_flu_enu(path):
    pose, meta = read_ulog(path, "px4", timebase="attitude")
    raw = _raw(path, "vehicle_attitude")
    t_raw = raw["timestamp"].astype(np.int64)
    offset = meta["utc_offset_us"]
    assert abs(offset - _raw_utc_offset_us(path)) <= 0.5
    p_enu_ned = np.array([[0.0, 1, 0], [1, 0, 0], [0, 0, -1]])
    d_frd_flu = np.diag([1.0, -1, -1])
    for i in (0, 7, len(pose) // 3, len(pose) - 1):
        row = pose.iloc[i]
        j = int(np.flatnonzero((t_raw + offset) * 1e-6 == row["t"])[0])
        q_ned = np.array([raw[f"q[{k}]"][j] for k in range(4)], float)
        want = p_enu_ned @ _matrix(q_ned / np.linalg.norm(q_ned)) @ d_frd_flu
        got = _matrix(row[["qw", "qx", "qy", "qz"]].to_numpy(float))
        np.testing.assert_allclose(got, want, atol=1e-6)


def test_ulog_identity_attitude_faces_north():
    """Hand-computed: level, heading north (q_ned = 1) is FLU -> ENU yaw +90 deg."""
    from rplearn.core.geometry import quat_ned_frd_to_enu_flu

    q = quat_ned_frd_to_enu_flu(np.array([1.0, 0, 0, 0]))
    np.testing.assert_allclose(q, [np.sqrt(0.5), 0, 0, np.sqrt(0.5)], atol=1e-12)


def test_two_ulogs_share_origin_and_clock():
    pose, meta = read_ulogs({str(ULOGS[0]): "a", str(ULOGS[1]): "b"})
    assert set(pose["node"]) == {"a", "b"}
    first = read_ulog(ULOGS[0], "a")[1]
    assert meta["origin_geodetic"] == first["anchor_geodetic"]
    assert all(m["time_reference"] == "utc" for m in meta["logs"])
    # both on UNIX time (2021 and 2024 flights)
    assert pose["t"].min() > 1.6e9 and pose["t"].max() < 1.8e9
    # log 1 re-expressed on log 0's origin: far away (different test sites), not at 0
    b = pose[pose["node"] == "b"]
    assert np.hypot(b["x"], b["y"]).min() > 1e5


# ---------------------------------------------------------------------------------- pcap


def _tcpdump(out_path):
    frames = {}
    for line in out_path.read_text().splitlines():
        m = re.match(r"\s*(\d+)\s+\d{4}-\d\d-\d\d (\S+) ", line)
        if not m:
            continue
        sig = re.search(r"(-?\d+)dBm signal", line)
        noise = re.search(r"(-?\d+)dBm noise", line)
        mhz = re.search(r" (\d+) MHz", line)
        frames[int(m.group(1))] = (
            m.group(2),
            None if sig is None else float(sig.group(1)),
            None if noise is None else float(noise.group(1)),
            None if mhz is None else float(mhz.group(1)) * 1e6,
        )
    return frames


@pytest.mark.parametrize("path", PCAPS, ids=lambda p: p.name)
def test_radiotap_values_equal_tcpdump_decode(path):
    want = _tcpdump(path.with_suffix(".out"))
    frames = read_radiotap_frames(str(path))
    assert len(frames) == len(want) > 0
    n_signal = 0
    for row in frames.itertuples():
        clock, sig, noise, freq = want[row.frame]
        got_sig = None if np.isnan(row.signal_dbm) else row.signal_dbm
        assert got_sig == sig, (row.frame, got_sig, sig)
        assert (None if np.isnan(row.noise_dbm) else row.noise_dbm) == noise
        assert (None if np.isnan(row.frequency_hz) else row.frequency_hz) == freq
        n_signal += sig is not None
        # capture time: tcpdump prints local wall clock (UTC in its test suite), microseconds
        import datetime as dt

        stamp = dt.datetime.fromtimestamp(row.t, dt.UTC).strftime("%H:%M:%S.%f")
        assert stamp == clock
    signal, meta = read_pcap(str(path), "monitor", 20.0, frequency_hz=None)
    assert len(signal) + sum(meta["dropped"].values()) == len(frames)
    assert meta["dropped"]["no_signal"] == len(frames) - n_signal
    assert set(signal["rx"]) <= {"monitor"}


def test_exthdr_antenna_index_and_missing_signal():
    """Extended presence bitmaps: antenna index as tcpdump prints it, tx-only frames dropped."""
    path = DATA / "radiotap-pcap" / "ieee802.11_exthdr.pcap"
    text = path.with_suffix(".out").read_text().splitlines()
    frames = read_radiotap_frames(str(path))
    for row in frames.itertuples():
        m = re.search(r"antenna (\d+)", text[row.frame - 1])
        if m:
            assert row.antenna == float(m.group(1))
    signal, meta = read_pcap(str(path), "mon", 20.0)
    # ACKs have no transmitter address; probe responses sent by the card have no signal
    assert meta["dropped"]["no_signal"] > 0 and meta["dropped"]["no_transmitter"] > 0
    assert signal["tx"].str.match(r"^([0-9a-f]{2}:){5}[0-9a-f]{2}$").all()


@pytest.mark.parametrize("path", PCAPS, ids=lambda p: p.name)
def test_radiotap_parser_agrees_with_dpkt(path):
    """Cross-check with dpkt's parser on signal and noise (dpkt reads the first namespace)."""
    import dpkt

    ours = read_radiotap_frames(str(path))

    def s8(v):
        return None if v is None else float(v - 256 if v > 127 else v)

    with open(path, "rb") as fh:
        for i, (_, buf) in enumerate(dpkt.pcap.Reader(fh)):
            rt = dpkt.radiotap.Radiotap(buf)
            sig = s8(rt.ant_sig.db) if rt.ant_sig_present else None
            noise = s8(rt.ant_noise.db) if rt.ant_noise_present else None
            o = ours.iloc[i]
            assert sig == (None if np.isnan(o.signal_dbm) else o.signal_dbm)
            assert noise == (None if np.isnan(o.noise_dbm) else o.noise_dbm)


# ---------------------------------------------------------------------------------- ROS 1


def test_ros1_odometry_matches_messages():
    from rosbags.highlevel import AnyReader

    topic = "/jackal_velocity_controller/odom"
    assert detect_format(BAG) == "ros1"
    logs, meta = read_rosbag(BAG, {topic: "jackal"})
    with AnyReader([BAG]) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        msgs = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(conns)]
    assert len(logs.pose) == len(msgs) == meta["topics"][topic] == 3060
    t = np.array([m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in msgs])
    order = np.argsort(t, kind="stable")
    pos = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z] for m in msgs])[order]
    q = np.array([[m.pose.pose.orientation.w, m.pose.pose.orientation.x, m.pose.pose.orientation.y,
                   m.pose.pose.orientation.z] for m in msgs])[order]
    np.testing.assert_allclose(logs.pose["t"], t[order], atol=1e-9)
    np.testing.assert_allclose(logs.pose[["x", "y", "z"]].to_numpy(), pos, atol=1e-12)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    np.testing.assert_allclose(logs.pose[["qw", "qx", "qy", "qz"]].to_numpy(), q, atol=1e-12)
    assert meta["frame_ids"][topic] == "odom"


def test_read_logs_dispatches_real_files():
    logs, meta = read_logs(
        [BAG, ULOGS[0]], ReaderOptions(pose_topics={"/jackal_velocity_controller/odom": "jackal"},
                                       nodes={str(ULOGS[0]): "px4"}),
    )
    assert set(logs.pose["node"]) == {"jackal", "px4"}
    assert [f["format"] for f in meta["files"]] == ["ros1", "ulog"]
