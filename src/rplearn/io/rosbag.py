"""ROS 2 bags (sqlite3, MCAP) and ROS 1 bags -> pose and signal logs, through ``rosbags``.

No ROS installation is needed: :class:`rosbags.highlevel.AnyReader` reads both generations
and the message definitions embedded in the bag. Types a bag does not describe (custom RSSI
messages of an older ROS 2 bag, say) are registered from their ``.msg`` definitions with
``msg_definitions={"pkg/msg/Type": "path/to/Type.msg" or definition text}``, the way rosbags
documents (``get_types_from_msg`` + ``Typestore.register``); bags without any embedded
definition are read with the ROS 2 Jazzy typestore (the paper's drones ran Jazzy), or ROS 1
Noetic for ``.bag`` files.

Poses come from ``nav_msgs/Odometry``, ``geometry_msgs/PoseStamped`` or
``geometry_msgs/PoseWithCovarianceStamped``, one topic per node (``pose_topics={topic: node}``).
ROS uses REP-103 frames already (world ENU, body FLU): values are taken as they are.

RSSI comes from topics the user names (``rssi_topics={topic: (tx, rx)}``) and a field path
in the message (``rssi_field="rssi"``, dots for nested fields, e.g. ``"link.rssi_dbm"``).

Times are the message header stamps (``time_source="header"``; the bag's receive time for
messages without a header or with a zero stamp) or the bag's receive times
(``time_source="bag"``), in seconds of ROS time (UNIX epoch on a real robot).

A ROS 1 bag cut off before its index (an interrupted copy), or whose recorder never wrote
it, is read record by record from the start the way ``rosbag reindex`` rebuilds an index:
every message before the cut is read, and the cut is said (``cut_off_at_byte``,
``records_read``; :func:`rplearn.io.damage.file_damage`).

A message equal to an earlier one of its topic in receive time and every byte (a recorder
writing each message twice) is read once and counted (``metadata["repeated_messages"]``).
"""

from __future__ import annotations

import hashlib
import io
import math
import os
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.data.tables import validate_pose_log
from rplearn.errors import InputError, LogFormatError
from rplearn.io._common import Logs

POSE_MSGTYPES: tuple[str, ...] = (
    "nav_msgs/msg/Odometry",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
)


def _rosbags() -> Any:
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    except ImportError:  # pragma: no cover - rosbags is a dependency
        raise InputError("reading ROS bags needs the 'rosbags' package (pip install rosbags)") from None
    return AnyReader, Stores, get_types_from_msg, get_typestore


def _bag_paths(path: str | os.PathLike) -> list[Path]:
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file or directory")
    if p.is_dir():
        return [p]
    if p.suffix == ".bag":
        return [p]
    if p.suffix in (".db3", ".mcap"):
        # a ROS 2 bag is a directory with metadata.yaml; rosbags also opens a lone storage file
        return [p.parent] if (p.parent / "metadata.yaml").exists() else [p]
    raise InputError(f"{p}: not a ROS bag (expected a .bag file or a ROS 2 bag directory)")


def _load_definitions(msg_definitions: Mapping[str, str] | None) -> dict[str, Any]:
    _, _, get_types_from_msg, _ = _rosbags()
    types: dict[str, Any] = {}
    for name, text_or_path in (msg_definitions or {}).items():
        text = str(text_or_path)
        if os.path.exists(text):
            with open(text, encoding="utf-8") as fh:
                text = fh.read()
        elif text.endswith(".msg") and "\n" not in text:
            raise InputError(
                f"message definition of {name} (msg_definitions): {text}: no such file",
                param="msg_definitions",
            )
        try:
            types.update(get_types_from_msg(text, name))
        except Exception as exc:
            raise InputError(
                f"message definition of {name} (msg_definitions): cannot parse it ({exc})",
                param="msg_definitions",
            ) from None
    return types


