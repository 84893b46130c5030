"""Cost of one poll of ``rplearn live``'s MAVLink source as the recorded ``.tlog`` grows.

A simulated flight (the ``ground`` preset flown there and back, over and over: about 42 minutes at
50 Hz) is written as a ``.tlog`` by the project's MAVLink writer (:func:`rplearn.io.write_tlog`);
copies of it are grown to 1, 5, 10 and 30 minutes of flight and each read by its own
:class:`rplearn.io.tlog_tail.TlogTail` (every earlier poll of the session done first). Then, in
turns (the marks timed alternately, so that a change of the machine's load falls on all of
them), one more second of records is appended to each copy and polled; the best of the repeats is
kept. Printed: ms per poll, messages parsed per poll, the ratio of each mark to the 1-minute mark
(the reference, timed in the same turns), the length of the structures the tail keeps between
polls, and, once per mark up to 10 minutes, the old way (the whole log read again by ``sync``'s
reader, :func:`rplearn.io.read_logs`).

Run: ``.venv/bin/python benchmarks/live_tlog.py`` (``--tiny``: marks at 0.25, 0.5 and 1 minute of
the flight's first 2 minutes, one repeat, the whole log read again at the 0.5-minute mark only).
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
#: The session's polls before a mark are made every this long of log [s].
WARM_UP_EVERY_S = 10.0
#: A mark in a silent stretch of the flight moves this long past its end [s].
SETTLE_AFTER_SILENCE_S = 30.0


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


def _there_and_back(frame: pd.DataFrame, end: float, laps: int) -> pd.DataFrame:
    """The rows, then the same rows flown backwards from ``end`` on, and so on ``laps`` times (a
    continuous flight ``laps`` times as long)."""
    parts, t = [frame], frame["t"].to_numpy()
    for k in range(1, laps):
        part = frame.iloc[::-1].copy() if k % 2 else frame.copy()
        part["t"] = (k * end + (end - t[::-1] if k % 2 else t - t[0])) + 0.01 * k
        parts.append(part)
    return pd.concat(parts, ignore_index=True)


def tlog(folder: str, laps: int, minutes: float | None = None) -> str:
    """The ``ground`` flight flown there and back ``laps`` times (about 7 minutes each), as a .tlog
    (only its first ``minutes`` when given)."""
    sim = simulate("ground", seed=1)
    pose, signal = sim.pose_log, sim.signal_log
    if minutes is not None:
        cut = float(min(pose["t"].min(), signal["t"].min())) + 60.0 * minutes
        pose, signal = pose[pose["t"] <= cut], signal[signal["t"] <= cut]
    g = pose[pose["node"] == "G"]
    station = g.iloc[:1].copy()
    station[["x", "y", "z"]] = g[["x", "y", "z"]].median().to_numpy()
    end = float(max(pose["t"].max(), signal["t"].max()))
    logs = Logs(pd.concat([_there_and_back(pose[pose["node"] == "D"], end, laps), station], ignore_index=True),
                _there_and_back(signal[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]]
                                .sort_values("t", kind="stable"), end, laps))
    path = os.path.join(folder, "flight.tlog")
    write_tlog(logs, path, vehicle="D", station="G", origin_geodetic=ORIGIN)
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="marks at 0.25, 0.5, 1 minute of a 2-minute flight, one repeat")
    parser.add_argument("--repeats", type=int, default=5, help="turns of polls timed (best kept)")
    args = parser.parse_args()
    marks, repeats, laps = ((0.5, 0.25, 1.0), 1, 1) if args.tiny else ((1.0, 5.0, 10.0, 30.0), args.repeats, 6)
    print(f"before: {load()} (uptime's 1/5/15-minute averages; 2 cores)")
    with tempfile.TemporaryDirectory() as folder:
        whole = tlog(folder, laps, 2.0 if args.tiny else None)
        data = open(whole, "rb").read()
        ends, times = record_ends(data)
        span_min = (times[-1] - times[0]) / 60.0
        print(f"synthetic .tlog: {len(ends):,} messages, {span_min:.1f} min, {len(data) / 1e6:.1f} MB")
        options = ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G")
        tails: dict[float, tuple[TlogTail, str, int]] = {}
        for mark in marks:
            if mark * 60.0 + repeats + 1 > (times[-1] - times[0]):
                print(f"  {mark:g} min: beyond the flight ({span_min:.1f} min), skipped")
                continue
            grown = os.path.join(folder, f"grown{mark:g}.tlog")
            at = int(np.searchsorted(times, times[0] + mark * 60.0))
            while times[at] - times[at - 1] > 1.0 or times[min(at + 200, len(times) - 1)] - times[at] > 5.0:
                at += 1  # out of a silent stretch of the flight (the vehicle on the ground): a mark in the stream
            if times[at] - times[0] > mark * 60.0 + 1.0:  # and on, to a poll like any other
                at = int(np.searchsorted(times, times[at] + SETTLE_AFTER_SILENCE_S))
                print(f"  {mark:g} min: in a silent stretch, moved to {(times[at] - times[0]) / 60.0:.2f} min")
            open(grown, "wb").close()
            tail = TlogTail(grown, ReaderOptions(tx_power_dbm=20.0, frequency_hz=2.412e9, station="G",
                                                 nodes={grown: "D"}))
            written = 0
            for t in [*np.arange(times[0] + WARM_UP_EVERY_S, times[at], WARM_UP_EVERY_S), times[at]]:
                nxt = int(np.searchsorted(times, t))  # the session's earlier polls
                with open(grown, "ab") as fh:
                    fh.write(data[written:ends[nxt]])
                written = int(ends[nxt])
                tail.poll()
            tails[mark] = (tail, grown, at)
        best = dict.fromkeys(tails, np.inf)
        parsed = dict.fromkeys(tails, 0)
        for _ in range(repeats):
            for mark, (tail, grown, at) in tails.items():  # in turns: the reference (1 min) among them
                nxt = int(np.searchsorted(times, times[at] + 1.0))
                with open(grown, "ab") as fh:
                    fh.write(data[ends[at]:ends[nxt]])
                tails[mark] = (tail, grown, nxt)
                t0 = time.perf_counter()
                tail.poll()
                best[mark] = min(best[mark], time.perf_counter() - t0)
                parsed[mark] = tail.parsed
        old = {}
        for mark, (_, grown, _) in tails.items():
            if (mark == marks[0]) if args.tiny else (mark <= 10.0):  # tiny: the reference's only (the same read)
                t0 = time.perf_counter()
                read_logs([grown], options)  # the old way: the whole log read again
                old[mark] = time.perf_counter() - t0
        ref = marks[0]
        for mark, (tail, _, _) in tails.items():
            kept = tail.sizes()
            largest = max(kept, key=kept.__getitem__)
            line = (f"  {mark:g} min: {best[mark] * 1e3:.1f} ms per poll ({parsed[mark]} messages parsed), "
                    f"{best[mark] / best[ref]:.2f}x the {ref:g}-min poll; state kept {sum(kept.values()):,} entries "
                    f"(largest {largest} {kept[largest]:,})")
            if mark in old:
                line += f"; whole log read again {old[mark] * 1e3:.0f} ms ({old[mark] / best[mark]:.1f}x the poll)"
            print(line)
            tail.close()
        for mark in dict.fromkeys((10.0, 30.0, marks[-1])):  # the target's ratio, and the longest's
            if mark in best and mark != ref:
                ratio = best[mark] / best[ref]
                verdict = f" (target within 1.3x: {'ok' if ratio <= 1.3 else 'MISS'})" if mark == 10.0 else ""
                print(f"ratio {mark:g}-min / {ref:g}-min poll: {ratio:.2f}x{verdict}")
    print(f"after: {load()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
