"""PX4 ULogs with a telemetry radio for the tests: a real sample log (tests/fixtures/px4-ulog,
BSD-3) with ``radio_status`` messages added, as PX4 logs them (one of the logger's default
topics), in the ULog format (https://docs.px4.io/main/en/dev_log/ulog_file_format.html)."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "px4-ulog"
#: The pyulog project's sample log with a home position (SITL, 31 s, barely off the ground).
EVENTS_LOG = FIXTURES / "sample_px4_events.ulg"
_HEADER_BYTES = 16
#: ``radio_status`` as PX4 defines it (msg/RadioStatus.msg), its fields ordered by size as the
#: logger orders them (the trailing padding is not written).
RADIO_FORMAT = ("radio_status:uint64_t timestamp;uint16_t rxerrors;uint16_t fix;uint8_t rssi;uint8_t remote_rssi;"
                "uint8_t txbuf;uint8_t noise;uint8_t remote_noise;")
_MSG_ID = 61000  # not one of the sample log's subscriptions


def _message(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def _first_data_message(data: bytes) -> int:
    """The offset of the first message of the data section (the first ``A``: subscriptions)."""
    at = _HEADER_BYTES
    while at + 3 <= len(data):
        size, kind = struct.unpack_from("<HB", data, at)
        if kind == ord("A"):
            return at
        at += 3 + size
    raise ValueError("no data section")


def ulog_times_us(path: Path = EVENTS_LOG) -> tuple[int, int]:
    """The first and last timestamps [us] of the sample log's local positions."""
    from pyulog import ULog

    lp = next(d for d in ULog(str(path), ["vehicle_local_position"]).data_list if d.name == "vehicle_local_position")
    return int(lp.data["timestamp"][0]), int(lp.data["timestamp"][-1])


def with_radio(out: Path, t_us: np.ndarray, rssi: np.ndarray, remote_rssi: np.ndarray, src: Path = EVENTS_LOG,
               twice: bool = False) -> Path:
    """``src`` with ``radio_status`` readings at ``t_us`` [us, the log's clock] added (the
    format among the definitions, a subscription and the data messages at the end; each
    message ``twice`` when asked, as a logger writing a packet twice); written to ``out``."""
    data = src.read_bytes()
    cut = _first_data_message(data)
    parts = [data[:cut], _message(b"F", RADIO_FORMAT.encode()), data[cut:],
             _message(b"A", struct.pack("<BH", 0, _MSG_ID) + b"radio_status")]
    for t, a, b in zip(np.asarray(t_us, np.int64), np.asarray(rssi), np.asarray(remote_rssi)):
        body = struct.pack("<HQHHBBBBB", _MSG_ID, int(t), 0, 0, int(a), int(b), 100, 40, 42)
        parts += [_message(b"D", body)] * (2 if twice else 1)
    out.write_bytes(b"".join(parts))
    return out


def radio_log(out: Path, rate_hz: float = 2.0, seed: int = 0, twice: bool = False) -> tuple[Path, np.ndarray]:
    """The sample log with plausible SiK readings at ``rate_hz`` over its flight (raw units
    around 150-170, both ways); also returns the readings' times [us]."""
    first, last = ulog_times_us()
    t = np.arange(first + 500_000, last - 500_000, int(1e6 / rate_hz), dtype=np.int64)
    rng = np.random.default_rng(seed)
    return with_radio(out, t, rng.integers(150, 170, len(t)), rng.integers(150, 170, len(t)), twice=twice), t
