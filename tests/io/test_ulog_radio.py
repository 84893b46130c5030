"""The telemetry radio of a PX4 ULog (``radio_status``) as both links to the ground station."""

from __future__ import annotations

import types

import numpy as np
import pandas as pd
import pytest
from pyulog import ULog
from ulogfiles import EVENTS_LOG, radio_log, ulog_times_us, with_radio

from rplearn.errors import InputError, LogFormatError
from rplearn.io import ReaderOptions, read_logs
from rplearn.io.ulog_radio import RadioReadings, UlogRadio, radio_readings, radio_signal_log


def _options(path, **extra) -> ReaderOptions:
    return ReaderOptions(nodes={str(path): "px4"}, ulog_radio=True, tx_power_dbm=20.0, frequency_hz=915e6, **extra)


def test_the_readings_become_both_links_on_the_pose_logs_clock(tmp_path):
    path, t_us = radio_log(tmp_path / "r.ulg")
    raw = next(d.data for d in ULog(str(path), ["radio_status"]).data_list)
    logs, meta = read_logs([path], _options(path))
    f = meta["files"][0]
    assert f["kind"] == "pose+signal" and f["radio_readings"] == len(t_us) == 61
    offset = f["utc_offset_us"] if f["time_reference"] == "utc" else 0
    sig = logs.signal
    for tx, rx, field in (("gcs", "px4", "rssi"), ("px4", "gcs", "remote_rssi")):  # the air radio's report
        link = sig[(sig["tx"] == tx) & (sig["rx"] == rx)].sort_values("t")
        np.testing.assert_allclose(link["t"], (raw["timestamp"] + offset) * 1e-6, rtol=0, atol=1e-6)
        np.testing.assert_allclose(link["rssi_dbm"], raw[field] / 1.9 - 127.0, rtol=0, atol=1e-12)
        assert (link["tx_power_dbm"] == 20.0).all() and (link["frequency_hz"] == 915e6).all()
    assert not sig["outage"].any()
    # the station: one static row at the home position (local NED -> ENU, the vehicle's frame)
    home = next(d.data for d in ULog(str(EVENTS_LOG), ["home_position"]).data_list)
    first = int(np.flatnonzero((home["valid_hpos"] != 0) & (home["valid_lpos"] != 0))[0])  # the home set, not a blank one
    gcs = logs.pose[logs.pose["node"] == "gcs"]
    assert len(gcs) == 1
    np.testing.assert_allclose(gcs[["x", "y", "z"]].to_numpy()[0], [home["y"][first], home["x"][first], -home["z"][first]],
                               atol=1e-6)
    assert any("home_position" in n for n in f["notes"])
    # the vehicle's poses are those of the pose reader alone
    alone, _ = read_logs([path], ReaderOptions(nodes={str(path): "px4"}))
    pd.testing.assert_frame_equal(logs.pose[logs.pose["node"] == "px4"].reset_index(drop=True), alone.pose)


def test_without_ulog_radio_a_ulog_gives_poses_and_counts_its_readings(tmp_path):
    path, t_us = radio_log(tmp_path / "r.ulg")
    logs, meta = read_logs([path], ReaderOptions(nodes={str(path): "px4"}))
    assert logs.signal is None and set(logs.pose["node"]) == {"px4"}
    assert meta["files"][0]["kind"] == "pose"
    assert any(f"{len(t_us)} telemetry-radio reading(s) (radio_status) not read" in n and "ulog_radio" in n
               for n in meta["files"][0]["notes"])


def test_a_zero_is_a_lost_link_both_ways_and_255_drops_one_direction(tmp_path):
    first, last = ulog_times_us()
    t = np.arange(first + 500_000, last - 500_000, 500_000, dtype=np.int64)
    rssi, remote = np.full(len(t), 160), np.full(len(t), 150)
    rssi[3], remote[7] = 0, 0  # SiK zeroes its statistics when the link drops
    rssi[10], remote[12] = 255, 255  # unknown
    path = with_radio(tmp_path / "r.ulg", t, rssi, remote)
    logs, meta = read_logs([path], _options(path))
    counts, sig = meta["files"][0]["signal"], logs.signal
    assert counts["link_lost"] == 2 and counts["outage_vehicle_to_station"] == counts["outage_station_to_vehicle"] == 2
    assert counts["unknown_station_to_vehicle"] == 1 and counts["unknown_vehicle_to_station"] == 1
    assert sig["outage"].sum() == 4 and sig.loc[sig["outage"], "rssi_dbm"].isna().all()
    down = sig[(sig["tx"] == "gcs") & ~sig["outage"]]
    assert len(down) == len(t) - 2 - 1 and not np.isclose(down["rssi_dbm"], 255 / 1.9 - 127).any()
    assert any("link lost" in n for n in meta["files"][0]["notes"])
    assert any("readings of 255 (unknown) dropped: 1 px4 -> gcs, 1 gcs -> px4" in n for n in meta["files"][0]["notes"])


