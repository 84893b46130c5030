"""CSV logs whose header line comes again mid-file (a logger restarted appending to its file, two files joined with
``cat``): the line repeating the file's own header is dropped and counted (``repeated_header``) and the rows after it
read, by ``read_logs``, ``sync`` (its signal tables streamed) and ``inspect`` alike; a header of other columns mid-file
is refused naming the file and the line."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

from rplearn.errors import InputError, LogFormatError
from rplearn.io import read_logs
from rplearn.io.inspect import inspect_logs
from rplearn.io.inspect_json import inspect_to_dict
from rplearn.io.tables import iter_signal_table, read_pose_table, read_signal_table
from rplearn.workflows.logs import sync_logs


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> tuple[Path, Path]:
    """The smoke preset's flight written as CSV by the simulator's writers (``pose_log.csv``, ``signal_log.csv``)."""
    from rplearn.sim import simulate

    out = tmp_path_factory.mktemp("smoke")
    paths = simulate("smoke", seed=0, out_dir=str(out), log_format="csv").paths
    return Path(paths["pose_log"]), Path(paths["signal_log"])


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines(keepends=True)


def _with_lines(path: Path, out: Path, inserts: dict[int, str]) -> Path:
    """``path`` written to ``out`` with ``inserts[k]`` put before its line ``k`` (0-based)."""
    lines = _lines(path)
    for at in sorted(inserts, reverse=True):
        lines[at:at] = [inserts[at]]
    out.write_text("".join(lines))
    return out


def _header_again(path: Path, out: Path, *at: int) -> Path:
    return _with_lines(path, out, {k: _lines(path)[0] for k in at})


def test_read_logs_drops_and_counts_the_header_repeated(flight, tmp_path):
    pose, signal = flight
    clean, _ = read_logs([str(pose), str(signal)])
    logs, meta = read_logs([str(_header_again(pose, tmp_path / "pose.csv", 500)),
                            str(_header_again(signal, tmp_path / "signal.csv", 700, 1500))])
    pd.testing.assert_frame_equal(logs.pose, clean.pose)
    pd.testing.assert_frame_equal(logs.signal, clean.signal)
    assert [f["dropped"]["repeated_header"] for f in meta["files"]] == [1, 2]


def test_sync_matches_the_same_samples_as_the_clean_file(flight, tmp_path):
    """The signal table is streamed in chunks; the pose table read whole: both say what they dropped."""
    pose, signal = flight
    clean = sync_logs([str(pose)], [str(signal)], str(tmp_path / "clean.parquet"))
    p = _header_again(pose, tmp_path / "pose.csv", 3000)
    s = _header_again(signal, tmp_path / "signal.csv", 900)
    out = sync_logs([str(p)], [str(s)], str(tmp_path / "rep.parquet"))
    assert out.streamed and out.counts.n_out == clean.counts.n_out > 2000
    assert out.counts.n_in == clean.counts.n_in and out.counts.dropped == clean.counts.dropped
    assert f"{p}: dropped 1 header line(s) repeated mid-file (repeated_header: line 3001)" in out.notes  # review 51:
    assert f"{s}: dropped 1 header line(s) repeated mid-file (repeated_header: line 901)" in out.notes  # the lines
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "rep.parquet"), pd.read_parquet(tmp_path / "clean.parquet"))


def test_inspect_says_the_repeated_header_and_finds_nothing_else(flight, tmp_path):
    pose, signal = flight
    clean = inspect_logs([str(pose), str(signal)])
    report = inspect_logs([str(_header_again(pose, tmp_path / "pose.csv", 10)),
                           str(_header_again(signal, tmp_path / "signal.csv", 20))])
    assert report.problems == clean.problems
    assert [n.rows for n in report.nodes] == [n.rows for n in clean.nodes]
    assert [lk.samples for lk in report.links] == [lk.samples for lk in clean.links]
    files = inspect_to_dict(report)["files"]
    assert files[0]["dropped"] == {"repeated_header": 1} and files[0]["repeated_header_lines"] == [11]
    assert files[1]["signal_dropped"] == {"repeated_header": 1} and files[1]["repeated_header_lines"] == [21]
    assert "dropped on reading: 1 header line(s) repeated mid-file (repeated_header: line 21)" in files[1]["findings"]
    assert "dropped on reading: 1 header line(s) repeated mid-file (repeated_header: line 11)" in report.to_text()


def test_a_header_of_other_columns_mid_file_is_refused_naming_file_and_line(flight, tmp_path):
    pose, signal = flight
    other = ",".join(reversed(_lines(signal)[0].strip().split(","))) + "\n"
    s = _with_lines(signal, tmp_path / "signal.csv", {40: other})
    with pytest.raises(LogFormatError, match=rf"^{s}: line 41: another header in the file \('unit,frequency_hz"):
        read_logs([str(pose), str(s)])
    with pytest.raises(LogFormatError, match=rf"^{s}: line 41: another header"):
        sync_logs([str(pose)], [str(s)], str(tmp_path / "out.parquet"))
    assert not (tmp_path / "out.parquet").exists()
    p = _with_lines(pose, tmp_path / "pose.csv", {7: "t,node,lat,lon,alt,qw,qx,qy,qz\n"})
    report = inspect_logs([str(p), str(signal)])
    assert any(f"{p}: unreadable: {p}: line 8: another header" in line for line in report.problems)


def test_a_row_whose_first_field_is_a_column_name_is_a_row(flight, tmp_path):
    """A node named like a column (``x``) in a table whose first column is the node: its rows hold numbers."""
    pose, _ = flight
    table = pd.read_csv(pose)
    table["node"] = table["node"].replace({"A": "x"})
    path = tmp_path / "nodes_first.csv"
    table[["node", *[c for c in table.columns if c != "node"]]].to_csv(path, index=False)
    read, meta = read_pose_table(str(_header_again(path, tmp_path / "again.csv", 100)))
    assert sorted(read["node"].unique()) == ["B", "x"] and len(read) == len(table)
    assert meta["dropped"]["repeated_header"] == 1


def test_chunks_and_scan_blocks_do_not_change_what_is_read(flight, tmp_path, monkeypatch):
    """Headers at a chunk's first row and at the end of the file without its newline, CRLF line ends; the scan read
    in blocks of 100 bytes, so that lines are cut at every place."""
    from rplearn.io import _csv_headers

    _, signal = flight
    crlf = tmp_path / "crlf.csv"
    crlf.write_bytes(signal.read_bytes().replace(b"\n", b"\r\n"))
    header = _lines(crlf)[0]
    path = _with_lines(crlf, tmp_path / "again.csv", {101: header, 250: header, len(_lines(crlf)): header.rstrip()})
    whole, meta = read_signal_table(str(signal))
    monkeypatch.setattr(_csv_headers, "SCAN_BYTES", 100)
    chunks = list(iter_signal_table(str(path), chunk_rows=100))
    assert [c.attrs["repeated_header"] for c in chunks] == [3] * len(chunks)
    pd.testing.assert_frame_equal(pd.concat(chunks, ignore_index=True), whole)
    again, meta = read_signal_table(str(path))
    pd.testing.assert_frame_equal(again, whole)
    assert meta["dropped"] == {"repeated_header": 3}


def test_a_header_from_a_file_joined_with_cat_is_the_same_header(flight, tmp_path):
    """A second file's header with its byte-order mark, or its names quoted and spaced, names the same columns."""
    _, signal = flight
    names = _lines(signal)[0].strip().split(",")
    bom = "\ufeff" + _lines(signal)[0]
    quoted = ", ".join(f'"{n}"' for n in names) + "\n"
    path = _with_lines(signal, tmp_path / "joined.csv", {300: bom, 600: quoted})
    whole, _ = read_signal_table(str(signal))
    again, meta = read_signal_table(str(path))
    pd.testing.assert_frame_equal(again, whole)
    assert meta["dropped"] == {"repeated_header": 2}


