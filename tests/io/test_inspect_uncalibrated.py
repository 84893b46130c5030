"""rplearn.io.inspect: a link whose RSSI no radio reports in dBm (radio units, a constant
offset, above the transmit power) is said, with what sync does and the way out."""

from __future__ import annotations

from rplearn.io.inspect import inspect_logs


def test_inspect_says_rssi_above_the_transmit_power(tmp_path, flight):
    pose, signal = flight
    pose_path, signal_path = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.to_csv(pose_path, index=False)
    signal.assign(rssi_dbm=signal["rssi_dbm"] + 120.0).to_csv(signal_path, index=False)
    report = inspect_logs([str(pose_path), str(signal_path)])
    lines = [p for p in report.problems if "implausible_rssi" in p]
    assert len(lines) == len(report.links) == 2
    n = int((signal["tx"] == report.links[0].tx).sum())
    assert lines[0].startswith(f"link {report.links[0].tx} -> {report.links[0].rx}: {n} RSSI value(s) outside -150 to 30 dBm")
    assert "rssi_scale='relative'" in lines[0] and report.links[0].implausible_rssi == n
    signal.to_csv(signal_path, index=False)
    assert not any("implausible_rssi" in p for p in inspect_logs([str(pose_path), str(signal_path)]).problems)
