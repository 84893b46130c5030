"""rplearn.io.tables: pose rows written twice (copies, counted as ``duplicate_pose``) and two
different poses of one node and time (a conflict: refused naming file, node, rows and field, or
all of that time's rows dropped as ``conflicting_pose``), on a messy export of a real log."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.errors import InputError, LogFormatError
from rplearn.io.options import ReaderOptions
from rplearn.io.tables import read_pose_table

REAL_TLOG = Path("tests/fixtures/ardupilot/mavlink-log_2013-10-13_16-58-51.tlog")
BLOCK = slice(400, 420)  # the 20 rows a logger writes twice


@pytest.fixture(scope="module")
def real_logs() -> tuple[pd.DataFrame, pd.DataFrame]:
    """The canonical pose and signal logs of a real 2013 tlog (2,735 vehicle rows and the
    station; both links), read once."""
    from rplearn.io.mavlink import read_mavlink

    logs, _ = read_mavlink(REAL_TLOG, tx_power_dbm=20.0, frequency_hz=915e6)
    return logs.pose.drop(columns=["armed"]), logs.signal


@pytest.fixture(scope="module")
def real_poses(real_logs) -> pd.DataFrame:
    return real_logs[0]


def _block_twice(pose: pd.DataFrame) -> pd.DataFrame:
    """The pose rows in file order with rows ``BLOCK`` written again right after themselves."""
    return pd.concat([pose.iloc[:BLOCK.stop], pose.iloc[BLOCK], pose.iloc[BLOCK.stop:]], ignore_index=True)


@pytest.mark.parametrize("ext", ["csv", "parquet"])
@pytest.mark.parametrize("policy", ["error", "drop"])
def test_a_real_log_with_a_block_written_twice_reads_with_the_copies_counted(tmp_path, real_poses, ext, policy):
    path = tmp_path / f"poses.{ext}"
    messy = _block_twice(real_poses)
    messy.to_csv(path, index=False) if ext == "csv" else messy.to_parquet(path, index=False)
    pose, meta = read_pose_table(str(path), nan_policy=policy)
    clean, _ = read_pose_table(str(_write(tmp_path / f"clean.{ext}", real_poses)), nan_policy=policy)
    assert meta["dropped"]["duplicate_pose"] == 20 and meta["dropped"]["conflicting_pose"] == 0
    pd.testing.assert_frame_equal(pose, clean)
    (note,) = [n for n in meta["notes"] if "duplicate_pose" in n]
    assert note.startswith(f"{path}: 20 pose row(s) repeat") and f"first at row {BLOCK.stop}" in note
    assert f"a copy of row {BLOCK.start}" in note and "\n" not in note


def _write(path: Path, df: pd.DataFrame) -> Path:
    df.to_csv(path, index=False) if path.suffix == ".csv" else df.to_parquet(path, index=False)
    return path


def _conflicting(real_poses: pd.DataFrame) -> pd.DataFrame:
    """Rows 500..509 given again with another altitude (two poses of one instant)."""
    other = real_poses.iloc[500:510].assign(z=real_poses["z"].iloc[500:510] + 3.0)
    return pd.concat([real_poses.iloc[:510], other, real_poses.iloc[510:]], ignore_index=True)


def test_two_different_poses_of_one_node_and_time_are_refused_naming_file_node_rows_and_field(tmp_path, real_poses):
    path = _write(tmp_path / "poses.csv", _conflicting(real_poses))
    with pytest.raises(InputError) as e:
        read_pose_table(str(path))
    msg = str(e.value)
    t500 = float(real_poses["t"].iloc[500])
    assert msg.startswith(f"{path}: field z: 20 pose row(s) share a node and time") and "\n" not in msg
    assert f"node sys1 at t = {t500!r}" in msg and "rows 500 and 510 differ in z" in msg
    assert "nan_policy='drop'" in msg


def test_with_drop_all_rows_of_a_conflicting_time_are_dropped_and_counted(tmp_path, real_poses):
    path = _write(tmp_path / "poses.csv", _conflicting(real_poses))
    pose, meta = read_pose_table(str(path), nan_policy="drop")
    assert meta["dropped"]["conflicting_pose"] == 20 and meta["dropped"]["duplicate_pose"] == 0
    assert len(pose) == len(real_poses) - 10
    assert not np.isin(pose["t"].to_numpy(), real_poses["t"].iloc[500:510].to_numpy()).any()
    assert any("conflicting_pose" in n for n in meta["notes"])


def test_a_copy_and_a_conflict_of_one_time_drop_the_copy_and_refuse_the_conflict(tmp_path):
    rows = pd.DataFrame({"t": [0.0, 0.1, 0.1, 0.1, 0.2], "node": "D", "x": [0.0, 1.0, 1.0, 1.5, 2.0], "y": 0.0,
                         "z": 5.0, "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    path = _write(tmp_path / "p.csv", rows)
    with pytest.raises(InputError, match=r"field x: 2 pose row\(s\).*rows 1 and 3 differ in x"):
        read_pose_table(str(path))
    pose, meta = read_pose_table(str(path), nan_policy="drop")
    assert meta["dropped"]["duplicate_pose"] == 1 and meta["dropped"]["conflicting_pose"] == 2
    assert pose["t"].tolist() == [0.0, 0.2]


def test_a_copy_is_no_step_back_but_a_real_step_back_is_still_refused(tmp_path):
    rows = pd.DataFrame({"t": [0.0, 0.1, 0.2, 0.1, 0.3], "node": "D", "x": [0.0, 1.0, 2.0, 1.0, 3.0], "y": 0.0,
                         "z": 5.0, "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    pose, meta = read_pose_table(str(_write(tmp_path / "copy.csv", rows)))
    assert meta["dropped"]["duplicate_pose"] == 1 and pose["t"].tolist() == [0.0, 0.1, 0.2, 0.3]
    back = rows.assign(t=[0.0, 0.1, 0.2, 0.15, 0.3])
    with pytest.raises(LogFormatError, match="field t goes backwards at row 3"):
        read_pose_table(str(_write(tmp_path / "back.csv", back)))


def test_sync_and_inspect_say_the_copies_of_a_real_log(tmp_path, real_logs):
    from rplearn.io.inspect import inspect_logs
    from rplearn.workflows.logs import sync_logs

    path = str(_write(tmp_path / "poses.csv", _block_twice(real_logs[0])))
    signal = str(_write(tmp_path / "signal.csv", real_logs[1].iloc[:300]))
    opts = ReaderOptions()
    outcome = sync_logs([path], [signal], str(tmp_path / "m.csv"), opts)
    assert outcome.counts.n_out > 0
    assert f"{path}: dropped 20 pose row(s) (duplicate_pose)" in outcome.notes
    report = inspect_logs([path], opts)
    text = report.to_text()
    assert "duplicate_pose" in text and "20 pose row(s) repeat" in text
    assert not any("time goes backwards" in p for p in report.problems)  # the copies are no step back


def test_rows_differing_only_beside_the_pose_are_copies(tmp_path):
    """Review 44: a column beside the pose (a satellite count) written again with another value
    does not make two poses of one instant: the rows are copies, as the live source finds them."""
    rows = pd.DataFrame({"t": [0.0, 0.1, 0.1, 0.2], "node": "D", "x": [0.0, 1.0, 1.0, 2.0], "y": 0.0,
                         "z": 5.0, "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0, "sats": [9, 9, 99, 9]})
    pose, meta = read_pose_table(str(_write(tmp_path / "sats.csv", rows)))
    assert meta["dropped"]["duplicate_pose"] == 1 and meta["dropped"]["conflicting_pose"] == 0
    assert pose["t"].tolist() == [0.0, 0.1, 0.2]


def test_a_step_back_after_copies_names_its_row_in_the_file(real_poses, tmp_path):
    """Rows are the file's (from 0 at the first data row): copies dropped before a time that goes back do not move
    the row named (was its place among the rows kept: 20 rows early here)."""
    table = _block_twice(real_poses)
    at = 1000
    table.loc[at, "t"] = float(table.loc[at - 1, "t"]) - 5.0
    path = tmp_path / "back.csv"
    table.to_csv(path, index=False)
    with pytest.raises(LogFormatError, match=rf"field t goes backwards at row {at} \(node "):
        read_pose_table(str(path))


@pytest.mark.parametrize("ext", ["csv", "parquet"])
def test_a_zero_quaternion_after_copies_names_its_row_in_the_file(real_poses, tmp_path, ext):
    """Review 51: the zero-norm refusal named its place among the rows kept (20 rows early here, after the copies),
    not its row in the file as the other pose refusals do."""
    table = _block_twice(real_poses)
    at = 1000
    table.loc[at, ["qw", "qx", "qy", "qz"]] = 0.0
    path = _write(tmp_path / f"zero.{ext}", table)
    with pytest.raises(InputError, match=rf"zero\.{ext}: quaternion \(qw, qx, qy, qz\) has zero norm at row {at}$"):
        read_pose_table(str(path))


def test_a_zero_quaternion_after_dropped_rows_and_a_repeated_header_names_its_row_in_the_file(tmp_path):
    """A row dropped for a NaN (``--nan-policy drop``) and a repeated header line before it: the row is still the
    file's (from 0 at the first data row, the header lines not counted), as docs/guides/csv.md says."""
    path = tmp_path / "z.csv"
    header = "t,node,x,y,z,qw,qx,qy,qz\n"
    path.write_text(header + "0,A,0,0,5,1,0,0,0\n0.1,A,,0,5,1,0,0,0\n" + header + "0.2,A,0,0,5,1,0,0,0\n0.3,A,0,0,5,0,0,0,0\n")
    with pytest.raises(InputError, match=r"has zero norm at row 3$"):
        read_pose_table(str(path), nan_policy="drop")
    copy = tmp_path / "c.csv"
    copy.write_text(header + "0,A,0,0,5,1,0,0,0\n0,A,0,0,5,1,0,0,0\n0.1,A,0,0,5,1,0,0,0\n0.2,A,0,0,5,0,0,0,0\n")
    with pytest.raises(InputError, match=r"has zero norm at row 3$"):
        read_pose_table(str(copy))
