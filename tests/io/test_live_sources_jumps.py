"""rplearn.io.live_sources.CsvTail: every pose row is checked for a position jump against its
node's last row kept, across polls (a poll of one row included), and rows are named by their
row in the file (as ``sync`` names them), not by their place in the poll; copies of rows
written twice across polls are counted, not refused."""

from __future__ import annotations

import pytest

from rplearn.errors import InputError
from rplearn.io.live_sources import CsvTail
from rplearn.io.options import ReaderOptions

POSE_HEAD = "t,node,x,y,z,qw,qx,qy,qz\n"
SIGNAL_HEAD = "t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n"


def _row(t: float, x: float, z: float = 10.0) -> str:
    return f"{t:.1f},A,{x:g},0,{z:g},1,0,0,0\n"


def _tail(tmp_path, policy: str = "error"):
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text(POSE_HEAD + "".join(_row(0.1 * i, float(i)) for i in range(10)))  # 10 m/s
    signal.write_text(SIGNAL_HEAD)
    tail = CsvTail(str(pose), str(signal), ReaderOptions(nan_policy=policy))
    assert len(tail.poll().poses) == 10
    return tail, pose


def _append(path, text: str) -> None:
    with path.open("a") as fh:
        fh.write(text)


def test_a_one_row_poll_with_a_sentinel_is_refused_naming_its_row_in_the_file(tmp_path):
    """Was handed out: a poll of one row was never checked."""
    tail, pose = _tail(tmp_path)
    _append(pose, _row(1.0, 10.0, z=-1000.0))
    with pytest.raises(InputError) as e:
        tail.poll()
    msg = str(e.value)
    assert msg.startswith(f"{pose}: fields x, y, z of node A jump") and "at row 10 (t = 1.000 s)" in msg
    assert "\n" not in msg and "nan_policy='drop'" in msg


def test_with_drop_a_sentinel_between_polls_is_dropped_counted_and_the_track_goes_on(tmp_path):
    tail, pose = _tail(tmp_path, "drop")
    _append(pose, _row(1.0, 10.0, z=-1000.0))
    got = tail.poll()
    assert got.poses.empty and got.dropped["position_jump"] == 1
    _append(pose, _row(1.1, 11.0) + _row(1.2, 12.0))
    got = tail.poll()
    assert list(got.poses["x"]) == [11.0, 12.0] and got.dropped["position_jump"] == 1


def test_rows_of_a_later_poll_are_named_by_their_row_in_the_file(tmp_path):
    """Row numbers counted from the poll's start (row 1 here) named a row the file does not
    have there."""
    tail, pose = _tail(tmp_path)
    _append(pose, _row(1.0, 10.0) + _row(1.1, 11.0) + _row(1.2, 11.0, z=-1000.0) + _row(1.3, 13.0))
    with pytest.raises(InputError, match=r"first at row 12 \(a sentinel"):
        tail.poll()


def test_a_block_written_again_in_a_later_poll_is_no_step_back(tmp_path):
    tail, pose = _tail(tmp_path)
    _append(pose, _row(1.0, 10.0))
    tail.poll()
    _append(pose, _row(1.0, 10.0) + _row(1.1, 11.0))  # the last row written twice, then the next
    got = tail.poll()
    assert list(got.poses["t"]) == [1.1] and got.dropped["duplicate_pose"] == 1


def _signal_row(t: float, rssi: float = -60.0) -> str:
    return f"{t:.2f},A,B,{rssi:g},20,2.4e9\n"


def test_a_signal_logger_that_rebooted_between_polls_is_refused_as_sync_refuses_it(tmp_path):
    """Was read on: its later rows matched with poses of another moment (out_of_span, pose_gap)."""
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text(POSE_HEAD + "".join(_row(0.1 * i, float(i)) for i in range(10)))
    signal.write_text(SIGNAL_HEAD + "".join(_signal_row(0.1 * i + 0.05) for i in range(5)))
    tail = CsvTail(str(pose), str(signal))
    tail.poll()
    _append(signal, _signal_row(0.45) + _signal_row(0.55, -61.0))  # a copy of the last row: no step back
    assert len(tail.poll().signals) == 2
    _append(signal, _signal_row(0.02))  # the clock restarted
    with pytest.raises(Exception, match=r"signal.csv: field t goes backwards at row 7 \(link A -> B: 0.55 -> 0.02; "
                                        "a logger that rebooted"):
        tail.poll()


def test_a_file_that_shrinks_while_it_is_read_is_refused_naming_it(tmp_path):
    """Review 44: a pose file truncated or rotated under the session was waited on past its end
    for ever; its rows, row numbers and last times are those read before, so it is refused."""
    from rplearn.errors import LogFormatError

    tail, pose = _tail(tmp_path)
    pose.write_text(POSE_HEAD + _row(0.0, 0.0))
    with pytest.raises(LogFormatError, match=r"pose\.csv: the file shrank from .* bytes while it was read"):
        tail.poll()
