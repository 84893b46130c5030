"""rplearn.io.tlog: a simulated flight written as a MAVLink telemetry log and read back."""

from __future__ import annotations

import struct

import numpy as np
import pandas as pd
import pytest
from flightfiles import ground_flight, ground_simulation, rplearn_here
from pymavlink.dialects.v10 import ardupilotmega as mavlink1

from rplearn.core.geometry import quat_wxyz_from_yaw
from rplearn.data.sync import synchronise
from rplearn.errors import InputError
from rplearn.io import ReaderOptions, read_logs
from rplearn.io._common import Logs
from rplearn.io.files import read_table, write_table
from rplearn.io.inspect import file_damage
from rplearn.io.mavlink import SIK_UNITS_PER_DB, MavlinkOptions, read_mavlink
from rplearn.io.tlog import dbm_to_sik_rssi, write_tlog

ORIGIN = (47.3977, 8.5456, 488.0)  # lat, lon [deg], alt [m AMSL] of the simulation's ENU origin
#: the ``ground`` preset's station faces 10 deg ccw from east (ENU) = compass heading 80 deg
STATION_YAW_ENU_DEG = 10.0
HALF_STEP_DB = 0.5 / SIK_UNITS_PER_DB


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    """The ``ground`` preset's flight with its station static (a tlog cannot log the station's
    pose: one row, its median position and true heading), as Parquet logs and as a .tlog."""
    pose, signal = ground_flight(STATION_YAW_ENU_DEG)
    folder = tmp_path_factory.mktemp("tlog")
    write_table(pose, str(folder / "pose.parquet"))
    write_table(signal, str(folder / "signal.parquet"))
    written = write_tlog(Logs(pose, signal), folder / "flight.tlog", vehicle="D", station="G", origin_geodetic=ORIGIN)
    return folder, written, len(signal)


def _tlog_options(folder) -> ReaderOptions:
    return ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, nodes={str(folder / "flight.tlog"): "D"},
                         station="G", station_heading_deg=90.0 - STATION_YAW_ENU_DEG, origin_geodetic=ORIGIN)


def _by_link(dataset: pd.DataFrame) -> dict[tuple[str, str], pd.DataFrame]:
    return {k: g.sort_values("t", kind="stable").reset_index(drop=True) for k, g in dataset.groupby(["tx", "rx"])}


