"""rplearn.io._dataflash_records: a DataFlash log holding every record twice (a logger or a router
duplicating the stream: the same record again at the same TimeUS, or up to 1 ms later with the same
fields) reads as the log written once, the copies counted (``close_copies``) and said; records repeated
farther apart, or at the same TimeUS with other fields, are no copies."""

from __future__ import annotations

import struct
from collections.abc import Callable
from pathlib import Path

import pandas as pd
import pytest
from flightfiles import rplearn_here, simulated_dataflash

from rplearn.io.damage import file_damage
from rplearn.io.dataflash_writer import _FORMATS
from rplearn.io.files import read_table
from rplearn.io.mavlink import read_mavlink

REAL_BIN = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "pymavlink_test.BIN"
#: the real log's whole records (it ends 24 bytes into an AHR2 record)
REAL_WHOLE = 65512
_FMT = 128


def _records(data: bytes) -> list[bytes]:
    """The records of a binary DataFlash log (every one framed by an FMT before it)."""
    lengths, out, at = {_FMT: 89}, [], 0
    while at < len(data):
        assert data[at:at + 2] == b"\xa3\x95"
        kind = data[at + 2]
        if kind == _FMT:
            lengths[data[at + 3]] = data[at + 4]
        out.append(data[at:at + lengths[kind]])
        at += lengths[kind]
    return out


def _later(record: bytes, apart_us: int) -> bytes:
    """The record with its TimeUS (the first field, uint64, of every record written here) ``apart_us`` later."""
    copy = bytearray(record)
    struct.pack_into("<Q", copy, 3, struct.unpack_from("<Q", copy, 3)[0] + apart_us)
    return bytes(copy)


def _twice(data: bytes, apart_us: int = 0, batch: int = 1) -> tuple[bytes, int]:
    """Every record but the FMTs written again ``apart_us`` later, after each ``batch`` records (1: each
    right after itself); returns the bytes and the records copied."""
    out: list[bytes] = []
    pending: list[bytes] = []
    copied = 0
    for record in _records(data):
        out.append(record)
        if record[2] == _FMT:
            continue
        pending.append(_later(record, apart_us))
        copied += 1
        if len(pending) == batch:
            out += pending
            pending = []
    return b"".join(out + pending), copied


def _read(path):
    return read_mavlink(path, tx_power_dbm=20.0, frequency_hz=433e6)


#: the records of the simulated flight kept (its first 13 s: 1,247 ATT and POS and 496 RAD of its 76 s' 7,026 ATT
#: and POS and 2,658 RAD): every copy, buffer and repeat written below still occurs hundreds of times (the buffers
#: of 400, seven), and the reads take a fifth of the whole flight's
HEAD = 3000


@pytest.fixture(scope="module")
def once(tmp_path_factory) -> Path:
    """A simulated flight written by rplearn.io.dataflash_writer, its first ``HEAD`` records (thousands of ATT,
    POS and RAD; the FMT, ORGN and ARM records come first)."""
    folder = tmp_path_factory.mktemp("df_copies")
    whole = simulated_dataflash(folder / "flight.bin").read_bytes()
    path = folder / "once.bin"
    path.write_bytes(b"".join(_records(whole)[:HEAD]))
    return path


@pytest.fixture(scope="module")
def once_read(once):
    """``once`` read (the pose and signal tables and the metadata), once for the module: read-only."""
    logs, meta = _read(once)
    assert meta["close_copies"] == 0 and meta["repeated_messages"] == 0 and meta["reboots"] == 0
    assert meta["messages"] == {"ATT": 1247, "POS": 1247, "ORGN": 2, "RAD": 496}
    return logs, meta


def _read_twice(once, tmp_path, apart_us: int, once_read=None):
    """The log ``once`` (read: ``once_read``, else read here) with every record written twice ``apart_us`` later,
    read; asserted to give the same pose and signal tables as ``once``: its path, the copies written and both
    reads' metadata."""
    twice = tmp_path / "twice.bin"
    data, copied = _twice(once.read_bytes(), apart_us)
    twice.write_bytes(data)
    (logs1, m1), (logs2, m2) = once_read or _read(once), _read(twice)
    pd.testing.assert_frame_equal(logs1.pose, logs2.pose)
    pd.testing.assert_frame_equal(logs1.signal, logs2.signal)
    return twice, copied, (m1, m2)