def _field(msg: Any, dotted: str, where: str) -> Any:
    value = msg
    for part in dotted.split("."):
        try:
            value = getattr(value, part)
        except AttributeError:
            raise InputError(
                f"{where}: field {dotted!r} not found (no {part!r} in {type(value).__name__})"
            ) from None
    return value


def _float_field(msg: Any, dotted: str, where: str) -> float:
    value = _field(msg, dotted, where)
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError(
            f"{where}: field {dotted!r} is {type(value).__name__}, expected a number"
        ) from None


def _stamp_s(msg: Any, bag_ns: int, time_source: str) -> float:
    if time_source == "header":
        header = getattr(msg, "header", None)
        stamp = getattr(header, "stamp", None)
        if stamp is not None:
            sec = getattr(stamp, "sec", None)
            nsec = getattr(stamp, "nanosec", None)
            if sec is not None and nsec is not None and (sec or nsec):
                return float(sec) + float(nsec) * 1e-9
    return bag_ns * 1e-9


def _pose_of(msg: Any, msgtype: str) -> Any:
    if msgtype.endswith("Odometry") or msgtype.endswith("PoseWithCovarianceStamped"):
        return msg.pose.pose
    return msg.pose


_ROS1_MAGIC = b"#ROSBAG V2.0\n"


def ros1_index_pos(path: str | os.PathLike) -> int | None:
    """Where a ROS 1 bag says its index starts (the ``index_pos`` field of its bag header
    record, ROS bag format 2.0: ``uint32`` header length, then ``uint32``-length-prefixed
    ``name=value`` fields); None when the file does not begin with such a header."""
    with open(path, "rb") as fh:
        head = fh.read(len(_ROS1_MAGIC) + 4 + 4096)
    if not head.startswith(_ROS1_MAGIC) or len(head) < len(_ROS1_MAGIC) + 4:
        return None
    at = len(_ROS1_MAGIC)
    end = min(at + 4 + int.from_bytes(head[at:at + 4], "little"), len(head))
    pos = at + 4
    while pos + 4 <= end:
        n = int.from_bytes(head[pos:pos + 4], "little")
        name, _, value = head[pos + 4:pos + 4 + n].partition(b"=")
        if name == b"index_pos" and len(value) == 8:
            return int.from_bytes(value, "little")
        pos += 4 + n
    return None


def _open_reader(any_reader: Any, paths: list[Path], default: Any, scan: bool) -> Any:
    """An open AnyReader of ``paths``; with ``scan``, the ROS 1 bag read record by record
    (:mod:`rplearn.io._ros1_scan`) instead of through its index."""
    reader = any_reader(paths, default_typestore=default)
    if scan:
        from rplearn.io._ros1_scan import scanning_reader_class

        reader.readers = [scanning_reader_class()(p) for p in paths]
    reader.open()
    return reader


def bag_scan(reader: Any) -> Any:
    """What the record-by-record reading of an open bag found (a
    :class:`rplearn.io._ros1_scan.Ros1Scan`), or None when it was read through its index."""
    readers = getattr(reader, "readers", None) or [None]
    return getattr(readers[0], "scan", None)


