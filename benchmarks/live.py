"""Benchmark of ``rplearn live`` (issue 27, acceptance 2): the cost of a refit after each 1 s
batch, and memory over a long session.

A synthetic flight (a drone orbiting a static station at 50 packets a second, both directions
alternating, yawing as it goes; a smooth gain plus 2 dB of noise) is matched, then learned one
second at a time by :class:`rplearn.models.live_stats.LiveStatistics`: each batch's statistics
added, then a fixed-order SH-10 refit from them (2 nodes: 242 pattern columns; the solve, its
rank, condition number and covariance, as ``fit``). For each batch of the last minute of a
10-minute flight, the refit and the same-size reference, one dense Cholesky factorisation and
solve of a 242 x 242 system (scipy, one BLAS thread as the refit), are timed alternately;
printed: the median and 95th percentile [ms] and the ratio of the medians. Target: 95th
percentile under 20 ms.

Memory: a 1-hour flight through the whole session (matching, prediction, statistics, refits
every 10 s); the process's resident memory (RSS) is printed at 10, 30 and 60 minutes. What
grows by design is the duplicate-row hashes of the matching (8 bytes a signal row, as
``sync`` streaming) and the prequential record (two numbers a batch); the statistics and the
pose rows kept do not grow.

Run: ``.venv/bin/python benchmarks/live.py`` (``--tiny``: 2 and 6 minutes at 10 Hz, SH-6, the
target not enforced).
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

import numpy as np
import pandas as pd
import scipy.linalg

from rplearn.core.geometry import quat_wxyz_from_euler_ned_frd_deg
from rplearn.core.threads import blas_threads_for
from rplearn.data.sync import synchronise
from rplearn.models.live_stats import LiveStatistics
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.workflows.live import LiveOptions, replay_session

TARGET_MS = 20.0


def flight(minutes: float, rate_hz: float, seed: int = 0) -> tuple[pd.DataFrame, pd.DataFrame]:
    """A drone ``D`` orbiting station ``G`` (50 m, 20 m up), yawing; packets both ways."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, minutes * 60.0, 1.0 / rate_hz)
    ang = 2 * np.pi * t / 40.0
    yaw = np.degrees(2 * np.pi * t / 17.0) % 360.0
    pitch = 10.0 * np.sin(2 * np.pi * t / 23.0)
    q = quat_wxyz_from_euler_ned_frd_deg(np.zeros_like(t), pitch, yaw)
    drone = pd.DataFrame({"t": t, "node": "D", "x": 50 * np.cos(ang), "y": 50 * np.sin(ang),
                          "z": 20.0 + 5 * np.sin(ang / 3), "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3]})
    station = pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [1.5], "qw": [1.0], "qx": [0.0],
                            "qy": [0.0], "qz": [0.0]})
    ts = t[1:-1] + 0.5 / rate_hz
    tx = np.where(np.arange(ts.size) % 2 == 0, "D", "G")
    d = np.hypot(np.hypot(50.0, 50.0 * 0), 20.0)
    el = np.arctan2(20.0, 50.0)
    rssi = (20.0 - 20 * np.log10(4 * np.pi * d * 433e6 / 299_792_458.0) + 2.0 * np.cos(np.interp(ts, t, ang) * 3)
            + 3.0 * np.cos(el) ** 2 + rng.normal(0.0, 2.0, ts.size))
    signal = pd.DataFrame({"t": ts, "tx": tx, "rx": np.where(tx == "D", "G", "D"), "rssi_dbm": rssi,
                           "tx_power_dbm": 20.0, "frequency_hz": 433e6})
    return pd.concat([station, drone], ignore_index=True), signal


def rss_mib() -> float:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def refit_costs(minutes: float, rate_hz: float, order: int) -> tuple[list[float], list[float], list[float]]:
    """Each 1 s batch's statistics added, then a refit: the refits', the reference's and the
    additions' wall times [ms]."""
    pose, signal = flight(minutes, rate_hz)
    matched = synchronise(pose, signal).dataset
    spec = ModelSpec.parse("sh", order=order)
    live = LiveStatistics(spec, ["D", "G"], FitOptions())
    cols = 2 * (order + 1) ** 2
    rng = np.random.default_rng(1)
    a = rng.normal(size=(cols, cols))
    spd, rhs = a @ a.T + cols * np.eye(cols), rng.normal(size=cols)
    refits: list[float] = []
    refs: list[float] = []
    adds: list[float] = []
    t = matched["t"].to_numpy(np.float64)
    timed_from = 0.9 * minutes * 60.0
    with blas_threads_for(len(matched), cols):  # the reference on one BLAS thread too, as the refit
        for start_s in np.arange(0.0, minutes * 60.0, 1.0):
            rows = matched[(t >= start_s) & (t < start_s + 1.0)]
            if not len(rows):
                continue
            t0 = time.perf_counter()
            live.add(rows, live.samples(rows))
            added = 1e3 * (time.perf_counter() - t0)
            if live.n_samples < 4 * cols:
                continue
            t0 = time.perf_counter()
            live.refit()
            spent = 1e3 * (time.perf_counter() - t0)
            if start_s >= timed_from:
                refits.append(spent)
                adds.append(added)
                t0 = time.perf_counter()
                scipy.linalg.cho_solve(scipy.linalg.cho_factor(spd), rhs)
                refs.append(1e3 * (time.perf_counter() - t0))
    return refits, refs, adds


def memory(minutes: float, rate_hz: float, order: int, marks: list[float]) -> list[tuple[float, float]]:
    pose, signal = flight(minutes, rate_hz, seed=2)
    spec = ModelSpec.parse("sh", order=order)
    out: list[tuple[float, float]] = []
    left = sorted(marks)

    def on_update(status) -> None:
        if left and status.elapsed_s >= left[0] * 60.0:
            out.append((left.pop(0), rss_mib()))

    with tempfile.TemporaryDirectory() as d:
        replay_session(pose, signal, os.path.join(d, "m.json"), LiveOptions(spec=spec, fit=FitOptions(), refit_s=10.0),
                       batch_s=1.0, on_update=on_update)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="2 and 6 minutes at 10 Hz, SH-6 (seconds)")
    args = parser.parse_args()
    minutes, long_minutes, rate, order = (2.0, 6.0, 10.0, 6) if args.tiny else (10.0, 60.0, 50.0, 10)
    refits, refs, adds = refit_costs(minutes, rate, order)
    med, p95 = statistics.median(refits), float(np.percentile(refits, 95))
    ref = statistics.median(refs)
    print(f"refit after each 1 s batch (2 nodes, SH-{order}, {minutes:g} min at {rate:g} Hz; last tenth, "
          f"{len(refits)} refits): median {med:.1f} ms, 95th percentile {p95:.1f} ms "
          f"(adding the batch before it: median {statistics.median(adds):.1f} ms, coverage grid included)")
    print(f"reference (one dense Cholesky solve, {2 * (order + 1) ** 2} columns, timed alternately): median {ref:.2f} ms; "
          f"ratio refit / reference {med / ref:.1f}x")
    marks = [long_minutes / 6, long_minutes / 2, long_minutes]
    rss = memory(long_minutes, rate, order, marks)
    print("memory over a long session: " + ", ".join(f"{m:g} min {r:.0f} MiB" for m, r in rss)
          + f"; growth from the first to the last mark {rss[-1][1] - rss[0][1]:+.1f} MiB")
    met = p95 < TARGET_MS
    print(f"target (95th percentile under {TARGET_MS:g} ms): {'met' if met else 'MISSED'}")
    return 0 if met or args.tiny else 1


if __name__ == "__main__":
    raise SystemExit(main())
