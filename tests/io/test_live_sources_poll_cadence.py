"""rplearn.io.live_sources.CsvTail polled at the live loop's cadence (``run_live`` polls every 0.05 s
when idle, so a logger writing at 10 Hz is read a row or two per node per poll). Found by review45b:
the station rule of 23f9053 (a node standing still at the ENU origin as one pose is a station, handed
out at once) reads a node's first poll of one row as one pose, so a logger before its fix that logs
its attitude (turning, or noisy as a real autopilot's AHRS) is taken for a station and refused at its
jump, where ``sync`` on the whole file drops its zero rows and keeps the rest."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd

from rplearn.io.live_sources import CsvTail
from rplearn.io.options import ReaderOptions
from rplearn.io.tables import canonical_pose

POSE_HEAD = "t,node,x,y,z,qw,qx,qy,qz\n"


def _lines() -> list[str]:
    """Node A: 3 s at 0, 0, 0 before its fix, its attitude logged (turning), then a track 580 m away."""
    out = []
    for i in range(80):
        t, yaw = 0.1 * i, 0.01 * i
        xyz = "0,0,0" if i < 30 else f"{500 + 0.5 * (i - 30):g},300,50"
        out.append(f"{t:.2f},A,{xyz},{np.cos(yaw / 2):.9f},0,0,{np.sin(yaw / 2):.9f}\n")
    return out


def test_a_logger_before_its_fix_read_a_row_per_poll_ends_as_sync_reads_it(tmp_path):
    lines = _lines()
    offline, meta = canonical_pose(pd.read_csv(io.StringIO(POSE_HEAD + "".join(lines))), source="pose.csv",
                                   nan_policy="drop")
    assert {k: n for k, n in meta["dropped"].items() if n} == {"position_jump": 30}
    pose, signal = tmp_path / "pose.csv", tmp_path / "signal.csv"
    pose.write_text(POSE_HEAD)
    signal.write_text("t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n")
    tail = CsvTail(str(pose), str(signal), ReaderOptions(nan_policy="drop"))
    got = []
    for line in lines:  # one row per poll, as the live loop reads a 10 Hz logger
        with pose.open("a") as fh:
            fh.write(line)
        got.append(tail.poll().poses)  # was: InputError '... as one pose, taken for a station at the origin'
    last = tail.poll(final=True)
    got.append(last.poses)
    live = pd.concat([g for g in got if len(g)], ignore_index=True)
    assert len(live) == len(offline) == 50 and (live["x"] >= 500).all()
    assert last.dropped == {"position_jump": 30}
