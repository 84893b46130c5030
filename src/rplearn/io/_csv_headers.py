"""Header lines inside a CSV log: a logger restarted appending to its file, or two files joined with ``cat``, write
the header again mid-file. A line that repeats the file's own header (the same column names in the same order; its
line end, a UTF-8 byte-order mark and the spaces and quotes about a name aside) is dropped and counted
(``repeated_header``), the rows after it read; another header-like line (its first field a column name, none of its
fields a number: a logger restarted with other columns) is refused naming the file and the line. Shared by the
whole-file readers (:mod:`rplearn.io.tables`) and the tail of a CSV being appended to
(:class:`rplearn.io.live_sources.CsvTail`).

Rows and lines: a message naming a *row* of a CSV table counts its data rows from 0 at the first data row, the
header line and the header lines repeated mid-file not counted (a row has the number it has in the file without
them, and in the same table written as Parquet); a message naming a *line* gives the file's own line, counted from 1
with every line (the header and the repeated ones too), as a text editor numbers it. The parser's complaints name
file lines too: :func:`in_file_lines` turns the lines of what it read (the file without the lines dropped) into the
file's (:func:`file_line`).

Finding them is one regular-expression search for a line that begins with a column name (C speed, no Python loop
over the lines); only the lines it finds are looked at. A file is scanned in blocks of :data:`SCAN_BYTES`, so its
memory stays bounded, and read back without the lines dropped through :class:`SkippingReader`.
"""

from __future__ import annotations

import io
import os
import re
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, BinaryIO

from rplearn.data.tables import POSE_COLUMNS, SIGNAL_COLUMNS
from rplearn.errors import LogFormatError
from rplearn.io._columns import COLUMN_ALIASES, EULER_ENU_FLU_COLUMNS, EULER_NED_FRD_COLUMNS, GEODETIC_COLUMNS

#: The drop reason of a header line repeated mid-file.
REPEATED_HEADER = "repeated_header"
#: What the lines dropped as :data:`REPEATED_HEADER` are called when their count is said.
REPEATED_HEADER_LINES = "header line(s) repeated mid-file"
#: The metadata key (and ``DataFrame.attrs`` key) of the file lines of the first header lines dropped as
#: :data:`REPEATED_HEADER` (:data:`NAMED_LINES` at most; the count says them all).
REPEATED_HEADER_AT = "repeated_header_lines"
#: How many of the header lines repeated mid-file a report names (the first ones: memory bounded however many).
NAMED_LINES = 3
#: Bytes of a file scanned at a time.
SCAN_BYTES = 1 << 24
#: Column names a header-like line may begin with besides the file's own: the canonical ones and their aliases.
KNOWN_NAMES: frozenset[str] = frozenset(
    (*POSE_COLUMNS, *SIGNAL_COLUMNS, *GEODETIC_COLUMNS, *EULER_ENU_FLU_COLUMNS, *EULER_NED_FRD_COLUMNS, "unit", "outage",
     "armed", *COLUMN_ALIASES, *COLUMN_ALIASES.values()))
_BOM = b"\xef\xbb\xbf"


def _field(cell: bytes) -> bytes:
    """A CSV cell without the spaces and quotes around it."""
    return cell.strip().strip(b'"').strip()


def _is_number(cell: bytes) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _is_text(line: bytes) -> bool:
    """Whether a file's first line is text (UTF-8 without NUL bytes), as a CSV header is."""
    try:
        line.decode()
    except UnicodeDecodeError:
        return False
    return b"\0" not in line


def bare_header(line: bytes) -> bytes:
    """A header line without its line end and byte-order mark: what a repeated header is compared by."""
    return line.rstrip(b"\r\n").removeprefix(_BOM)


