"""A growing ``.tlog`` read where it grew (rplearn.io.tlog_tail): the rows handed out over many
polls are the offline reader's rows of the whole file, and a poll parses only the new messages."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from flightfiles import ground_flight

from rplearn.errors import InputError
from rplearn.io import ReaderOptions, read_logs
from rplearn.io._common import Logs
from rplearn.io.tlog import TlogDefects, write_tlog
from rplearn.io.tlog_copies import N_BINS
from rplearn.io.tlog_tail import DROPS, TlogTail, whole_records

ORIGIN = (47.3977, 8.5456, 90.0)
#: positions invalid for 15 s, a reboot at 200 s (10 s invalid after it), every reading twice
DEFECTS = TlogDefects(invalid_until_s=15.0, reboot_at_s=200.0, reboot_silence_s=5.0, invalid_after_reboot_s=10.0,
                      radio_twice=True)
#: The simulated flight keeps every THIN-th pose row and every THIN-th signal row of each direction (the same
#: seconds, a quarter of the messages: 25 Hz poses, ~22 Hz readings each way): what these tests read does not
#: depend on the messages' density, and pymavlink's pure-Python parsing of them was most of the file's time.
#: Byte counts that stand for seconds of flight (the pieces appended between polls) are divided by it.
THIN = 4


@pytest.fixture(scope="module")
def ground():
    """The ``ground`` flight (416 s), thinned by :data:`THIN` (its station row kept)."""
    pose, signal = ground_flight(10.0)
    pose = pose[(pose["node"] != "D") | (pose.groupby("node").cumcount() % THIN == 0)]
    signal = signal[signal.groupby(["tx", "rx"]).cumcount() % THIN == 0]
    return Logs(pose.reset_index(drop=True),
                signal[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]].reset_index(drop=True))


@pytest.fixture(scope="module")
def ground_260s(ground):
    """The first 260 s of ``ground`` (of 416 s): past :data:`DEFECTS`' reboot at 200 s and the
    15 s after it, with some 17,000 messages (:data:`THIN`) to tail in a hundred pieces."""
    end = float(ground.pose["t"].min()) + 260.0
    return Logs(ground.pose[ground.pose["t"] < end].reset_index(drop=True),
                ground.signal[ground.signal["t"] < end].reset_index(drop=True))


@pytest.fixture(scope="module")
def clean_260s(ground_260s, tmp_path_factory):
    """``ground_260s`` written once as a clean tlog (per module and xdist worker): tests read it,
    none writes to it (each grows its own copy in its own ``tmp_path``)."""
    whole = tmp_path_factory.mktemp("clean_260s") / "whole.tlog"
    write_tlog(ground_260s, whole, vehicle="D", station="G", origin_geodetic=ORIGIN)
    return whole


@pytest.fixture(scope="module")
def second_260s(ground_260s, tmp_path_factory):
    """``ground_260s`` written once as the tlog of a second vehicle (system 2), for
    :func:`_second_vehicle_twice` (read only)."""
    second = tmp_path_factory.mktemp("second_260s") / "second.tlog"
    write_tlog(ground_260s, second, vehicle="D", station="G", origin_geodetic=ORIGIN, system_id=2)
    return second


@pytest.fixture(scope="module")
def late_fix_260s(ground_260s, tmp_path_factory):
    """``ground_260s`` written once with its first 60 s of positions invalid (no origin, altitude
    0.8 m): the log of the two review-37 station tests (read only)."""
    whole = tmp_path_factory.mktemp("late_fix_260s") / "whole.tlog"
    write_tlog(ground_260s, whole, vehicle="D", station="G", origin_geodetic=ORIGIN,
               defects=TlogDefects(invalid_until_s=60.0))
    return whole


def _options(path) -> ReaderOptions:
    return ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, nodes={str(path): "D"}, station="G")


def _record_ends(data: bytes) -> np.ndarray:
    """The byte where each record of a whole tlog ends."""
    ends, i = [], 0
    while i < len(data):
        i += whole_records(data[i:i + 8 + 10 + 255 + 2 + 13][:8 + 10 + data[i + 9] + 2 + 13 * (data[i + 10] & 1)])
        ends.append(i)
    return np.asarray(ends)


def _grow(whole, grown, seed: int = 0):
    """Append ``whole``'s bytes to ``grown`` in random pieces (records cut anywhere), polling
    after each: the rows handed out and the messages parsed per poll against those appended."""
    data = whole.read_bytes()
    ends = _record_ends(data)
    grown.write_bytes(b"")
    tail = TlogTail(str(grown), _options(grown))
    rng = np.random.default_rng(seed)
    poses, signals, pos, done = [], [], 0, 0
    while pos < len(data):
        pos = min(len(data), pos + int(rng.integers(2_000 // THIN, 60_000 // THIN)))
        with grown.open("ab") as fh:
            fh.write(data[grown.stat().st_size:pos])
        p, s = tail.poll()
        whole_now = int(np.searchsorted(ends, pos, side="right"))  # records wholly written
        assert tail.parsed == whole_now - done  # only the new messages are parsed
        done = whole_now
        poses.append(p)
        signals.append(s)
    p, s = tail.poll(final=True)
    assert tail.parsed == 0 and done == len(ends)
    poses.append(p)
    signals.append(s)
    tail.close()
    return (pd.concat([x for x in poses if len(x)], ignore_index=True),
            pd.concat([x for x in signals if len(x)], ignore_index=True), tail)


#: every reading copied 0.2 ms later: copies within a quarter of the report period, merged by the reader
COPIES = TlogDefects(radio_twice=True, copy_delay_s=0.0002)


@pytest.mark.parametrize("defects", [DEFECTS, COPIES], ids=["invalid-start-reboot-doubled", "copies"])
def test_rows_handed_out_while_the_log_grows_are_the_offline_readers_rows(ground_260s, tmp_path, defects):
    """(The clean log: :func:`test_the_state_kept_between_polls_does_not_grow_with_the_log`.)"""
    whole, grown = tmp_path / "whole.tlog", tmp_path / "grown.tlog"
    written = write_tlog(ground_260s, whole, vehicle="D", station="G", origin_geodetic=ORIGIN, defects=defects)
    ref, meta = read_logs([str(whole)], _options(whole))
    if defects is COPIES:  # the offline reader merges the copies
        assert meta["files"][0]["signal"]["duplicate_reading"] >= written["radio"]
    else:  # the offline reader excludes what the defects spoil
        assert meta["files"][0]["reboots"] == 1 and written["radio"] > 0
        assert {p["reason"] for p in meta["files"][0]["excluded_periods"]} >= {"before_valid_position", "after_reboot"}
    poses, signals, tail = _grow(whole, grown)
    assert tail.dropped == dict.fromkeys(tail.dropped, 0)  # nothing appeared or vanished behind
    _assert_offline_rows(poses, signals, ref)


def _assert_offline_rows(poses: pd.DataFrame, signals: pd.DataFrame, ref: Logs) -> None:
    """The rows handed out are the offline reader's ``ref``, all columns."""
    rp = ref.pose.sort_values(["node", "t"], kind="stable").reset_index(drop=True)
    gp = poses.sort_values(["node", "t"], kind="stable").reset_index(drop=True)
    assert list(gp["node"].astype(str)) == list(rp["node"].astype(str))
    # the time base is fixed from each boot's first 100 messages, sync takes the whole log's
    # median: the boot clock's 1-ms ticks leave them ~0.1 ms apart; all else is equal (to the
    # last bits of the vectorised arithmetic over arrays of other lengths)
    assert np.abs(gp["t"].to_numpy() - rp["t"].to_numpy()).max() < 2e-4
    np.testing.assert_array_equal(gp["armed"].to_numpy(), rp["armed"].to_numpy())
    for c in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        np.testing.assert_allclose(gp[c].to_numpy(), rp[c].to_numpy(), rtol=0, atol=1e-12, err_msg=c)
    rs = ref.signal.sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    gs = signals.sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    assert len(gs) == len(rs) and list(gs.columns) == list(rs.columns)
    for c in rs.columns:
        np.testing.assert_array_equal(gs[c].to_numpy(), rs[c].to_numpy(), err_msg=c)


