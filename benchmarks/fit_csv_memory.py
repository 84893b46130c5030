"""Benchmark: peak memory of ``rplearn fit`` on a big matched-dataset CSV (issue 10).

A matched dataset of N rows (default 6,000,000, about 1.6 GB of CSV: two drones, random
positions and attitudes, SH-5 ground truth plus noise) is written as CSV. Then, alternating,
``repeats`` times each, in a fresh child process:

- **streamed**: the command-line ``rplearn fit --degree 5`` (a CSV this big is read a chunk at a
  time, :mod:`rplearn.models.streamed`);
- **reference, whole**: the pre-streaming way, ``read_dataset`` + ``samples_of`` + ``fit_model``.

Each child prints its peak resident memory (VmHWM) and the model's coefficients; the best of
each is printed with the ratio streamed / whole, and the two models are checked to agree.

Usage: ``python benchmarks/fit_csv_memory.py [--rows 6000000] [--repeats 2]`` (``--tiny``: 20,000
rows, once).
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
import pandas as pd

CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
mode, data, out = sys.argv[1:4]
if mode == "streamed":
    from rplearn.cli import app
    try:
        app(["fit", data, "--degree", "5", "-o", out])
    except SystemExit as e:
        assert not e.code, e.code
    from rplearn.models import load_model
    model = load_model(out)
else:
    from rplearn.io.files import read_dataset
    from rplearn.data.units import learning_units, samples_of
    from rplearn.models import ModelSpec, fit_model
    df = read_dataset(data)
    model = fit_model(samples_of(df, learning_units(df, None, data).units, data), ModelSpec("sh", 5)).model
hwm = [int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM:")][0]
print(json.dumps({"peak_mib": hwm / 1024, "seconds": time.perf_counter() - t0, "coef": model.coef.ravel().tolist()}))
"""


def write_dataset(path: str, rows: int, chunk: int = 500_000) -> None:
    from rplearn.core.geometry import quat_wxyz_from_yaw

    rng = np.random.default_rng(0)
    with open(path, "w") as fh:
        for start in range(0, rows, chunk):
            n = min(chunk, rows - start)
            a_to_b = rng.random(n) < 0.5
            cols = {"t": (start + np.arange(n)) / 100.0, "tx": np.where(a_to_b, "A", "B"), "rx": np.where(a_to_b, "B", "A"),
                    "rssi_dbm": np.round(rng.uniform(-85, -35, n)), "tx_power_dbm": 20.0, "frequency_hz": 2.412e9}
            for end in ("tx", "rx"):
                xyz = rng.uniform(-100, 100, (n, 3))
                xyz[:, 2] = rng.uniform(5, 60, n)
                q = quat_wxyz_from_yaw(rng.uniform(-np.pi, np.pi, n))
                cols.update({f"{end}_{c}": xyz[:, i] for i, c in enumerate("xyz")})
                cols.update({f"{end}_{c}": q[:, i] for i, c in enumerate(("qw", "qx", "qy", "qz"))})
            cols["unit"] = "learn_0"
            pd.DataFrame(cols).to_csv(fh, index=False, header=start == 0, float_format="%.6f")


def run_child(mode: str, data: str, out: str) -> dict:
    proc = subprocess.run([sys.executable, "-c", CHILD, mode, data, out], capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=6_000_000)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--tiny", action="store_true", help="20,000 rows, one repeat (seconds)")
    args = ap.parse_args()
    if args.tiny:
        args.rows, args.repeats = 20_000, 1
    with tempfile.TemporaryDirectory() as d:
        data = os.path.join(d, "matched.csv")
        t0 = time.perf_counter()
        write_dataset(data, args.rows)
        print(f"matched CSV: {args.rows:,} rows, {os.path.getsize(data) / 2**20:.0f} MiB (written in {time.perf_counter() - t0:.0f} s)")
        best: dict[str, dict] = {}
        for i in range(args.repeats):
            for mode in ("streamed", "whole"):
                r = run_child(mode, data, os.path.join(d, f"{mode}.json"))
                print(f"  run {i + 1} {mode:8s}: peak {r['peak_mib']:7.0f} MiB, {r['seconds']:6.1f} s")
                if mode not in best or r["peak_mib"] < best[mode]["peak_mib"]:
                    best[mode] = r
        s, w = best["streamed"], best["whole"]
        diff = float(np.max(np.abs(np.array(s["coef"]) - np.array(w["coef"]))))
        print(f"largest coefficient difference streamed - whole: {diff:.2e}")
        print(f"peak memory, best of {args.repeats}: streamed {s['peak_mib']:.0f} MiB, whole {w['peak_mib']:.0f} MiB; "
              f"ratio streamed / whole = {s['peak_mib'] / w['peak_mib']:.2f}")
        print(f"time: streamed {s['seconds']:.1f} s, whole {w['seconds']:.1f} s; ratio = {s['seconds'] / w['seconds']:.2f}")


if __name__ == "__main__":
    main()
