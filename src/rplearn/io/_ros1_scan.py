"""A ROS 1 bag without a readable index (cut off, or never closed), read record by record.

ROS bag format 2.0 (wiki.ros.org/Bags/Format/2.0): after the ``#ROSBAG V2.0`` line and the
bag header record come, in file order, chunk records (``op=5``: a header with the
``compression`` and the uncompressed ``size``, then the chunk data: connection records,
``op=7``, and message data records, ``op=2``, each a ``uint32``-length-prefixed header and a
``uint32``-length-prefixed data field) each followed by its index data records (``op=4``),
and at ``index_pos`` the connection and chunk info records (``op=6``). A bag cut off (an
interrupted copy, a disk filled up) lacks that index; a bag whose recorder never closed it
has ``index_pos = 0``. Both are read here from the start, chunk by chunk, the way
``rosbag reindex`` rebuilds the index: every message whose record is whole is read, and
where the reading stopped is said (:class:`Ros1Scan`).

``rosbags`` is imported only inside the functions (``io`` reads its format libraries
lazily).
"""

from __future__ import annotations

import io
import mmap
import os
import struct
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, BinaryIO

OP_MSGDATA, _OP_BAGHEADER, _OP_IDXDATA, _OP_CHUNK, _OP_CHUNK_INFO, OP_CONNECTION = 2, 3, 4, 5, 6, 7


@dataclass
class Ros1Scan:
    """What a record-by-record reading of a ROS 1 bag found.

    Attributes
    ----------
    messages_read : int
        Message records read whole (every connection).
    cut_off_at_byte : int or None
        The file offset of the first record not read whole: where the file ends inside a
        record, or where an unreadable record starts; the file's size when it ends between
        records but before the index it promises; None when nothing was lost.
    cut_off_record : str or None
        What is lost there, in words (``"chunk 3 (bz2), after its 0 whole message(s)"``).
    index_pos : int
        Where the bag header says the index starts (0: never written, the recorder did not
        close the bag).
    damaged_chunks : list of dict
        Whole chunk records that cannot be read (a flipped byte: their data do not decompress,
        or a record in them does not parse), skipped to read the chunks after them: ``chunk``
        (number from 1), ``at_byte``, ``compression``, ``what``, ``lost_messages`` (None: not
        known without the index).
    index_error : str or None
        Why the bag's index could not be read, when it was read record by record for that
        reason (a damaged index; None otherwise).
    """

    messages_read: int = 0
    index_pos: int = 0
    cut_off_at_byte: int | None = None
    cut_off_record: str | None = None
    chunks: dict[int, Any] = field(default_factory=dict)
    chunk_infos: list[Any] = field(default_factory=list)
    connections: dict[int, Any] = field(default_factory=dict)
    indexes: dict[int, list[Any]] = field(default_factory=dict)
    damaged_chunks: list[dict[str, Any]] = field(default_factory=list)
    index_error: str | None = None


def _fields(buf: bytes, start: int, end: int) -> dict[str, bytes] | None:
    """The ``name=value`` fields of ``buf[start:end]``, each ``uint32``-length-prefixed;
    None when they do not parse."""
    fields: dict[str, bytes] = {}
    pos = start
    while pos < end:
        if pos + 4 > end:
            return None
        (n,) = struct.unpack_from("<I", buf, pos)
        name, sep, value = buf[pos + 4:pos + 4 + n].partition(b"=")
        if not sep or pos + 4 + n > end:
            return None
        fields[name.decode("latin-1")] = value
        pos += 4 + n
    return fields


def _header(buf: bytes, at: int) -> tuple[dict[str, bytes], int, int] | None:
    """The header of the record starting at ``at`` of ``buf``: ``(fields, data start, data
    length)``; None when the header runs past the end of ``buf`` or does not parse (its data
    may run past the end)."""
    if at + 4 > len(buf):
        return None
    (hlen,) = struct.unpack_from("<I", buf, at)
    hend = at + 4 + hlen
    if hend + 4 > len(buf):
        return None
    fields = _fields(buf, at + 4, hend)
    if fields is None or len(fields.get("op", b"")) != 1:
        return None
    return fields, hend + 4, struct.unpack_from("<I", buf, hend)[0]


def bag_record(buf: bytes, at: int) -> tuple[dict[str, bytes], int, int] | None:
    """The whole record starting at ``at``: ``(header fields, data start, data end)``; None
    when it runs past the end of ``buf`` or its header does not parse."""
    head = _header(buf, at)
    if head is None or head[1] + head[2] > len(buf):
        return None
    return head[0], head[1], head[1] + head[2]


