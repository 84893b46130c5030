"""Defects of real ArduPilot logs written into a simulated flight (rplearn.io.tlog.TlogDefects,
rplearn.io.dataflash_writer) and what the reader (rplearn.io.mavlink) makes of them: positions
before the EKF origin is set, a reboot, radio readings written twice."""

from __future__ import annotations

import numpy as np
import pytest
from flightfiles import ground_flight, rplearn_here

from rplearn.analysis.pattern_error import node_directions, pattern_errors_db
from rplearn.data.sync import synchronise
from rplearn.data.tables import link_samples
from rplearn.errors import InputError
from rplearn.io import ReaderOptions, read_logs
from rplearn.io._common import Logs
from rplearn.io.dataflash_writer import write_dataflash
from rplearn.io.mavlink import MavlinkOptions, read_mavlink
from rplearn.io.tlog import TlogDefects, write_tlog
from rplearn.models import ModelSpec, fit_model

#: the station ~90 m AMSL, as in the real log whose 0.8 m altitude put the drone ~89 m below it
ORIGIN = (47.3977, 8.5456, 90.0)
STATION_YAW_ENU_DEG = 10.0
#: 15 s before the origin is set; a reboot at 200 s, 5 s silent, 10 s more before the origin is set
#: again. Longer windows take more of the flight's data away: the SH-6 patterns of the clean log
#: cut to the valid periods differ from the whole clean log's by ~0.16 dB RMS with these, ~0.44 dB
#: with 30 s + 30 s (data lost, not the reader's doing: the test compares both).
DEFECTS = TlogDefects(invalid_until_s=15.0, reboot_at_s=200.0, reboot_silence_s=5.0, invalid_after_reboot_s=10.0)
#: the same windows of the simulated flight's time [s], from its first row
TRUE_WINDOWS = ((-np.inf, 15.0), (200.0, 215.0))


@pytest.fixture(scope="module")
def ground():
    """The ``ground`` preset's flight, its station one static row (as a tlog holds it)."""
    pose, signal = ground_flight(STATION_YAW_ENU_DEG)
    return Logs(pose, signal[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]])


def _options(path) -> ReaderOptions:
    return ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, nodes={str(path): "D"}, station="G",
                         station_heading_deg=90.0 - STATION_YAW_ENU_DEG, origin_geodetic=ORIGIN)


@pytest.fixture(scope="module")
def written(ground, tmp_path_factory):
    folder = tmp_path_factory.mktemp("defects")
    clean, broken = folder / "clean.tlog", folder / "broken.tlog"
    w_clean = write_tlog(ground, clean, vehicle="D", station="G", origin_geodetic=ORIGIN)
    w_broken = write_tlog(ground, broken, vehicle="D", station="G", origin_geodetic=ORIGIN, defects=DEFECTS)
    return folder, clean, broken, w_clean, w_broken


@pytest.fixture(scope="module")
def written_230s(ground, tmp_path_factory):
    """The flight's first 230 s (past :data:`DEFECTS`' reboot and the 15 s after it), clean and
    broken, for the tests that check only that each period is named (the CLI, inspect)."""
    folder = tmp_path_factory.mktemp("defects_230s")
    end = float(ground.pose["t"].min()) + 230.0
    short = Logs(ground.pose[ground.pose["t"] < end].reset_index(drop=True),
                 ground.signal[ground.signal["t"] < end].reset_index(drop=True))
    clean, broken = folder / "clean.tlog", folder / "broken.tlog"
    write_tlog(short, clean, vehicle="D", station="G", origin_geodetic=ORIGIN)
    write_tlog(short, broken, vehicle="D", station="G", origin_geodetic=ORIGIN, defects=DEFECTS)
    return clean, broken


def _sim_time(t_log, w, ground):
    """Log time -> the simulated flight's time from the vehicle's first row [s]."""
    t0 = ground.pose.loc[ground.pose["node"] == "D", "t"].min()
    return np.asarray(t_log) - w["clock_offset_s"] - t0