@pytest.mark.parametrize("apart_us", [0, 500, 1000])
def test_every_record_twice_reads_as_the_log_once(once, once_read, tmp_path, apart_us):
    # was: the same TimeUS twice dropped the attitude copies as duplicate_time (7,026) and merged the
    # radio copies in sync as duplicate_reading; 0.5 ms later every pose was read twice (14,053 rows; the whole flight)
    twice, copied, (m1, m2) = _read_twice(once, tmp_path, apart_us, once_read)
    assert m1["close_copies"] == 0 and m2["close_copies"] == copied
    assert m2["messages"] == m1["messages"] and m2["dropped"] == m1["dropped"] and m2["signal"] == m1["signal"]
    assert m2["repeated_messages"] == 0 and m2["reboots"] == 0
    said = file_damage(str(twice), m2)
    assert any(f"{copied:,} DataFlash record(s) repeat one of their kind read shortly before them" in line
               for line in said)
    assert not any("in the file twice" in line for line in said)


@pytest.mark.parametrize(("apart_us", "batch"), [(0, 3), (300, 5), (0, 50), (800, 400)])
def test_every_buffer_of_records_written_twice_reads_as_the_log_once(once, once_read, tmp_path, apart_us, batch):
    # a logger writing each buffer twice: the copies step back in time (was: with the copies 0.3 ms later every
    # pose twice, 14,053 rows of the whole flight; at the same TimeUS, buffers of 2, some as duplicate_time and the RAD counts inflated)
    again = tmp_path / "again.bin"
    data, copied = _twice(once.read_bytes(), apart_us, batch)
    again.write_bytes(data)
    (logs1, m1), (logs2, m2) = once_read, _read(again)
    pd.testing.assert_frame_equal(logs1.pose, logs2.pose)
    pd.testing.assert_frame_equal(logs1.signal, logs2.signal)
    assert m2["close_copies"] == copied and m2["repeated_messages"] == 0 and m2["messages"] == m1["messages"]
    assert m2["reboots"] == 0 and m2["dropped"] == m1["dropped"]


def test_records_repeated_more_than_1_ms_later_are_no_copies(once, once_read, tmp_path):
    # the same fields 1.5 ms later: a second reading that reads alike (a vehicle at rest), kept
    later = tmp_path / "later.bin"
    later.write_bytes(_twice(once.read_bytes(), 1500)[0])
    (logs1, _), (logs2, m2) = once_read, _read(later)
    assert m2["close_copies"] == 0
    assert (logs2.pose["node"] == "sys1").sum() == 2 * (logs1.pose["node"] == "sys1").sum()


def test_a_record_at_the_same_time_with_other_fields_is_no_copy(once, tmp_path):
    # a RAD of another reading at the same TimeUS right after one: kept for the reader's other checks
    rad = _FORMATS["RAD"][0]
    out, changed = [], 0
    for record in _records(once.read_bytes()):
        out.append(record)
        if record[2] == rad and changed < 5:
            other = bytearray(record)
            other[3 + 8 + 3] = 77  # Noise (after TimeUS, RSSI, RemRSSI, TxBuf): another reading's
            out.append(bytes(other))
            changed += 1
    assert changed == 5
    path = tmp_path / "other.bin"
    path.write_bytes(b"".join(out))
    assert _read(path)[1]["close_copies"] == 0


def test_a_log_in_the_file_twice_is_still_a_repeated_copy_not_close_copies(once, once_read, tmp_path):
    # the copy's records repeat the first log's at the same TimeUS, but after the time stepped back
    # by the whole log: merge_copied_boots's business (repeated_messages), none a close copy
    twice = tmp_path / "concatenated.bin"
    twice.write_bytes(once.read_bytes() * 2)
    (_, m1), (_, m2) = once_read, _read(twice)
    assert m2["close_copies"] == 0 and m2["repeated_messages"] == sum(m1["messages"].values()) + 1


@pytest.mark.parametrize("apart_us", [0, 400])
def test_the_real_log_with_every_record_twice_reads_as_once(tmp_path, apart_us):
    whole = tmp_path / "whole.bin"
    whole.write_bytes(REAL_BIN.read_bytes()[:REAL_WHOLE])
    # was: 4 signal rows for 2 (its one RAD twice), and 45 pose rows for 23 with the copies 0.4 ms later
    _, copied, (m1, m2) = _read_twice(whole, tmp_path, apart_us)
    assert m2["messages"] == m1["messages"] == {"ATT": 24, "POS": 23, "GPS": 5, "ORGN": 2, "RAD": 1}
    # every record of the types read (GPS: also those without a 3-D fix; ORGN; ARM, EV) read once
    assert 0 < m2["close_copies"] <= copied and m2["repeated_messages"] == 0 and m2["dropped"] == m1["dropped"]