def test_a_reading_logged_twice_is_one_row(tmp_path):
    once, t_us = radio_log(tmp_path / "once.ulg")
    twice, _ = radio_log(tmp_path / "twice.ulg", twice=True)
    a, _ = read_logs([once], _options(once))
    b, meta = read_logs([twice], _options(twice))
    assert meta["files"][0]["signal"]["duplicate_reading"] == len(t_us)
    assert any(f"{len(t_us)} radio reading(s) logged twice: read once" in n for n in meta["files"][0]["notes"])
    pd.testing.assert_frame_equal(a.signal, b.signal)


def test_a_given_station_position_places_the_station(tmp_path):
    path, _ = radio_log(tmp_path / "r.ulg")
    anchor = read_logs([path], _options(path))[1]["files"][0]["anchor_geodetic"]
    north = (anchor[0] + 100.0 / 111_195.0, anchor[1], anchor[2])  # about 100 m north of the anchor
    logs, meta = read_logs([path], _options(path, station_geodetic=north, station="base", station_heading_deg=0.0))
    base = logs.pose[logs.pose["node"] == "base"]
    np.testing.assert_allclose(base[["x", "y", "z"]].to_numpy()[0], [0.0, 100.0, 0.0], atol=0.5)
    assert {"base"} == set(logs.signal["tx"]) - {"px4"}
    assert any("station position given" in n for n in meta["files"][0]["notes"])


def test_asking_for_the_radio_of_a_ulog_without_one_is_refused_naming_the_file():
    with pytest.raises(LogFormatError, match=r"sample_px4_events\.ulg: no radio_status"):
        read_logs([EVENTS_LOG], _options(EVENTS_LOG))


@pytest.mark.parametrize("missing", ["tx_power_dbm", "frequency_hz"])
def test_the_radio_without_power_or_frequency_is_refused_naming_the_option(tmp_path, missing):
    path, _ = radio_log(tmp_path / "r.ulg")
    given = {"tx_power_dbm": 20.0, "frequency_hz": 915e6}
    del given[missing]
    with pytest.raises(InputError, match=f"r.ulg: give the telemetry radios'.*ReaderOptions.{missing}") as info:
        read_logs([path], ReaderOptions(nodes={str(path): "px4"}, ulog_radio=True, **given))
    assert info.value.param == missing


def test_older_px4_telemetry_status_rows_of_a_sik_radio_are_read():
    def topic(name, **fields):
        return types.SimpleNamespace(name=name, data={k: np.asarray(v) for k, v in fields.items()})

    ulog = types.SimpleNamespace(data_list=[
        topic("telemetry_status", timestamp=[3, 1, 2], type=[1, 1, 0], rssi=[10, 11, 0], remote_rssi=[20, 21, 0]),
        topic("telemetry_status", timestamp=[5], type=[2], rssi=[0], remote_rssi=[0]),  # another link, not a SiK radio
    ])
    got = radio_readings(ulog)
    assert got is not None and got.topic == "telemetry_status"
    assert got.t_us.tolist() == [1, 3] and got.rssi.tolist() == [11, 10] and got.remote_rssi.tolist() == [21, 20]
    assert radio_readings(types.SimpleNamespace(data_list=[topic("telemetry_status", timestamp=[1], type=[1])])) is None


def test_the_signal_log_of_readings_keeps_every_count_balanced():
    n = 40
    rng = np.random.default_rng(1)
    readings = RadioReadings(np.arange(n, dtype=np.int64) * 500_000, rng.integers(0, 256, n), rng.integers(0, 256, n),
                             "radio_status")
    sig, counts = radio_signal_log(readings.t_us * 1e-6, readings, "px4", UlogRadio(20.0, 433e6))
    for name, tx in (("vehicle_to_station", "px4"), ("station_to_vehicle", "gcs")):
        kept = counts[f"rows_{name}"] + counts[f"outage_{name}"]
        assert kept + counts[f"unknown_{name}"] == n - counts["duplicate_reading"]
        assert (sig["tx"] == tx).sum() == kept


def invoke(args, ok=True):
    """``rplearn ARGS`` in this process; with ``ok``, assert that it succeeded."""
    from typer.testing import CliRunner

    from rplearn.cli import app

    res = CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
    assert not ok or res.exit_code == 0, f"{args}: {res.output}"
    return res


def test_sync_learns_from_a_ulog_given_as_poses_and_signals(tmp_path):
    path, _ = radio_log(tmp_path / "r.ulg")
    out = tmp_path / "m.parquet"
    res = invoke(["sync", "--poses", path, "--signals", path, "--node", f"{path}=px4", "--ulog-radio", "--tx-power", "20",
                  "--frequency", "915e6", "--link", "all", "-o", out])
    matched = pd.read_parquet(out)
    assert len(matched) > 0 and set(matched["tx"]) <= {"px4", "gcs"}
    assert "station placed at the vehicle's home" in res.output
    refused = invoke(["sync", "--poses", path, "--signals", path, "--node", f"{path}=px4", "--ulog-radio", "-o",
                      tmp_path / "n.parquet"], ok=False)
    assert refused.exit_code != 0 and "--tx-power" in refused.output and "--frequency" in refused.output
    assert not (tmp_path / "n.parquet").exists()