def test_periods_before_the_origin_and_after_a_reboot_are_excluded_counted_and_named(ground, written):
    _, _, broken, _, w = written
    assert w["home_position"] == 2 and w["silent_rows"] > 0 and w["invalid_position_rows"] > 0
    logs, meta = read_mavlink(broken, 20.0, 2.412e9, "D", "G", MavlinkOptions(origin_geodetic=ORIGIN))
    periods = meta["excluded_periods"]
    assert [p["reason"] for p in periods] == ["before_valid_position", "after_reboot"]
    assert meta["reboots"] == 1
    # the periods end where the origin is set, the reboot's begins at the vehicle's last message
    assert _sim_time(periods[0]["to_t"], w, ground) == pytest.approx(15.0, abs=0.02)
    assert _sim_time(periods[1]["from_t"], w, ground) == pytest.approx(200.0, abs=0.02)
    assert _sim_time(periods[1]["to_t"], w, ground) == pytest.approx(215.0, abs=0.02)
    for p in periods:
        assert p["pose_rows"] > 900 and p["signal_rows"] > 900
        assert meta["dropped"][p["reason"]] == p["pose_rows"] and meta["signal"][p["reason"]] == p["signal_rows"]
        assert any(f"excluded {p['reason']}" in n and f"{p['pose_rows']:,} pose row(s)" in n for n in meta["notes"])
    assert "step of" in periods[0]["detail"] and "no HOME_POSITION or GPS_GLOBAL_ORIGIN until 15.0 s" in periods[0]["detail"]
    assert "reboot" in periods[1]["detail"]
    # every ATTITUDE written is a pose row or a counted drop; every radio row kept or counted
    vehicle = logs.pose[logs.pose["node"] == "D"]
    assert len(vehicle) + sum(meta["dropped"].values()) == w["attitude"]
    t = _sim_time(vehicle["t"], w, ground)
    for lo, hi in TRUE_WINDOWS:
        assert not np.any((t > lo) & (t < hi))
    # no position of the kept rows is the wrong altitude: the drone never below its station
    assert vehicle["z"].min() > logs.pose.loc[logs.pose["node"] == "G", "z"].iloc[0] - 1.0
    # the armed column: the vehicle's rows from its HEARTBEAT, the station's False
    assert vehicle["armed"].mean() > 0.99 and not logs.pose.loc[logs.pose["node"] == "G", "armed"].any()


def test_a_clean_simulated_tlog_has_no_excluded_period(written):
    _, clean, _, w, _ = written
    logs, meta = read_mavlink(clean, 20.0, 2.412e9, "D", "G", MavlinkOptions(origin_geodetic=ORIGIN))
    assert meta["excluded_periods"] == [] and meta["reboots"] == 0
    assert meta["signal"]["duplicate_reading"] == 0
    assert not any("excluded" in n or "merged" in n for n in meta["notes"])
    assert bool(logs.pose.loc[logs.pose["node"] == "D", "armed"].all())


def test_no_matched_row_from_the_excluded_periods_and_the_same_patterns(ground, written):
    """Issue 24, acceptance 1: read + sync the defective log and the clean one; fit SH-6."""
    _, clean, broken, w_clean, w_broken = written
    got = {}
    for name, path, w in (("clean", clean, w_clean), ("broken", broken, w_broken)):
        logs, meta = read_logs([str(path)], _options(path))
        assert "armed" in logs.pose.columns  # read_logs keeps the optional column
        got[name] = synchronise(logs.pose, logs.signal).dataset, w
    clean_rows, broken_rows = got["clean"][0], got["broken"][0]
    t = _sim_time(broken_rows["t"], w_broken, ground)
    for lo, hi in TRUE_WINDOWS:
        assert not np.any((t > lo) & (t < hi))
    # what was lost is the excluded periods' rows, not more
    t_clean = _sim_time(clean_rows["t"], w_clean, ground)
    outside = ~np.any([(t_clean > lo) & (t_clean < hi) for lo, hi in TRUE_WINDOWS], axis=0)
    assert len(broken_rows) >= 0.99 * outside.sum()
    assert broken_rows["tx_z"].min() > -5.0 and broken_rows["rx_z"].min() > -5.0
    spec = ModelSpec("sh", 6)
    datasets = {"clean": clean_rows, "broken": broken_rows, "clean_cut": clean_rows[outside]}
    models = {k: fit_model(link_samples(rows), spec).model for k, rows in datasets.items()}
    directions = node_directions(link_samples(broken_rows))  # where the defective log learned
    # RMS over the covered directions [dB], the constant the two-node fit cannot identify removed
    rms = pattern_errors_db(models["broken"], models["clean"], directions)
    same_data = pattern_errors_db(models["broken"], models["clean_cut"], directions)
    print(f"SH-6 RMS difference over covered directions [dB]: defective vs clean log {rms}, "
          f"vs the clean log cut to the same periods {same_data}")
    assert {str(n) for n in rms} == {"D", "G"} and max(rms.values()) < 0.3
    assert max(same_data.values()) < 0.05  # the rest is the data the excluded periods took away


