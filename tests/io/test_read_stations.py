"""rplearn.io.read: a ground station several files place (ULogs read with their radio, MAVLink
logs): at one pose it is one static station for every flight; at different poses (a station
moved between flights, two vehicles' homes) it is refused naming both files, both positions and
``--station`` as the way out."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from ulogfiles import FIXTURES, radio_log, ulog_times_us, with_radio

from rplearn.errors import InputError
from rplearn.io import read_logs
from rplearn.io.damage import one_station
from rplearn.io.options import ReaderOptions

SMALL_LOG = FIXTURES / "sample_log_small.ulg"  # another flight, another place, no home_position


@pytest.fixture(scope="module")
def two_flights(tmp_path_factory) -> tuple[Path, Path]:
    d = tmp_path_factory.mktemp("flights")
    a, _ = radio_log(d / "a.ulg")
    first, last = ulog_times_us(SMALL_LOG)
    t = np.arange(first + 500_000, last - 500_000, 500_000, dtype=np.int64)
    b = with_radio(d / "b.ulg", t, np.full(t.size, 160), np.full(t.size, 160), src=SMALL_LOG)
    return a, b


def _options(*paths: Path, **kw) -> ReaderOptions:
    return ReaderOptions(ulog_radio=True, tx_power_dbm=20.0, frequency_hz=915e6,
                         nodes={str(p): f"d{k}" for k, p in enumerate(paths)}, **kw)


def test_two_flights_with_different_homes_are_refused_naming_both_files_homes_and_station(two_flights):
    """Was read with the station moving between the two places over the years between the
    flights, every sample dropped, and the advice of a max_gap_s that bridges years."""
    a, b = two_flights
    with pytest.raises(InputError) as e:
        read_logs([str(a), str(b)], _options(a, b))
    msg = str(e.value)
    assert msg.startswith(f"{b} and {a} place the ground station gcs at (")  # in time order: b flew first
    assert "home_position" in msg and "first position" in msg and "ReaderOptions.station_geodetic" in msg
    assert "\n" not in msg and e.value.param == "station_geodetic"


def _flight(node: str, t0: float, station_xyz: tuple[float, float, float]) -> pd.DataFrame:
    t = t0 + np.arange(5.0)
    vehicle = pd.DataFrame({"t": t, "node": node, "x": 10.0 * np.arange(5), "y": 0.0, "z": 20.0, "qw": 1.0,
                            "qx": 0.0, "qy": 0.0, "qz": 0.0})
    station = pd.DataFrame({"t": [t0], "node": ["gcs"], "x": [station_xyz[0]], "y": [station_xyz[1]],
                            "z": [station_xyz[2]], "qw": [1.0], "qx": [0.0], "qy": [0.0], "qz": [0.0]})
    return pd.concat([vehicle, station], ignore_index=True)


def test_two_flights_an_hour_apart_from_one_home_share_one_static_station():
    """Two station rows an hour apart made the station a node logged over that hour only: the
    later flight's samples fell out of its span."""
    files = [{"source": "a.ulg", "station": "gcs"}, {"source": "b.ulg", "station": "gcs"}]
    logs = one_station([_flight("d0", 0.0, (1.0, 2.0, 0.5)), _flight("d1", 3600.0, (1.0, 2.0, 0.5))], [0, 1], files)
    station = pd.concat(logs)[lambda df: df["node"] == "gcs"]
    assert station["t"].tolist() == [0.0] and len(logs[1]) == 5
    assert files[1]["notes"] == ["b.ulg: ground station gcs at the pose a.ulg gives it: one static station for both flights"]
    with pytest.raises(InputError, match=r"^a.ulg and b.ulg place the ground station gcs at \(1.00, 2.30, 0.50\) m and at "
                                         r"\(1.00, 2.00, 0.50\) m"):
        one_station([_flight("d1", 3600.0, (1.0, 2.0, 0.5)), _flight("d0", 0.0, (1.0, 2.3, 0.5))], [0, 1],
                    [{"source": "b.ulg", "station": "gcs"}, {"source": "a.ulg", "station": "gcs"}])


def test_inspect_says_the_two_homes_sync_refuses(two_flights):
    from rplearn.io.inspect import inspect_logs

    a, b = two_flights
    report = inspect_logs([str(a), str(b)], _options(a, b))
    [line] = [p for p in report.problems if "place the ground station gcs" in p]
    assert line.startswith(f"{b} and {a} place the ground station gcs at (") and line.endswith("(sync refuses these files)")