def _partial_decompressor(compression: str) -> Any:
    """A function decompressing as much of a cut chunk's data as its whole blocks give."""
    if compression == "bz2":
        import bz2

        def bz2_part(data: bytes) -> bytes:
            try:
                return bz2.BZ2Decompressor().decompress(data)
            except (OSError, EOFError, ValueError):
                return b""
        return bz2_part
    if compression == "lz4":
        from lz4.frame import LZ4FrameDecompressor  # type: ignore[import-untyped]

        def lz4_part(data: bytes) -> bytes:
            try:
                return bytes(LZ4FrameDecompressor().decompress(data))
            except RuntimeError:
                return b""
        return lz4_part
    return lambda data: data


def _connection(fields: dict[str, bytes], data: bytes, owner: Any) -> Any:
    """A rosbags :class:`Connection` of a connection record (``data``: its second header)."""
    from rosbags.interfaces import Connection, ConnectionExtRosbag1, MessageDefinition, MessageDefinitionFormat
    from rosbags.rosbag1.reader import normalize
    from rosbags.typesys.msg import normalize_msgtype

    info = _fields(data, 0, len(data))
    if info is None:
        raise ValueError("connection record's second header does not parse")
    latching = info.get("latching", b"").decode()
    return Connection(
        struct.unpack("<I", fields["conn"])[0], normalize(fields["topic"].decode()),
        normalize_msgtype(info["type"].decode()),
        MessageDefinition(MessageDefinitionFormat.MSG, info.get("message_definition", b"").decode()),
        info.get("md5sum", b"").decode(), 0,
        ConnectionExtRosbag1(info["callerid"].decode() if "callerid" in info else None,
                             int(latching) if latching else None),
        owner)


def _chunk_records(scan: Ros1Scan, raw: bytes, chunk_pos: int, owner: Any) -> tuple[int, int]:
    """Index the whole records of one chunk's (maybe partial) data ``raw``: ``(messages
    indexed, offset in ``raw`` where the whole records end)``."""
    from rosbags.rosbag1.reader import IndexData

    at, found = 0, 0
    times: list[int] = []
    counts: dict[int, int] = {}
    while at < len(raw):
        rec = bag_record(raw, at)
        if rec is None:
            break
        fields, dstart, dend = rec
        op = fields["op"][0]
        if op == OP_CONNECTION:
            try:
                conn = _connection(fields, raw[dstart:dend], owner)
            except (KeyError, ValueError, struct.error, UnicodeDecodeError):
                break
            scan.connections.setdefault(conn.id, conn)
        elif op == OP_MSGDATA:
            try:
                conn_id = struct.unpack("<I", fields["conn"])[0]
                sec, nsec = struct.unpack("<II", fields["time"])
            except (KeyError, struct.error):
                break
            if conn_id not in scan.connections:
                break
            t_ns = sec * 10**9 + nsec
            scan.indexes.setdefault(conn_id, []).append(IndexData(t_ns, chunk_pos, at))
            times.append(t_ns)
            counts[conn_id] = counts.get(conn_id, 0) + 1
            found += 1
        at = dend
    if found:
        from rosbags.rosbag1.reader import ChunkInfo

        scan.chunk_infos.append(ChunkInfo(chunk_pos, min(times), max(times) + 1, counts))
    return found, at


_KNOWN_OPS = (_OP_CHUNK, _OP_IDXDATA, OP_CONNECTION, _OP_CHUNK_INFO, _OP_BAGHEADER)


def _stop(scan: Ros1Scan, at: int, what: str) -> Ros1Scan:
    scan.cut_off_at_byte, scan.cut_off_record = int(at), what
    return scan


def scan_ros1(bio: BinaryIO, owner: Any) -> Ros1Scan:
    """Read a ROS 1 bag's records from the start, building the connections, chunks and
    per-connection index of :class:`rosbags.rosbag1.Reader` (``owner``) for every message
    read whole, and saying where the reading stopped."""
    bio.seek(0)
    try:  # mapped, not read: a bag may be larger than the memory
        buf: Any = mmap.mmap(bio.fileno(), 0, access=mmap.ACCESS_READ)
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):  # empty, or not a file
        buf = bio.read()
    try:
        return _scan_buffer(buf, owner)
    finally:
        if isinstance(buf, mmap.mmap):
            buf.close()