@contextmanager
def open_rosbag(
    path: str | os.PathLike, msg_definitions: Mapping[str, str] | None = None
) -> Iterator[Any]:
    """Open a ROS 1 or ROS 2 bag as a :class:`rosbags.highlevel.AnyReader`, custom types registered.

    Errors of rosbags (missing metadata, corrupt or truncated files, unknown types) become
    :class:`LogFormatError` naming the bag.
    """
    AnyReader, Stores, _, get_typestore = _rosbags()
    paths = _bag_paths(path)
    is_ros1 = paths[0].suffix == ".bag"
    default = get_typestore(Stores.ROS1_NOETIC if is_ros1 else Stores.ROS2_JAZZY)
    extra = _load_definitions(msg_definitions)
    if extra:
        try:
            default.register(extra)
        except Exception as exc:
            raise InputError(
                f"message definitions (msg_definitions): cannot register types ({type(exc).__name__}: {exc})",
                param="msg_definitions",
            ) from None
    index_at = ros1_index_pos(paths[0]) if is_ros1 else None
    size = paths[0].stat().st_size
    scan = is_ros1 and index_at is not None and (index_at == 0 or index_at >= size)
    try:
        reader = _open_reader(AnyReader, paths, default, scan)
    except (InputError, LogFormatError):
        raise
    except Exception as exc:
        msg = str(exc).splitlines()[0] if str(exc) else ""
        if index_at is None:
            raise LogFormatError(f"{path}: cannot open bag ({type(exc).__name__}: {msg})") from None
        try:  # a damaged index, or a chunk header it points to: read record by record as `rosbag reindex` does
            reader = _open_reader(AnyReader, paths, default, True)
            bag_scan(reader).index_error = f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__
        except Exception as exc2:
            raise LogFormatError(
                f"{path}: the bag's index (from byte {index_at:,} of {size:,}) cannot be read ({msg}), nor its "
                f"records from the start ({type(exc2).__name__}: {str(exc2).splitlines()[0] if str(exc2) else ''}); "
                "`rosbag reindex` rebuilds it") from None
    found = bag_scan(reader)
    if found is not None and found.messages_read == 0 and (found.cut_off_at_byte is not None or found.damaged_chunks):
        reader.close()
        first = found.damaged_chunks[0] if found.damaged_chunks else None
        at, what = ((found.cut_off_at_byte, found.cut_off_record) if first is None
                    else (first["at_byte"], f"chunk {first['chunk']} ({first['compression']}): {first['what']}"))
        raise LogFormatError(
            f"{path}: the bag is cut off or damaged at byte {at:,} ({what}) before "
            f"any whole message (of {size:,} bytes; its index "
            + ("was never written" if found.index_pos == 0 else f"was to start at byte {found.index_pos:,}")
            + "): no message to read") from None
    try:
        if extra:
            missing = {k: v for k, v in extra.items() if k not in reader.typestore.fielddefs}
            if missing:
                reader.typestore.register(missing)
        yield reader
    finally:
        reader.close()


def _damaged_entries(reader: Any, connections: list) -> list[dict[str, Any]]:
    """The chunks of an indexed ROS 1 bag that hold messages of ``connections`` no reader can
    read, each a dict: ``chunk`` (its number, from 1, in file order), ``at_byte`` (where its
    record starts), ``compression``, ``what`` (in words), ``lost_messages`` (the messages of
    ``connections`` it held that cannot be read); those index entries are removed from the
    reader, so that the other chunks are read. Empty for a ROS 2 bag or a bag read record by
    record (:mod:`rplearn.io._ros1_scan`, which says where it stopped)."""
    from rplearn.io._ros1_scan import OP_CONNECTION, OP_MSGDATA, bag_record

    readers = getattr(reader, "readers", None) or []
    one = readers[0] if len(readers) == 1 else None
    if one is None or not hasattr(one, "chunks") or not hasattr(one, "indexes") or one.bio is None:
        return []
    ids = {c.id for c in connections}
    numbers = {pos: k + 1 for k, pos in enumerate(sorted(one.chunks))}
    damaged: list[dict[str, Any]] = []
    for pos in sorted(one.chunks):
        entries = [(cid, e) for cid in ids for e in one.indexes.get(cid, []) if e.chunk_pos == pos]
        if not entries:
            continue
        chunk = one.chunks[pos]
        one.bio.seek(chunk.datapos)
        data = one.bio.read(chunk.datasize)
        compression = getattr(chunk.decompressor, "__module__", "") or ""
        compression = "bz2" if "bz2" in compression else "lz4" if "lz4" in compression else "none"
        try:
            raw = chunk.decompressor(data) if len(data) == chunk.datasize else None
        except Exception:  # the decompressor's own error: a damaged chunk
            raw = None
        bad = []
        for cid, e in entries:
            rec = None if raw is None else bag_record(raw, e.offset)
            while rec is not None and rec[0]["op"][:1] == bytes([OP_CONNECTION]):
                rec = bag_record(raw, rec[2]) if raw is not None else None
            ok = (rec is not None and rec[0]["op"][:1] == bytes([OP_MSGDATA])
                  and rec[0].get("conn") == cid.to_bytes(4, "little")
                  and len(rec[0].get("time", b"")) == 8
                  and int.from_bytes(rec[0]["time"][:4], "little") * 10**9
                  + int.from_bytes(rec[0]["time"][4:], "little") == e.time)
            if not ok:
                bad.append((cid, e))
        if not bad:
            continue
        what = ("its data do not decompress" if raw is None and compression != "none"
                else "its data are cut" if raw is None else "a damaged record")
        gone = {(cid, e.offset) for cid, e in bad}
        for cid in ids:
            one.indexes[cid] = [e for e in one.indexes.get(cid, []) if not (e.chunk_pos == pos and (cid, e.offset) in gone)]
        damaged.append({"chunk": numbers[pos], "at_byte": int(pos), "compression": compression, "what": what,
                        "lost_messages": len(bad)})
    return damaged