def test_sync_prints_each_excluded_period(written_230s, tmp_path):
    _, broken = written_230s
    out = tmp_path / "m.parquet"
    proc = rplearn_here(["sync", "--poses", str(broken), "--signals", str(broken), "--tx-power", "20",
                         "--frequency", "2.412e9", "--link", "all", "--node", f"{broken}=D", "--station-node", "G",
                         "-o", str(out)])
    assert proc.returncode == 0, proc.stdout + proc.stderr
    for reason in ("before_valid_position", "after_reboot"):
        assert f"excluded {reason} from t =" in proc.stdout
        assert f"pose row(s) ({reason})" in proc.stdout


def _slow_radio(ground: Logs, every: int = 40) -> Logs:
    """The flight with a SiK-like radio: every ``every``-th reading (~1 Hz per direction)."""
    return Logs(ground.pose, ground.signal.iloc[::every].reset_index(drop=True))


#: The first seconds of the flight where a test's point is the radio reports (before the
#: flight's 60-s silence at 99 s): ~180 readings of the slow radio, each direction's ~90.
RADIO_ONLY_S = 90.0


def _first_seconds(flight: Logs, seconds: float) -> Logs:
    """The flight's first ``seconds`` [s] (the station's static row kept)."""
    end = float(flight.pose["t"].min()) + seconds
    pose = flight.pose[(flight.pose["t"] < end) | (flight.pose["node"] == "G")].reset_index(drop=True)
    return Logs(pose, flight.signal[flight.signal["t"] < end].reset_index(drop=True))


@pytest.mark.parametrize("fmt", ["tlog", "dataflash"])
def test_readings_written_twice_give_one_row_each(ground, tmp_path, fmt):
    """Issue 24, acceptance 2 (reader, and inspect): RADIO_STATUS + RADIO, or RAD twice, 4 ms
    apart: one row per reading, and inspect reads each link's rate within 10% of the true
    report rate. (The flight's first 90 s: the copies are judged report by report.)"""
    from rplearn.io.inspect import inspect_logs

    flight = _first_seconds(_slow_radio(ground), RADIO_ONLY_S)
    path = tmp_path / ("twice.tlog" if fmt == "tlog" else "twice.bin")
    writer = write_tlog if fmt == "tlog" else write_dataflash
    writer(flight, path, vehicle="D", station="G", origin_geodetic=ORIGIN, defects=TlogDefects(radio_twice=True))
    logs, meta = read_mavlink(path, 20.0, 2.412e9, "D", "G", MavlinkOptions(origin_geodetic=ORIGIN))
    n = len(flight.signal)
    copies = meta["messages"].get("RADIO", 0) if fmt == "tlog" else meta["messages"]["RAD"] - n
    assert copies == n and meta["signal"]["duplicate_reading"] == n
    assert len(logs.signal) == n  # exactly one row per reading
    want = flight.signal.groupby(["tx", "rx"]).size().to_dict()
    assert logs.signal.groupby(["tx", "rx"]).size().to_dict() == want
    spacing = np.median(np.diff(np.sort(flight.signal["t"].to_numpy())))  # the two directions' reports
    assert meta["radio_report_period_s"] == pytest.approx(spacing, rel=0.05)
    assert any("merged: one row per reading" in note for note in meta["notes"])
    report = inspect_logs([path], _options(path))
    for (tx, rx), rows in flight.signal.groupby(["tx", "rx"]):
        t = np.sort(rows["t"].to_numpy())
        true_hz = 1.0 / np.median(np.diff(t))
        (link,) = [lk for lk in report.links if (lk.tx, lk.rx) == (tx, rx)]
        assert link.rate_hz == pytest.approx(true_hz, rel=0.10), (tx, rx, link.rate_hz, true_hz)
    # written once, nothing is merged
    once = tmp_path / ("once.tlog" if fmt == "tlog" else "once.bin")
    writer(flight, once, vehicle="D", station="G", origin_geodetic=ORIGIN)
    logs1, meta1 = read_mavlink(once, 20.0, 2.412e9, "D", "G", MavlinkOptions(origin_geodetic=ORIGIN))
    assert meta1["signal"]["duplicate_reading"] == 0 and len(logs1.signal) == n


