"""What a file is, from its first bytes, to turn natural mistakes into messages that say what to run.

A user who gives a raw flight log to ``fit``, swaps ``predict``'s model and dataset, or swaps
``sync``'s ``--poses`` and ``--signals`` should read what the file *is* and the command that
would work, not a decoder's complaint about bytes. Everything here only reads a file's head
(or a table's header) and never raises: a hint is a suffix for an error message, or ``""``.
"""

from __future__ import annotations

import os
import shlex
from collections.abc import Sequence

from rplearn._argtypes import check_types
from rplearn.errors import InputError, LogFormatError

#: Raw log kinds (:func:`detect_format`) and how a message names them.
RAW_LOG_NAMES: dict[str, str] = {
    "mavlink": "MAVLink (.tlog) or ArduPilot DataFlash",
    "ulog": "PX4 ULog",
    "ros1": "ROS 1 bag",
    "ros2": "ROS 2 bag",
    "pcap": "packet capture (pcap)",
}
#: Columns that only a pose table or only a signal table has (the canonical schemas).
POSE_ONLY_COLUMNS = frozenset({"node", "x", "y", "z", "qw", "qx", "qy", "qz"})
SIGNAL_ONLY_COLUMNS = frozenset({"tx", "rx", "rssi_dbm"})


_MAGIC: tuple[tuple[bytes, str], ...] = (
    (b"ULog\x01\x12\x35", "ulog"),
    (b"#ROSBAG V2.0", "ros1"),
    (b"\x89MCAP", "ros2"),
    (b"SQLite format 3\x00", "ros2"),
    (b"\x0a\x0d\x0d\x0a", "pcap"),
    (b"\xd4\xc3\xb2\xa1", "pcap"),
    (b"\xa1\xb2\xc3\xd4", "pcap"),
    (b"\x4d\x3c\xb2\xa1", "pcap"),
    (b"\xa1\xb2\x3c\x4d", "pcap"),
    (b"PAR1", "table"),
    (b"\xa3\x95\x80", "mavlink"),  # DataFlash: the first record is an FMT (type 128)
    (b"FMT, ", "mavlink"),  # DataFlash as text
)
_EXTENSIONS: dict[str, str] = {
    ".ulg": "ulog",
    ".bag": "ros1",
    ".mcap": "ros2",
    ".db3": "ros2",
    ".pcap": "pcap",
    ".pcapng": "pcap",
    ".cap": "pcap",
    ".csv": "table",
    ".parquet": "table",
    ".pq": "table",
    ".tlog": "mavlink",
    ".bin": "mavlink",
}


#: Bytes below which a file is no binary log: a ``.tlog`` record is an 8-byte time stamp and a
#: MAVLink frame of at least 8 bytes; a DataFlash log starts with an 89-byte FMT record.
_SHORTEST_LOG = 16


@check_types
def detect_format(path: str | os.PathLike) -> str:
    """Format of a log: ``"ulog"``, ``"ros1"``, ``"ros2"``, ``"pcap"``, ``"mavlink"`` (a
    ``.tlog`` or an ArduPilot DataFlash log) or ``"table"``.

    A directory holding ``metadata.yaml`` is a ROS 2 bag. Files are judged by their first
    bytes, then by extension.
    """
    p = str(path)
    if not os.path.exists(p):
        raise InputError(f"{p}: no such file or directory")
    if os.path.isdir(p):
        if os.path.exists(os.path.join(p, "metadata.yaml")):
            return "ros2"
        raise InputError(f"{p}: a directory but not a ROS 2 bag (no metadata.yaml)")
    with open(p, "rb") as fh:
        head = fh.read(16)
    ext = os.path.splitext(p)[1].lower()
    if not head:
        raise LogFormatError(f"{p}: empty file (0 bytes), not a log")
    for magic, kind in _MAGIC:
        if head.startswith(magic):
            if magic == b"PAR1" and ext not in (".parquet", ".pq"):
                raise LogFormatError(f"{p}: a Parquet table named {ext or 'without an extension'}; tables are read by "
                                     "their extension: rename it .parquet")
            return kind
    if len(head) < _SHORTEST_LOG and _EXTENSIONS.get(ext, "table") != "table":
        raise LogFormatError(f"{p}: {len(head)} byte(s), too short to be a {ext} log (cut off, or not a log)")
    if ext in _EXTENSIONS:
        return _EXTENSIONS[ext]
    raise InputError(
        f"{p}: unknown log format; expected one of {', '.join(sorted(set(_EXTENSIONS)))} "
        "or a ROS 2 bag directory"
    )


def _head(path: str, n: int = 64) -> bytes:
    try:
        with open(path, "rb") as fh:
            return fh.read(n)
    except OSError:
        return b""


def sniff(path: str | os.PathLike[str]) -> str | None:
    """``"json"`` (a JSON document, such as a model file), ``"table"`` (Parquet or CSV), a raw
    log kind of :data:`RAW_LOG_NAMES`, or None (missing, or unknown)."""
    p = os.fspath(path)
    if not os.path.exists(p):
        return None
    if not os.path.isdir(p):
        head = _head(p)
        if head.lstrip()[:1] == b"{":
            return "json"
        if len(head) > 9 and head[8] in (0xFE, 0xFD) and not head.startswith(b"PAR1"):
            # a .tlog: an 8-byte time stamp, then a MAVLink v1 (0xFE) or v2 (0xFD) frame
            return "mavlink"
    try:
        return detect_format(p)
    except Exception:  # unknown format: no hint
        return None


