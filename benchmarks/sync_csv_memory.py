"""Benchmark: peak memory of ``rplearn sync`` on a big signal CSV (issue 10).

A signal log of N rows (default 5,000,000, both directions of one link over a 2-hour flight
with two 100 Hz pose logs) is written as CSV. Then, alternating, ``repeats`` times each, in a
fresh child process:

- **streamed**: the command-line ``rplearn sync`` (which reads CSV signal tables in chunks);
- **reference, whole**: the same matching done the pre-streaming way, the whole CSV read with
  ``read_logs``, matched with ``synchronise`` and written with ``write_table``.

Each child prints its peak resident memory (VmHWM); the best of each is printed with the
ratio streamed / whole and the 1 GiB budget. Both outputs are checked to hold the same rows.

Usage: ``python benchmarks/sync_csv_memory.py [--rows 5000000] [--repeats 2]`` (``--tiny``: 20,000
rows over 2 minutes, once).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sync import pose_logs, signal_chunk  # noqa: E402  (same flight model as benchmarks/sync.py)

CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
mode, pose, sig, out = sys.argv[1:5]
if mode == "streamed":
    from rplearn.cli import app
    try:
        app(["sync", "--poses", pose, "--signals", sig, "--link", "all", "-o", out])
    except SystemExit as e:
        assert not e.code, e.code
else:
    from rplearn.io import read_logs
    from rplearn.data.sync import synchronise
    from rplearn.io.files import write_table
    logs, _ = read_logs([pose, sig])
    write_table(synchronise(logs.pose, logs.signal).dataset, out)
hwm = [int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM:")][0]
print(json.dumps({"peak_mib": hwm / 1024, "seconds": time.perf_counter() - t0}))
"""


def write_inputs(folder: str, rows: int, duration_s: float) -> tuple[str, str]:
    pose_path = os.path.join(folder, "pose.parquet")
    sig_path = os.path.join(folder, "signal.csv")
    pose_logs(duration_s).to_parquet(pose_path, index=False)
    rng = np.random.default_rng(0)
    step = 500_000
    with open(sig_path, "w") as fh:
        for start in range(0, rows, step):
            chunk = signal_chunk(start, min(step, rows - start), rng, rate_hz=rows / duration_s)
            chunk.to_csv(fh, index=False, header=start == 0)
    return pose_path, sig_path


def run_child(mode: str, pose: str, sig: str, out: str) -> dict:
    proc = subprocess.run([sys.executable, "-c", CHILD, mode, pose, sig, out],
                          capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=5_000_000)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--duration-s", type=float, default=7200.0)
    ap.add_argument("--tiny", action="store_true", help="20,000 rows over 120 s, one repeat (seconds)")
    args = ap.parse_args()
    if args.tiny:
        args.rows, args.repeats, args.duration_s = 20_000, 1, 120.0
    import pyarrow.parquet as pq

    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        pose, sig = write_inputs(d, args.rows, args.duration_s)
        print(f"signal CSV: {args.rows:,} rows, {os.path.getsize(sig) / 2**20:.0f} MiB "
              f"(written in {time.perf_counter() - t0:.0f} s); pose log: 2 x 100 Hz over {args.duration_s:.0f} s")
        best: dict[str, dict] = {}
        for i in range(args.repeats):
            for mode in ("streamed", "whole"):
                out = os.path.join(d, f"{mode}.parquet")
                r = run_child(mode, pose, sig, out)
                print(f"  run {i + 1} {mode:8s}: peak {r['peak_mib']:7.0f} MiB, {r['seconds']:6.1f} s")
                if mode not in best or r["peak_mib"] < best[mode]["peak_mib"]:
                    best[mode] = r
        rows = {m: pq.ParquetFile(os.path.join(d, f"{m}.parquet")).metadata.num_rows for m in best}
        assert rows["streamed"] == rows["whole"], rows
        s, w = best["streamed"], best["whole"]
        print(f"matched rows: {rows['streamed']:,} (both)")
        print(f"peak memory, best of {args.repeats}: streamed {s['peak_mib']:.0f} MiB, whole {w['peak_mib']:.0f} MiB; "
              f"ratio streamed / whole = {s['peak_mib'] / w['peak_mib']:.2f}")
        print(f"time: streamed {s['seconds']:.1f} s, whole {w['seconds']:.1f} s; "
              f"ratio = {s['seconds'] / w['seconds']:.2f}")
        print(f"budget 1 GiB for the streamed sync: {'met' if s['peak_mib'] < 1024 else 'NOT met'}")


if __name__ == "__main__":
    main()