def _angle_deg(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    return np.degrees(2 * np.arccos(np.clip(np.abs((qa * qb).sum(axis=1)), 0.0, 1.0)))


def test_simulated_flight_as_tlog_gives_the_same_matched_dataset(flight):
    folder, written, n_signal = flight
    assert written["radio_status"] == n_signal and written["rssi_clipped"] == 0
    parquet, _ = read_logs([str(folder / "pose.parquet"), str(folder / "signal.parquet")])
    tlog, meta = read_logs([str(folder / "flight.tlog")], _tlog_options(folder))
    want, got = synchronise(parquet.pose, parquet.signal), synchronise(tlog.pose, tlog.signal)
    assert got.summary.n_out == want.summary.n_out > 0.99 * n_signal
    want_links, got_links = _by_link(want.dataset), _by_link(got.dataset)
    assert set(got_links) == set(want_links) == {("D", "G"), ("G", "D")}
    for link, a in want_links.items():
        b = got_links[link]
        assert len(a) == len(b)
        shift = b["t"].to_numpy() - a["t"].to_numpy()  # the tlog's clock is UNIX time
        assert np.ptp(shift) < 1e-5
        # RSSI within the SiK quantisation (1/1.9 dB steps): at most half a step
        assert np.abs(b["rssi_dbm"] - a["rssi_dbm"]).max() <= HALF_STEP_DB + 1e-9
        assert np.abs(b["rssi_dbm"] - a["rssi_dbm"]).max() > 0.2  # it did go through SiK units
        for end in ("tx", "rx"):
            xyz = [f"{end}_{c}" for c in "xyz"]
            q = [f"{end}_q{c}" for c in "wxyz"]
            # 1e-7 deg (1.1 cm) and 1 mm in GLOBAL_POSITION_INT, 1 ms in time_boot_ms
            assert np.abs(b[xyz].to_numpy() - a[xyz].to_numpy()).max() < 0.02
            assert _angle_deg(a[q].to_numpy(), b[q].to_numpy()).max() < 0.2


def test_station_heading_sets_the_station_attitude(first_minute):
    _, _, path = first_minute
    logs, meta = read_mavlink(path, 20.0, 2.412e9, "D", "G", MavlinkOptions(station_heading_deg=80.0))
    row = logs.pose[logs.pose["node"] == "G"]
    q = quat_wxyz_from_yaw(np.radians(STATION_YAW_ENU_DEG))
    assert len(row) == 1 and _angle_deg(row[["qw", "qx", "qy", "qz"]].to_numpy(), q[None, :])[0] < 1e-9
    assert "HOME_POSITION" in meta["station_note"]
    with pytest.raises(InputError) as err:
        read_mavlink(path, 20.0, 2.412e9, options=MavlinkOptions(station_heading_deg=float("nan")))
    assert err.value.param == "station_heading_deg"


def test_cli_sync_of_the_simulated_tlog(first_minute, tmp_path):
    _, _, path = first_minute
    tlog, out = str(path), tmp_path / "m.parquet"
    proc = rplearn_here(["sync", "--poses", tlog, "--signals", tlog, "--tx-power", "20", "--frequency", "2.412e9",
                         "--link", "all", "--node", f"{tlog}=D", "--station-node", "G", "--station-heading", "80",
                         "-o", str(out)])
    assert proc.returncode == 0, proc.stdout + proc.stderr
    matched = read_table(str(out))
    g = matched[matched["rx"] == "G"]
    q = quat_wxyz_from_yaw(np.radians(STATION_YAW_ENU_DEG))
    assert _angle_deg(g[["rx_qw", "rx_qx", "rx_qy", "rx_qz"]].to_numpy(), q[None, :]).max() < 1e-9


def test_a_log_that_switches_from_mavlink_1_to_2_is_read_whole(first_minute, tmp_path):
    """Ground stations start in MAVLink 1 and negotiate 2: frames of both kinds are read."""
    data, whole, _ = first_minute
    v1 = mavlink1.MAVLink(None, srcSystem=51, srcComponent=68)
    t_us = struct.unpack(">Q", data[:8])[0]
    head = b"".join(struct.pack(">Q", t_us - 10_000_000 * (3 - k)) + v1.radio_status_encode(0, 0, 100, 0, 0, 0, 0).pack(v1)
                    for k in range(3))  # link-lost reports 30-10 s before the vehicle appears
    mixed = tmp_path / "mixed.tlog"
    mixed.write_bytes(head + data)
    _, meta = read_mavlink(mixed, 20.0, 2.412e9, vehicle="D", station="G")
    assert meta["messages"]["RADIO_STATUS"] == whole["messages"]["RADIO_STATUS"] + 3
    assert meta["messages"].get("BAD_DATA", 0) == 0
    assert whole["signal"]["link_lost"] == 0 and meta["signal"]["link_lost"] == 3


def test_sik_units_clip_and_count():
    raw, clipped = dbm_to_sik_rssi([-127.0, -60.0, 6.6, 20.0, -200.0])
    assert raw.tolist() == [1, 127, 254, 254, 1] and clipped == 3
    with pytest.raises(InputError, match="1 value"):
        dbm_to_sik_rssi([-60.0, float("nan")])


def test_write_tlog_rejects_other_links_and_nodes(flight, tmp_path):
    folder, _, _ = flight
    pose = read_table(str(folder / "pose.parquet"))
    signal = read_table(str(folder / "signal.parquet")).head(10).copy()
    bad = signal.copy()
    bad.loc[0, "rx"] = "X"
    with pytest.raises(InputError, match="D <-> G only"):
        write_tlog(Logs(pose, bad), tmp_path / "a.tlog", vehicle="D", station="G", origin_geodetic=ORIGIN)
    with pytest.raises(InputError, match="no pose rows"):
        write_tlog(Logs(pose, signal), tmp_path / "a.tlog", vehicle="Q", station="G", origin_geodetic=ORIGIN)
    with pytest.raises(InputError) as err:
        write_tlog(Logs(pose, signal), tmp_path / "a.tlog", vehicle="D", station="G", origin_geodetic=ORIGIN,
                   system_id=51)
    assert err.value.param == "system_id"
    nan_pose = pose.copy()
    nan_pose.loc[3, "qw"] = float("nan")
    with pytest.raises(InputError, match="1 pose row"):
        write_tlog(Logs(nan_pose, signal), tmp_path / "a.tlog", vehicle="D", station="G", origin_geodetic=ORIGIN)
    with pytest.raises(InputError):
        write_tlog(Logs(pose, None), tmp_path / "a.tlog", vehicle="D", station="G", origin_geodetic=ORIGIN)
    assert not (tmp_path / "a.tlog").exists()


@pytest.fixture(scope="module")
def first_minute(flight):
    """The written .tlog's first records, up to the first GLOBAL_POSITION_INT after 60 s of
    flight (a log whose last record is one, as the whole file's is): its bytes, what
    :func:`read_mavlink` says of it (read once: the cut tests compare a cut copy with it) and
    its path (for the tests whose point does not need the whole flight: the station's
    attitude, MAVLink 1 frames before it)."""
    folder, _, _ = flight
    data = (folder / "flight.tlog").read_bytes()
    t0, at = int.from_bytes(data[:8], "big"), 0
    while True:  # MAVLink 2 records: 8-byte time, 10-byte header (message id at 7-9), payload, CRC
        end = at + 8 + 10 + data[at + 9] + 2
        if int.from_bytes(data[at:at + 8], "big") - t0 > 60e6 and int.from_bytes(data[at + 15:at + 18], "little") == 33:
            break
        at = end
    short = folder / "first_minute.tlog"
    short.write_bytes(data[:end])
    return data[:end], read_mavlink(short, 20.0, 2.412e9, vehicle="D", station="G")[1], short


@pytest.mark.parametrize("cut", [1, 7, 33, 39, 40, 44, 47])
def test_a_truncated_tlog_reads_its_complete_messages_and_reports_the_cut_off_one(first_minute, tmp_path, cut):
    """The last record (8-byte time, then a 40-byte GLOBAL_POSITION_INT frame: a MAVLink 2 header
    of 10 bytes, its 28-byte payload, the CRC) loses its last ``cut`` bytes: in its frame, or in
    its time (the frame's name is then unknown). (The first minute of the flight: what is read
    before the cut does not change with its length.)"""
    data, whole, _ = first_minute
    cut_file = tmp_path / "cut.tlog"
    cut_file.write_bytes(data[:-cut])
    logs, meta = read_mavlink(cut_file, 20.0, 2.412e9, vehicle="D", station="G")
    assert meta["cut_off_at_byte"] == len(data) - 48
    assert meta["cut_off_record"] == ("GLOBAL_POSITION_INT" if cut <= 30 else None)  # 10-byte header kept
    assert whole["cut_off_at_byte"] is None and whole["messages"]["GLOBAL_POSITION_INT"] > 5_000
    assert meta["messages"]["GLOBAL_POSITION_INT"] == whole["messages"]["GLOBAL_POSITION_INT"] - 1
    assert meta["messages"]["ATTITUDE"] == whole["messages"]["ATTITUDE"]
    said = file_damage(str(cut_file), meta)
    assert meta["records_read"] == whole["records_read"] - 1
    assert any(f"cut off inside the message at byte {len(data) - 48:,}" in n and "complete record(s) before it were read" in n
               for n in said)
    assert not any("cut off" in n for n in meta["notes"])  # said once, by file_damage
    assert len(logs.signal) > 0


def test_a_whole_tlog_is_not_reported_cut(first_minute):
    _, whole, _ = first_minute
    assert whole["cut_off_at_byte"] is None and whole["cut_off_record"] is None
    assert not any("cut off" in n for n in whole["notes"])


def test_the_station_heading_and_clock_offset_are_returned_for_the_reader(tmp_path):
    """A simulated station's pose rows (estimator noise) give its heading; a moving one is refused."""
    pose_log, signal_log = ground_simulation()
    signal = signal_log.head(200)
    written = write_tlog(Logs(pose_log, signal), tmp_path / "a.tlog", vehicle="D", station="G",
                         origin_geodetic=ORIGIN, system_id=np.int64(7))
    assert abs(written["station_heading_deg"] - (90.0 - STATION_YAW_ENU_DEG)) < 2.0
    assert 0.05 < written["station_spread_m"] < 2.0
    logs, meta = read_mavlink(tmp_path / "a.tlog", 20.0, 2.412e9, "D", "G", MavlinkOptions(origin_geodetic=ORIGIN))
    assert meta["system_id"] == 7
    np.testing.assert_allclose(np.sort(logs.signal["t"].to_numpy()) - written["clock_offset_s"],
                               np.sort(signal["t"].to_numpy()), atol=2e-6)
    moving = pose_log.replace({"node": {"D": "G", "G": "D"}})  # the flying drone as the "station"
    with pytest.raises(InputError, match="moves") as err:
        write_tlog(Logs(moving, signal), tmp_path / "b.tlog", vehicle="D", station="G", origin_geodetic=ORIGIN)
    assert err.value.param == "station"


@pytest.mark.parametrize("change, param", [
    (lambda p, s: (p, s.assign(t=np.where(np.arange(len(s)) == 3, np.nan, s["t"]))), "signal"),
    (lambda p, s: (p, s.head(0)), "signal"),
])
def test_write_tlog_refuses_bad_signal_logs(flight, tmp_path, change, param):
    folder, _, _ = flight
    pose, signal = change(read_table(str(folder / "pose.parquet")), read_table(str(folder / "signal.parquet")).head(20))
    with pytest.raises(InputError) as err:
        write_tlog(Logs(pose, signal), tmp_path / "a.tlog", vehicle="D", station="G", origin_geodetic=ORIGIN)
    assert err.value.param == param and not (tmp_path / "a.tlog").exists()


@pytest.mark.parametrize("kwargs, param", [
    ({"start_unix_s": float("nan")}, "start_unix_s"), ({"start_unix_s": -1e9}, "start_unix_s"),
    ({"origin_geodetic": "abc"}, "origin_geodetic"), ({"system_id": True}, "system_id"),
])
def test_write_tlog_refuses_bad_arguments(flight, tmp_path, kwargs, param):
    folder, _, _ = flight
    pose, signal = read_table(str(folder / "pose.parquet")), read_table(str(folder / "signal.parquet")).head(20)
    args = {"vehicle": "D", "station": "G", "origin_geodetic": ORIGIN, **kwargs}
    with pytest.raises(InputError) as err:
        write_tlog(Logs(pose, signal), tmp_path / "a.tlog", **args)
    assert err.value.param == param


def test_inspect_finds_no_problem_in_the_written_tlog(flight):
    """A static station's one pose row holds at every time: its instant is no span to overlap."""
    from rplearn.io.inspect import inspect_logs

    folder, _, _ = flight
    report = inspect_logs([str(folder / "flight.tlog")], _tlog_options(folder))
    assert not [p for p in report.problems if "overlap" in p], report.problems