#: What ``sync`` needs besides each raw log kind, so that the command a hint names runs once its
#: placeholders are filled in: a MAVLink log carries neither the radios' power nor their band, a
#: ULog's readings are its telemetry radio's and its vehicle needs a name, a bag's topics are named.
_SYNC_ARGUMENTS: dict[str, str] = {
    "mavlink": "--poses {log} --signals {log} --tx-power DBM --frequency HZ",
    "ulog": "--poses {log} --signals {log} --node {log}=NODE --ulog-radio --tx-power DBM --frequency HZ",
    "ros1": "--poses {log} --signals {log} --pose-topic TOPIC=NODE --rssi-topic TOPIC=TX:RX",
    "ros2": "--poses {log} --signals {log} --pose-topic TOPIC=NODE --rssi-topic TOPIC=TX:RX",
    "pcap": "--poses POSE_LOG --signals {log} --receiver {log}=NODE --address MAC=NODE --tx-power DBM",
}


def raw_log_hint(path: str | os.PathLike[str]) -> str:
    """``"a raw ... log, not a matched dataset: run ... first"``, or ``""``."""
    p = os.fspath(path)
    kind = sniff(p)
    if kind not in RAW_LOG_NAMES:
        return ""
    q = shlex.quote(p)  # a path with spaces runs as pasted
    run = f"rplearn sync {_SYNC_ARGUMENTS[kind].format(log=q)} -o data.parquet"
    return (f"a raw {RAW_LOG_NAMES[kind]} log, not a matched dataset: run `{run}` first "
            f"(`rplearn inspect {q}` shows what it holds)")


def not_a_table_hint(path: str | os.PathLike[str]) -> str:
    """The hint for a file given where a table (a dataset or a log table) was expected."""
    p = os.fspath(path)
    if sniff(p) == "json":
        return ("a JSON file (a model file?), not a table: a dataset or log table goes here "
                "(evaluate and predict take MODEL.json first, then the dataset)")
    return raw_log_hint(p)


def not_a_model_hint(path: str | os.PathLike[str]) -> str:
    """The hint for a file given where a model file was expected."""
    p = os.fspath(path)
    kind = sniff(p)
    if kind == "table":
        return ("a table (a dataset?), not a model file: are the arguments in the wrong order? "
                "(evaluate and predict take MODEL.json first, then the dataset)")
    return raw_log_hint(p)


def table_read_error(name: str, path: str | os.PathLike[str] | None, exc: BaseException) -> str:
    """The one-line message for a table that could not be read: what the file is and what to run
    when :func:`not_a_table_hint` knows (``path`` None: a URL, not sniffed), else the parser's
    complaint (its first line)."""
    if path is not None and os.path.isfile(path) and os.path.getsize(path) <= 4096:
        size = os.path.getsize(path)
        if size == 0:
            return f"{name}: empty file (0 bytes), not a table"
        with open(path, "rb") as fh:
            if not fh.read().strip():
                return f"{name}: empty file ({size} bytes of blank lines), not a table"
    hint = "" if path is None else not_a_table_hint(path)
    if hint:
        return f"{name}: {hint}"
    first = str(exc).splitlines()[0] if str(exc) else ""
    return f"{name}: cannot read table ({type(exc).__name__}: {first})"


def _table_columns(path: str) -> set[str]:
    """A table's column names from its header alone (canonical names, no renaming); empty when
    it is not a table or cannot be read."""
    if sniff(path) != "table":
        return set()
    try:
        if _head(path, 4) == b"PAR1":
            import pyarrow.parquet as pq

            return set(pq.ParquetFile(path).schema_arrow.names)
        import pandas as pd

        return {str(c).strip() for c in pd.read_csv(path, nrows=0).columns}
    except Exception:  # an unreadable table: no hint
        return set()


def swapped_logs_hint(pose_paths: Sequence[str], signal_paths: Sequence[str]) -> str:
    """``"; ... swap --poses and --signals"`` when the pose files look like signal tables and the
    signal files like pose tables (by their columns), else ``""``."""
    poses = [_table_columns(str(p)) for p in pose_paths]
    signals = [_table_columns(str(p)) for p in signal_paths]
    if any(c & SIGNAL_ONLY_COLUMNS == SIGNAL_ONLY_COLUMNS for c in poses) and \
            any(c & POSE_ONLY_COLUMNS == POSE_ONLY_COLUMNS for c in signals):
        return ("; the --poses file(s) hold radio readings (tx, rx, rssi_dbm) and the --signals file(s) poses: "
                "swap --poses and --signals")
    return ""


__all__ = ["detect_format", "POSE_ONLY_COLUMNS", "RAW_LOG_NAMES", "SIGNAL_ONLY_COLUMNS", "not_a_model_hint", "not_a_table_hint",
           "raw_log_hint", "sniff", "swapped_logs_hint", "table_read_error"]