@dataclass(frozen=True)
class HeaderRule:
    """How the lines of one file are told apart: ``header`` (:func:`bare_header` of its first line), the search for
    a line that begins with a column name (the file's own or :data:`KNOWN_NAMES`) and the header's names."""

    header: bytes
    pattern: re.Pattern[bytes]
    #: The header's column names (spaces and quotes about them aside): a line of the same names repeats it.
    fields: tuple[bytes, ...]

    @classmethod
    def of(cls, first_line: bytes) -> HeaderRule:
        header = bare_header(first_line)
        fields = tuple(_field(c) for c in header.split(b","))
        names = set(fields) | {n.encode() for n in KNOWN_NAMES}
        names.discard(b"")
        alternatives = b"|".join(re.escape(n) for n in sorted(names, key=len, reverse=True))
        starts = re.escape(bytes(sorted({n[0] for n in names} | {_BOM[0], ord(" "), ord("\t"), ord('"')})))
        # the look-ahead turns a line away at its first byte (a number, most lines) before the names are tried
        return cls(header, re.compile(rb"\n(?=[" + starts + rb"])(?:" + _BOM + rb')?[ \t]*"?(?:' + alternatives
                                      + rb')"?[ \t]*(?=[,\r\n]|\Z)'), fields)

    def lines(self, region: bytes) -> Iterator[tuple[int, int, bool]]:
        """The header-like lines of ``region`` (complete lines, each after a newline: it begins with one):
        ``(start, end, repeated)``, ``start`` the index of the line's first byte, ``end`` that of its newline (or
        the region's end), ``repeated`` whether it repeats the header."""
        for m in self.pattern.finditer(region):
            start = m.start() + 1
            end = region.find(b"\n", start)
            end = len(region) if end < 0 else end
            fields = tuple(_field(c) for c in bare_header(region[start:end]).split(b","))
            if fields == self.fields:
                yield start, end, True
            elif not any(_is_number(c) for c in fields):
                yield start, end, False

    def refusal(self, source: str, line_number: int, line: bytes, advice: str) -> LogFormatError:
        """The one-line error of another header at ``line_number`` (1-based) of ``source``."""
        text = bare_header(line).decode(errors="replace")[:80]
        return LogFormatError(f"{source}: line {line_number}: another header in the file ({text!r}; the first: "
                              f"{self.header.decode(errors='replace')[:80]!r}): a logger restarted with other "
                              f"columns; {advice}")


def without_repeated_headers(data: bytes, rule: HeaderRule, first_line: int, source: str,
                             advice: str) -> tuple[bytes, tuple[int, ...]]:
    """``data`` (complete lines, the first numbered ``first_line``, from a line start) without the lines that repeat
    the header, and their line numbers (in file order); another header-like line is refused
    (:meth:`HeaderRule.refusal`)."""
    region = b"\n" + data
    kept, at, dropped = [], 1, []
    line, counted = first_line, 1  # the number of the line that begins after `counted`
    for start, end, repeated in rule.lines(region):
        line, counted = line + region.count(b"\n", counted, start), start
        if not repeated:
            raise rule.refusal(source, line, region[start:end], advice)
        kept.append(region[at:start])
        at = end + 1
        dropped.append(line)
    if not dropped:
        return data, ()
    kept.append(region[at:])
    return b"".join(kept), tuple(dropped)


def file_line(line: int, dropped: Sequence[int], first_line: int = 1) -> int:
    """The file line of line ``line`` (from 1) of what was read of a file from its line ``first_line`` on, without
    its lines ``dropped`` (file lines, sorted)."""
    out = first_line + line - 1
    for d in dropped:
        if d > out:
            break
        out += 1
    return out


#: A line a parser's complaint names: ``line N`` (from 1), ``starting at row N`` (pandas' quoted field left open;
#: its row is the line from 0).
_PARSER_LINE = re.compile(r"\b(line|starting at row) (\d+)\b")


def in_file_lines(text: str, to_file: Callable[[int], int]) -> str:
    """A parser's complaint ``text`` about what it read with the lines it names as the file's lines (``to_file``: a
    line of what was read, from 1, to the file's line), each said as ``line N``."""
    def line(m: re.Match[str]) -> str:
        n = int(m[2]) + (m[1] != "line")
        return f"{'line' if m[1] == 'line' else 'starting at line'} {to_file(n)}"

    return _PARSER_LINE.sub(line, text)


@dataclass(frozen=True)
class HeaderScan:
    """What :func:`scan_csv_headers` found in a file: the byte ranges ``[start, end)`` of the lines repeating its
    header (with their line ends), in file order, and their line numbers (from 1)."""

    spans: tuple[tuple[int, int], ...] = ()
    lines: tuple[int, ...] = ()

    def file_line(self, line: int) -> int:
        """The file line of line ``line`` (from 1) of the file read without the lines repeating its header."""
        return file_line(line, self.lines)

    @property
    def repeated(self) -> int:
        """Lines repeating the header (dropped)."""
        return len(self.spans)


def lines_text(first: Sequence[int], count: int) -> str:
    """The file lines ``first`` (the first of ``count`` lines) as said: ``line 604``, ``lines 604, 1210``,
    ``lines 602, 1203, 1804 and 2 more`` ('' without any)."""
    if not first:
        return ""
    more = f" and {count - len(first):,} more" if count > len(first) else ""
    return f"line{'s' if count > 1 else ''} {', '.join(str(n) for n in first)}{more}"