def _messages(reader: Any, connections: list, path: str, repeated: dict[str, int] | None = None,
              damaged: list[dict[str, Any]] | None = None) -> Iterator[tuple[Any, int, Any]]:
    """The messages of ``connections``, deserialised; with ``repeated``, a message equal to an
    earlier one of its topic in receive time and every byte (the bag's messages written twice)
    is skipped and counted under its topic. The reader gives the messages in receive-time
    order, so only those of the current receive time are remembered.

    With ``damaged`` (a list), a chunk of an indexed ROS 1 bag that cannot be read (a flipped
    byte: its data do not decompress, or a record in it does not parse) is said there
    (:func:`_damaged_entries`) and its unreadable messages skipped: the other chunks are read.
    """
    it = reader.messages(connections=connections)
    pulled = 0  # index entries read so far: those of damaged chunks are removed, these stay first
    seen: set[tuple[str, bytes]] = set()
    seen_ns: int | None = None
    while True:
        try:
            conn, ts, raw = next(it)
            pulled += 1
        except StopIteration:
            return
        except Exception as exc:
            found = _damaged_entries(reader, connections) if damaged is not None else []
            if not found:
                raise LogFormatError(
                    f"{path}: truncated or corrupt bag while reading messages ({type(exc).__name__})"
                ) from None
            damaged.extend(found)  # type: ignore[union-attr]
            for one in reader.readers:  # the chunk it held open was closed when the damaged one failed
                one.current_chunk = (-1, io.BytesIO())
            it = reader.messages(connections=connections)
            for _ in range(pulled):  # the entries already read: every one readable, so none was removed
                next(it)
            continue
        if repeated is not None:
            if int(ts) != seen_ns:
                seen, seen_ns = set(), int(ts)
            key = (conn.topic, hashlib.blake2b(bytes(raw), digest_size=16).digest())
            if key in seen:
                repeated[conn.topic] = repeated.get(conn.topic, 0) + 1
                continue
            seen.add(key)
        try:
            msg = reader.deserialize(raw, conn.msgtype)
        except Exception as exc:
            raise LogFormatError(
                f"{path}: topic {conn.topic}: cannot deserialise {conn.msgtype} "
                f"({type(exc).__name__}); register its definition "
                f"(msg_definitions={{{conn.msgtype!r}: 'FILE.msg'}})",
                param="msg_definitions",
            ) from None
        yield conn, ts, msg


@check_types
def bag_topics(
    path: str | os.PathLike, msg_definitions: Mapping[str, str] | None = None
) -> dict[str, str]:
    """Topics of a bag and their message types, ``{topic: "pkg/msg/Type"}``, sorted by topic."""
    with open_rosbag(path, msg_definitions) as reader:
        return {c.topic: c.msgtype for c in sorted(reader.connections, key=lambda c: c.topic)}


