"""Monitor-mode Wi-Fi captures (pcap, pcapng) with radiotap headers -> signal logs.

Per frame: the capture time, the dBm antenna signal (and noise, antenna index, channel
frequency where present) from the radiotap header, and the transmitter address (802.11
address 2) from the frame header. The capturing node is the receiver.

The radiotap header is parsed here from the specification (https://www.radiotap.org).
dpkt 1.9.8's ``Radiotap`` was checked against the real captures in tests/fixtures: it skips
extended presence words correctly and gives the same dBm signal and noise as tcpdump there
(a test cross-checks it), but it decodes only the first namespace, does not know bits 15-17
(TX flags, RTS/data retries) so it misplaces a following XChannel field, and it eagerly
decodes the 802.11 payload, raising on corrupt frames. The own parser below avoids these.
The rules followed:

- fields appear in bit order, each aligned to its natural size relative to the header start;
- bit 31 of a presence word announces another word; bit 29 switches the next word to the
  radiotap namespace (bit numbering restarts at 0), bit 30 to a vendor namespace whose data
  is skipped by its declared length;
- on a bit whose size is unknown parsing stops, keeping the fields already read (tcpdump
  does the same: it prints ``[bit N]`` and stops);
- the first dBm antenna signal / noise / antenna index found is the frame's value (the
  first namespace carries the combined signal, later ones per-antenna values).

The pcap container is read with dpkt (``dpkt.pcap.Reader`` / ``dpkt.pcapng.Reader``),
imported lazily.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any, BinaryIO

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn.errors import InputError, LogFormatError

LINKTYPE_IEEE802_11_RADIOTAP = 127

#: radiotap field bit -> (alignment, size) in bytes, default namespace.
RADIOTAP_FIELDS: dict[int, tuple[int, int]] = {
    0: (8, 8),    # TSFT
    1: (1, 1),    # flags
    2: (1, 1),    # rate
    3: (2, 4),    # channel: u16 frequency MHz, u16 flags
    4: (2, 2),    # FHSS
    5: (1, 1),    # dBm antenna signal (s8)
    6: (1, 1),    # dBm antenna noise (s8)
    7: (2, 2),    # lock quality
    8: (2, 2),    # TX attenuation
    9: (2, 2),    # dB TX attenuation
    10: (1, 1),   # dBm TX power (s8)
    11: (1, 1),   # antenna index
    12: (1, 1),   # dB antenna signal
    13: (1, 1),   # dB antenna noise
    14: (2, 2),   # RX flags
    15: (2, 2),   # TX flags
    16: (1, 1),   # RTS retries
    17: (1, 1),   # data retries
    18: (4, 8),   # XChannel: u32 flags, u16 freq, u8 channel, u8 maxpower
    19: (1, 3),   # MCS
    20: (4, 8),   # A-MPDU status
    21: (2, 12),  # VHT
    22: (8, 12),  # timestamp
    23: (2, 12),  # HE
    24: (2, 12),  # HE-MU
    25: (2, 6),   # HE-MU-other-user
    26: (1, 1),   # 0-length PSDU
    27: (2, 4),   # L-SIG
}
_BIT_FLAGS = 1
#: Radiotap flags bit: the frame failed its FCS check (IEEE80211_RADIOTAP_F_BADFCS): its bytes
#: were damaged on the air, the address read from it may be wrong.
F_BADFCS = 0x40
_BIT_TSFT, _BIT_CHANNEL, _BIT_SIGNAL, _BIT_NOISE, _BIT_TXPOWER, _BIT_ANTENNA, _BIT_XCHANNEL = (
    0, 3, 5, 6, 10, 11, 18)
_BIT_RT_NS, _BIT_VENDOR_NS, _BIT_EXT = 29, 30, 31


@dataclass(frozen=True)
class Radiotap:
    """Fields of one radiotap header that rplearn uses (None where absent).

    Attributes
    ----------
    length : int
        Header length [bytes]; the 802.11 frame starts there.
    signal_dbm, noise_dbm : int or None
        First dBm antenna signal / noise [dBm].
    antenna : int or None
        First antenna index.
    frequency_hz : float or None
        Channel (or XChannel) centre frequency [Hz].
    tx_power_dbm : int or None
        dBm TX power field (present on frames the capturing card sent).
    tsft_us : int or None
        MAC timestamp [us].
    flags : int or None
        The flags byte (:data:`F_BADFCS`: the frame failed its FCS check).
    """

    length: int
    signal_dbm: int | None = None
    noise_dbm: int | None = None
    antenna: int | None = None
    frequency_hz: float | None = None
    tx_power_dbm: int | None = None
    tsft_us: int | None = None
    flags: int | None = None

    @property
    def bad_fcs(self) -> bool:
        """Whether the card marked the frame as failing its FCS check (damaged on the air)."""
        return bool((self.flags or 0) & F_BADFCS)


def parse_radiotap(buf: bytes) -> Radiotap:
    """Parse a radiotap header (see the module docstring for the rules).

    Raises
    ------
    LogFormatError
        On a header shorter than its stated length, a version other than 0, or presence
        words running past the header.
    """
    if len(buf) < 8:
        raise LogFormatError(f"radiotap header truncated: {len(buf)} byte(s), expected at least 8")
    version, _pad, length = struct.unpack_from("<BBH", buf, 0)
    if version != 0:
        raise LogFormatError(f"radiotap version {version}, expected 0")
    if length < 8 or length > len(buf):
        raise LogFormatError(f"radiotap length {length} does not fit the frame ({len(buf)} bytes)")
    # presence words: (namespace, word index within namespace, bits)
    words: list[tuple[str, int, int]] = []
    off = 4
    ns, ns_word = "radiotap", 0
    while True:
        if off + 4 > length:
            raise LogFormatError("radiotap presence bitmap runs past the header length")
        (word,) = struct.unpack_from("<I", buf, off)
        off += 4
        words.append((ns, ns_word, word))
        if not word & (1 << _BIT_EXT):
            break
        if word & (1 << _BIT_RT_NS):
            ns, ns_word = "radiotap", 0
        elif word & (1 << _BIT_VENDOR_NS):
            ns, ns_word = "vendor", 0
        else:
            ns_word += 1
    fields: dict[str, Any] = {}
    pos = off
    for ns, ns_word, word in words:
        if ns == "vendor":
            if ns_word == 0:
                # vendor namespace data: OUI(3) sub_ns(1) skip_length(u16), aligned to 2
                pos += (-pos) % 2
                if pos + 6 > length:
                    break
                (skip,) = struct.unpack_from("<H", buf, pos + 4)
                pos += 6 + skip
                if pos > length:
                    break
            continue
        stop = False
        for bit in range(29):
            if not word & (1 << bit):
                continue
            index = bit + 32 * ns_word
            if index not in RADIOTAP_FIELDS:
                stop = True
                break
            align, size = RADIOTAP_FIELDS[index]
            pos += (-pos) % align
            if pos + size > length:
                stop = True
                break
            if index == _BIT_SIGNAL and "signal" not in fields:
                fields["signal"] = struct.unpack_from("<b", buf, pos)[0]
            elif index == _BIT_NOISE and "noise" not in fields:
                fields["noise"] = struct.unpack_from("<b", buf, pos)[0]
            elif index == _BIT_ANTENNA and "antenna" not in fields:
                fields["antenna"] = buf[pos]
            elif index == _BIT_TXPOWER and "txpower" not in fields:
                fields["txpower"] = struct.unpack_from("<b", buf, pos)[0]
            elif index == _BIT_CHANNEL and "freq" not in fields:
                mhz = struct.unpack_from("<H", buf, pos)[0]
                if mhz:
                    fields["freq"] = mhz * 1e6
            elif index == _BIT_XCHANNEL and "freq" not in fields:
                mhz = struct.unpack_from("<H", buf, pos + 4)[0]
                if mhz:
                    fields["freq"] = mhz * 1e6
            elif index == _BIT_FLAGS and "flags" not in fields:
                fields["flags"] = buf[pos]
            elif index == _BIT_TSFT and "tsft" not in fields:
                fields["tsft"] = struct.unpack_from("<Q", buf, pos)[0]
            pos += size
        if stop:
            # a later namespace could still be parsed only if we knew where this one ends
            break
    return Radiotap(
        length=length,
        signal_dbm=fields.get("signal"),
        noise_dbm=fields.get("noise"),
        antenna=fields.get("antenna"),
        frequency_hz=fields.get("freq"),
        tx_power_dbm=fields.get("txpower"),
        tsft_us=fields.get("tsft"),
        flags=fields.get("flags"),
    )


def transmitter_address(frame: bytes) -> str | None:
    """802.11 transmitter address (address 2) as ``aa:bb:cc:dd:ee:ff``, or None.

    Control frames without a second address (ACK, CTS) have no transmitter.
    """
    if len(frame) < 16:
        return None
    fc = frame[0]
    ftype = (fc >> 2) & 0x3
    subtype = (fc >> 4) & 0xF
    if ftype == 1 and subtype in (0xC, 0xD):  # CTS, ACK: only the receiver address
        return None
    return ":".join(f"{b:02x}" for b in frame[10:16])


def _pcap_header_at(head: bytes) -> bool:
    """Whether ``head`` starts with a classic pcap file header of any kind (its magic number and
    version 2.4 in that byte order)."""
    if head[:4] in (b"\xd4\xc3\xb2\xa1", b"\x4d\x3c\xb2\xa1"):
        return head[4:8] == b"\x02\x00\x04\x00"
    if head[:4] in (b"\xa1\xb2\xc3\xd4", b"\xa1\xb2\x3c\x4d"):
        return head[4:8] == b"\x00\x02\x00\x04"
    return False


def _pcap_complete_frames(fh: BinaryIO, magic: bytes) -> tuple[int, int | None, int | None]:
    """Walk a classic pcap's record headers: ``(complete frames, cut at, second header)``,
    where ``cut at`` is the byte where the last record starts when it runs past the end of the
    file (a capture cut off while it was written; dpkt would hand on such a partial frame as if
    it were whole), else None, and ``second header`` is the byte where another capture's file
    header starts instead of a record (captures concatenated), else None. A record's time
    starting with the magic number would be in 2055 (0xa1b2c3d4 s) or later: no real record
    does. A capture of another kind (microseconds or nanoseconds, either byte order) is known by
    its magic number followed by its version, 2.4: eight bytes no record starts with."""
    order = "<" if magic in (b"\xd4\xc3\xb2\xa1", b"\x4d\x3c\xb2\xa1") else ">"
    size = os.fstat(fh.fileno()).st_size
    offset, frames = 24, 0
    fh.seek(0)
    while offset < size:
        fh.seek(offset)
        head = fh.read(16)
        if head[:4] == magic or _pcap_header_at(head):
            return frames, None, offset
        if len(head) < 16:
            return frames, offset, None
        (incl_len,) = struct.unpack(order + "I", head[8:12])
        if offset + 16 + incl_len > size:
            return frames, offset, None
        offset += 16 + incl_len
        frames += 1
    fh.seek(0)
    return frames, None, None


def _open_capture(path: str, fh: BinaryIO, cut: dict[str, Any] | None = None) -> Any:
    """A dpkt reader of the capture and its kind. A classic pcap cut inside a frame fills
    ``cut`` with ``cut_off_at_byte``, ``cut_off_record`` and ``records_read`` (the complete
    frames, after which the reader must stop); without ``cut`` it is refused."""
    import dpkt

    magic = fh.read(4)
    fh.seek(0)
    if len(magic) < 4:
        raise LogFormatError(f"{path}: file too short for a pcap or pcapng header")
    if magic == b"\x0a\x0d\x0d\x0a":
        return dpkt.pcapng.Reader(fh), "pcapng"
    if magic in (b"\xd4\xc3\xb2\xa1", b"\xa1\xb2\xc3\xd4", b"\x4d\x3c\xb2\xa1", b"\xa1\xb2\x3c\x4d"):
        frames, cut_at, second = _pcap_complete_frames(fh, magic)
        if second is not None:
            raise LogFormatError(f"{path}: another capture's file header at byte {second:,}, after frame {frames}: "
                                 "captures concatenated (or one in the file twice); split them (editcap, mergecap)")
        if cut_at is not None:
            if cut_at < 24 or cut is None:
                raise LogFormatError(f"{path}: truncated capture: the file ends inside "
                                     + ("its file header" if cut_at < 24 else f"frame {frames + 1}"))
            cut.update(cut_off_at_byte=int(cut_at), cut_off_record=f"frame {frames + 1}", records_read=frames)
        fh.seek(0)
        return dpkt.pcap.Reader(fh), "pcap"
    raise LogFormatError(f"{path}: not a pcap or pcapng file (magic {magic.hex()})")


def iter_radiotap_frames(
    path: str, cut: dict[str, Any] | None = None
) -> Iterator[tuple[float, Radiotap | None, str | None, int]]:
    """Yield ``(capture_time_s, radiotap or None, transmitter or None, frame_number)`` per frame.

    ``radiotap`` is None for a frame whose header cannot be parsed (counted by the caller).
    With ``cut`` (a dict), a capture cut off inside its last frame yields the complete frames
    and fills ``cut`` (``cut_off_at_byte``, ``cut_off_record``, ``records_read``); without it
    such a capture is refused.

    Raises
    ------
    LogFormatError
        On a file that is not pcap/pcapng, a link type other than radiotap (127), or a
        truncated or corrupt container.
    """
    source = str(path)
    try:
        import dpkt  # noqa: F401
    except ImportError:  # pragma: no cover - dpkt is a dependency
        raise InputError(f"{source}: reading pcap needs the 'dpkt' package") from None
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise InputError(f"{source}: cannot open ({exc.strerror})") from None
    with fh:
        try:
            reader, _kind = _open_capture(source, fh, cut)
            linktype = reader.datalink()
        except LogFormatError:
            raise
        except Exception as exc:
            raise LogFormatError(f"{source}: corrupt capture header ({type(exc).__name__})") from None
        if linktype != LINKTYPE_IEEE802_11_RADIOTAP:
            raise LogFormatError(
                f"{source}: link type {linktype}, expected 127 (802.11 with radiotap headers: "
                "capture in monitor mode)"
            )
        number = 0
        last = (cut or {}).get("records_read")
        it = iter(reader)
        while last is None or number < last:
            try:
                ts, buf = next(it)
            except StopIteration:
                return
            except Exception as exc:
                raise LogFormatError(
                    f"{source}: truncated or corrupt capture after frame {number} "
                    f"({type(exc).__name__})"
                ) from None
            number += 1
            try:
                rt = parse_radiotap(bytes(buf))
            except LogFormatError:
                yield float(ts), None, None, number
                continue
            yield float(ts), rt, transmitter_address(bytes(buf[rt.length:])), number


def read_radiotap_frames(path: str, cut: dict[str, Any] | None = None) -> pd.DataFrame:
    """All frames of a capture as a table, nothing dropped (``cut``: as
    :func:`iter_radiotap_frames`).

    Columns: ``frame`` (1-based number), ``t`` (capture time [s], UNIX epoch), ``transmitter``
    (or None), ``signal_dbm``, ``noise_dbm``, ``antenna``, ``frequency_hz``, ``tx_power_dbm``,
    ``radiotap_ok`` (False where the header is corrupt), ``bad_fcs`` (the card marked the
    frame as failing its FCS check). Missing values are NaN.
    """
    rows: list[tuple[int, float, str | None, float, float, float, float, float, bool, bool]] = []
    for ts, rt, ta, number in iter_radiotap_frames(path, cut):
        if rt is None:
            rows.append((number, ts, None, np.nan, np.nan, np.nan, np.nan, np.nan, False, False))
        else:
            rows.append((
                number, ts, ta,
                np.nan if rt.signal_dbm is None else float(rt.signal_dbm),
                np.nan if rt.noise_dbm is None else float(rt.noise_dbm),
                np.nan if rt.antenna is None else float(rt.antenna),
                np.nan if rt.frequency_hz is None else float(rt.frequency_hz),
                np.nan if rt.tx_power_dbm is None else float(rt.tx_power_dbm),
                True, rt.bad_fcs,
            ))
    cols = ["frame", "t", "transmitter", "signal_dbm", "noise_dbm", "antenna", "frequency_hz",
            "tx_power_dbm", "radiotap_ok", "bad_fcs"]
    return pd.DataFrame(rows, columns=cols)


@check_types
def read_pcap(
    path: str,
    receiver: str,
    tx_power_dbm: float | Mapping[str, float],
    address_map: Mapping[str, str] | None = None,
    frequency_hz: float | None = None,
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read a monitor-mode capture into a canonical signal log.

    Parameters
    ----------
    path : str
        pcap or pcapng file, link type 127 (radiotap).
    receiver : str
        Node id of the capturing node (the ``rx`` of every sample).
    tx_power_dbm : float or mapping of node id to float
        Transmit power of the senders [dBm] (radiotap carries only the receiver's view).
    address_map : mapping of MAC address to node id, optional
        Frames from other addresses are dropped (``unmapped_address``). Without a map the
        address itself is the node id. Addresses are compared in lower case.
    frequency_hz : float, optional
        Carrier frequency [Hz] for frames without a radiotap channel field; when given it
        also overrides the channel field.

    Returns
    -------
    signal : DataFrame
        ``t, tx, rx, rssi_dbm, tx_power_dbm, frequency_hz`` plus ``noise_dbm``, ``antenna``
        (NaN where absent) and ``frame`` (number in the capture).
    metadata : dict
        ``source``, ``format``, ``frames``, ``dropped`` (per reason: ``corrupt_radiotap``,
        ``bad_fcs`` (frames the card marked as failing their FCS check: damaged on the air),
        ``no_signal``, ``no_transmitter``, ``unmapped_address``, ``no_frequency``,
        ``no_tx_power``), ``addresses`` (frames per transmitter address), ``time_reference``,
        ``cut_off_at_byte`` and ``cut_off_record`` (where a capture cut off ends inside a frame,
        lost; None when it ends whole), ``records_read`` (the complete frames).
    """
    source = str(path)
    if not isinstance(receiver, str) or not receiver:
        raise InputError(f"{source}: receiver must be the node id of the capturing node")
    amap = {str(k).lower(): str(v) for k, v in (address_map or {}).items()}
    cut: dict[str, Any] = {}
    frames = read_radiotap_frames(path, cut)
    dropped = dict.fromkeys(
        ["corrupt_radiotap", "bad_fcs", "no_signal", "no_transmitter", "unmapped_address", "no_frequency",
         "no_tx_power"], 0)
    keep = np.ones(len(frames), bool)

    def drop(mask: np.ndarray, reason: str) -> None:
        hit = mask & keep
        dropped[reason] += int(hit.sum())
        keep[hit] = False

    drop(~frames["radiotap_ok"].to_numpy(bool), "corrupt_radiotap")
    drop(frames["bad_fcs"].to_numpy(bool), "bad_fcs")
    drop(~np.isfinite(frames["signal_dbm"].to_numpy(np.float64)), "no_signal")
    ta = frames["transmitter"].to_numpy(dtype=object)
    drop(pd.isna(ta), "no_transmitter")
    addresses = pd.Series(ta[keep]).value_counts().to_dict()
    if amap:
        tx = np.array([amap.get(a) if isinstance(a, str) else None for a in ta], dtype=object)
        drop(pd.isna(tx), "unmapped_address")
    else:
        tx = ta
    freq = frames["frequency_hz"].to_numpy(np.float64).copy()
    if frequency_hz is not None:
        freq[:] = float(frequency_hz)
    drop(~np.isfinite(freq), "no_frequency")
    if isinstance(tx_power_dbm, Mapping):
        ptx = np.array([float(tx_power_dbm.get(n, np.nan)) if isinstance(n, str) else np.nan
                        for n in tx])
        drop(~np.isfinite(ptx), "no_tx_power")
    else:
        ptx = np.full(len(frames), float(tx_power_dbm))
    idx = np.flatnonzero(keep)
    signal = pd.DataFrame({
        "t": frames["t"].to_numpy(np.float64)[idx],
        "tx": tx[idx].astype(str) if idx.size else np.array([], dtype=object),
        "rx": np.full(idx.size, receiver, dtype=object),
        "rssi_dbm": frames["signal_dbm"].to_numpy(np.float64)[idx],
        "tx_power_dbm": ptx[idx],
        "frequency_hz": freq[idx],
        "noise_dbm": frames["noise_dbm"].to_numpy(np.float64)[idx],
        "antenna": frames["antenna"].to_numpy(np.float64)[idx],
        "frame": frames["frame"].to_numpy(np.int64)[idx],
    })
    meta = {
        "source": source,
        "format": "pcap",
        "frames": int(len(frames)),
        "dropped": dropped,
        "addresses": {str(k): int(v) for k, v in addresses.items()},
        "time_reference": "capture time, seconds since the UNIX epoch (capturing host clock)",
        "cut_off_at_byte": cut.get("cut_off_at_byte"), "cut_off_record": cut.get("cut_off_record"),
        "records_read": cut.get("records_read", int(len(frames))),
    }
    return signal, meta