def _edited(path: Path, out: Path, line: int, edit) -> Path:
    """``path`` written to ``out`` with its line ``line`` (0-based) passed through ``edit``."""
    lines = _lines(path)
    lines[line] = edit(lines[line])
    out.write_text("".join(lines))
    return out


def _field(k: int, value: str):
    def edit(line: str) -> str:
        cells = line.rstrip("\n").split(",")
        cells[k] = value
        return ",".join(cells) + "\n"
    return edit


def _message(call) -> str:
    with pytest.raises((InputError, LogFormatError)) as info:
        call()
    return str(info.value)


def test_a_row_after_a_repeated_header_has_its_number_in_the_file_without_it(flight, tmp_path, monkeypatch):
    """Rows are counted from 0 at the first data row, header lines not counted (rplearn.io._csv_headers): a bad value
    after a header dropped mid-file is named by the row it has in the file without that line, by read_logs, the
    table readers, sync (its signal table streamed in chunks) and the live tail's reader; that row is on the file's
    line row + 2 + the header lines dropped before it."""
    from rplearn.workflows import logs as wlogs

    pose, signal = flight
    bad_pose = _edited(pose, tmp_path / "bad_pose.csv", 601, _field(4, "nan"))  # data row 600: z NaN
    bad_signal = _edited(signal, tmp_path / "bad_signal.csv", 601, _field(0, "0.001"))  # data row 600: t back
    monkeypatch.setattr(wlogs, "SYNC_CHUNK_ROWS", 97)  # the row in the seventh chunk
    for again in (False, True):
        p = _header_again(bad_pose, tmp_path / "p.csv", 300, 450) if again else bad_pose
        s = _header_again(bad_signal, tmp_path / "s.csv", 300, 450) if again else bad_signal
        for call in (lambda: read_logs([str(p), str(signal)]), lambda: read_pose_table(str(p)),
                     lambda: sync_logs([str(p)], [str(signal)], str(tmp_path / "o.parquet"))):
            assert "(first at row 600)" in _message(call)
        for call in (lambda: read_logs([str(pose), str(s)]), lambda: read_signal_table(str(s)),
                     lambda: list(iter_signal_table(str(s), chunk_rows=97)),
                     lambda: sync_logs([str(pose)], [str(s)], str(tmp_path / "o.parquet"))):
            assert "field t goes backwards at row 600 " in _message(call)
        dropped = 2 if again else 0
        assert _field(4, "nan")(_lines(bad_pose)[601]) == _lines(p)[600 + 1 + dropped]  # row 600: line 602 + 2
        assert _lines(s)[600 + 1 + dropped].startswith("0.001,")