def describe_topics(topics: Mapping[str, str], limit: int = 10) -> str:
    """One line listing topics with their types, pose topics first, at most ``limit`` of them.

    Example: ``/A/odom (nav_msgs/msg/Odometry), /A/rssi (pkg/msg/LinkQuality) and 3 more``.
    """
    if not topics:
        return "no topics"
    order = sorted(topics, key=lambda t: (topics[t] not in POSE_MSGTYPES, t))
    shown = ", ".join(f"{t} ({topics[t]})" for t in order[:limit])
    rest = len(order) - limit
    return shown + (f" and {rest} more" if rest > 0 else "")


@check_types
@dataclass(frozen=True)
class RosbagOptions:
    """How :func:`read_rosbag` reads the signal fields, message types and times of a bag.

    Attributes
    ----------
    tx_power_field, frequency_field : str, optional
        Fields of the RSSI messages carrying the tx power [dBm] and the frequency [Hz]
        (instead of the constants ``tx_power_dbm``, ``frequency_hz``); dots for nested fields.
    msg_definitions : mapping of type name to .msg path or text, optional
        Custom message types to register (``"pkg/msg/Type"``).
    time_source : {"header", "bag"}
        Header stamps (falling back to receive time) or the bag's receive times.

    Raises
    ------
    InputError
        On the first invalid option, naming it (``param``).
    """

    tx_power_field: str | None = None
    frequency_field: str | None = None
    msg_definitions: Mapping[str, str] | None = None
    time_source: str = "header"

    def __post_init__(self) -> None:
        for name in ("tx_power_field", "frequency_field"):
            value = getattr(self, name)
            if value is not None and (not isinstance(value, str) or not value.strip()):
                raise InputError(f"{name}: expected a message field name, got {value!r}", param=name)
        if self.msg_definitions is not None and not isinstance(self.msg_definitions, Mapping):
            raise InputError(f"msg_definitions: expected a mapping of type name to .msg path or text, got "
                             f"{self.msg_definitions!r}", param="msg_definitions")
        if self.time_source not in ("header", "bag"):
            raise InputError(f"time_source: expected 'header' or 'bag', got {self.time_source!r}", param="time_source")


