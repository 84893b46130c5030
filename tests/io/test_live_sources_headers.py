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
    with signal.open("a") as fs:
        fs.write("t,tx,rx,rssi_dbm\n")
    with pytest.raises(LogFormatError, match=r"signal.csv: line 23: another header in the file"):
        tail.poll()
