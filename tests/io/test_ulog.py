"""PX4 ULogs with defects: the log in the file twice, two logs concatenated."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from rplearn.errors import LogFormatError
from rplearn.io import inspect_logs
from rplearn.io.inspect import file_damage
from rplearn.io.ulog import read_ulog, ulog_layout

DATA = Path(__file__).resolve().parents[1] / "fixtures" / "px4-ulog"
SMALL, EVENTS = DATA / "sample_log_small.ulg", DATA / "sample_px4_events.ulg"


@pytest.mark.parametrize("extra", [b"", b"cut"])
def test_a_ulog_in_the_file_twice_reads_as_once_and_says_so(tmp_path, extra):
    data = SMALL.read_bytes()
    twice = tmp_path / "twice.ulg"
    twice.write_bytes(data + data + (data[:5000] if extra else b""))  # a third copy cut short
    (once, m1), (doubled, m2) = read_ulog(SMALL, "A"), read_ulog(twice, "A")
    pd.testing.assert_frame_equal(once, doubled)
    assert not m2["corrupt"] and m2["cut_off_at_byte"] is None  # was: corrupt bytes skipped
    assert m2["invalid_flag_rows"] == m1["invalid_flag_rows"] and m2["dropped"] == m1["dropped"]
    assert m1["repeated_messages"] == 0 and m2["records_read"] == m1["records_read"]
    assert m2["repeated_messages"] >= m1["records_read"]
    assert (m2["repeated_messages"] == m1["records_read"]) == (not extra)
    lines = file_damage(str(twice), m2)
    assert any("part of the log is in the file twice" in line for line in lines)
    assert not any("corrupt" in line for line in lines)


def test_inspect_says_a_doubled_ulog_once(tmp_path):
    from rplearn.io import ReaderOptions

    data = SMALL.read_bytes()
    twice = tmp_path / "twice.ulg"
    twice.write_bytes(data * 2)
    problems = inspect_logs(twice, ReaderOptions(nodes={str(twice): "A"})).problems
    assert any("twice.ulg" in p and "in the file twice" in p for p in problems)
    assert not any("corrupt" in p for p in problems)


def test_two_different_ulogs_concatenated_are_refused_naming_the_byte(tmp_path):
    first = SMALL.read_bytes()
    both = tmp_path / "both.ulg"
    both.write_bytes(first + EVENTS.read_bytes())
    with pytest.raises(LogFormatError, match=rf"both.ulg: a second ULog starts at byte {len(first):,} .*concatenated"):
        read_ulog(both, "A")


def test_layout_of_a_whole_log():
    layout = ulog_layout(str(SMALL))
    assert layout["log_bytes"] == SMALL.stat().st_size and layout["repeated_messages"] == 0
    assert layout["cut_off_at_byte"] is None and layout["messages"] > 1000


def test_a_cut_ulog_says_where_and_how_many_messages_were_read(tmp_path):
    from rplearn.io.ulog import ulog_cut_off_at

    data = SMALL.read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[:len(data) * 2 // 3])
    _, m_whole = read_ulog(SMALL, "A")
    _, meta = read_ulog(cut, "A")
    at = meta["cut_off_at_byte"]
    assert at is not None and at == ulog_cut_off_at(str(cut)) and at < len(data) * 2 // 3
    assert 0 < meta["records_read"] < m_whole["records_read"]
    whole_part = tmp_path / "part.ulg"
    whole_part.write_bytes(data[:at])  # the same bytes ending whole
    assert read_ulog(whole_part, "A")[1]["records_read"] == meta["records_read"]
    assert read_ulog(whole_part, "A")[1]["cut_off_at_byte"] is None
    lines = file_damage(str(cut), meta)
    assert any(f"cut off inside the message at byte {at:,}" in line
               and f"the {meta['records_read']:,} complete record(s) before it were read" in line for line in lines)


def _message_offsets(data: bytes) -> list[int]:
    pos, out = 16, []
    while pos + 3 <= len(data):
        out.append(pos)
        pos += 3 + (data[pos] | (data[pos + 1] << 8))
    return out


@pytest.mark.parametrize("new_type", [ord("X"), 0])
def test_a_flipped_message_type_is_said_corrupt_naming_the_byte(tmp_path, new_type):
    data = bytearray(EVENTS.read_bytes())
    at = _message_offsets(bytes(data))[len(_message_offsets(bytes(data))) // 2]
    assert data[at + 2] == ord("D")
    data[at + 2] = new_type  # a data message's type byte damaged: pyulog skipped an unknown type silently
    bad = tmp_path / "flipped.ulg"
    bad.write_bytes(bytes(data))
    _, meta = read_ulog(bad, "A")
    assert meta["corrupt"] and meta["corrupt_at_byte"] == at
    assert meta["cut_off_at_byte"] is None and meta["records_read"] is None
    lines = file_damage(str(bad), meta)
    assert any(f"corrupt bytes were skipped by the ULog reader (pyulog) (the first at byte {at:,}" in line
               for line in lines)
    assert not read_ulog(EVENTS, "A")[1]["corrupt"]


def test_a_ulog_cut_before_its_first_position_says_it_is_cut_off(tmp_path):
    """Cut 5 % into the file, before any vehicle_local_position message: the refusal says the file
    is cut off and where, not only that the topic is missing."""
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(SMALL.read_bytes()[:46_081])
    with pytest.raises(LogFormatError, match=r"cut.ulg: topic vehicle_local_position missing or empty: the file is "
                                             r"cut off at byte 46,080 of 46,081, before the topic's first message"):
        read_ulog(cut, "A")


def test_pyulog_prints_nothing_on_a_damaged_ulog(tmp_path, capfd):
    """A block of the log repeated inside it (a damaged copy): pyulog's own lines ("File corruption
    detected ...") stay off the terminal; the metadata says the damage (``corrupt``)."""
    data = SMALL.read_bytes()
    at, n = int(len(data) * 0.2), 20_000
    bad = tmp_path / "block.ulg"
    bad.write_bytes(data[:at + n] + data[at:at + n] + data[at + n:])
    capfd.readouterr()
    _, meta = read_ulog(bad, "A")
    assert meta["corrupt"]
    out, err = capfd.readouterr()
    assert out == "" and err == ""