# ------------------------------------------------------------------ two fixes of one unmoved station (GPS noise)

FRAME = (47.3977, 8.5456, 488.0)


def _files(acc_a, acc_b, frame_b=FRAME):
    return [{"source": "a.ulg", "station": "gcs", "station_accuracy_m": acc_a, "origin_geodetic": FRAME},
            {"source": "b.ulg", "station": "gcs", "station_accuracy_m": acc_b, "origin_geodetic": frame_b}]


def test_two_fixes_of_one_station_within_their_reported_gps_noise_are_one_station():
    # was refused for any difference over 1 mm: two homes of an unmoved station differ by the fixes' noise
    files = _files((1.72, 1.82), (3.26, 6.98))  # eph, epv [m] of the real fixtures' fixes (events and small logs)
    logs = one_station([_flight("d0", 0.0, (1.0, 2.0, 0.5)), _flight("d1", 3600.0, (2.5, 3.0, -3.0))], [0, 1], files)
    station = pd.concat(logs)[lambda df: df["node"] == "gcs"]
    assert station["t"].tolist() == [0.0] and station["x"].tolist() == [1.0]  # the earliest file's fix
    assert files[1]["notes"] == ["b.ulg: ground station gcs at the pose a.ulg gives it: one static station for both "
                                 "flights (its fixes 1.80 m across, 3.50 m up/down apart: within the GPS noise the logs "
                                 "report, 10.00 m and 10.00 m)"]


def test_a_station_moved_beyond_the_reported_gps_noise_is_still_refused():
    files = _files((0.5, 0.8), (0.6, 0.9))  # 3 sigma: 2.34 m across, 3.61 m up/down
    with pytest.raises(InputError) as e:
        one_station([_flight("d0", 0.0, (1.0, 2.0, 0.5)), _flight("d1", 3600.0, (4.0, 2.0, 0.5))], [0, 1], files)
    assert ("a station moved between flights (3.00 m across, 0.00 m up/down apart: more than the GPS noise the logs "
            "report for their fixes allows, 2.34 m and 3.61 m)") in str(e.value)
    # the cap: a poor fix (eph 50 m) does not make a station moved 20 m one station
    with pytest.raises(InputError, match="more than the GPS noise"):
        one_station([_flight("d0", 0.0, (1.0, 2.0, 0.5)), _flight("d1", 3600.0, (21.0, 2.0, 0.5))], [0, 1],
                    _files((50.0, 50.0), (50.0, 50.0)))


def test_without_a_reported_accuracy_or_a_common_frame_the_fixes_must_agree_to_1_mm():
    for files in (_files(None, (0.6, 0.9)), [{**f, "origin_geodetic": None} for f in _files((0.5, 0.8), (0.6, 0.9))]):
        with pytest.raises(InputError, match="two fixes of one station apart by GPS noise"):
            one_station([_flight("d0", 0.0, (1.0, 2.0, 0.5)), _flight("d1", 3600.0, (1.0, 2.002, 0.5))], [0, 1], files)


def test_fixes_of_two_logs_in_their_own_frames_are_compared_in_one():
    # inspect reads each ULog around its own anchor: the same place has other ENU coordinates in each
    from rplearn.core.geometry import enu_to_ned
    from rplearn.io.geodetic import geodetic_to_enu, local_ned_to_geodetic

    frame_b = (47.3978, 8.5458, 489.0)
    lat, lon, alt = local_ned_to_geodetic(enu_to_ned(np.array([1.0, 2.0, 0.5])), FRAME)
    b_xyz = tuple(np.asarray(geodetic_to_enu(lat, lon, alt, frame_b), np.float64).reshape(3))
    assert np.hypot(b_xyz[0] - 1.0, b_xyz[1] - 2.0) > 10.0
    files = _files((0.5, 0.8), (0.6, 0.9), frame_b)
    logs = one_station([_flight("d0", 0.0, (1.0, 2.0, 0.5)), _flight("d1", 3600.0, b_xyz)], [0, 1], files)
    assert (pd.concat(logs)["node"] == "gcs").sum() == 1