def _scan_buffer(buf: Any, owner: Any) -> Ros1Scan:
    """:func:`scan_ros1` of the bag's bytes ``buf`` (bytes or a read-only map)."""
    from rosbags.rosbag1.reader import Chunk, decompressors

    scan = Ros1Scan()
    line = buf.find(b"\n") + 1
    head = bag_record(buf, line)
    if head is None:
        return _stop(scan, line, "the bag header record")
    index_pos = struct.unpack("<Q", head[0]["index_pos"])[0] if len(head[0].get("index_pos", b"")) == 8 else 0
    scan.index_pos = index_pos
    at, number = head[2], 0
    while at < len(buf):
        found = _header(buf, at)
        if found is None:
            return _stop(scan, at, f"the header of the record after chunk {number}" if number
                         else "the header of the first record after the bag header")
        fields, dstart, dlen = found
        op, dend = fields["op"][0], dstart + dlen
        if op == OP_MSGDATA:
            return _stop(scan, at, f"message records outside any chunk after chunk {number} (a chunk its "
                                   "recorder never closed)")
        if op not in _KNOWN_OPS:
            return _stop(scan, at, f"a record of no bag kind (op {op}) after chunk {number}: damaged")
        if op == _OP_CHUNK:
            number += 1
            compression = fields.get("compression", b"none").decode("latin-1")
            if compression not in decompressors:
                return _stop(scan, at, f"chunk {number}: unknown compression {compression!r}")
            whole = dend <= len(buf)
            unpack = decompressors[compression] if whole else _partial_decompressor(compression)
            data = buf[dstart:min(dend, len(buf))]
            try:
                raw = unpack(data)
            except Exception:  # the decompressor's own error: a damaged chunk
                if not whole:
                    return _stop(scan, at, f"chunk {number} ({compression}): its data do not decompress: damaged")
                scan.damaged_chunks.append({"chunk": number, "at_byte": int(at), "compression": compression,
                                            "what": "its data do not decompress", "lost_messages": None})
                at = dend  # the chunk record is whole: the records after it are read
                continue
            scan.chunks[at] = Chunk(len(data), dstart, unpack)
            n, whole_to = _chunk_records(scan, raw, at, owner)
            scan.messages_read += n
            if not whole:
                lost_at = dstart + whole_to if compression == "none" else at
                return _stop(scan, lost_at, f"chunk {number} ({compression}), after its {n:,} whole message(s)")
            if whole_to < len(raw):
                scan.damaged_chunks.append({"chunk": number, "at_byte": int(at), "compression": compression,
                                            "what": f"a damaged record after its {n:,} message(s)",
                                            "lost_messages": None})
        elif dend > len(buf):
            what = "the index data" if op == _OP_IDXDATA else "the bag's index"
            return _stop(scan, at, f"{what} after chunk {number}")
        elif op == OP_CONNECTION:
            try:
                conn = _connection(fields, buf[dstart:dend], owner)
            except (KeyError, ValueError, struct.error, UnicodeDecodeError):
                return _stop(scan, at, "a connection record of the bag's index: damaged")
            scan.connections.setdefault(conn.id, conn)
        at = dend
    if index_pos > len(buf):
        return _stop(scan, len(buf), f"the end of the file after chunk {number}, before the bag's index at "
                                     f"byte {index_pos:,}")
    return scan


@lru_cache(maxsize=1)
def scanning_reader_class() -> type:
    """A :class:`rosbags.rosbag1.Reader` that opens a bag by :func:`scan_ros1` instead of
    its index (``.scan`` holds what the reading found)."""
    from rosbags.rosbag1 import Reader

    class ScanningReader(Reader):
        scan: Ros1Scan

        def open(self) -> None:
            self.bio = self.path.open("rb")
            try:
                self.scan = scan_ros1(self.bio, self)
            except BaseException:
                self.bio.close()
                self.bio = None
                raise
            self.chunks = dict(self.scan.chunks)
            self.chunk_infos = list(self.scan.chunk_infos)
            ids = sorted(self.scan.connections)
            self.indexes = {i: sorted(self.scan.indexes.get(i, [])) for i in ids}
            self.connections = [self.scan.connections[i]._replace(msgcount=len(self.indexes[i])) for i in ids]

    return ScanningReader


def ros1_trailing_bytes(path: str | os.PathLike) -> tuple[int, bool]:
    """Bytes after the index of a whole ROS 1 bag (its ``conn_count`` connection and
    ``chunk_count`` chunk info records from ``index_pos``), which no reader reads: junk
    appended, or another bag (the second item: they begin with a bag's ``#ROSBAG`` line).
    ``(0, False)`` when the index cannot be walked (a cut or unindexed bag is read by
    :func:`scan_ros1` instead)."""
    with open(path, "rb") as fh:
        head = fh.read(4096 + 64)
        line = head.find(b"\n") + 1
        rec = bag_record(head, line)
        if rec is None:
            return 0, False
        fields = rec[0]
        try:
            index_pos = struct.unpack("<Q", fields["index_pos"])[0]
            count = struct.unpack("<I", fields["conn_count"])[0] + struct.unpack("<I", fields["chunk_count"])[0]
        except (KeyError, struct.error):
            return 0, False
        fh.seek(0, 2)
        size = fh.tell()
        if not 0 < index_pos < size:
            return 0, False
        at = index_pos
        for _ in range(count):  # each record's header read, its data skipped: what follows may be large
            fh.seek(at)
            length = fh.read(4)
            if len(length) < 4:
                return 0, False
            head = length + fh.read(struct.unpack("<I", length)[0] + 4)
            found = _header(head, 0)
            if found is None or found[1] + found[2] > size - at:
                return 0, False
            at += found[1] + found[2]
        fh.seek(at)
        return size - at, fh.read(7).startswith(b"#ROSBAG")