def test_the_parsers_complaint_names_the_files_line_after_a_repeated_header(flight, tmp_path, monkeypatch):
    """A row of too many fields, or a quote left open, after header lines dropped mid-file: the line the parser
    names is the file's (was the line in the file without them: two lines early here), whole or in chunks."""
    from rplearn.workflows import logs as wlogs

    pose, signal = flight
    monkeypatch.setattr(wlogs, "SYNC_CHUNK_ROWS", 97)
    for name, path in (("pose", pose), ("signal", signal)):
        extra = _header_again(_edited(path, tmp_path / f"x_{name}.csv", 601, lambda line: line.rstrip("\n") + ",5\n"),
                              tmp_path / f"{name}.csv", 300, 450)
        assert _lines(extra)[603].endswith(",5\n")  # the file's line 604
        logs = [str(extra), str(signal)] if name == "pose" else [str(pose), str(extra)]
        calls = [lambda: read_logs(logs), lambda: sync_logs(logs[:1], logs[1:], str(tmp_path / "o.parquet"))]
        if name == "signal":
            calls.append(lambda: list(iter_signal_table(str(extra), chunk_rows=97)))
        for call in calls:
            assert re.search(r"Expected \d+ fields in line 604, saw", _message(call))
        report = inspect_logs(logs)
        assert any("fields in line 604, saw" in line for line in report.problems)
    quote = _header_again(_edited(signal, tmp_path / "q.csv", 601, _field(2, '"A')), tmp_path / "quote.csv", 300)
    assert "EOF inside string starting at line 603" in _message(lambda: read_signal_table(str(quote)))


def test_the_scan_numbers_the_header_lines_it_drops_as_the_file_does(flight, tmp_path, monkeypatch):
    """The lines the parser's are turned into (HeaderScan.lines): right in blocks of any size, CRLF line ends too."""
    from rplearn.io import _csv_headers

    _, signal = flight
    crlf = tmp_path / "crlf.csv"
    crlf.write_bytes(signal.read_bytes().replace(b"\n", b"\r\n"))
    header = _lines(crlf)[0]
    path = _with_lines(crlf, tmp_path / "again.csv", {101: header, 102: header, 250: header})
    expected = (102, 104, 253)  # each header pushes the ones after it a line further
    assert [_lines(path)[k - 1] for k in expected] == [header] * 3
    assert _csv_headers.scan_csv_headers(str(path), "s").lines == expected
    monkeypatch.setattr(_csv_headers, "SCAN_BYTES", 100)
    scan = _csv_headers.scan_csv_headers(str(path), "s")
    assert scan.lines == expected
    assert [scan.file_line(k) for k in (1, 101, 102, 250, 251)] == [1, 101, 103, 252, 254]


def test_many_repeated_headers_are_counted_and_the_first_few_named(flight, tmp_path):
    """Review 51: where the header lines were (was the count alone); the first :data:`NAMED_LINES` named whatever
    the count, so that the report and the memory stay bounded."""
    from rplearn.io._csv_headers import NAMED_LINES

    pose, signal = flight
    at = list(range(100, 1100, 100))  # 10 headers: file lines 101, 202, 303, ...
    s = _header_again(signal, tmp_path / "signal.csv", *at)
    first = [k + 1 + i for i, k in enumerate(at)][:NAMED_LINES]
    assert [_lines(s)[n - 1] for n in first] == [_lines(signal)[0]] * NAMED_LINES
    out = sync_logs([str(pose)], [str(s)], str(tmp_path / "d.parquet"))
    said = f"{s}: dropped 10 header line(s) repeated mid-file (repeated_header: lines 101, 202, 303 and 7 more)"
    assert said in out.notes
    _, meta = read_signal_table(str(s), tx_power_dbm=20.0, frequency_hz=2.4e9)
    assert meta["dropped"] == {"repeated_header": 10} and meta["repeated_header_lines"] == first
    chunks = list(iter_signal_table(str(s), 500, tx_power_dbm=20.0, frequency_hz=2.4e9))
    assert all(c.attrs["repeated_header_lines"] == first for c in chunks)
    report = inspect_logs([str(s)])
    assert inspect_to_dict(report)["files"][0]["repeated_header_lines"] == first
    assert f"dropped on reading: {said.split('dropped ', 1)[1]}" in report.to_text()