@check_types
@dataclass(frozen=True)
class RadiotapFields:
    """Optional radiotap fields of :func:`write_radiotap_pcap`.

    Attributes
    ----------
    noise_dbm : int or None
        The dBm antenna noise written in every frame (none when None).
    antenna : int or None
        The antenna index written in every frame (none when None).
    bad_fcs : ndarray of bool or None
        One per sample: frames marked as failing their FCS check (:data:`F_BADFCS`).
    """

    noise_dbm: int | None = None
    antenna: int | None = None
    bad_fcs: np.ndarray | None = None


@check_types
def write_radiotap_pcap(
    path: str,
    t_s: np.ndarray,
    rssi_dbm: np.ndarray,
    transmitter: list[str],
    frequency_hz: float,
    fields: RadiotapFields = RadiotapFields(),
    pcapng: bool = False,
) -> None:
    """Write a radiotap pcap (or pcapng) of 802.11 data frames, one per sample (fixtures, demos).

    The header carries TSFT, flags, channel, dBm antenna signal, and optionally noise and
    antenna index (``fields``); RSSI values are rounded to integers (radiotap stores an s8).
    ``fields.bad_fcs`` (booleans, one per sample) marks frames as failing their FCS check
    (:data:`F_BADFCS`).
    """
    noise_dbm, antenna, bad_fcs = fields.noise_dbm, fields.antenna, fields.bad_fcs
    import dpkt

    present = (1 << 0) | (1 << 1) | (1 << _BIT_CHANNEL) | (1 << _BIT_SIGNAL)
    if noise_dbm is not None:
        present |= 1 << _BIT_NOISE
    if antenna is not None:
        present |= 1 << _BIT_ANTENNA
    with atomic_open(path, "wb") as fh:
        if pcapng:
            writer = dpkt.pcapng.Writer(fh, snaplen=65535, linktype=LINKTYPE_IEEE802_11_RADIOTAP)
        else:
            writer = dpkt.pcap.Writer(fh, linktype=LINKTYPE_IEEE802_11_RADIOTAP, nano=True)
        bad = np.zeros(len(transmitter), bool) if bad_fcs is None else np.asarray(bad_fcs, bool)
        for i, (t, rssi, ta) in enumerate(zip(np.asarray(t_s, float), np.asarray(rssi_dbm), transmitter)):
            body = struct.pack("<Q", int(round(t * 1e6)) & 0xFFFFFFFFFFFFFFFF)  # TSFT at 8 (aligned)
            body += struct.pack("<B", F_BADFCS if bad[i] else 0)  # flags (no FCS in the frame)
            body += b"\x00"  # pad to 2 for channel
            body += struct.pack("<HH", int(round(frequency_hz / 1e6)), 0x00A0)
            body += struct.pack("<b", int(round(float(rssi))))
            if noise_dbm is not None:
                body += struct.pack("<b", int(noise_dbm))
            if antenna is not None:
                body += struct.pack("<B", int(antenna))
            header = struct.pack("<BBHI", 0, 0, 8 + len(body), present) + body
            mac = bytes(int(b, 16) for b in ta.split(":"))
            dot11 = struct.pack("<BBH", 0x08, 0x00, 0) + b"\xff" * 6 + mac + mac + struct.pack("<H", (i % 4096) << 4)
            writer.writepkt(header + dot11 + b"rplearn", ts=float(t))


__all__ = [
    "F_BADFCS",
    "Radiotap",
    "RadiotapFields",
    "iter_radiotap_frames",
    "parse_radiotap",
    "read_pcap",
    "read_radiotap_frames",
    "transmitter_address",
    "write_radiotap_pcap",
]
