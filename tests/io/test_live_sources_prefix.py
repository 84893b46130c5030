"""rplearn.io.live_sources.CsvTail on a pose CSV whose logger starts before the fix (rows at the zero
position, then the real track far away): the rows it keeps and the drops it counts are those of ``sync``'s
reader on the whole file (:func:`rplearn.io.tables.canonical_pose`), however the file is written in pieces;
a node's zero start is held back (bounded) until which side of its first jump is valid can be told."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.live_sources import HOLD_S, STATION_SPAN_S, CsvTail
from rplearn.io.options import ReaderOptions
from rplearn.io.tables import canonical_pose

POSE_HEAD = "t,node,x,y,z,qw,qx,qy,qz\n"
SIGNAL_HEAD = "t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n"


def _row(t: float, node: str, x: float, y: float, z: float, yaw_rad: float = 0.0) -> str:
    return f"{t:.2f},{node},{x:g},{y:g},{z:g},{np.cos(yaw_rad / 2):.9f},0,0,{np.sin(yaw_rad / 2):.9f}\n"


def _prefix_log(n_zero: int, n_real: int, other: bool = True, sentinel_at: int | None = None) -> list[str]:
    """Node A: ``n_zero`` rows at 0, 0, 0 (before the fix; its attitude logged, turning) then ``n_real`` rows
    of a track 580 m away (a ``z = -1000`` sentinel at real row ``sentinel_at``); node B, interleaved, a track
    of its own."""
    lines = []
    for i in range(n_zero + n_real):
        t = 0.1 * i
        if i < n_zero:
            lines.append(_row(t, "A", 0, 0, 0, yaw_rad=0.01 * i))
        else:
            k = i - n_zero
            lines.append(_row(t, "A", 500 + 0.5 * k, 300, -1000 if k == sentinel_at else 50))
        if other:
            lines.append(_row(t + 0.05, "B", 10 + 0.3 * i, -20, 30))
    return lines


def _offline(lines: list[str]) -> tuple[pd.DataFrame, dict[str, int]]:
    df = pd.read_csv(io.StringIO(POSE_HEAD + "".join(lines)))
    pose, meta = canonical_pose(df, source="pose.csv", nan_policy="drop")
    return pose, {k: n for k, n in meta["dropped"].items() if n}


def _live(tmp_path, lines: list[str], cuts: list[int]) -> tuple[pd.DataFrame, dict[str, int], list[int]]:
    """The rows a tail hands out with the file written in pieces (ending at ``cuts``), then a final poll."""
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text(POSE_HEAD)
    signal.write_text(SIGNAL_HEAD)
    tail = CsvTail(str(pose), str(signal), ReaderOptions(nan_policy="drop"))
    got, per_poll, start = [], [], 0
    for end in [*cuts, len(lines)]:
        with pose.open("a") as fh:
            fh.write("".join(lines[start:end]))
        start = end
        polled = tail.poll()
        got.append(polled.poses)
        per_poll.append(len(polled.poses))
    last = tail.poll(final=True)
    got.append(last.poses)
    rows = pd.concat([g for g in got if len(g)], ignore_index=True)
    return rows, last.dropped, per_poll


def _same_rows(live: pd.DataFrame, offline: pd.DataFrame) -> None:
    key = ["node", "t"]
    a = live.sort_values(key, kind="stable").reset_index(drop=True)
    b = offline.sort_values(key, kind="stable").reset_index(drop=True)
    pd.testing.assert_frame_equal(a[list(b.columns)], b, check_dtype=False)


def test_a_first_poll_of_zeros_only_ends_as_sync_reads_the_file(tmp_path):
    # was: the zeros were handed out, the real rows after them dropped as the wrong side, then refused
    # ("which side is valid is unclear"); sync drops the 30 zeros
    lines = _prefix_log(30, 120)
    offline, dropped = _offline(lines)
    assert dropped == {"position_jump": 30}
    first_real = 2 * 30  # A and B interleaved
    live, live_dropped, per_poll = _live(tmp_path, lines, [first_real, first_real + 20, first_real + 100])
    _same_rows(live, offline)
    assert live_dropped == dropped
    assert per_poll[0] == 30  # B's rows are not held: only A's zero start waits
    assert set(live["node"]) == {"A", "B"} and (live.loc[live["node"] == "A", "x"] >= 500).all()


@pytest.mark.parametrize("seed", range(6))
def test_written_in_random_pieces_the_tail_keeps_what_sync_keeps(tmp_path, seed):
    rng = np.random.default_rng(seed)
    n_zero, n_real = int(rng.integers(1, 40)), int(rng.integers(60, 150))
    lines = _prefix_log(n_zero, n_real, sentinel_at=int(rng.integers(5, 50)))
    cuts = sorted(set(rng.integers(1, len(lines), size=int(rng.integers(1, 12))).tolist()))
    offline, dropped = _offline(lines)
    live, live_dropped, _ = _live(tmp_path, lines, cuts)
    _same_rows(live, offline)
    assert live_dropped == dropped == {"position_jump": n_zero + 1}


@pytest.mark.parametrize("still", [False, True])
def test_a_node_that_starts_at_the_origin_and_moves_on_is_handed_out_when_it_moves(tmp_path, still):
    # odometry starting at 0, 0, 0: the first step is one the speeds explain, so the zeros are valid; held
    # until it moves (turning there, or standing still for less than STATION_SPAN_S: no station yet)
    lines = [_row(0.1 * i, "A", 0.0 if i < 5 else 0.2 * (i - 4), 0, 0, 0.0 if still else 0.01 * i) for i in range(20)]
    offline, dropped = _offline(lines)
    live, live_dropped, per_poll = _live(tmp_path, lines, [5, 8])
    assert per_poll[:2] == [0, 8] and not dropped and not live_dropped
    _same_rows(live, offline)


def test_a_node_standing_still_at_the_origin_is_a_station_handed_out_at_once(tmp_path):
    # the ENU origin is a station's natural place (positions measured from it): standing there as one pose for
    # STATION_SPAN_S its rows are handed out, so its links' rows are matched (held, they were dropped as
    # unknown_node for HOLD_S)
    assert STATION_SPAN_S <= 1.0
    steps = int(HOLD_S / 0.5) + 4
    lines = []
    for i in range(steps):
        lines += [_row(0.5 * i, "G", 0, 0, 0), _row(0.5 * i + 0.1, "A", 3 + 0.5 * i, 1, 10)]
    offline, dropped = _offline(lines)
    live, live_dropped, per_poll = _live(tmp_path, lines, [2, 2 * (steps - 6), 2 * (steps - 2)])
    assert per_poll == [1, 2 * (steps - 6) - 1, 8, 4]  # the station's first row waits until it stood STATION_SPAN_S
    _same_rows(live, offline)
    assert not dropped and not live_dropped


def test_a_still_node_at_the_origin_that_jumps_off_it_is_refused(tmp_path):
    # a logger before its fix that writes one pose (no attitude) looks like a station at the origin: handed out,
    # its jump to the real track is refused (the rows matched meanwhile cannot be taken back), naming why
    lines = [_row(0.1 * i, "A", 0, 0, 0) for i in range(15)] + [_row(1.5 + 0.1 * i, "A", 500, 300, 50) for i in range(30)]
    with pytest.raises(InputError, match=r"node A: it stood at the zero position from its first row as one pose, taken "
                                         r"for a station at the origin .* now jumps off it at t = 1\.500 s") as e:
        _live(tmp_path, lines, [15, 25])
    assert "\n" not in str(e.value)


def test_a_zero_start_longer_than_the_hold_is_refused_when_it_jumps_not_read_wrong(tmp_path):
    # beyond the bound the zeros are handed out as they stand; their jump to the real track is refused (was:
    # the rows 14 s or more after the jump read as reachable from the zeros, 610 zeros kept that sync drops)
    n_zero = int(HOLD_S / 0.1) + 10
    lines = _prefix_log(n_zero, 3 * n_zero, other=False)
    offline, dropped = _offline(lines)
    assert dropped == {"position_jump": n_zero}
    with pytest.raises(InputError, match=r"pose\.csv: fields x, y, z of node A: it stood at the zero position .* "
                                         r"now jumps off it at t = 61\.000 s: a logger writing before its fix") as e:
        _live(tmp_path, lines, [n_zero, n_zero + 5, 2 * n_zero + 20])
    assert "\n" not in str(e.value)


def _geodetic_log(n_zero: int, n_real: int) -> list[str]:
    """Node A in lat, lon, alt: ``n_zero`` rows at lat = lon = 0 (before the fix), then a track north."""
    return [f"{0.1 * i:.2f},A,{0.0 if i < n_zero else 47.0 + 2e-6 * i:.7f},{0.0 if i < n_zero else 8.0:.7f},"
            f"{0.0 if i < n_zero else 500.0:g},1,0,0,0\n" for i in range(n_zero + n_real)]


@pytest.mark.parametrize("n_zero", [0, 15])
def test_a_geodetic_table_written_in_pieces_stays_in_one_frame(tmp_path, n_zero):
    # was: each poll put its ENU origin at its own first fix, so the track went back to y = 0 at every poll
    lines = _geodetic_log(n_zero, 60)
    head = "t,node,lat,lon,alt,qw,qx,qy,qz\n"
    offline, meta = canonical_pose(pd.read_csv(io.StringIO(head + "".join(lines))), source="pose.csv",
                                   nan_policy="drop")
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text(head)
    signal.write_text(SIGNAL_HEAD)
    tail = CsvTail(str(pose), str(signal), ReaderOptions(nan_policy="drop"))
    got = []
    for a, b in ((0, n_zero + 10), (n_zero + 10, n_zero + 30), (n_zero + 30, len(lines))):
        with pose.open("a") as fh:
            fh.write("".join(lines[a:b]))
        got.append(tail.poll().poses)
    got.append(tail.poll(final=True).poses)
    _same_rows(pd.concat([g for g in got if len(g)], ignore_index=True), offline)
    assert meta["dropped"]["position_jump"] == n_zero