def test_whole_records_leaves_a_cut_record_for_later():
    from rplearn.io.tlog import _dialect

    mav = _dialect()
    enc = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    frame = enc.heartbeat_encode(2, 3, 0, 0, 4).pack(enc)
    record = b"\0" * 8 + frame
    assert whole_records(record * 3) == 3 * len(record)
    for cut in (1, 8, 9, 12, len(record) - 1):
        assert whole_records(record * 2 + record[:cut]) == 2 * len(record)
    assert whole_records(b"\0" * 8 + b"junk" * 5) == 28  # not a frame: left to pymavlink (BAD_DATA)


def test_a_tail_without_transmit_power_names_it(tmp_path):
    with pytest.raises(InputError, match="tx_power_dbm"):
        TlogTail(str(tmp_path / "x.tlog"), ReaderOptions(frequency_hz=433e6))


#: Bytes appended between two polls where a test's point is what a late message changes about
#: rows handed out earlier (the rows handed out before it over several polls), not the polls
#: themselves: about 8 s of the ground flight, 31 polls over 260 s.
LATE_PIECE_BYTES = 80_000 // THIN


def _poll_in_pieces(whole, grown, piece_bytes: int = 40_000 // THIN):
    """Append ``whole`` to ``grown`` a piece at a time (40 kB / :data:`THIN`: about 4 s of the ground flight),
    polling after each: the rows handed out, the tail, and its :meth:`TlogTail.sizes` after each
    poll with the share of the log's bytes read."""
    data = whole.read_bytes()
    grown.write_bytes(b"")
    tail = TlogTail(str(grown), _options(grown))
    poses, signals, sizes = [], [], []
    for pos in range(piece_bytes, len(data) + piece_bytes, piece_bytes):
        with grown.open("ab") as fh:
            fh.write(data[pos - piece_bytes:pos])
        p, s = tail.poll()
        poses.append(p)
        signals.append(s)
        sizes.append((pos / len(data), tail.sizes()))
    p, s = tail.poll(final=True)
    tail.close()
    return (pd.concat([x for x in [*poses, p] if len(x)], ignore_index=True),
            pd.concat([x for x in [*signals, s] if len(x)], ignore_index=True), tail, sizes)


def test_the_state_kept_between_polls_does_not_grow_with_the_log(clean_260s, tmp_path):
    """Over the 260 s of the clean log, the rows handed out are the offline reader's, and the
    most the tail keeps between polls in the second and third quarters of the log is the same
    as in the last quarter (the window of the last seconds and a summary): no structure grows
    with the flight (one growing with it would keep a third more at the end of the last quarter
    than at the end of the middle ones, whatever the log's length). (The first quarter holds
    the start, read whole until the station is known and the first rows are handed out.)"""
    ref, _ = read_logs([str(clean_260s)], _options(clean_260s))
    poses, signals, tail, sizes = _poll_in_pieces(clean_260s, tmp_path / "grown.tlog")

    def most(lo, hi):
        kept = [k for f, k in sizes if lo < f <= hi]
        return {name: max(k[name] for k in kept) for name in kept[-1]}

    middle, last = most(0.25, 0.75), most(0.75, 1.0)
    assert "rows" not in middle and "rows" not in last  # the messages of the whole log are no longer kept
    assert set(middle) == set(last)
    for name, n in last.items():
        assert n <= 1.05 * middle[name] + 8, (name, middle[name], n)
    # about 10 s of window: under 6,000 of the full flight's ~69,700 messages over 260 s (THIN); the copies'
    # histogram of gaps has its fixed N_BINS + 1 bins whatever the density
    assert last.pop("window.copies.bins") == N_BINS + 1
    assert max(last.values()) < 6_000 / 69_700 * len(_records(clean_260s.read_bytes())), last
    assert tail.dropped == dict.fromkeys(tail.dropped, 0)  # nothing appeared or vanished behind
    _assert_offline_rows(poses, signals, ref)


def test_a_position_jump_that_never_returns_withdraws_the_rows_handed_out_before_it(ground_260s, tmp_path):
    """A position that jumps 50 m mid-flight and stays (an origin set late) makes the offline
    reader exclude everything before the jump (only the last piece of a boot is surely valid):
    the rows handed out before it, most of them long behind the window, are counted withdrawn,
    and the rows after it are the offline reader's."""
    pose = ground_260s.pose.copy()
    jump_t = float(pose["t"].min()) + 200.0
    moved = (pose["node"] == "D") & (pose["t"] >= jump_t)
    pose.loc[moved, "z"] += 50.0
    whole, grown = tmp_path / "whole.tlog", tmp_path / "grown.tlog"
    write_tlog(Logs(pose, ground_260s.signal), whole, vehicle="D", station="G", origin_geodetic=ORIGIN)
    ref, meta = read_logs([str(whole)], _options(whole))
    reasons = {p["reason"] for p in meta["files"][0]["excluded_periods"]}
    assert reasons == {"before_valid_position"}
    poses, signals, tail, _ = _poll_in_pieces(whole, grown, LATE_PIECE_BYTES)
    vehicle = poses[poses["node"] == "D"]
    ref_vehicle = ref.pose[ref.pose["node"] == "D"]
    # the first row the offline reader keeps (the live time base may place it up to 2e-4 s earlier)
    cut = float(ref_vehicle["t"].min()) - 2e-4
    before = vehicle[vehicle["t"] < cut]
    assert len(before) > 0.5 * int((~moved & (pose["node"] == "D")).sum())  # handed out while they were valid
    assert tail.dropped["withdrawn_pose_rows"] == len(before)
    assert tail.dropped["withdrawn_signal_rows"] == int((signals["t"] < cut).sum())
    after = vehicle[vehicle["t"] >= cut].reset_index(drop=True)
    assert len(after) == len(ref_vehicle)
    for c in ("x", "y", "z", "qw"):
        np.testing.assert_allclose(after[c].to_numpy(), ref_vehicle[c].to_numpy(), rtol=0, atol=1e-12, err_msg=c)


def test_a_real_log_appended_in_pieces_gives_the_offline_readers_rows(tmp_path):
    """The real ground-station log of the fixtures (GPS fix types, heartbeats, a lost link at the
    end): the same rows as the offline reader, the vehicle's times shifted by one constant (its
    boot's time base, fixed from its first messages where ``sync`` takes the whole log's median)."""
    real = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_16-58-51.tlog"
    options = ReaderOptions(tx_power_dbm=20.0, frequency_hz=433e6)
    ref, meta = read_logs([str(real)], options)
    assert meta["files"][0]["signal"]["link_lost"] > 0
    data = real.read_bytes()
    grown = tmp_path / "grown.tlog"
    grown.write_bytes(b"")
    tail = TlogTail(str(grown), options)
    rng = np.random.default_rng(3)
    poses, signals, pos = [], [], 0
    while pos < len(data):
        pos = min(len(data), pos + int(rng.integers(2_000, 60_000)))
        with grown.open("ab") as fh:
            fh.write(data[grown.stat().st_size:pos])
        for out, new in zip((poses, signals), tail.poll(), strict=True):
            out.append(new)
    for out, new in zip((poses, signals), tail.poll(final=True), strict=True):
        out.append(new)
    assert tail.window is not None and tail.dropped == dict.fromkeys(tail.dropped, 0)
    gp, rp = (pd.concat([x for x in frames if len(x)]).sort_values(["node", "t"]).reset_index(drop=True)
              for frames in (poses, [ref.pose]))
    assert list(gp["node"]) == list(rp["node"])
    vehicle = (rp["node"] != "gcs").to_numpy()
    shift = gp["t"].to_numpy()[vehicle] - rp["t"].to_numpy()[vehicle]
    assert np.ptp(shift) < 1e-6 and abs(shift[0]) < 0.2
    for c in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        np.testing.assert_allclose(gp[c].to_numpy(), rp[c].to_numpy(), rtol=0, atol=1e-12, err_msg=c)
    gs = pd.concat([x for x in signals if len(x)]).sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    rs = ref.signal.sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    pd.testing.assert_frame_equal(gs, rs)


def _records(data: bytes) -> list[tuple[int, bytes]]:
    """(receive time [us], record) of every record of a whole tlog."""
    ends = _record_ends(data)
    starts = np.concatenate([[0], ends[:-1]])
    return [(int.from_bytes(data[a:a + 8], "big"), data[a:b]) for a, b in zip(starts, ends, strict=True)]


def _second_vehicle_twice(second, clean_260s, tmp_path, again_us: int):
    """The clean log (system 1) with a second vehicle (system 2, the tlog ``second``) heard from
    a third of the way on, each of its messages (but 51) received again ``again_us`` microseconds later."""
    ones = _records(clean_260s.read_bytes())
    late = [r for r in _records(second.read_bytes()) if r[0] > ones[len(ones) // 3][0] and r[1][8 + 5] != 51]
    again = [(t + again_us, (t + again_us).to_bytes(8, "big") + r[8:]) for t, r in late]
    whole = tmp_path / "whole.tlog"
    whole.write_bytes(b"".join(r[1] for r in sorted(ones + late + again, key=lambda r: r[0])))
    return whole


def test_a_second_vehicle_that_overtakes_the_first_withdraws_every_row_handed_out(second_260s, clean_260s, tmp_path):
    """The offline reader reads the system sending most ATTITUDE over the whole log; when a
    second one, heard from a third of the way on and twice as often, overtakes the vehicle the
    tail chose, every row handed out, before the change and after, is counted withdrawn."""
    # twice as often: each message again 2 ms later (an exact copy, same receive time, is one
    # message in the file twice, and one within 1 ms one message received twice: the offline
    # reader reads both once)
    whole, grown = _second_vehicle_twice(second_260s, clean_260s, tmp_path, 2_000), tmp_path / "grown.tlog"
    _, meta = read_logs([str(whole)], ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G"))
    assert meta["files"][0]["system_id"] == 2
    poses, signals, tail, _ = _poll_in_pieces(whole, grown, LATE_PIECE_BYTES)
    assert tail.dropped["withdrawn_pose_rows"] == len(poses[poses["node"] != "G"])  # before and after the change
    assert tail.dropped["withdrawn_signal_rows"] == len(signals)


def test_messages_received_twice_within_a_millisecond_are_read_once_as_offline(second_260s, clean_260s, tmp_path):
    """Review 44: a second vehicle's messages each received twice, 1 us apart (a router, or two
    links forwarding each): offline and the tail read each once (``close_copies``), so both keep
    the first vehicle, which sends more distinct messages, and the tail withdraws nothing (it
    had counted the copies, switched to the second vehicle and withdrawn every row)."""
    whole, grown = _second_vehicle_twice(second_260s, clean_260s, tmp_path, 1), tmp_path / "grown.tlog"
    ref, meta = read_logs([str(whole)], ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G"))
    assert meta["files"][0]["system_id"] == 1 and meta["files"][0]["close_copies"] > 0
    poses, signals, tail, _ = _poll_in_pieces(whole, grown, LATE_PIECE_BYTES)
    assert tail.dropped["close_copies"] == meta["files"][0]["close_copies"]
    assert tail.dropped["withdrawn_pose_rows"] == 0 and tail.dropped["withdrawn_signal_rows"] == 0
    assert len(poses[poses["node"] != "G"]) == len(ref.pose[ref.pose["node"] != "G"])


def test_a_log_with_close_copies_written_twice_is_counted_alike_by_tail_and_offline(clean_260s, tmp_path):
    """Review 44b: the log's first minute with every message received twice 1 us apart, the whole
    file then written again: offline drops the stretch written again first and the close copies
    after, as the tail meets them, so both count the same ``repeated_messages`` and ``close_copies``."""
    ones = [r for r in _records(clean_260s.read_bytes())]
    minute = [r for r in ones if r[0] - ones[0][0] < 60_000_000]
    doubled = sorted(minute + [(t + 1, (t + 1).to_bytes(8, "big") + r[8:]) for t, r in minute], key=lambda r: r[0])
    once = b"".join(r[1] for r in doubled)
    whole, grown = tmp_path / "whole.tlog", tmp_path / "grown.tlog"
    whole.write_bytes(once + once)
    _, meta = read_logs([str(whole)], _options(whole))
    info = meta["files"][0]
    assert info["close_copies"] > 0 and info["repeated_messages"] > 0
    _, _, tail, _ = _poll_in_pieces(whole, grown, LATE_PIECE_BYTES)
    assert (tail.dropped["close_copies"], tail.dropped["repeated_messages"]) == (info["close_copies"],
                                                                                info["repeated_messages"])


def test_bursts_of_messages_received_twice_are_counted_alike_by_tail_and_offline(clean_260s, tmp_path):
    """The log's first minute received in bursts of 8 messages (receive times 1 us apart), each burst again 4 us
    later: the copies are found among the last messages of their kind, by the tail as offline (was: only against
    the sender's last message of the kind, the tail and offline finding 68 of the 23,536 copies)."""
    every = _records(clean_260s.read_bytes())
    ones = [r for r in every if r[0] - every[0][0] < 60_000_000]
    parts = []
    for at in range(0, len(ones), 8):
        burst = [(ones[at][0] + j, r[8:]) for j, (_, r) in enumerate(ones[at:at + 8])]
        parts += [(t + d).to_bytes(8, "big") + frame for d in (0, 4) for t, frame in burst]
    whole, grown = tmp_path / "bursts.tlog", tmp_path / "grown.tlog"
    whole.write_bytes(b"".join(parts))
    ref, meta = read_logs([str(whole)], _options(whole))
    info = meta["files"][0]
    assert info["close_copies"] == info["messages"]["ATTITUDE"] + info["messages"]["GLOBAL_POSITION_INT"]
    poses, _, tail, _ = _poll_in_pieces(whole, grown, LATE_PIECE_BYTES)
    assert tail.dropped["close_copies"] == info["close_copies"]
    assert len(poses[poses["node"] != "G"]) == len(ref.pose[ref.pose["node"] != "G"])


def _tail_withdraws_then_gives_syncs_rows(whole: Path, grown: Path) -> dict:
    """``whole`` read by the tail in late pieces (``grown``) against ``sync``'s reading of it: the tail ends at sync's
    station, every vehicle row (and signal row) it handed out before sync's first vehicle row is counted withdrawn,
    the vehicle rows after it are sync's. Returns sync's metadata of the file."""
    ref, meta = read_logs([str(whole)], _options(whole))
    poses, signals, tail, _ = _poll_in_pieces(whole, grown, LATE_PIECE_BYTES)
    assert tail._station == pytest.approx(tuple(meta["files"][0]["station_geodetic"]), abs=1e-9)
    vehicle = poses[poses["node"] == "D"].sort_values("t").reset_index(drop=True)
    ref_vehicle = ref.pose[ref.pose["node"] == "D"].sort_values("t").reset_index(drop=True)
    cut = float(ref_vehicle["t"].min()) - 2e-4
    before, after = vehicle[vehicle["t"] < cut], vehicle[vehicle["t"] >= cut].reset_index(drop=True)
    assert len(before) > 0 and tail.dropped["withdrawn_pose_rows"] == len(before)
    assert tail.dropped["withdrawn_signal_rows"] == int((signals["t"] < cut).sum())
    assert len(after) == len(ref_vehicle)
    for c in ("x", "y", "z"):
        np.testing.assert_allclose(after[c].to_numpy(), ref_vehicle[c].to_numpy(), rtol=0, atol=1e-9, err_msg=c)
    return meta


def test_a_home_position_after_the_station_was_taken_from_a_fix_moves_the_station(late_fix_260s, tmp_path):
    """Review 37: positions invalid (no origin, altitude 0.8 m) for the first 60 s, so no
    ``HOME_POSITION`` for longer than :data:`HOME_WAIT_S`: the tail takes its station from the
    first fix, then ``HOME_POSITION`` arrives, which ``sync`` takes as the station of the whole
    log. The rows handed out after it are ``sync``'s (same station, same positions), and every row
    handed out in the other frame before it is counted withdrawn: none silently ~90 m off."""
    meta = _tail_withdraws_then_gives_syncs_rows(late_fix_260s, tmp_path / "grown.tlog")
    assert {p["reason"] for p in meta["files"][0]["excluded_periods"]} == {"before_valid_position"}


def test_a_station_taken_from_a_fix_found_invalid_later_moves_to_syncs_first_valid_fix(late_fix_260s, tmp_path):
    """Review 37: a log with no origin message at all (``HOME_POSITION``, ``GPS_GLOBAL_ORIGIN``
    removed) whose first 60 s of positions are invalid (altitude 0.8 m): the tail takes the
    first fix as its station after :data:`HOME_WAIT_S`; the step at 60 s makes ``sync`` exclude
    those fixes and take the first valid fix after them. The rows handed out after it are
    ``sync``'s, every row handed out before counted withdrawn."""
    whole, grown = tmp_path / "whole.tlog", tmp_path / "grown.tlog"
    whole.write_bytes(b"".join(r for _, r in _records(late_fix_260s.read_bytes()) if int.from_bytes(r[8 + 7:8 + 10], "little") not in (242, 49)))
    meta = _tail_withdraws_then_gives_syncs_rows(whole, grown)
    assert "first position fix" in meta["files"][0]["station_note"]


def test_the_state_kept_does_not_grow_with_a_long_gap_of_position_fixes(clean_260s, tmp_path):
    """Review 37: 180 s without ``GLOBAL_POSITION_INT`` (attitude and radio reports go on; 18
    times the window of the last seconds): the rows are still the offline reader's, but the most
    the tail keeps during the gap should stay that of the window of the last seconds, as before
    it (kept since the gap began, it was 12 times that after 280 s of gap)."""
    records = _records(clean_260s.read_bytes())
    t0 = records[0][0]
    kept = [(t, r) for t, r in records if not (int.from_bytes(r[8 + 7:8 + 10], "little") == 33 and 60e6 < t - t0 < 240e6)]
    whole, grown = tmp_path / "whole.tlog", tmp_path / "grown.tlog"
    whole.write_bytes(b"".join(r for _, r in kept))
    ends = np.cumsum([len(r) for _, r in kept]) / whole.stat().st_size

    def share_read(at_s: float) -> float:
        """The share of the log's bytes written up to ``at_s`` [s] of flight."""
        return float(ends[np.searchsorted([t - t0 for t, _ in kept], at_s * 1e6)])

    ref, _ = read_logs([str(whole)], _options(whole))
    poses, signals, tail, sizes = _poll_in_pieces(whole, grown)
    assert len(poses) == len(ref.pose) and len(signals) == len(ref.signal)
    assert tail.dropped == dict.fromkeys(tail.dropped, 0)
    before = max(k["window.att"] for f, k in sizes if share_read(20.0) < f <= share_read(60.0))
    during = max(k["window.att"] for f, k in sizes if share_read(90.0) < f <= share_read(240.0))
    assert during <= 2 * before, (before, during)


def test_glitches_that_return_leave_the_counts_balanced(ground_260s, tmp_path):
    """Review 37: twenty 1-s position glitches of 60 m that return: ``sync`` excludes each
    glitch; the tail hands out the same rows, so what it counts withdrawn and late must balance
    (rows handed out - withdrawn + late = ``sync``'s rows). A poll during a glitch found every
    piece before it invalid (the glitch the boot's last piece) and the next one valid again:
    the flips were counted each way (~20k rows withdrawn, ~21.5k late, the glitches' own
    messages counted late and never taken back)."""
    pose = ground_260s.pose.copy()
    t0 = float(pose["t"].min())
    vehicle = pose["node"] == "D"
    for k in range(20):
        a = t0 + 40.0 + 8.0 * k
        pose.loc[vehicle & (pose["t"] >= a) & (pose["t"] < a + 1.0), "z"] += 60.0
    whole, grown = tmp_path / "whole.tlog", tmp_path / "grown.tlog"
    write_tlog(Logs(pose, ground_260s.signal), whole, vehicle="D", station="G", origin_geodetic=ORIGIN)
    ref, meta = read_logs([str(whole)], _options(whole))
    assert {p["reason"] for p in meta["files"][0]["excluded_periods"]} == {"invalid_position"}
    poses, signals, tail, _ = _poll_in_pieces(whole, grown)
    got = np.sort(poses.loc[poses["node"] == "D", "t"].to_numpy())
    want = np.sort(ref.pose.loc[ref.pose["node"] == "D", "t"].to_numpy())
    assert len(got) == len(want) and np.abs(got - want).max() < 2e-4 and len(signals) == len(ref.signal)
    d = tail.dropped
    assert len(poses) - d["withdrawn_pose_rows"] + d["late_pose_rows"] == len(ref.pose), d
    assert len(signals) - d["withdrawn_signal_rows"] + d["late_signal_rows"] == len(ref.signal), d


@pytest.mark.xfail(strict=True, reason="review 37: the signal counts are 22 rows short of balance (handed out - "
                   "withdrawn + late = 4755 against sync's 4733 over the first 260 s at full density, 19766 against 19744 over the "
                   "whole 416 s; the pose rows balance); cause not traced (not from the pieces' counts by received "
                   "messages: none turned valid without rows handed out)")
def test_glitches_then_a_jump_that_stays_leave_the_signal_counts_balanced(ground_260s, tmp_path):
    """Review 37: twenty returning 1-s glitches, then a 50-m jump at 240 s that stays (``sync``
    excludes everything before it): rows handed out - withdrawn + late = ``sync``'s rows. Before
    the net counts (review 37) the pose rows were 3998 off and the signal rows 6055; now the pose
    rows balance and the signal rows are 22 off. (The first 260 s of the flight hold the glitches
    and the 20 s after the jump: the same 22 rows off as the whole 416 s.)"""
    pose = ground_260s.pose.copy()
    t0 = float(pose["t"].min())
    vehicle = pose["node"] == "D"
    for k in range(20):
        a = t0 + 20.0 + 10.0 * k
        pose.loc[vehicle & (pose["t"] >= a) & (pose["t"] < a + 1.0), "z"] += 60.0
    pose.loc[vehicle & (pose["t"] >= t0 + 240.0), "z"] += 50.0
    whole, grown = tmp_path / "whole.tlog", tmp_path / "grown.tlog"
    write_tlog(Logs(pose, ground_260s.signal), whole, vehicle="D", station="G", origin_geodetic=ORIGIN)
    ref, meta = read_logs([str(whole)], _options(whole))
    assert "before_valid_position" in {p["reason"] for p in meta["files"][0]["excluded_periods"]}
    poses, signals, tail, _ = _poll_in_pieces(whole, grown)
    d = tail.dropped
    assert len(poses) - d["withdrawn_pose_rows"] + d["late_pose_rows"] == len(ref.pose), d
    assert len(signals) - d["withdrawn_signal_rows"] + d["late_signal_rows"] == len(ref.signal), d


@pytest.mark.parametrize("copies", [2, 2.5])
def test_a_log_in_the_file_twice_is_read_once_live_as_offline(tmp_path, copies):
    """The real log 18-31-24 written into the file again (whole, or a third copy cut short):
    the tail hands out the offline reader's rows and counts the same repeated messages (before:
    3,596 signal rows instead of 2,228, 82 pose rows counted late)."""
    real = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_18-31-24.tlog"
    data = real.read_bytes()
    twice = tmp_path / "twice.tlog"
    twice.write_bytes(data * 2 + (data[:len(data) // 2] if copies == 2.5 else b""))
    options = ReaderOptions(tx_power_dbm=20.0, frequency_hz=433e6)
    ref, meta = read_logs([str(twice)], options)
    assert meta["files"][0]["repeated_messages"] > 0
    tail, poses, signals = _tail_while_growing(twice, tmp_path / "grown.tlog", options, seed=5)
    assert tail.dropped["repeated_messages"] == meta["files"][0]["repeated_messages"]
    assert {k: n for k, n in tail.dropped.items() if k != "repeated_messages"} == dict.fromkeys(DROPS[:-1], 0)
    gp = pd.concat([x for x in poses if len(x)]).sort_values(["node", "t"]).reset_index(drop=True)
    rp = ref.pose.sort_values(["node", "t"]).reset_index(drop=True)
    assert list(gp["node"]) == list(rp["node"])
    gs = pd.concat([x for x in signals if len(x)]).sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    rs = ref.signal.sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    pd.testing.assert_frame_equal(gs, rs)


def _tail_while_growing(source: Path, grown: Path, options: ReaderOptions, seed: int):
    """Tail ``grown`` while ``source``'s bytes are appended to it in random pieces of 2-60 kB:
    the closed tail and the pose and signal tables of every poll."""
    grown.write_bytes(b"")
    tail = TlogTail(str(grown), options)
    rng = np.random.default_rng(seed)
    poses, signals, pos, whole = [], [], 0, source.read_bytes()
    while pos < len(whole):
        pos = min(len(whole), pos + int(rng.integers(2_000, 60_000)))
        with grown.open("ab") as fh:
            fh.write(whole[grown.stat().st_size:pos])
        for out, new in zip((poses, signals), tail.poll(), strict=True):
            out.append(new)
    for out, new in zip((poses, signals), tail.poll(final=True), strict=True):
        out.append(new)
    tail.close()
    return tail, poses, signals


def _record_starts(data: bytes) -> list[int]:
    from rplearn.io.tlog_tail import whole_records

    starts, at = [], 0
    while at < len(data):
        starts.append(at)
        at += whole_records(data[at:at + 8 + 280])  # the first record of what follows
    return starts


@pytest.mark.parametrize("stretch", ["middle", "last_3", "last_1"])
def test_a_later_stretch_in_the_file_again_is_read_once_live_as_offline(tmp_path, stretch):
    """A copy of a stretch not starting at the file's first record (was: FileCopy found only a
    copy from the start, so the tail handed out the copy's rows and counted no repeats while
    the offline reader dropped them)."""
    real = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_18-31-24.tlog"
    data = real.read_bytes()
    starts = _record_starts(data)
    part = {"middle": data[starts[len(starts) // 3]:starts[len(starts) // 2]], "last_3": data[starts[-3]:],
            "last_1": data[starts[-1]:]}[stretch]
    copied = tmp_path / "copied.tlog"
    copied.write_bytes(data + part)
    options = ReaderOptions(tx_power_dbm=20.0, frequency_hz=433e6)
    ref, meta = read_logs([str(copied)], options)
    assert meta["files"][0]["repeated_messages"] > 0 or stretch != "middle"
    tail, poses, signals = _tail_while_growing(copied, tmp_path / "grown.tlog", options, seed=7)
    assert tail.dropped["repeated_messages"] == meta["files"][0]["repeated_messages"]
    assert {k: n for k, n in tail.dropped.items() if k != "repeated_messages"} == dict.fromkeys(DROPS[:-1], 0)
    gs = pd.concat([x for x in signals if len(x)]).sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    rs = ref.signal.sort_values(["t", "tx"], kind="stable").reset_index(drop=True)
    pd.testing.assert_frame_equal(gs, rs)
    gp = pd.concat([x for x in poses if len(x)])
    assert len(gp) == len(ref.pose)


def test_file_copy_finds_the_file_written_again_from_its_start(tmp_path):
    from rplearn.io.tlog_tail import FileCopy

    rec = [bytes([i]) * 10 for i in range(4)]
    path = tmp_path / "f.bin"
    path.write_bytes(b"".join(rec) + rec[0] + rec[1] + rec[3] + rec[0])
    copy = FileCopy(str(path))
    verdicts = [copy.repeats(10 * i, 10 * i + 10) for i in range(8)]
    copy.close()
    # rec0..3 new; rec0, rec1 repeat from the start; rec3 at 60 is not rec2: new; rec0 again: a copy
    assert verdicts == [False, False, False, False, True, True, False, True]


def test_a_corrupt_position_fix_is_refused_live_as_offline_naming_the_log(ground, tmp_path):
    """One position fix 60 km up (a corrupt record) in the first 120 s of ``ground``: the offline
    reader and the tail of the growing log both refuse it, in one line naming the log."""
    end = float(ground.pose["t"].min()) + 120.0
    pose = ground.pose[ground.pose["t"] < end].reset_index(drop=True)
    d = pose.index[pose["node"] == "D"]
    pose.loc[d[len(d) // 2], "z"] = 60_000.0
    whole, grown = tmp_path / "whole.tlog", tmp_path / "grown.tlog"
    write_tlog(Logs(pose, ground.signal[ground.signal["t"] < end].reset_index(drop=True)), whole, vehicle="D",
               station="G", origin_geodetic=ORIGIN)
    with pytest.raises(InputError, match=r"altitude \[m\] 60090") as offline:
        read_logs([str(whole)], _options(whole))
    assert str(offline.value).startswith(f"{whole}: ") and "\n" not in str(offline.value)
    with pytest.raises(InputError, match=r"altitude \[m\] 60090") as live:
        _grow(whole, grown)
    assert str(live.value).startswith(f"{grown}: ") and "\n" not in str(live.value)
