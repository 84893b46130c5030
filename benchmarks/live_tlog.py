"""Cost of one poll of ``rplearn live``'s MAVLink source as the recorded ``.tlog`` grows.

A simulated flight (the ``ground`` preset flown there and back, about 14 minutes at 50 Hz) is written as a ``.tlog``
by the project's MAVLink writer (:func:`rplearn.io.write_tlog`); the file is then grown to 1, 5
and 10 minutes of flight and, at each mark, one more second of records is appended and polled
by :class:`rplearn.io.tlog_tail.TlogTail` (best of several such seconds). Printed: ms per poll,
messages parsed per poll, the ratio to the first mark, and, timed alternately, the old way (the
whole log read again by ``sync``'s reader, :func:`rplearn.io.read_logs`) and the ratio of the two.

Run: ``.venv/bin/python benchmarks/live_tlog.py`` (``--tiny``: marks at 0.5, 1 and 2 minutes,
one repeat).
"""

from __future__ import annotations

import argparse
import os
import struct
import sys
import tempfile
import time

import numpy as np
import pandas as pd

from rplearn.io import ReaderOptions, read_logs
from rplearn.io._common import Logs
from rplearn.io.tlog import write_tlog
from rplearn.io.tlog_tail import TlogTail, whole_records
from rplearn.sim.flight import simulate

ORIGIN = (47.3977, 8.5456, 90.0)


def load() -> str:
    return "load " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def record_ends(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """The byte where each record ends and its receive time [s]."""
    ends, times, i = [], [], 0
    while i < len(data):
        t = struct.unpack(">Q", data[i:i + 8])[0] * 1e-6
        n = whole_records(data[i:i + 8 + 10 + data[i + 9] + 2 + 13 * (data[i + 10] & 1)])
        if n == 0:
            break
        i += n
        ends.append(i)
        times.append(t)
    return np.asarray(ends), np.asarray(times)


def _there_and_back(frame: pd.DataFrame, end: float) -> pd.DataFrame:
    """The rows, then the same rows flown backwards from ``end`` on (a continuous flight twice as long)."""
    back = frame.iloc[::-1].copy()
    back["t"] = 2.0 * end - back["t"].to_numpy() + 0.01
    return pd.concat([frame, back], ignore_index=True)


def tlog(folder: str) -> str:
    """The ``ground`` flight, then flown backwards (about 14 minutes), written as a .tlog."""
    sim = simulate("ground", seed=1)
    pose, signal = sim.pose_log, sim.signal_log
    g = pose[pose["node"] == "G"]
    station = g.iloc[:1].copy()
    station[["x", "y", "z"]] = g[["x", "y", "z"]].median().to_numpy()
    end = float(max(pose["t"].max(), signal["t"].max()))
    logs = Logs(pd.concat([_there_and_back(pose[pose["node"] == "D"], end), station], ignore_index=True),
                _there_and_back(signal[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]], end))
    path = os.path.join(folder, "flight.tlog")
    write_tlog(logs, path, vehicle="D", station="G", origin_geodetic=ORIGIN)
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="marks at 0.5, 1, 2 minutes, one repeat")
    args = parser.parse_args()
    marks, repeats = ((0.5, 1.0, 2.0), 1) if args.tiny else ((1.0, 5.0, 10.0), 3)
    print(f"before: {load()} (uptime's 1/5/15-minute averages; 2 cores)")
    with tempfile.TemporaryDirectory() as folder:
        whole = tlog(folder)
        data = open(whole, "rb").read()
        ends, times = record_ends(data)
        span_min = (times[-1] - times[0]) / 60.0
        print(f"synthetic .tlog: {len(ends):,} messages, {span_min:.1f} min, {len(data) / 1e6:.1f} MB")
        grown = os.path.join(folder, "grown.tlog")
        options = ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G")
        rows = []
        for mark in marks:
            if mark * 60.0 + repeats + 1 > (times[-1] - times[0]):
                print(f"  {mark:g} min: beyond the flight ({span_min:.1f} min), skipped")
                continue
            at = int(np.searchsorted(times, times[0] + mark * 60.0))
            with open(grown, "wb") as fh:
                fh.write(data[:ends[at]])
            tail = TlogTail(grown, options)
            tail.poll()  # the flight so far (the session's earlier polls)
            best, best_old, parsed = np.inf, np.inf, 0
            for k in range(repeats):
                nxt = int(np.searchsorted(times, times[at] + 1.0))
                with open(grown, "ab") as fh:
                    fh.write(data[ends[at]:ends[nxt]])
                at = nxt
                t0 = time.perf_counter()
                tail.poll()
                best = min(best, time.perf_counter() - t0)
                parsed = tail.parsed
                if k == 0 or not args.tiny:
                    t0 = time.perf_counter()
                    read_logs([grown], options)  # the old way: the whole log read again
                    best_old = min(best_old, time.perf_counter() - t0)
            tail.close()
            rows.append((mark, best * 1e3, parsed, best_old * 1e3))
    first = rows[0][1]
    for mark, ms, parsed, old in rows:
        print(f"  {mark:g} min: {ms:.1f} ms per poll ({parsed} messages parsed), ratio to the first "
              f"{ms / first:.2f}x; whole log read again {old:.0f} ms ({old / ms:.1f}x the poll)")
    print(f"after: {load()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