def test_the_ulog_reader_reports_the_accuracy_of_the_fix_the_station_was_placed_at(two_flights):
    from rplearn.io.ulog_radio import UlogRadio, read_ulog_logs

    a, b = two_flights
    radio = UlogRadio(20.0, 915e6)
    (_, home), (_, first) = (read_ulog_logs(str(p), "d", radio) for p in (a, b))
    assert "home_position" in home["station_note"] and "first position" in first["station_note"]
    assert home["station_accuracy_m"] == pytest.approx((1.72, 1.82), abs=1e-3)  # vehicle_gps_position at the home
    assert first["station_accuracy_m"] == pytest.approx((3.26, 6.984), abs=1e-3)
    given = read_ulog_logs(str(a), "d", UlogRadio(20.0, 915e6, station_geodetic=FRAME))[1]
    assert given["station_accuracy_m"] is None


# ------------------------------------------------------- MAVLink logs: the accuracy GPS_RAW_INT and GPA report

MAV_ORIGIN = (47.3977, 8.5456, 90.0)


def _mavlink_flight(path: Path, moved_m: tuple[float, float, float], accuracy, start_s: float) -> Path:
    """10 s of the ground flight as a .tlog (or a DataFlash .bin), its station moved ``moved_m`` (ENU) from where it
    stood, the GPS reporting ``accuracy`` (horizontal, vertical [m]; None: none); the tlog received from
    ``start_s`` [UNIX s]."""
    from flightfiles import ground_flight

    from rplearn.io._common import Logs
    from rplearn.io.dataflash_writer import write_dataflash
    from rplearn.io.tlog import DEFAULT_START_UNIX_S, TlogDefects, write_tlog

    pose, signal = ground_flight(10.0)
    end = float(pose["t"].min()) + 10.0
    pose = pose[(pose["t"] < end) | (pose["node"] == "G")].reset_index(drop=True)
    pose.loc[pose["node"] == "G", ["x", "y", "z"]] += np.asarray(moved_m)
    flight = Logs(pose, signal[signal["t"] < end][["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]])
    defects = TlogDefects(fix_accuracy_m=accuracy)
    if path.suffix == ".bin":
        write_dataflash(flight, path, vehicle="D", station="G", origin_geodetic=MAV_ORIGIN, defects=defects)
    else:
        write_tlog(flight, path, vehicle="D", station="G", origin_geodetic=MAV_ORIGIN,
                   start_unix_s=DEFAULT_START_UNIX_S + start_s, defects=defects)
    return path


def _mav_options(*paths: Path) -> ReaderOptions:
    return ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G",
                         nodes={str(p): f"d{k}" for k, p in enumerate(paths)})


@pytest.mark.parametrize("suffix", [".tlog", ".bin"])
def test_two_mavlink_flights_within_the_reported_gps_noise_share_one_station(tmp_path, suffix):
    """Were refused for any difference over 1 mm (a MAVLink log reported no accuracy): the stations' fixes 1.2 m
    across and 0.5 m up/down apart, the GPS reporting 0.8 m and 1.4 m, are one station (3 sigma: 3.39 m, 5.94 m)."""
    a = _mavlink_flight(tmp_path / f"a{suffix}", (0.0, 0.0, 0.0), (0.8, 1.4), 0.0)
    b = _mavlink_flight(tmp_path / f"b{suffix}", (1.2, 0.0, 0.5), (0.8, 1.4), 3600.0)
    from rplearn.io.mavlink import read_mavlink

    meta = read_mavlink(a, 20.0, 2.412e9, "D", "G")[1]
    assert meta["station_accuracy_m"] == pytest.approx((0.8, 1.4)) and "home" in meta["station_note"]
    logs, info = read_logs([str(a), str(b)], _mav_options(a, b))
    assert (logs.pose["node"] == "G").sum() == 1
    [note] = [n for f in info["files"] for n in f.get("notes", []) if "one static station for both flights" in n]
    assert "1.20 m across, 0.50 m up/down apart: within the GPS noise the logs report, 3.39 m and 5.94 m" in note


def test_mavlink_flights_without_a_reported_accuracy_or_beyond_it_are_refused(tmp_path):
    a = _mavlink_flight(tmp_path / "a.tlog", (0.0, 0.0, 0.0), None, 0.0)
    b = _mavlink_flight(tmp_path / "b.tlog", (1.2, 0.0, 0.5), None, 3600.0)
    with pytest.raises(InputError, match="two fixes of one station apart by GPS noise"):
        read_logs([str(a), str(b)], _mav_options(a, b))
    c = _mavlink_flight(tmp_path / "c.tlog", (0.0, 0.0, 0.0), (0.2, 0.2), 0.0)
    d = _mavlink_flight(tmp_path / "d.tlog", (1.2, 0.0, 0.5), (0.2, 0.2), 3600.0)
    with pytest.raises(InputError, match=r"1.20 m across, 0.50 m up/down apart: more than the GPS noise the logs "
                                         r"report for their fixes allows, 0.85 m and 0.85 m"):
        read_logs([str(c), str(d)], _mav_options(c, d))


def test_the_real_mavlink_logs_report_their_accuracy_where_they_give_it_in_metres():
    # the DataFlash log's GPA at the home (ORGN type 1): HAcc 1.61 m, VAcc 2.41 m; the MAVLink 1 .tlogs' GPS_RAW_INT
    # give eph (HDOP x 100: 158-331) and no h_acc/v_acc: no accuracy, the 1 mm rule
    from rplearn.io.mavlink import read_mavlink

    real = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot"
    whole = real / "pymavlink_test.BIN"
    meta = read_mavlink(whole, 20.0, 433e6)[1]
    assert "home" in meta["station_note"] and meta["station_accuracy_m"] == pytest.approx((1.61, 2.41))
    for tlog in sorted(real.glob("*.tlog")):
        assert read_mavlink(tlog, 20.0, 433e6)[1]["station_accuracy_m"] is None


def test_inspect_reads_two_mavlink_flights_within_the_gps_noise_with_one_station(tmp_path):
    # was: the second flight's station row kept in inspect's node summary, G "logged" over the hour between the
    # flights (a clock jump, a pose gap of 3,600 s and a pose rate of 0.00 Hz said); sync reads one static row
    from rplearn.io.inspect import inspect_logs

    a = _mavlink_flight(tmp_path / "a.tlog", (0.0, 0.0, 0.0), (0.8, 1.4), 0.0)
    b = _mavlink_flight(tmp_path / "b.tlog", (1.2, 0.0, 0.5), (0.8, 1.4), 3600.0)
    report = inspect_logs([str(a), str(b)], _mav_options(a, b))
    assert not [p for p in report.problems if "node G" in p or "ground station" in p]
    [station] = [n for n in report.nodes if n.node == "G"]
    assert station.static


def test_two_dataflash_flights_from_one_home_are_no_repeated_file(tmp_path):
    # two flights of one vehicle, each a DataFlash log with its own home at one place: both give the station as one
    # row at the first time of their boot clock, the same row. Was said by sync's reader notes and inspect as "1 pose
    # row(s) repeat rows of a.bin exactly (the same log given twice, or overlapping exports)"; a single static
    # station row two flights share is one station (one_station), no evidence of a file given twice
    from flightfiles import simulated_dataflash

    from rplearn.io.damage import file_damage
    from rplearn.io.inspect import inspect_logs

    a, b = (simulated_dataflash(tmp_path / f"{name}.bin", seed, station_xyz=(0.0, 0.0, 0.0))
            for name, seed in (("a", 3), ("b", 4)))
    options = ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="B",
                            nodes={str(a): "A1", str(b): "A2"})
    logs, meta = read_logs([str(a), str(b)], options)
    assert (logs.pose["node"] == "B").sum() == 1 and set(logs.pose["node"]) == {"A1", "A2", "B"}
    assert not any("repeated_rows" in f for f in meta["files"])
    assert not [line for f in meta["files"] for line in file_damage(f["source"], f) if "repeat" in line]
    [note] = [n for f in meta["files"] for n in f.get("notes", []) if "one static station for both flights" in n]
    assert note.startswith(f"{b}: ground station B at the pose {a} gives it")
    report = inspect_logs([str(a), str(b)], options)
    assert not [p for p in report.problems if "repeat" in p or "ground station" in p]
    [station] = [n for n in report.nodes if n.node == "B"]
    assert station.static
    # the same log under two names still repeats every row, the station's too
    copy = tmp_path / "copy.bin"
    copy.write_bytes(a.read_bytes())
    _, meta = read_logs([str(a), str(copy)], ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="B",
                                                          nodes={str(a): "A1", str(copy): "A1"}))
    assert meta["files"][1]["repeated_rows"]["pose"] == {str(a): int((logs.pose["node"] == "A1").sum()) + 1}