def test_sync_matches_as_many_samples_as_the_log_written_once(once, tmp_path):
    twice = tmp_path / "twice.bin"
    twice.write_bytes(_twice(once.read_bytes(), 500)[0])
    matched = []
    for path in (once, twice):
        out = tmp_path / f"{path.stem}.parquet"
        proc = rplearn_here(["sync", "--poses", path, "--signals", path, "--tx-power", "20", "--frequency", "433e6",
                             "--link", "all", "--max-gap", "1.0", "-o", out])
        assert proc.returncode == 0, proc.stdout + proc.stderr
        matched.append(read_table(str(out)))
    pd.testing.assert_frame_equal(matched[0], matched[1])
    assert "DataFlash record(s) repeat one of their kind read shortly before them" in proc.stdout


def test_copies_among_many_records_of_equal_fields(tmp_path):
    # a vehicle at rest: 3,000 ATT records with equal fields 5 ms apart (none a copy, every one within the
    # 1,024-record window of many others of its key); 7 of them written again, 0-1 ms later, right after
    # themselves or after a buffer of 200 records (the time stepping back): exactly those 7 are close copies
    # (at most a fifth of the interval: far below it; was 2.5 ms apart, copies up to 0.4 of the interval)
    again = {10: 0, 500: 700, 1200: 1000, 2999: 300}  # record -> us later, written right after it
    buffered = {1500: 0, 1600: 999, 1690: 1}  # record -> us later, written after record 1700
    path = _att_log(tmp_path / "rest.bin", [(5000, 3000)], again, buffered=buffered, flush_after=1700, orgn_type=0)
    logs, meta = _read(path)
    assert meta["close_copies"] == len(again) + len(buffered)
    assert meta["messages"]["ATT"] == 3000 and meta["repeated_messages"] == 0 and meta["reboots"] == 0


