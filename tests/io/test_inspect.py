"""rplearn.io.inspect: summaries of logs and the suspicious things in them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.io.inspect import InspectReport, inspect_logs
from rplearn.io.options import ReaderOptions

DATA = Path(__file__).resolve().parents[1] / "fixtures"


def _pose(node, t, x0=0.0):
    t = np.asarray(t, float)
    return pd.DataFrame({"t": t, "node": node, "x": x0 + t, "y": 0.0, "z": 1.0,
                         "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})


@pytest.fixture
def logs(tmp_path):
    t = np.round(np.arange(0, 10, 0.01), 6)
    a = _pose("A", np.r_[t[t < 4], t[t > 5]])  # 1 s gap
    b = _pose("B", t, 5.0)
    b.loc[100, "x"] = np.nan
    pose = pd.concat([a, b], ignore_index=True)
    pose.to_csv(tmp_path / "pose.csv", index=False)
    ts = np.arange(0, 10, 0.0125)
    rssi = np.round(np.linspace(-80, -40, ts.size))
    rssi[::50] = -127
    sig = pd.DataFrame({"t": ts, "tx": "A", "rx": "B", "rssi_dbm": rssi, "tx_power_dbm": 20.0,
                        "frequency_hz": 2.4e9})
    extra = pd.DataFrame({"t": [1.0, 2.0], "tx": "C", "rx": "B", "rssi_dbm": [-50.0, -51.0],
                          "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})
    pd.concat([sig, extra]).to_parquet(tmp_path / "signal.parquet", index=False)
    return tmp_path, rssi


def test_report_contents(logs):
    tmp, rssi = logs
    (tmp / "broken.pcap").write_bytes(b"\xd4\xc3\xb2\xa1" + b"\x00" * 7)
    rep = inspect_logs([tmp / "pose.csv", tmp / "signal.parquet", tmp / "broken.pcap"])
    assert isinstance(rep, InspectReport) and not rep.ok
    nodes = {n.node: n for n in rep.nodes}
    assert nodes["A"].gaps == 1 and nodes["A"].longest_gap_s == pytest.approx(1.02, abs=1e-6)
    assert nodes["A"].clock_jumps == 0
    assert nodes["A"].rate_hz == pytest.approx(100.0, rel=1e-6)
    assert nodes["B"].nan_rows == 1 and nodes["B"].rows == 999
    link = {(lk.tx, lk.rx): lk for lk in rep.links}[("A", "B")]
    good = rssi[rssi != -127]
    assert link.sentinel_rssi == int((rssi == -127).sum())
    assert (link.rssi_min_dbm, link.rssi_max_dbm) == (good.min(), good.max())
    assert link.rate_hz == pytest.approx(80.0, rel=1e-6)
    text = rep.to_text()
    joined = "\n".join(rep.problems)
    assert "node A: 1 pose gap(s) longer than 0.2 s" in joined
    assert "node B: 1 pose row(s) with NaN" in joined
    assert f"link A -> B: {int((rssi == -127).sum())} sentinel" in joined
    assert "node C: named by signals but has no pose log" in joined
    assert "broken.pcap: unreadable" in joined
    assert "problems:" in text and "A -> B" in text
    md = rep.to_markdown()
    assert md.count("| A | B |") == 1 and "## Problems" in md


def test_clock_jump_backwards_and_offset(tmp_path):
    t = np.arange(0, 5, 0.01)
    a = _pose("A", np.r_[t, t[-1] + 60 + t])  # 60 s forward jump
    b = _pose("B", np.r_[t[:100], t[50:60] - 0.001, t[100:]])  # goes backwards
    pd.concat([a, b]).to_csv(tmp_path / "p.csv", index=False)
    sig = pd.DataFrame({"t": [1000.0, 1001.0], "tx": "A", "rx": "B", "rssi_dbm": -50.0,
                        "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})
    sig.to_csv(tmp_path / "s.csv", index=False)
    rep = inspect_logs([tmp_path / "p.csv", tmp_path / "s.csv"])
    joined = "\n".join(rep.problems)
    assert "node A: 1 clock jump(s)" in joined
    assert "node B: time goes backwards 1 time(s)" in joined
    assert "do not overlap the poses" in joined and "clock offset" in joined


def test_clean_real_bag_has_no_sentinels():
    rep = inspect_logs(DATA / "ros1-bag" / "test2.bag",
                       ReaderOptions(pose_topics={"/jackal_velocity_controller/odom": "jackal"}))
    assert [n.node for n in rep.nodes] == ["jackal"]
    assert rep.nodes[0].rows == 3060 and rep.nodes[0].rate_hz == pytest.approx(50.0, rel=0.05)
    assert rep.files[0]["format"] == "ros1"


def test_real_pcap_links():
    rep = inspect_logs(DATA / "radiotap-pcap" / "ieee802.11_rx-stbc.pcap")
    assert sum(lk.samples for lk in rep.links) == 3
    assert {lk.rx for lk in rep.links} == {"capture"}
    assert min(lk.rssi_min_dbm for lk in rep.links) == -51.0  # tcpdump: -51dBm, -46dBm, -45dBm


def test_a_capture_s_dropped_frames_are_signal_rows_not_pose_rows():
    # 26 frames: 10 with a signal level and a transmitter, 8 without a signal, 8 without a transmitter
    text = inspect_logs(DATA / "radiotap-pcap" / "ieee802.11_exthdr.pcap").to_text()
    assert "dropped on reading: 8 signal row(s) (no_signal)" in text
    assert "dropped on reading: 8 signal row(s) (no_transmitter)" in text
    assert "pose row(s) (no_" not in text


def test_link_lost_messages_kept_as_outages_are_not_called_dropped():
    text = inspect_logs(DATA / "ardupilot" / "mavlink-log_2013-10-13_18-31-24.tlog").to_text()
    assert "695 radio message(s) with a zero RSSI while the vehicle was silent" in text
    assert "(link_lost)" not in text and "(outage_" not in text


def test_ulog_node_named_after_file():
    rep = inspect_logs(DATA / "px4-ulog" / "sample_log_small.ulg")
    assert [n.node for n in rep.nodes] == ["sample_log_small"]
    assert rep.nodes[0].rate_hz == pytest.approx(200.0, rel=0.1)  # vehicle_attitude, ~5 ms steps


def test_ulog_rows_flagged_invalid_are_reported():
    import os

    from rplearn.io.inspect import inspect_logs

    path = os.path.join(os.path.dirname(os.path.dirname(__file__)), "fixtures", "px4-ulog", "sample_log_small.ulg")
    report = inspect_logs([path])
    assert any("636 pose row(s) flagged invalid" in p for p in report.problems)


def test_pauses_where_both_logs_stop_are_not_gaps_or_clock_jumps(tmp_path):
    t = np.round(np.arange(0, 10, 0.01), 6)
    tp = np.r_[t, t + 130.0]  # a 120 s pause between two units
    a = _pose("A", np.r_[tp[tp < 133], tp[tp > 134]])  # a genuine 1 s gap in the second unit
    b = _pose("B", tp, 5.0)
    a.loc[7, "qw"] = 5.0  # a quaternion far from unit norm
    pd.concat([a, b]).to_csv(tmp_path / "pose.csv", index=False)
    ts = np.r_[np.arange(0.005, 9.99, 0.0125), 130.0 + np.arange(0.005, 9.99, 0.0125)]
    sig = pd.DataFrame({"t": ts, "tx": "A", "rx": "B", "rssi_dbm": -50.0, "tx_power_dbm": 20.0,
                        "frequency_hz": 2.4e9, "unit": np.where(ts < 100, "u1", "u2")})
    pd.concat([sig, sig.iloc[:3]]).to_parquet(tmp_path / "signal.parquet", index=False)
    rep = inspect_logs([tmp_path / "pose.csv", tmp_path / "signal.parquet"])
    nodes = {n.node: n for n in rep.nodes}
    assert (nodes["B"].pauses, nodes["B"].gaps, nodes["B"].clock_jumps) == (1, 0, 0)
    assert nodes["B"].longest_pause_s == pytest.approx(120.01, abs=1e-6)
    assert (nodes["A"].pauses, nodes["A"].gaps, nodes["A"].clock_jumps) == (1, 1, 0)
    joined = "\n".join(rep.problems)
    assert "clock jump" not in joined and "node B" not in joined
    assert "node A: 1 pose gap(s) longer than 0.2 s (longest 1.0" in joined
    assert "link A -> B: 3 exact duplicate row(s); sync drops them (duplicate)" in joined
    assert "pose.csv: 1 pose row(s) with a quaternion norm off 1 by more than 0.001" in joined
    assert "pauses (signals stop too): 1 (longest 120.0 s)" in rep.to_text()
    assert {lk.duplicates for lk in rep.links} == {3}


def test_pose_only_long_step_stays_flagged(tmp_path):
    t = np.arange(0, 5, 0.01)
    _pose("A", np.r_[t, t[-1] + 60 + t]).to_csv(tmp_path / "p.csv", index=False)
    rep = inspect_logs([tmp_path / "p.csv"])
    assert rep.nodes[0].pauses == 0 and rep.nodes[0].clock_jumps == 1 and rep.nodes[0].gaps == 1


T0 = 1_381_700_000.0


def _flight_files(tmp_path, radius_m, doubled=False, name="f", height_m=10.0):
    """A drone circling its station at ``radius_m`` and ``height_m`` up (on the ground, still, for the first
    10 s), 10 Hz poses from T0 (log clock); a 1 Hz radio at 2.4 GHz, every reading written twice
    2-6 ms apart when ``doubled``. Returns (pose path, signal path, readings per link)."""
    t = np.round(np.arange(0.0, 300.0, 0.1), 6)
    s = np.clip(t - 10, 0, None)
    z = np.clip(t - 10, 0, height_m)
    drone = pd.DataFrame({"t": T0 + t, "node": "D", "x": radius_m * np.cos(s / 20), "y": radius_m * np.sin(s / 20),
                          "z": z, "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    station = pd.DataFrame({"t": [T0], "node": "S", "x": [0.0], "y": [0.0], "z": [0.0], "qw": 1.0, "qx": 0.0,
                            "qy": 0.0, "qz": 0.0})
    pose_path = tmp_path / f"{name}_pose.csv"
    pd.concat([drone, station]).to_csv(pose_path, index=False)
    rng = np.random.default_rng(0)
    rows = []
    n = 290
    for tx, rx in (("D", "S"), ("S", "D")):
        ts = T0 + 5.0 + np.cumsum(rng.uniform(0.97, 1.03, n))
        rssi = np.round(rng.uniform(-80, -60, n))
        copies = [ts, ts + rng.uniform(0.002, 0.006, n)] if doubled else [ts]
        rows += [pd.DataFrame({"t": c, "tx": tx, "rx": rx, "rssi_dbm": rssi, "tx_power_dbm": 20.0,
                               "frequency_hz": 2.4e9}) for c in copies]
    sig_path = tmp_path / f"{name}_signal.parquet"
    pd.concat(rows).sort_values("t", kind="stable").to_parquet(sig_path, index=False)
    return pose_path, sig_path, n


def test_doubled_readings_read_at_the_report_rate(tmp_path):
    pose, sig, n = _flight_files(tmp_path, 40.0, doubled=True)
    rep = inspect_logs([pose, sig])
    for lk in rep.links:
        assert lk.samples == 2 * n and lk.repeated_readings == n
        assert lk.rate_hz == pytest.approx(1.0, rel=0.10)  # the radio's report rate, not ~200 Hz
    joined = "\n".join(rep.problems)
    assert f"link D -> S: {n} reading(s) logged twice" in joined and "sync merges them (duplicate_reading)" in joined
    assert "no calibration flight" not in joined
    # times from the log start, the absolute start once
    text = rep.to_text()
    assert text.splitlines()[0] == "log start: t = 1381700000.000 s on the log's clock; times below are seconds from it"
    assert "D: 3000 rows, 0.000 .. 299.900 s (299.9 s), 10.0 Hz" in text
    assert "repeated readings: 290" in text and "| repeated readings |" in rep.to_markdown()


def test_a_drone_that_never_leaves_its_station_is_no_calibration_flight(tmp_path):
    pose, sig, _ = _flight_files(tmp_path, 2.0, name="near", height_m=2.5)  # up to 3.2 m away, 2.5 m up
    rep = inspect_logs([pose, sig])
    assert rep.calibration and rep.calibration[0].startswith(
        "no calibration flight: nodes D and S never get farther apart than 3.2 m")
    assert "at 2400 MHz" in rep.calibration[0]
    text = rep.to_text()
    assert "problems: none found" not in text and "- no calibration flight: nodes D and S" in text
    # the same flight 40 m out holds one
    pose, sig, _ = _flight_files(tmp_path, 40.0, name="far")
    assert inspect_logs([pose, sig]).calibration == []


def test_reader_findings_are_listed_with_times_from_the_log_start():
    from rplearn.io.inspect import NodeSummary

    f = {"path": "a.tlog", "format": "tlog", "kind": "pose+signal", "error": None,
         "excluded_periods": [{"reason": "no_position_fix", "from_t": T0 - 250.0, "to_t": T0 - 0.5,
                               "pose_rows": 1200, "signal_rows": 250, "detail": "EKF origin not set"},
                              {"reason": "reboot", "from_t": T0 + 100.0, "to_t": T0 + 130.0, "pose_rows": 90,
                               "signal_rows": 30, "detail": ""}],
         "dropped": {"gap": 4, "nan_attitude": 0}, "signal_dropped": {"duplicate_reading": 17}}
    rep = InspectReport(files=[f], nodes=[NodeSummary("sys1", 10, T0, T0 + 500.0, 5.0, 0, 0.1)], start_s=T0)
    text = rep.to_text()
    assert "    excluded (no_position_fix): -250.000 .. -0.500 s, 1200 pose row(s), 250 signal row(s): " \
        "EKF origin not set" in text
    assert "    excluded (reboot): 100.000 .. 130.000 s, 90 pose row(s), 30 signal row(s)" in text
    assert "dropped on reading: 4 pose row(s) (gap)" in text and "(nan_attitude)" not in text
    assert "dropped on reading: 17 signal row(s) (duplicate_reading)" in text
    assert "sys1: 10 rows, 0.000 .. 500.000 s" in text
    assert "## Reader findings" in rep.to_markdown()


def test_a_slow_pose_log_is_told_the_max_gap_it_needs(tmp_path):
    t = np.arange(0.0, 60.0, 1 / 1.2)  # 1.2 Hz poses
    pose = pd.concat([_pose("A", t), _pose("B", [0.0], 30.0)], ignore_index=True)
    pose.to_csv(tmp_path / "slow.csv", index=False)
    rep = inspect_logs([tmp_path / "slow.csv"])
    assert any("node A: pose rate 1.20 Hz is below 1 / max_gap_s; most samples would drop (sync with "
               "max_gap_s=1.3: 1.5 x its median pose interval)" in p for p in rep.problems), rep.problems