def test_dataflash_positions_before_the_origin_are_excluded(ground, tmp_path):
    flight = _slow_radio(ground)
    path = tmp_path / "early.bin"
    w = write_dataflash(flight, path, vehicle="D", station="G", origin_geodetic=ORIGIN,
                        defects=TlogDefects(invalid_until_s=60.0))
    logs, meta = read_mavlink(path, 20.0, 2.412e9, "D", "G", MavlinkOptions(origin_geodetic=ORIGIN))
    (period,) = meta["excluded_periods"]
    assert period["reason"] == "before_valid_position" and "no ORGN until 60.0 s" in period["detail"]
    assert period["pose_rows"] == w["invalid_position_rows"] == meta["dropped"]["before_valid_position"]
    t0 = flight.pose.loc[flight.pose["node"] == "D", "t"].min()
    assert (logs.signal["t"] - w["clock_offset_s"] - t0).min() > 60.0
    armed = logs.pose.loc[logs.pose["node"] == "D", "armed"]
    assert armed.all()  # ARM 1 where the origin is set: the disarmed rows were all excluded
    with pytest.raises(InputError) as err:
        write_dataflash(flight, tmp_path / "x.bin", vehicle="D", station="G", origin_geodetic=ORIGIN,
                        defects=TlogDefects(reboot_at_s=10.0))
    assert err.value.param == "defects" and not (tmp_path / "x.bin").exists()


@pytest.mark.parametrize("kwargs, param", [
    ({"invalid_until_s": -1.0}, "invalid_until_s"), ({"reboot_at_s": float("nan")}, "reboot_at_s"),
    ({"invalid_alt_m": float("inf")}, "invalid_alt_m"), ({"copy_delay_s": True}, "copy_delay_s"),
])
def test_tlog_defects_refuse_bad_values(kwargs, param):
    with pytest.raises(InputError) as err:
        TlogDefects(**kwargs)
    assert err.value.param == param


def test_a_dataflash_reboot_is_counted_and_excluded_until_the_origin_is_set_again(ground, tmp_path):
    """Two boots in one file (TimeUS restarts): the second boot's first 10 s read 0.8 m."""
    flight = _slow_radio(ground)
    t0 = flight.pose.loc[flight.pose["node"] == "D", "t"].min()
    parts = []
    for k, (lo, hi) in enumerate(((-np.inf, t0 + 200.0), (t0 + 200.0, np.inf))):
        pose = flight.pose[((flight.pose["t"] >= lo) & (flight.pose["t"] < hi)) | (flight.pose["node"] == "G")]
        signal = flight.signal[(flight.signal["t"] >= lo) & (flight.signal["t"] < hi)]
        path = tmp_path / f"boot{k}.bin"
        write_dataflash(Logs(pose, signal), path, vehicle="D", station="G", origin_geodetic=ORIGIN,
                        defects=TlogDefects(invalid_until_s=10.0 * k))
        parts.append(path.read_bytes())
    both = tmp_path / "both.bin"
    both.write_bytes(parts[0] + parts[1])  # the second boot's FMT records again, as a new log would
    logs, meta = read_mavlink(both, 20.0, 2.412e9, "D", "G", MavlinkOptions(origin_geodetic=ORIGIN))
    assert meta["reboots"] == 1
    (period,) = meta["excluded_periods"]
    assert period["reason"] == "after_reboot" and "reboot" in period["detail"] and "no ORGN until" in period["detail"]
    assert period["pose_rows"] == meta["dropped"]["after_reboot"] >= 1000  # 10 s at 100 Hz, and more
    # the reader puts the new boot 1 s after the old one's last record (the log holds no clock across)
    assert period["to_t"] - period["from_t"] == pytest.approx(1.0 + 10.0, abs=0.05)
    assert "later boots placed right after the previous one" in meta["time_reference"]
    vehicle = logs.pose[logs.pose["node"] == "D"]
    assert vehicle["z"].min() > 0.0  # no row at the wrong altitude


def test_inspect_names_each_excluded_period_from_the_log_start(written_230s):
    """Issue 24, acceptance 1 (inspect): the reader's periods, with their reasons and times."""
    from rplearn.io.inspect import inspect_logs

    clean, broken = written_230s
    report = inspect_logs([broken], _options(broken))
    text = report.to_text()
    for reason in ("before_valid_position", "after_reboot"):
        assert reason in text, text
    assert "reboot" in text
    clean_text = inspect_logs([clean], _options(clean)).to_text()
    assert "before_valid_position" not in clean_text and "after_reboot" not in clean_text