def _att_log(path: Path, stretches: list[tuple[int, int]], again: dict[int, int] | None = None, *,
             yaw: Callable[[int], float] | None = None, buffered: dict[int, int] | None = None,
             flush_after: int | None = None, orgn_type: int = 1) -> Path:
    """A vehicle logging ATT at rates changing within one boot: ``stretches`` of (interval [us], records), one after
    the other, at rest (equal fields: yaw 90 deg) or turning (``yaw``: record number -> yaw [deg]); a POS and a RAD
    every 100th record. The records numbered in ``again`` are written again that many microseconds later, right
    after themselves; those in ``buffered`` that many microseconds later after record ``flush_after`` (the time
    stepping back). ``orgn_type``: of the ORGN record at the start (1: the home)."""
    from rplearn.io.dataflash_writer import _fmt_records, _record

    lat, lon = 473977000, 85456000
    out = [*_fmt_records(), _record("ORGN", 1_000_000, orgn_type, lat, lon, 90.0), _record("ARM", 1_000_000, 1)]
    again, buffered, held = again or {}, buffered or {}, []
    t, i = 1_000_100, 0
    for interval_us, n in stretches:
        for _ in range(n):
            heading = 90.0 if yaw is None else yaw(i)
            out.append(_record("ATT", t, 0.0, 0.0, heading))
            if i % 100 == 0:
                out.append(_record("POS", t + 1, lat + i, lon, 100.0))
                out.append(_record("RAD", t + 2, 200, 190 - i // 100, 100, 0, 0, 0, 0))
            if i in again:
                out.append(_record("ATT", t + again[i], 0.0, 0.0, heading))
            if i in buffered:
                held.append(_record("ATT", t + buffered[i], 0.0, 0.0, heading))
            if i == flush_after:
                out += held
            t += interval_us
            i += 1
    path.write_bytes(b"".join(out))
    return path


@pytest.mark.parametrize("interval_us", [1000, 999, 1001])
def test_a_kind_logged_every_millisecond_at_rest_is_no_copy(tmp_path, interval_us):
    # was: 3,000 ATT records of equal fields 1 ms apart read as 1,500 and 1,500 close copies ("the file holds records
    # written twice"); its records' interval is the kind's own. A record written again at the same TimeUS, or
    # 0.1 ms later (a tenth of the interval), still is a copy
    again = {40: 0, 41: 0, 1700: 100}  # 41: a record read 1 ms after an equal one, again at its TimeUS
    logs, meta = _read(_att_log(tmp_path / "fast.bin", [(interval_us, 3000)], again))
    assert meta["messages"]["ATT"] == 3000 and meta["close_copies"] == len(again)
    assert (logs.pose["node"] == "sys1").sum() == 3000 - meta["dropped"]["out_of_span"]  # after the last POS
    assert not any("repeat one of their kind" in line and "3,0" in line for line in file_damage("fast.bin", meta))


def test_a_slower_kind_at_rest_still_has_its_copies_1_ms_later(tmp_path):
    # the same records 1 ms later at 10 ms apart: a tenth of the interval, copies (as before)
    again = dict.fromkeys(range(0, 3000, 7), 1000)
    _, meta = _read(_att_log(tmp_path / "slow.bin", [(10_000, 3000)], again))
    assert meta["messages"]["ATT"] == 3000 and meta["close_copies"] == len(again)


def test_a_rest_before_the_flight_does_not_hide_the_flights_copies(tmp_path):
    # 400-Hz ATT: 1,000 records of equal fields at rest (2.5 ms apart), then 2,000 moving, each written again
    # 0.7 ms later. A moving record's fields no other repeats: its copy is judged by itself, not by the rest's
    # interval (was: the rest's 2.5-ms median of ATT taken for every ATT, 0 of the 2,000 copies found)
    path = _att_log(tmp_path / "rest_then_fly.bin", [(2500, 3000)], dict.fromkeys(range(1000, 3000), 700),
                    yaw=lambda i: 90.0 if i < 1000 else 90.0 + 0.01 * (i - 999))
    _, meta = _read(path)
    assert meta["close_copies"] == 2000 and meta["messages"]["ATT"] == 3000


def test_a_rate_raised_within_a_boot_keeps_its_fast_records(tmp_path):
    # ATT of equal fields at 10 Hz (2,000 records) then at 1 kHz (1,000): every other fast record is read 1 ms after
    # an equal one. Judged by the whole log's median interval (100 ms) they were copies: 500 records dropped; by the
    # cadence of the last records of their key (CADENCE_SPAN), 1 kHz: none. Copies written into both stretches,
    # at the change too, are still found
    again = {5: 500, 1999: 400, 2000: 0, 2001: 0, 2600: 0}
    _, meta = _read(_att_log(tmp_path / "faster.bin", [(100_000, 2000), (1000, 1000)], again))
    assert meta["messages"]["ATT"] == 3000 and meta["close_copies"] == len(again)


def test_a_rate_lowered_within_a_boot_still_has_its_copies(tmp_path):
    # ATT of equal fields at 1 kHz (3,000) then at 10 Hz (500), every slow record written again 0.5 ms later. Judged
    # by the whole log's median interval (2 ms: the fast records, every other one read 1 ms after an equal one) none
    # of the 500 copies was one; by the local cadence (100 ms) every one is, and no fast record is
    again = dict.fromkeys(range(3000, 3500), 500)
    _, meta = _read(_att_log(tmp_path / "slower.bin", [(1000, 3000), (100_000, 500)], again))
    assert meta["messages"]["ATT"] == 3500 and meta["close_copies"] == len(again)


@pytest.mark.parametrize("slow_us", [100_000, 10_000])
def test_the_last_fast_record_before_a_rate_lowered_is_no_copy(tmp_path, slow_us):
    # ATT of equal fields at 1 kHz (3,001 records: every other one read 1 ms after an equal one, the last such too),
    # then at 10 Hz or 100 Hz (500). The last fast record came 1 ms after the one before it, as every fast record
    # did; judged by the local cadence it falls on the slow side of the change (the interval it falls in reaches
    # the first slow record) and was dropped as a copy: 1 false close copy, 3,500 ATT read of 3,501
    _, meta = _read(_att_log(tmp_path / "lowered.bin", [(1000, 3001), (slow_us, 500)]))
    assert meta["messages"]["ATT"] == 3501 and meta["close_copies"] == 0


def test_a_copy_of_the_last_fast_record_before_a_rate_lowered_is_still_a_copy(tmp_path):
    # as above, the last fast record read on its own (record 3,000) written again 0.3 ms later, before the last one
    # read 1 ms after an equal one (3,001), and every slow record 0.5 ms later: all those are copies, 3,001 none
    again = {3000: 300, **dict.fromkeys(range(3002, 3501), 500)}
    _, meta = _read(_att_log(tmp_path / "lowered_copies.bin", [(1000, 3001), (100_000, 500)], again))
    assert meta["messages"]["ATT"] == 3501 and meta["close_copies"] == len(again)
