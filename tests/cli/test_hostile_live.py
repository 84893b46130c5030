"""``rplearn live`` on damaged or incomplete CSV tables: refusals name live's own flags (never a
library option live has no flag for), drops are counted, and a stream read in one batch says it
has no prequential score yet (not ``nan dB over 0 samples``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_helpers import invoke


def _tables(d: Path, n: int = 300) -> tuple[pd.DataFrame, pd.DataFrame]:
    """A drone circling a station at 40 m, yawing; 10 Hz poses, a packet each way per 0.1 s."""
    t = np.arange(n) * 0.1
    a = 2 * np.pi * t / 20.0
    yaw = a * 3.0
    drone = pd.DataFrame({"t": t, "node": "D", "x": 40 * np.cos(a), "y": 40 * np.sin(a), "z": 20.0 + 5 * np.sin(a * 2),
                          "qw": np.cos(yaw / 2), "qx": 0.0, "qy": 0.0, "qz": np.sin(yaw / 2)})
    station = pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [1.5], "qw": [1.0],
                            "qx": [0.0], "qy": [0.0], "qz": [0.0]})
    rng = np.random.default_rng(3)
    sig = pd.DataFrame({"t": t + 0.05, "tx": "D", "rx": "G", "rssi_dbm": -60.0 + rng.normal(0, 2, n),
                        "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})
    return pd.concat([drone, station], ignore_index=True), sig


def _live(d: Path, pose: pd.DataFrame, sig: pd.DataFrame, *flags: str):
    pose.to_csv(d / "pose.csv", index=False)
    sig.to_csv(d / "signal.csv", index=False)
    return invoke(["live", f"{d / 'pose.csv'},{d / 'signal.csv'}", "-o", d / "m.json", "--quiet", "--no-advice",
                   "--idle", "0.2", "--order", "2", *flags], ok=False)


def _error(res, code: int = 1) -> str:
    """The one ``error:`` line, exit ``code`` (2: a flag's value that is none of its words or not of its form)."""
    lines = [line for line in res.output.splitlines() if line.strip()]
    assert res.exit_code == code and len(lines) == 1 and lines[0].startswith("error:"), res.output
    return lines[0]


def test_a_nan_pose_names_the_live_flag_and_drop_counts_it(tmp_path):
    pose, sig = _tables(tmp_path)
    pose.loc[7, "y"] = np.nan
    line = _error(_live(tmp_path, pose, sig))
    assert "pose.csv: field y" in line and "--nan-policy drop" in line and "nan_policy" not in line
    assert not (tmp_path / "m.json").exists()
    res = _live(tmp_path, pose, sig, "--nan-policy", "drop")
    assert res.exit_code == 0, res.output
    assert "dropped (nan_pose): 1" in res.output


def test_a_signal_table_without_rx_names_the_live_flags(tmp_path):
    pose, sig = _tables(tmp_path)
    line = _error(_live(tmp_path, pose, sig.drop(columns=["rx", "frequency_hz"])))
    assert "--receiver NODE" in line and "--frequency HZ" in line and "ReaderOptions" not in line
    res = _live(tmp_path, pose, sig.drop(columns=["rx", "frequency_hz"]), "--receiver", "G", "--frequency", "2.4e9")
    assert res.exit_code == 0, res.output


def test_a_stream_read_in_one_batch_says_it_has_no_score_yet(tmp_path):
    pose, sig = _tables(tmp_path)
    res = _live(tmp_path, pose, sig)
    assert res.exit_code == 0, res.output
    assert "nan dB" not in res.output and "no score yet: no batch was predicted before it was learned from" in res.output


@pytest.mark.parametrize("flag", [["--receiver", "G"]])
def test_a_csv_only_flag_is_refused_for_a_mavlink_stream(tmp_path, flag):
    res = invoke(["live", "udpin:127.0.0.1:1", "-o", tmp_path / "m.json", "--tx-power", "20", "--frequency", "433e6",
                  *flag], ok=False)
    assert "--receiver: names the receiver of a signal CSV's rows" in _error(res)


def test_the_spread_over_the_covered_directions_alone_is_refused_as_a_stop(tmp_path):
    """It is small from the first seconds, while they are a few percent of the sphere: it ends a
    session only with a coverage target (one line naming the flag)."""
    pose, sig = _tables(tmp_path)
    line = _error(_live(tmp_path, pose, sig, "--until-spread", "2", "--spread-over", "covered"))
    assert "needs a coverage target too" in line and "--until-coverage" in line and "until_coverage_pct" not in line
    assert not (tmp_path / "m.json").exists()
    line = _error(_live(tmp_path, pose, sig, "--spread-over", "everywhere"), 2)
    assert "--spread-over" in line and "sphere or covered" in line


def test_the_fixed_nodes_are_said_as_sync_says_them_in_lives_flags(tmp_path):
    """The station of a MAVLink log (a .tlog written by io.tlog, read as a connection) is named fixed as sync names
    it, the options that place it as live's flag, the one live has no flag for as sync's (was: not a word)."""
    from rplearn.io._common import Logs
    from rplearn.io.tlog import write_tlog

    pose, sig = _tables(tmp_path, 600)
    write_tlog(Logs(pose, sig), tmp_path / "flight.tlog", vehicle="D", station="G", origin_geodetic=(47.3977, 8.5456, 90.0))
    res = invoke(["live", tmp_path / "flight.tlog", "-o", tmp_path / "m.json", "--quiet", "--no-advice", "--idle", "0.5",
                  "--order", "2", "--tx-power", "20", "--frequency", "2.4e9"])
    [fixed] = [line.strip() for line in res.output.splitlines() if "fixed node(s)" in line]
    assert fixed.startswith("fixed node(s) (a pose log of one row, or of identical rows, is a node holding still at that "
                            "pose): gcs at every time (one pose row)")
    [station] = [line.strip() for line in res.output.splitlines() if "gcs is the ground station" in line]
    assert "station placed at the vehicle's home from HOME_POSITION" in station
    assert station.endswith("--station LAT,LON,ALT places it if it stood elsewhere, sync --station-heading (live has no "
                            "flag for it) says where its antenna faced")
    assert "Options" not in res.output


@pytest.mark.parametrize("flags, text", [
    (["--nodes", "D,D,G"], "--nodes: D is named twice"),  # was: a traceback (ValueError from the statistics' node index)
    (["--nodes", "D", "--nodes", "D,G"], "--nodes: D is named twice"),
    (["--nodes", ",,"], "--nodes: no node id in ',,'"),  # was: read as not given, the nodes of the first samples learned
    (["--fixed", "G,G"], "--fixed: G is named twice"),
    (["--fixed", " , "], "--fixed: no node id in ' , '"),
    (["--until-spread", "nan"], "--until-spread: expected a positive number of dB, got nan"),  # was: 'floor_db: ...'
    (["--until-spread", "-1"], "--until-spread: expected a positive number of dB, got -1.0"),
    (["--until-spread", "inf"], "--until-spread: expected a positive number of dB, got inf"),
])
def test_nonsense_node_lists_and_spread_targets_are_one_line_naming_the_flag(tmp_path, flags, text):
    """With the ranking on (its floor is --until-spread), each refused before any work, naming live's flag."""
    pose, sig = _tables(tmp_path)
    pose.to_csv(tmp_path / "pose.csv", index=False)
    sig.to_csv(tmp_path / "signal.csv", index=False)
    res = invoke(["live", f"{tmp_path / 'pose.csv'},{tmp_path / 'signal.csv'}", "-o", tmp_path / "m.json", "--quiet",
                  "--idle", "0.2", "--order", "2", *flags], ok=False)
    line = _error(res, 2 if "no node id" in text else 1)
    assert line.startswith(f"error: {text}"), line
    assert not (tmp_path / "m.json").exists()


def test_live_options_refuse_a_node_named_twice_naming_the_field():
    from rplearn.errors import InputError
    from rplearn.workflows.live import LiveOptions

    for kw, name in (({"nodes": ("D", "D")}, "nodes"), ({"nodes": ()}, "nodes"), ({"fixed_nodes": ("G", "G")}, "fixed_nodes"),
                     ({"nodes": ("D", " ")}, "nodes")):
        with pytest.raises(InputError) as err:
            LiveOptions(**kw)
        assert err.value.param == name and str(err.value).startswith(f"{name}: ") and "\n" not in str(err.value)


def test_only_a_fixed_node_the_user_named_gets_the_never_seen_note(tmp_path):
    """A MAVLink session holds its station still by default (--fixed's default, not the user's): no note for it;
    a --fixed node the user named that no row names gets one, naming the node, the flag and the session's nodes."""
    from rplearn.io._common import Logs
    from rplearn.io.tlog import write_tlog

    pose, sig = _tables(tmp_path, 600)
    write_tlog(Logs(pose, sig), tmp_path / "flight.tlog", vehicle="D", station="G", origin_geodetic=(47.3977, 8.5456, 90.0))
    args = ["live", tmp_path / "flight.tlog", "-o", tmp_path / "m.json", "--quiet", "--idle", "0.5", "--order", "2",
            "--tx-power", "20", "--frequency", "2.4e9"]
    res = invoke(args)
    assert "--fixed" not in res.output
    res = invoke([*args, "--fixed", "X"])
    [note] = [line.strip() for line in res.output.splitlines() if line.strip().startswith("--fixed ")]
    assert note.startswith("--fixed X: no matched row names it (the session's nodes: gcs, sys1)")
