"""A CSV being appended to whose logger restarted and wrote its header again (audit48): the line is dropped and
counted (``repeated_header``) also when it comes in a later poll; another header is refused naming its line."""

from __future__ import annotations

import pytest

from rplearn.errors import LogFormatError
from rplearn.io.live_sources import CsvTail

POSE = "t,node,x,y,z,qw,qx,qy,qz\n"
SIGNAL = "t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n"


def _rows(t0: int) -> tuple[str, str]:
    pose = "".join(f"{t0 + k * 0.1:.1f},D,{k},0,10,1,0,0,0\n{t0 + k * 0.1:.1f},G,0,0,0,1,0,0,0\n" for k in range(10))
    signal = "".join(f"{t0 + k * 0.1 + 0.05:.2f},D,G,-60,20,2.4e9\n" for k in range(10))
    return pose, signal


def test_a_header_written_again_between_polls_is_dropped_and_counted(tmp_path):
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    p, s = _rows(0)
    pose.write_text(POSE + p)
    signal.write_text(SIGNAL + s)
    tail = CsvTail(str(pose), str(signal))
    first = tail.poll()
    assert len(first.signals) == 10
    p, s = _rows(1)
    with pose.open("a") as fp, signal.open("a") as fs:
        fp.write(POSE + p)
        fs.write(SIGNAL + s)
    again = tail.poll()
    assert len(again.signals) == 10 and again.dropped == {"repeated_header": 2}
    assert again.where == {"repeated_header": f"{pose} line 22; {signal} line 12"}  # review 51: where (was not said)
    with signal.open("a") as fs:
        fs.write("t,tx,rx,rssi_dbm\n")
    with pytest.raises(LogFormatError, match=r"signal.csv: line 23: another header in the file"):
        tail.poll()


def test_the_tail_tells_headers_from_rows_as_sync_does(tmp_path):
    """One rule with the whole-file readers (rplearn.io._csv_headers): a row whose first field is a column name (a
    node called ``x`` in a table whose first column is the node) holds numbers and is a row (was refused as another
    header); the header written again quoted, or with a byte-order mark (a file joined with cat), is the header."""
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    head = "node,t,x,y,z,qw,qx,qy,qz\n"
    rows = "".join(f"x,{k * 0.1:.1f},{k},0,10,1,0,0,0\nG,{k * 0.1:.1f},5,5,0,1,0,0,0\n" for k in range(10))
    pose.write_text(head + rows)
    signal.write_text(SIGNAL)
    tail = CsvTail(str(pose), str(signal))
    assert len(tail.poll().poses) == 20
    later = "".join(f"x,{1 + k * 0.1:.1f},{10 + k},0,10,1,0,0,0\n" for k in range(5))
    with pose.open("a") as fp:
        fp.write('"node", "t", "x", "y", "z", "qw", "qx", "qy", "qz"\n' + later + "\ufeff" + head + later.replace("x,1.", "x,2."))
    again = tail.poll()
    assert len(again.poses) == 10 and again.dropped == {"repeated_header": 2}


def test_rows_and_lines_after_a_header_written_again_are_numbered_as_sync_numbers_them(tmp_path):
    """Rows counted from 0 at the first data row without the header lines, lines as the file's (rplearn.io._csv_headers):
    a step back in time after the header written again is the row the whole-file reader names; a line of too many
    fields, the file's line (was the line within the poll's rows)."""
    from rplearn.io.tables import read_signal_table

    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    p, s = _rows(0)
    pose.write_text(POSE + p)
    signal.write_text(SIGNAL + s)
    tail = CsvTail(str(pose), str(signal))
    tail.poll()
    p, s = _rows(1)
    with signal.open("a") as fs:
        fs.write(SIGNAL + s.replace("1.35,", "0.37,"))  # data row 13, the file's line 16
    with pytest.raises(LogFormatError, match=r"field t goes backwards at row 13 ") as live:
        tail.poll()
    with pytest.raises(LogFormatError, match=r"field t goes backwards at row 13 ") as whole:
        read_signal_table(str(signal))
    assert str(live.value) == str(whole.value)
    assert signal.read_text().splitlines()[15].startswith("0.37,")

    pose.write_text(POSE + p)
    signal.write_text(SIGNAL + s)
    tail = CsvTail(str(pose), str(signal))
    tail.poll()
    with signal.open("a") as fs:
        fs.write(SIGNAL + s.replace("1.25,D,G,-60,20,2.4e9", "1.25,D,G,-60,20,2.4e9,7"))  # the file's line 15
    with pytest.raises(LogFormatError, match=r"signal.csv: cannot parse the rows appended \(ParserError: .*Expected 6 "
                                             r"fields in line 15, saw 7\)$"):
        tail.poll()
    assert signal.read_text().splitlines()[14].endswith(",7")


def test_the_tail_names_the_first_few_repeated_headers_and_counts_them_all(tmp_path):
    """Review 51: the live summary says where the header lines were; the tail keeps the first NAMED_LINES, however
    many come (its memory does not grow with them)."""
    from rplearn.io._csv_headers import NAMED_LINES

    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    p, s = _rows(0)
    pose.write_text(POSE + p)
    signal.write_text(SIGNAL + s)
    tail = CsvTail(str(pose), str(signal))
    tail.poll()
    for k in range(1, 8):  # seven restarts of the signal logger, one a poll
        with signal.open("a") as fs:
            fs.write(SIGNAL + _rows(k)[1])
        got = tail.poll()
    assert got.dropped == {"repeated_header": 7} and len(tail.signal.repeated.first) == NAMED_LINES
    assert got.where == {"repeated_header": f"{signal} lines 12, 23, 34 and 4 more"}