def repeated_header_text(count: int, first: Sequence[int] = ()) -> str:
    """A count of header lines repeated mid-file, dropped, with where the first were:
    ``2 header line(s) repeated mid-file (repeated_header: lines 604, 1210)``."""
    where = lines_text(first, count)
    return f"{count:,} {REPEATED_HEADER_LINES} ({REPEATED_HEADER}{': ' + where if where else ''})"


@dataclass
class HeaderDrops:
    """The header lines repeated mid-file that a file read in parts dropped so far: how many, and the file lines of
    the first :data:`NAMED_LINES`."""

    count: int = 0
    first: tuple[int, ...] = ()

    def add(self, lines: Sequence[int]) -> None:
        """Count the header lines dropped at file lines ``lines`` (in file order)."""
        self.count += len(lines)
        self.first += tuple(lines[:max(NAMED_LINES - len(self.first), 0)])

    def where(self, source: str) -> str:
        """``source lines 604, 1210`` ('' without any)."""
        return f"{source} {lines_text(self.first, self.count)}" if self.count else ""


#: Why a file with another header mid-file is refused, and what to do (the whole-file readers).
FILE_ADVICE = "split the file there and give each part as a log of its own"


def scan_csv_headers(path: str, source: str, advice: str = FILE_ADVICE) -> HeaderScan:
    """The lines of a CSV file that repeat its header; another header-like line is refused naming ``source`` and
    the line. Reads the file in blocks of :data:`SCAN_BYTES`."""
    spans: list[tuple[int, int]] = []
    lines: list[int] = []
    with open(path, "rb") as fh:
        first = fh.readline(SCAN_BYTES)
        if not first.endswith(b"\n") or not _is_text(first):  # one line, or no text: the parser says what it is
            return HeaderScan()
        rule = HeaderRule.of(first)
        carry, base, line = b"\n", len(first) - 1, 2  # a region begins with the newline before line `line`, at `base`
        while True:
            block = fh.read(SCAN_BYTES)
            region = carry + block
            cut = region.rfind(b"\n") if block else len(region)  # complete lines only, but at the file's end
            if cut == 0:  # no line end in the block: the line goes on
                carry = region
                continue
            body = region[:cut]
            at, counted = line - 1, 0  # line `at` begins after byte `counted` of the body
            for start, end, repeated in rule.lines(body):
                at, counted = at + body.count(b"\n", counted, start), start
                if not repeated:
                    raise rule.refusal(source, at, body[start:end], advice)
                spans.append((base + start, base + min(end + 1, len(region))))  # with its line end
                lines.append(at)
            if not block:
                break
            line += body.count(b"\n")
            base += cut
            carry = region[cut:]
    return HeaderScan(tuple(spans), tuple(lines))


class SkippingReader(io.RawIOBase):
    """A binary file read without the byte ranges ``spans`` (sorted, disjoint ``(start, end)``)."""

    def __init__(self, fh: io.BufferedReader, spans: Iterable[tuple[int, int]]) -> None:
        super().__init__()
        self._fh, self._spans, self._at = fh, deque(spans), 0

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        while self._spans and self._at >= self._spans[0][0]:
            self._at = max(self._at, self._spans.popleft()[1])
            self._fh.seek(self._at)
        view = memoryview(buffer).cast("B")
        limit = len(view) if not self._spans else min(len(view), self._spans[0][0] - self._at)
        n = self._fh.readinto(view[:limit]) or 0
        self._at += n
        return n

    def close(self) -> None:
        self._fh.close()
        super().close()


@contextmanager
def csv_source(path: str, scan: HeaderScan) -> Iterator[str | BinaryIO]:
    """What :func:`pandas.read_csv` reads for a scanned file: its path, or, with header lines to drop, the file
    without them (a buffered :class:`SkippingReader`, closed on leaving)."""
    if not scan.spans:
        yield path
        return
    with io.BufferedReader(SkippingReader(open(path, "rb"), scan.spans), buffer_size=1 << 20) as reader:  # noqa: SIM115
        yield reader


def is_csv_file(path: str | os.PathLike[str]) -> bool:
    """Whether a table file is read as CSV (not Parquet, by its extension)."""
    return not str(path).lower().endswith((".parquet", ".pq"))


__all__ = ["FILE_ADVICE", "KNOWN_NAMES", "NAMED_LINES", "REPEATED_HEADER", "REPEATED_HEADER_AT", "REPEATED_HEADER_LINES", "SCAN_BYTES",
           "HeaderDrops", "HeaderRule", "HeaderScan", "SkippingReader", "bare_header", "csv_source", "file_line", "in_file_lines",
           "is_csv_file", "lines_text", "repeated_header_text", "scan_csv_headers", "without_repeated_headers"]
