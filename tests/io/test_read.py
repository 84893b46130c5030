"""read_logs over several files: one log given twice, overlapping exports, two logs of one node."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io import ReaderOptions, read_logs
from rplearn.io.files import write_table
from rplearn.io.inspect import file_damage

ARDUPILOT = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot"


@pytest.mark.parametrize("name", ["mavlink-log_2013-10-13_18-31-24.tlog", "mavlink-log_2013-10-13_16-58-51.tlog"])
def test_one_real_log_given_twice_under_two_names_is_read_once_and_said(tmp_path, name):
    # 16-58-51 ends with link-lost messages: signal rows whose RSSI is NaN, equal across the copies
    TLOG = ARDUPILOT / name
    copy = tmp_path / "copy.tlog"
    shutil.copy(TLOG, copy)
    options = ReaderOptions(tx_power_dbm=20.0, frequency_hz=433e6)
    once, _ = read_logs([TLOG], options)
    # was: "pose logs: field t: 1962 duplicate timestamp(s) within a node" (no file named)
    twice, meta = read_logs([TLOG, copy], options)
    pd.testing.assert_frame_equal(once.pose, twice.pose)
    pd.testing.assert_frame_equal(once.signal, twice.signal)
    counts = meta["files"][1]["repeated_rows"]
    assert counts == {"pose": {str(TLOG): len(once.pose)}, "signal": {str(TLOG): len(once.signal)}}
    assert "repeated_rows" not in meta["files"][0]
    lines = file_damage(str(copy), meta["files"][1])
    assert any(f"copy.tlog: {len(once.signal):,} signal row(s) repeat rows of {TLOG}" in line for line in lines)


def _tables(tmp_path, flight, ext="csv"):
    pose, sig = flight
    cut_p, cut_s = int(len(pose) * 0.6), int(len(sig) * 0.6)
    over_p, over_s = int(len(pose) * 0.4), int(len(sig) * 0.4)
    paths = {}
    for name, p, s in (("a", pose.iloc[:cut_p], sig.iloc[:cut_s]), ("b", pose.iloc[over_p:], sig.iloc[over_s:])):
        paths[name] = (tmp_path / f"pose_{name}.{ext}", tmp_path / f"signal_{name}.{ext}")
        write_table(p, str(paths[name][0]))
        write_table(s, str(paths[name][1]))
    write_table(pose, str(tmp_path / f"pose.{ext}"))
    write_table(sig, str(tmp_path / f"signal.{ext}"))
    return paths, (cut_p - over_p, cut_s - over_s)


@pytest.mark.parametrize("ext", ["csv", "parquet"])
def test_two_overlapping_exports_are_read_as_the_whole_log_counted_by_name(tmp_path, flight, ext):
    paths, (n_pose, n_sig) = _tables(tmp_path, flight, ext)
    whole, _ = read_logs([tmp_path / f"pose.{ext}", tmp_path / f"signal.{ext}"])
    files = [*paths["a"], *paths["b"]]
    got, meta = read_logs(files)
    pd.testing.assert_frame_equal(got.pose, whole.pose)
    pd.testing.assert_frame_equal(got.signal, whole.signal)
    assert meta["files"][2]["repeated_rows"] == {"pose": {str(paths["a"][0]): n_pose}}
    assert meta["files"][3]["repeated_rows"] == {"signal": {str(paths["a"][1]): n_sig}}
    # the order of the files does not change what is read
    back, _ = read_logs(files[::-1])
    pd.testing.assert_frame_equal(back.pose, whole.pose)
    pd.testing.assert_frame_equal(back.signal, whole.signal)


def test_two_different_logs_of_one_node_over_the_same_times_are_refused(tmp_path, flight):
    pose, _ = flight
    a = pose[pose["node"] == pose["node"].iloc[0]]
    b = a.assign(x=a["x"] + 3.0)  # another log of the same node: other positions
    write_table(a, str(tmp_path / "one.csv"))
    write_table(b, str(tmp_path / "other.csv"))
    # was: no error when the times differ; a duplicate-timestamp error naming no file when equal
    with pytest.raises(InputError, match=r"one.csv and .*other.csv both give node .*'s poses from t = .*not the same"):
        read_logs([tmp_path / "one.csv", tmp_path / "other.csv"])
    shifted = b.assign(t=b["t"] + 0.013)
    write_table(shifted, str(tmp_path / "shifted.csv"))
    with pytest.raises(InputError, match="two logs of one stream would interleave"):
        read_logs([tmp_path / "one.csv", tmp_path / "shifted.csv"])
    later = a.assign(t=a["t"] + (a["t"].max() - a["t"].min()) + 1.0)  # the next stretch: no overlap
    write_table(later, str(tmp_path / "later.csv"))
    logs, _ = read_logs([tmp_path / "one.csv", tmp_path / "later.csv"])
    assert len(logs.pose) == 2 * len(a)


def test_inspect_says_a_log_given_twice_and_two_logs_of_one_node(tmp_path, flight):
    from rplearn.io import inspect_logs

    pose, _ = flight
    a = pose[pose["node"] == pose["node"].iloc[0]]
    write_table(a, str(tmp_path / "one.csv"))
    write_table(a, str(tmp_path / "again.csv"))
    write_table(a.assign(x=a["x"] + 3.0, t=a["t"] + 0.013), str(tmp_path / "other.csv"))
    report = inspect_logs([tmp_path / "one.csv", tmp_path / "again.csv"])
    assert any(f"again.csv: {len(a):,} pose row(s) repeat rows of" in p for p in report.problems)
    assert report.nodes[0].backward_steps == 0 and report.files[1]["repeated_rows"]["pose"]
    report = inspect_logs([tmp_path / "one.csv", tmp_path / "other.csv"])
    assert any("both give node" in p and "sync refuses these files" in p for p in report.problems)