@check_types
def read_rosbag(
    path: str | os.PathLike,
    pose_topics: Mapping[str, str],
    rssi_topics: Mapping[str, tuple[str, str]] | None = None,
    rssi_field: str = "rssi",
    tx_power_dbm: float | None = None,
    frequency_hz: float | None = None,
    options: RosbagOptions | None = None,
) -> tuple[Logs, dict[str, Any]]:
    """Read poses and RSSI from a ROS 1 bag or a ROS 2 bag (sqlite3 or MCAP).

    Parameters
    ----------
    path : str or PathLike
        ``.bag`` file (ROS 1) or ROS 2 bag directory (or its ``.db3`` / ``.mcap`` file).
    pose_topics : mapping of topic to node id
        Topics of nav_msgs/Odometry, geometry_msgs/PoseStamped or PoseWithCovarianceStamped.
    rssi_topics : mapping of topic to (tx, rx), optional
        Topics carrying the RSSI of packets from ``tx`` received by ``rx``.
    rssi_field : str
        Field of the RSSI [dBm] in those messages; dots for nested fields.
    tx_power_dbm, frequency_hz : float, optional
        Constants for the signal log (required unless ``options`` names the field carrying it).
    options : RosbagOptions, optional
        Fields carrying the tx power and frequency, custom message types, the time source
        (default ``RosbagOptions()``).

    Returns
    -------
    logs : Logs
        ``pose`` (canonical pose log, sorted by node and time) and ``signal`` (canonical
        signal log, or None without ``rssi_topics``).
    metadata : dict
        ``source``, ``format`` ("ros1" or "ros2"), ``topics`` (message counts, each message
        once), ``frame_ids`` per pose topic, ``repeated_messages`` (messages skipped because
        they repeat an earlier one of their topic exactly: same receive time and bytes, the
        bag's messages recorded twice) and ``repeated_by_topic``, ``time_reference``;
        for a ROS 1 bag without a readable index (cut off, its index damaged, or never
        closed by its recorder: ``unindexed``), read record by record from the start:
        ``cut_off_at_byte`` and ``cut_off_record`` (where the first record not read whole
        starts, and what it is; None when nothing was lost) and ``records_read`` (the
        messages read whole, every topic); these three are None for a bag read through its
        index. A bag cut off before any whole message is refused (:class:`LogFormatError`).
        ``trailing_bytes``: bytes after a ROS 1 bag's index, which are not read (junk
        appended, or another bag after it: ``trailing_bag``), said by
        :func:`rplearn.io.damage.file_damage`. ``damaged_chunks``: the chunks of an indexed
        ROS 1 bag that cannot be read (a flipped byte: their data do not decompress, or a
        record in them does not parse; ``chunk`` number, ``at_byte``, ``compression``,
        ``what``, ``lost_messages`` of the topics read), skipped while the other chunks are
        read, and ``damaged_chunk_messages`` their lost messages in all (``lost_messages`` is
        None for a bag read record by record, which has no index to count them); said by
        :func:`~rplearn.io.damage.file_damage`.
    """
    options = RosbagOptions() if options is None else options
    tx_power_field, frequency_field = options.tx_power_field, options.frequency_field
    msg_definitions, time_source = options.msg_definitions, options.time_source
    source = str(path)
    rssi_topics = dict(rssi_topics or {})
    if rssi_topics:
        if tx_power_dbm is None and tx_power_field is None:
            raise InputError(
                f"{source}: the RSSI topics need the transmit power [dBm] "
                "(tx_power_dbm, or RosbagOptions.tx_power_field)",
                param="tx_power_dbm",
            )
        if frequency_hz is None and frequency_field is None:
            raise InputError(
                f"{source}: the RSSI topics need the carrier frequency [Hz] "
                "(frequency_hz, or RosbagOptions.frequency_field)",
                param="frequency_hz",
            )
    if not pose_topics and not rssi_topics:
        raise InputError(
            f"{source}: name at least one pose or RSSI topic "
            "(pose_topics={topic: node}, rssi_topics={topic: (tx, rx)})",
            param="pose_topics",
        )
    pose_rows: dict[str, list] = {k: [] for k in ("t", "node", "x", "y", "z", "qw", "qx", "qy", "qz")}
    sig_rows: dict[str, list] = {k: [] for k in ("t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz")}
    frame_ids: dict[str, str] = {}
    power_dbm = math.nan if tx_power_dbm is None else float(tx_power_dbm)  # None only with its field
    carrier_hz = math.nan if frequency_hz is None else float(frequency_hz)
    with open_rosbag(path, msg_definitions) as reader:
        by_topic = {c.topic: c for c in reader.connections}
        wanted = list(pose_topics) + list(rssi_topics)
        missing = [t for t in wanted if t not in by_topic]
        if missing:
            raise InputError(
                f"{source}: topic(s) {', '.join(missing)} not in the bag; it has "
                f"{', '.join(sorted(by_topic))}"
            )
        for topic in pose_topics:
            mt = by_topic[topic].msgtype
            if mt not in POSE_MSGTYPES:
                raise InputError(
                    f"{source}: topic {topic} is {mt}; expected one of {', '.join(POSE_MSGTYPES)}"
                )
        conns = [c for c in reader.connections if c.topic in wanted]
        counts = {t: 0 for t in wanted}
        repeated: dict[str, int] = {}
        damaged: list[dict[str, Any]] = []
        for conn, ts, msg in _messages(reader, conns, source, repeated, damaged):
            topic = conn.topic
            counts[topic] += 1
            t = _stamp_s(msg, ts, time_source)
            if topic in pose_topics:
                pose = _pose_of(msg, conn.msgtype)
                p, q = pose.position, pose.orientation
                for k, v in (("t", t), ("node", str(pose_topics[topic])), ("x", p.x), ("y", p.y),
                             ("z", p.z), ("qw", q.w), ("qx", q.x), ("qy", q.y), ("qz", q.z)):
                    pose_rows[k].append(v)
                if topic not in frame_ids:
                    frame_ids[topic] = str(getattr(getattr(msg, "header", None), "frame_id", ""))
            else:
                tx, rx = rssi_topics[topic]
                where = f"{source}: topic {topic}"
                sig_rows["t"].append(t)
                sig_rows["tx"].append(str(tx))
                sig_rows["rx"].append(str(rx))
                sig_rows["rssi_dbm"].append(_float_field(msg, rssi_field, where))
                sig_rows["tx_power_dbm"].append(
                    _float_field(msg, tx_power_field, where) if tx_power_field else power_dbm)
                sig_rows["frequency_hz"].append(
                    _float_field(msg, frequency_field, where) if frequency_field else carrier_hz)
        fmt = "ros1" if not getattr(reader, "is2", True) else "ros2"
        found = bag_scan(reader)
    trailing, another_bag = (0, False)
    if fmt == "ros1" and found is None:
        from rplearn.io._ros1_scan import ros1_trailing_bytes

        trailing, another_bag = ros1_trailing_bytes(_bag_paths(path)[0])
    pose = None
    if pose_topics:
        empty = [t for t in pose_topics if counts[t] == 0]
        if empty:
            raise InputError(f"{source}: pose topic(s) {', '.join(empty)} have no messages")
        df = pd.DataFrame(pose_rows)
        for c in ("t", "x", "y", "z", "qw", "qx", "qy", "qz"):
            df[c] = df[c].astype(np.float64)
        pose = validate_pose_log(df, source)
    signal = pd.DataFrame(sig_rows).sort_values("t", kind="stable").reset_index(drop=True) if rssi_topics else None
    meta = {
        "source": source,
        "format": fmt,
        "topics": counts,
        "frame_ids": frame_ids,
        "repeated_messages": sum(repeated.values()),
        "repeated_by_topic": dict(sorted(repeated.items())),
        "time_reference": f"ROS time [s] ({'header stamps' if time_source == 'header' else 'bag receive time'})",
        **_scan_facts(found),
        "unindexed": found is not None and found.index_pos == 0,
        "trailing_bytes": trailing,
        "trailing_bag": another_bag,
        "damaged_chunks": damaged + ([] if found is None else list(found.damaged_chunks)),
        "damaged_chunk_messages": sum(d["lost_messages"] or 0 for d in damaged),
    }
    return Logs(pose=pose, signal=signal), meta


