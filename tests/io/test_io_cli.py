"""`rplearn sync` and `rplearn inspect` on logs of every format, driven as a user would."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from flightfiles import DATA, FREQUENCY_HZ, POSE_TOPICS, RSSI_TOPICS, TX_POWER_DBM, write_bag, write_pcaps

from rplearn.io.files import read_table

RPLEARN = [os.path.join(os.path.dirname(sys.executable), "rplearn")]


def run(args, cwd, ok=True):
    """``rplearn ARGS`` in ``cwd``. A refusal (``ok=False``: its exit code and its one stderr line
    are the point) runs as the user's own process; a command that must succeed runs in this
    process (typer's runner, stdout and stderr apart, 400 columns), which saves the second of
    start-up a process of its own costs: what it prints is what the tests read."""
    if not ok:
        proc = subprocess.run(RPLEARN + [str(a) for a in args], cwd=cwd, capture_output=True, text=True, timeout=300)
        assert proc.returncode != 0, proc.stdout + proc.stderr
        return proc
    import contextlib

    from typer.testing import CliRunner

    from rplearn.cli import app

    with contextlib.chdir(cwd):
        res = CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
    assert res.exit_code == 0, f"{args}: {res.output} {res.exception!r}"
    return subprocess.CompletedProcess([str(a) for a in args], 0, res.stdout, res.stderr)


def _error(proc) -> str:
    lines = [ln for ln in proc.stderr.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1, proc.stderr
    return lines[0]


def test_sync_reads_rssi_topics_of_a_bag(tmp_path, flight):
    pose, sig = flight
    bag = write_bag(tmp_path / "flight.bag", pose.iloc[::5], sig.iloc[::5], "ros1")
    args = ["sync", "--poses", bag, "--signals", bag, "--link", "A:B", "-o", tmp_path / "m.parquet",
            "--tx-power", TX_POWER_DBM, "--frequency", FREQUENCY_HZ, "--rssi-field", "rssi_dbm"]
    for topic, node in POSE_TOPICS.items():
        args += ["--pose-topic", f"{topic}={node}"]
    for topic, (tx, rx) in RSSI_TOPICS.items():
        args += ["--rssi-topic", f"{topic}={tx}:{rx}"]
    proc = run(args, tmp_path)
    got = read_table(str(tmp_path / "m.parquet"))
    want = sig.iloc[::5]
    assert set(zip(got["tx"], got["rx"])) == {("A", "B")}
    assert 0.8 * ((want["tx"] == "A") & (want["rx"] == "B")).sum() < len(got)
    assert "matched" in proc.stdout
    bad = run(args[:-2] + ["--rssi-topic", "/Z/rssi=B"], tmp_path, ok=False)
    assert "--rssi-topic: expected TOPIC=TX:RX" in _error(bad)


def test_bag_without_topics_lists_its_topics(tmp_path):
    proc = run(["sync", "--poses", DATA / "ros1-bag" / "test2.bag", "--signals", DATA / "ros1-bag" / "test2.bag",
                "-o", tmp_path / "m.csv"], tmp_path, ok=False)
    msg = _error(proc)
    assert "(--pose-topic TOPIC=NODE, --rssi-topic TOPIC=TX:RX)" in msg
    assert "it has /jackal_velocity_controller/odom (nav_msgs/msg/Odometry), /imu/data (sensor_msgs/msg/Imu)" in msg


def test_describe_topics_is_shortened():
    from rplearn.io.rosbag import describe_topics

    topics = {f"/t{i:02d}": "std_msgs/msg/Int32" for i in range(30)} | {"/z/odom": "nav_msgs/msg/Odometry"}
    text = describe_topics(topics, limit=5)
    assert text.startswith("/z/odom (nav_msgs/msg/Odometry), /t00") and text.endswith("and 26 more")


@pytest.fixture
def tables(tmp_path):
    t = np.arange(0.0, 5.0, 0.01)
    pose = pd.concat([pd.DataFrame({"t": t, "node": n, "x": t + i, "y": 0.0, "z": 2.0, "qw": 1.0, "qx": 0.0,
                                    "qy": 0.0, "qz": 0.0}) for i, n in enumerate("AB")], ignore_index=True)
    ts = np.arange(0.005, 4.9, 0.05)
    sig = pd.DataFrame({"t": ts, "tx": "A", "rx": "B", "rssi_dbm": -50.0, "tx_power_dbm": 20.0,
                        "frequency_hz": 2.4e9})
    return tmp_path, pose, sig


def test_shuffled_and_nan_poses_name_the_cli_flags(tables):
    tmp, pose, sig = tables
    sig.to_csv(tmp / "s.csv", index=False)
    shuffled = pose.copy()
    shuffled.loc[[10, 11], "t"] = shuffled.loc[[11, 10], "t"].to_numpy()
    shuffled.to_csv(tmp / "p.csv", index=False)
    base = ["sync", "--poses", tmp / "p.csv", "--signals", tmp / "s.csv", "-o", tmp / "m.csv"]
    msg = _error(run(base, tmp, ok=False))
    assert "or sort them on reading (--allow-unsorted)" in msg
    assert "np.float64" not in msg and "0.1 -> 0.11" not in msg and "0.11 -> 0.1)" in msg
    run(base + ["--allow-unsorted"], tmp)

    nan = pose.copy()
    nan.loc[5, "x"] = np.nan
    nan.to_csv(tmp / "p.csv", index=False)
    msg = _error(run(base, tmp, ok=False))
    assert "(--nan-policy drop)" in msg
    run(base + ["--nan-policy", "drop"], tmp)
    assert "--nan-policy: expected 'error' or 'drop'" in _error(run(base + ["--nan-policy", "skip"], tmp, ok=False))


def test_ulog_and_pcap_messages_name_the_cli_flags(tmp_path, flight):
    ulog = DATA / "px4-ulog" / "sample_log_small.ulg"
    msg = _error(run(["sync", "--poses", ulog, "--signals", ulog, "-o", tmp_path / "m.csv"], tmp_path, ok=False))
    assert msg.endswith("give the node id of this ULog (--node FILE=NODE)")
    caps = write_pcaps(tmp_path, flight[1].iloc[:50])
    cap = caps["B"]
    args = ["sync", "--poses", ulog, "--signals", cap, "-o", tmp_path / "m.csv", "--node", f"{ulog}=A"]
    msg = _error(run(args, tmp_path, ok=False))
    assert msg.endswith(f"{cap}: give the capturing node (--receiver FILE=NODE)")
    msg = _error(run(args + ["--receiver", f"{cap}=B"], tmp_path, ok=False))
    assert msg.endswith("radiotap does not carry the sender's power (--tx-power DBM)")


def test_sync_reports_duplicates_and_non_unit_quaternions(tables):
    tmp, pose, sig = tables
    pose.loc[3, "qw"] = 5.0
    pose.to_csv(tmp / "p.csv", index=False)
    pd.concat([sig, sig.iloc[:4]], ignore_index=True).to_csv(tmp / "s.csv", index=False)
    proc = run(["sync", "--poses", tmp / "p.csv", "--signals", tmp / "s.csv", "-o", tmp / "m.csv"], tmp)
    assert "dropped (duplicate): 4" in proc.stdout
    assert "pose rows with a non-unit quaternion (|norm - 1| > 0.001, normalised): 1" in proc.stdout
    msg = _error(run(["sync", "--poses", tmp / "p.csv", "--signals", tmp / "s.csv", "-o", tmp / "m.csv",
                      "--link", "A:Q"], tmp, ok=False))
    assert msg.endswith("link A:Q: node Q is in no signal log; the signal logs name A, B (set it with --link TX:RX)")


def test_inspect_names_table_formats_alike(tables):
    tmp, pose, sig = tables
    pose.to_parquet(tmp / "p.parquet", index=False)
    sig.to_parquet(tmp / "s.parquet", index=False)
    proc = run(["inspect", tmp / "p.parquet", tmp / "s.parquet"], tmp)
    assert "p.parquet: parquet (pose log)" in proc.stdout and "s.parquet: parquet (signal log)" in proc.stdout
