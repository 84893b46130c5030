"""rplearn.io.live_sources.CsvTail on a file replaced under its name while it is read (logrotate, a logger
restarting with a new file), with the same or a larger size: refused naming the file, never read on from the
old offset (rows of the new file skipped, its times taken for the old log's); a log rewritten whole with the
bytes read so far at its start (a writer replacing it atomically) is the same log grown, read on."""

from __future__ import annotations

import os

import pytest

from rplearn.errors import LogFormatError
from rplearn.io.live_sources import FIRST_BYTES, CsvTail

POSE_HEAD = "t,node,x,y,z,qw,qx,qy,qz\n"
SIGNAL_HEAD = "t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n"


def _rows(t0: float, n: int) -> str:
    return "".join(f"{t0 + 0.1 * i:.1f},A,{5 * (t0 + 0.1 * i):.2f},0,10,1,0,0,0\n" for i in range(n))  # 5 m/s


def _signals(t0: float, n: int) -> str:
    return "".join(f"{t0 + 0.1 * i + 0.05:.2f},A,B,-60,20,2.4e9\n" for i in range(n))


@pytest.fixture()
def tail(tmp_path):
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text(POSE_HEAD + _rows(0.0, 10))
    signal.write_text(SIGNAL_HEAD + _signals(0.0, 5))
    tail = CsvTail(str(pose), str(signal))
    got = tail.poll()
    assert len(got.poses) == 10 and len(got.signals) == 5
    return tail, pose, signal


def _replace(path, text: str) -> None:
    """Another file under the name (written beside it, renamed over it: a new inode)."""
    new = path.with_suffix(".new")
    new.write_text(text)
    os.replace(new, path)


@pytest.mark.parametrize("which", ["pose", "signal"])
def test_a_file_replaced_by_a_larger_one_is_refused_naming_it(tail, which):
    # was: read on from the old offset: the new file's first rows skipped, the rest taken as the old log's
    tail, pose, signal = tail
    path = pose if which == "pose" else signal
    text = POSE_HEAD + _rows(100.0, 30) if which == "pose" else SIGNAL_HEAD + _signals(100.0, 30)
    assert len(text) > path.stat().st_size
    _replace(path, text)
    with pytest.raises(LogFormatError) as e:
        tail.poll()
    msg = str(e.value)
    assert msg.startswith(f"{path}: the file was replaced by another under its name while it was read")
    assert "give the new file as a session of its own" in msg and "\n" not in msg


def test_a_file_truncated_and_written_again_to_a_larger_size_is_refused(tail):
    # logrotate's copytruncate, then the logger writes on past the old size: same inode, other first bytes
    tail, pose, _ = tail
    ino = pose.stat().st_ino
    with pose.open("w") as fh:  # truncated in place, then refilled
        fh.write(POSE_HEAD + _rows(50.0, 30))
    assert pose.stat().st_ino == ino
    with pytest.raises(LogFormatError, match=r"pose\.csv: the file's first bytes changed while it was read \(rewritten in "
                                             r"place: rotated by copy and truncate"):
        tail.poll()


def test_a_file_that_went_away_is_refused(tail):
    tail, pose, _ = tail
    pose.rename(pose.with_suffix(".1"))  # rotated away, no new file yet
    with pytest.raises(LogFormatError, match=r"pose\.csv: the file went away while it was read"):
        tail.poll()


@pytest.mark.parametrize("rows", [10, 200])  # the bytes read within FIRST_BYTES, and beyond them
def test_a_log_rewritten_whole_with_the_same_start_is_read_on(tmp_path, rows):
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text(POSE_HEAD + _rows(0.0, rows))
    signal.write_text(SIGNAL_HEAD)
    tail = CsvTail(str(pose), str(signal))
    assert len(tail.poll().poses) == rows
    assert (pose.stat().st_size > FIRST_BYTES) == (rows == 200)
    _replace(pose, POSE_HEAD + _rows(0.0, rows) + _rows(0.1 * rows, 5))  # the same log, grown, atomically
    got = tail.poll()
    assert len(got.poses) == 5 and got.poses["t"].min() == pytest.approx(0.1 * rows)


def test_a_log_rewritten_whole_that_differs_past_the_first_bytes_is_refused(tmp_path):
    # a new inode whose first FIRST_BYTES are those read but whose later bytes are not: all the bytes are compared
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    text = POSE_HEAD + _rows(0.0, 200)
    pose.write_text(text)
    signal.write_text(SIGNAL_HEAD)
    tail = CsvTail(str(pose), str(signal))
    tail.poll()
    changed = text[:FIRST_BYTES + 100] + text[FIRST_BYTES + 100:].replace(",A,", ",C,", 1)
    _replace(pose, changed + _rows(20.0, 5))
    with pytest.raises(LogFormatError, match=r"pose\.csv: the file was replaced by another under its name"):
        tail.poll()
