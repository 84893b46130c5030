"""`rplearn sync --from/--to/--log-time/--airborne/--repeat-fraction` and the --max-gap advice,
driven by the command line a user types, in this process (``cli_helpers.run_here``: what sync
prints and counts is the point, not its process; each of the seven commands ran ~1 s of
interpreter start-up and imports as a process of its own)."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from cli_helpers import REAL_TLOG, run_here

T0 = 1_381_700_000.0


def run(args, cwd, ok=True):
    proc = run_here(args, cwd, ok=False)
    assert (proc.returncode == 0) == ok, proc.stdout + proc.stderr
    return proc


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """Drone A on the ground (still) 0-10 s, up to 20 m by 20 s, circling to 80 s, down by 90 s;
    station B static 30 m away; 10 Hz poses from T0, a 1 Hz radio whose readings are doubled."""
    d = tmp_path_factory.mktemp("phases")
    t = np.round(np.arange(0.0, 100.0, 0.1), 6)
    s = np.clip(t, 10, 90)
    z = np.interp(t, [0, 10, 20, 80, 90, 100], [0.0, 0.0, 20.0, 20.0, 0.0, 0.0])
    a = pd.DataFrame({"t": T0 + t, "node": "A", "x": 10 * np.cos(s / 10), "y": 10 * np.sin(s / 10), "z": z,
                      "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    b = pd.DataFrame({"t": [T0], "node": "B", "x": [30.0], "y": [0.0], "z": [0.0], "qw": 1.0, "qx": 0.0, "qy": 0.0,
                      "qz": 0.0})
    pd.concat([a, b]).to_csv(d / "pose.csv", index=False)
    a.iloc[::9].pipe(lambda p: pd.concat([p, b])).to_csv(d / "slow_pose.csv", index=False)  # 0.9 s poses
    ts = T0 + np.arange(0.5, 99.5, 1.0)
    rssi = np.round(np.linspace(-80, -50, ts.size))
    one = pd.DataFrame({"t": ts, "tx": "A", "rx": "B", "rssi_dbm": rssi, "tx_power_dbm": 20.0, "frequency_hz": 915e6})
    pd.concat([one, one.assign(t=ts + 0.004)]).sort_values("t").to_csv(d / "signal.csv", index=False)
    return d, ts


def _count(text, reason):
    found = re.search(rf"dropped \({reason}\): (\d+)", text)
    return int(found.group(1)) if found else 0


def test_window_airborne_and_repeats_on_the_command_line(logs):
    d, ts = logs
    base = ["sync", "--poses", "pose.csv", "--signals", "signal.csv", "-o", "m.parquet"]
    plain = run(base, d).stdout
    assert f"signal samples in: {2 * ts.size}, matched: {ts.size}" in plain
    assert _count(plain, "duplicate_reading") == ts.size
    assert "matched sample(s) were taken with an end on the ground or disarmed (kept; --airborne drops them)" in plain
    window = run(base + ["--from", "20", "--to", "50"], d).stdout
    inside = int(((ts >= T0 + 20) & (ts <= T0 + 50)).sum())
    assert f"matched: {inside}" in window and _count(window, "outside_window") == 2 * (ts.size - inside)
    log_time = run(base + ["--from", str(T0 + 20), "--to", str(T0 + 50), "--log-time"], d).stdout
    assert f"matched: {inside}" in log_time
    air = run(base + ["--airborne"], d).stdout
    height = np.interp(ts, T0 + np.array([0, 10, 20, 80, 90, 100.0]), [0, 0, 20, 20, 0, 0])
    assert f"matched: {int((height > 2.0).sum())}" in air
    assert _count(air, "on_ground") == int((height <= 2.0).sum())
    assert "airborne only: armed (where the log says) and more than 2 m above the take-off altitude" in air
    every = run(base + ["--repeat-fraction", "0"], d).stdout
    assert f"matched: {2 * ts.size}" in every


def test_a_slow_pose_log_names_the_max_gap_that_works(logs):
    d, ts = logs
    base = ["sync", "--poses", "slow_pose.csv", "--signals", "signal.csv", "-o", "slow.parquet"]
    proc = run(base, d)  # a few samples fall between close poses: a warning, not an error
    found = re.search(r"--max-gap ([\d.]+) \(1.5 x that interval\)", proc.stdout)
    assert found and _count(proc.stdout, "pose_gap") > 0.8 * ts.size, proc.stdout
    assert "max_gap_s" not in proc.stdout + proc.stderr  # named as the flag
    ok = run(base + ["--max-gap", found.group(1)], d).stdout
    assert f"matched: {ts.size}" in ok


def test_sync_names_the_fixed_nodes_with_the_advice_of_their_source(logs, tmp_path):
    # the station B of a pose table (one row): fixed, and if it moved, log its poses; a MAVLink log's station: its
    # one row is where the log places it, the flags that place and turn it named, no fault of the log's
    d, _ = logs
    table = run(["sync", "--poses", "pose.csv", "--signals", "signal.csv", "-o", "fixed.parquet"], d).stdout
    assert "fixed node(s) (a pose log of one row, or of identical rows, is a node holding still at that pose): B at " \
           "every time (one pose row)" in table
    assert "B: its pose table (pose.csv) gives it one pose, or only identical ones: right for a station or a parked " \
           "drone; if B moved, its motion was not logged: log its poses" in table
    real = REAL_TLOG
    out = run(["sync", "--poses", real, "--signals", real, "--tx-power", "20", "--frequency", "433e6", "--link", "all",
               "-o", "tlog.parquet"], tmp_path).stdout
    assert "gcs is the ground station, one pose row where" in out
    assert "--station LAT,LON,ALT places it if it stood elsewhere, --station-heading says where its antenna faced" in out
    assert "log its poses" not in out
    # the station's position given: it stands where given, and the note does not ask for --station (was: the
    # same note, '--station LAT,LON,ALT places it if it stood elsewhere', after the user had given it)
    placed = run(["sync", "--poses", real, "--signals", real, "--tx-power", "20", "--frequency", "433e6", "--link", "all",
                  "--station", "41.185700,-96.010600,305", "-o", "placed.parquet"], tmp_path).stdout
    [line] = [x for x in placed.splitlines() if "gcs is the ground station" in x]
    assert "at the position given for it (41.185700, -96.010600, 305.0 m)" in line
    assert "--station LAT" not in line and "places it" not in line and "--station-heading says" in line