def _scan_facts(found: Any) -> dict[str, Any]:
    """What a record-by-record reading (a :class:`rplearn.io._ros1_scan.Ros1Scan`, None for a
    bag read through its index) says of the file: where it is cut off (``cut_off_at_byte``,
    ``cut_off_record``), the message records read (``records_read``), and, for a bag whose
    index could not be read, ``damaged_index``: where the index starts (``index_pos``), the
    reader's complaint (``error``) and the unreadable record inside the index (``at_byte``,
    ``what``; None when none was found). A damaged record inside the index loses no message:
    it is said there, not as a cut."""
    if found is None:
        return {"cut_off_at_byte": None, "cut_off_record": None, "records_read": None, "damaged_index": None}
    at, what = found.cut_off_at_byte, found.cut_off_record
    # a damaged record inside the index (not the file ending there: a cut file is said as cut)
    in_index = found.index_pos > 0 and at is not None and at >= found.index_pos and str(what).endswith("damaged")
    damaged_index = None
    if found.index_error is not None and (at is None or in_index):  # a cut file: said as cut
        damaged_index = {"index_pos": int(found.index_pos), "error": found.index_error,
                         "at_byte": int(at) if in_index else None, "what": what if in_index else None}
    if in_index and damaged_index is not None:
        at = what = None
    return {"cut_off_at_byte": at, "cut_off_record": what, "records_read": found.messages_read,
            "damaged_index": damaged_index}


__all__ = ["POSE_MSGTYPES", "RosbagOptions", "bag_topics", "describe_topics", "open_rosbag", "read_rosbag"]
