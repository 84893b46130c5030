"""Benchmark of fleet fits (issue 13, item 3): partitioned Parquet, one process against Dask.

Simulates (once, cached in ``--data``) a fleet's flights written by ``simulate --preset
fleet`` until at least ``--samples`` matched samples (default 10 million, about 63 flights of
the paper's campaign by 4 drones), then fits SH-10 on the learning units of all of them:

- in one process (``rplearn fit DIR``: the parts read one after the other);
- on a 2-worker :class:`distributed.LocalCluster` (``rplearn fit DIR --dask local:2``).

Each run is a fresh Python process (so that its peak memory is its own), the two alternate,
best of ``--repeats``. Prints samples/s, the wall time (the cluster's start-up shown apart),
the peak resident memory of the process and, on Dask, of each worker; checks that the two
models agree to 1e-9.

Run: ``.venv/bin/python benchmarks/fleet.py`` (``--samples 2e6`` for a quick look; ``--tiny``: two
flights of the ``smoke`` preset in a fresh folder, SH-4, once).
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

ONE_RUN = r"""
import json, sys, time
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.workflows.learning import _fit_streamed
from rplearn.workflows.fleet import dask_client, worker_peak_rss_bytes
data, dask, out, order = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
spec = ModelSpec.parse("sh", order=order)
report = {}
if dask == "none":
    t0 = time.perf_counter()
    fit = _fit_streamed(data, spec, None, FitOptions(), out)
    report["fit_s"] = time.perf_counter() - t0
else:
    t0 = time.perf_counter()
    with dask_client(dask) as client:
        report["startup_s"] = time.perf_counter() - t0
        t1 = time.perf_counter()
        fit = _fit_streamed(data, spec, None, FitOptions(), out, client=client)
        report["fit_s"] = time.perf_counter() - t1
        report["workers_peak_bytes"] = worker_peak_rss_bytes(client)
report["samples"] = fit.n_samples
# VmHWM: ru_maxrss would keep the parent's high-water mark across fork and exec
report["peak_bytes"] = [int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM")][0] * 1024
print(json.dumps(report))
"""


def make_fleet(folder: str, samples: float, preset: str = "paper", flights: int | None = None) -> tuple[int, int]:
    """The cached fleet (flights, samples), simulated here when missing or too small."""
    from rplearn.sim.fleet import simulate_fleet

    meta_path = os.path.join(folder, "_fleet.json")
    if os.path.exists(meta_path):
        meta = json.load(open(meta_path))
        if meta["samples"] >= samples:
            return meta["flights"], meta["samples"]
        import shutil

        shutil.rmtree(folder)
    per_flight = 159_000
    flights = flights or int(np.ceil(samples / per_flight))
    t0 = time.perf_counter()
    result = simulate_fleet(folder, flights=flights, seed=11, preset=preset,
                            progress=lambda k, n: print(f"\r  simulated {k}/{n} flights", end="", flush=True))
    print(f"\n  {result.samples:,} samples in {flights} flights, {time.perf_counter() - t0:.0f} s")
    return flights, result.samples


def run(data: str, dask: str, out: str, order: int = 10) -> dict:
    proc = subprocess.run([sys.executable, "-c", ONE_RUN, data, dask, out, str(order)], capture_output=True, text=True)
    if proc.returncode:
        raise SystemExit(proc.stderr)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=float, default=10e6)
    parser.add_argument("--data", default=os.path.join(tempfile.gettempdir(), "rplearn-fleet-bench"))
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--tiny", action="store_true", help="two smoke flights in a fresh folder, SH-4, once (seconds)")
    args = parser.parse_args()
    order, preset = (4, "smoke") if args.tiny else (10, "paper")
    with tempfile.TemporaryDirectory() as d:
        if args.tiny:
            args.data, args.samples, args.repeats = os.path.join(d, "fleet"), 1, 1
        flights, total = make_fleet(args.data, args.samples, preset, 2 if args.tiny else None)
        best: dict[str, dict] = {}
        outs = {"none": os.path.join(d, "one.json"), "local:2": os.path.join(d, "dask.json")}
        for _ in range(args.repeats):
            for mode in ("none", "local:2"):
                r = run(args.data, mode, outs[mode], order)
                if mode not in best or r["fit_s"] < best[mode]["fit_s"]:
                    best[mode] = r
        from rplearn.models.load import load_model

        a, b = load_model(outs["none"]), load_model(outs["local:2"])
        diff = float(np.max(np.abs(np.asarray(a.coef) - np.asarray(b.coef))))
    mib = 2.0**20
    one, dk = best["none"], best["local:2"]
    print(f"SH-{order} on {flights} flights, {total:,} samples ({one['samples']:,} learning), partitioned Parquet; best of "
          f"{args.repeats}, alternating")
    print(f"  one process : {one['samples'] / one['fit_s']:>10,.0f} samples/s, {one['fit_s']:.1f} s, "
          f"peak {one['peak_bytes'] / mib:,.0f} MiB")
    workers = ", ".join(f"{v / mib:,.0f}" for v in dk["workers_peak_bytes"].values())
    print(f"  dask local:2: {dk['samples'] / dk['fit_s']:>10,.0f} samples/s, {dk['fit_s']:.1f} s "
          f"(+{dk['startup_s']:.1f} s cluster start), client peak {dk['peak_bytes'] / mib:,.0f} MiB, "
          f"workers' peaks {workers} MiB")
    print(f"  speed-up {one['fit_s'] / dk['fit_s']:.2f}x on 2 workers; largest coefficient difference {diff:.1e}")
    ok = diff < 1e-9 and dk["samples"] == one["samples"]
    print("models agree" if ok else "MODELS DIFFER")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
