"""Benchmark of the BLAS thread policy (issue 30, acceptance 2).

Each work below runs, alternately and best of several, under three settings of the one
override, ``RPLEARN_THREADS``: unset (the policy: threads from the work's size and the cores
free, ``rplearn.core.threads``), ``1`` (one BLAS thread) and the number of usable cores (every
thread: what predictions, spreads and big fits did before issue 30):

- ``fit_model`` SH-15 and SH-10 of the paper's size (56,164 samples, two nodes);
- ``NormalEquations.add`` of a 200,000-sample chunk at SH-10;
- ``predict_swarm`` of 10 drones x 1000 times with spreads;
- ``predict_dataset`` of 200,000 rows with spreads;
- the automatic order selection's order sweep (``validation_sweep``, SH-2..10, three units).

Printed per work: the times and the ratios policy / one thread (target <= 1.3 with a core
busy) and every thread / one thread. ``--busy`` first starts a process that keeps one core
busy (a Python loop) and stops it at the end; the report says which. ``--tiny``: small cases,
one round (seconds); the target is then not enforced.

Run: ``.venv/bin/python benchmarks/threads.py [--busy] [--rounds 5]``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

import numpy as np

from rplearn.core.geometry import Directions
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.threads import THREADS_ENV, free_cores, usable_cores
from rplearn.data.tables import LinkSamples
from rplearn.models import ModelSpec, fit_model

TARGET = 1.3


def samples(rng: np.random.Generator, n: int) -> LinkSamples:
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = np.arcsin(rng.uniform(-1.0, 1.0, (2, n)))
    y = 3 * np.sin(el[0]) + np.cos(az[1]) + rng.normal(0, 3.0, n)
    return LinkSamples(Directions(az[0], el[0], az[1], el[1]), np.zeros(n, np.intp), np.ones(n, np.intp), ("A", "B"),
                       y, np.full(n, 50.0), np.full(n, 2.4e9))


def works(tiny: bool) -> dict:
    """Name -> a call of the work (and the data it needs, built once)."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import pandas as pd
    from swarm import as_log, model_of, swarm_poses

    from rplearn.analysis.swarm import SwarmOptions, predict_swarm
    from rplearn.analysis.sweep import validation_sweep
    from rplearn.models.predict import predict_dataset

    rng = np.random.default_rng(0)
    n_fit = 2_000 if tiny else 56_164
    learn = samples(rng, n_fit)
    chunk = samples(rng, 5_000 if tiny else 200_000)
    units = {f"flight{i}": samples(rng, n_fit // 3) for i in range(3)}
    model = model_of(rng)
    n_drones, n_times = (4, 50) if tiny else (10, 1000)
    t, pos, quat = swarm_poses(n_drones, n_times)
    log = as_log(t, pos, quat)
    pattern_of = {f"d{i:03d}": ("A" if i % 2 == 0 else "B") for i in range(n_drones)}
    n_rows = 5_000 if tiny else 200_000
    q = rng.normal(size=(2, n_rows, 4))
    data = pd.DataFrame({"t": np.arange(n_rows) * 0.01, "tx": "A", "rx": "B", "tx_power_dbm": 20.0, "frequency_hz": 2.4e9,
                         **{f"{e}_{c}": rng.uniform(-50, 50, n_rows) for e in ("tx", "rx") for c in "xyz"},
                         **{f"{e}_{c}": q[i, :, j] for i, e in enumerate(("tx", "rx"))
                            for j, c in enumerate(("qw", "qx", "qy", "qz"))}})
    basis10 = ModelSpec("sh", 10).basis()
    return {
        "fit_model SH-15": lambda: fit_model(learn, ModelSpec("sh", 15)),
        "fit_model SH-10": lambda: fit_model(learn, ModelSpec("sh", 10)),
        "NormalEquations.add SH-10": lambda: NormalEquations(basis10, 2).add(
            chunk.directions, chunk.tx_index, chunk.rx_index, chunk.joint_gain_db),
        "predict_swarm with spreads": lambda: predict_swarm(model, log, 20.0, SwarmOptions(
            2.4e9, pattern_of, times_s=t, min_rssi_dbm=-80.0)),
        "predict_dataset with spreads": lambda: predict_dataset(model, data),
        "order sweep SH-2..10": lambda: validation_sweep(units, range(2, 11)),
    }


def timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--busy", action="store_true", help="keep one core busy with another process meanwhile")
    parser.add_argument("--rounds", type=int, default=5, help="best of this many")
    parser.add_argument("--tiny", action="store_true", help="small cases, one round (seconds)")
    args = parser.parse_args()
    rounds = 1 if args.tiny else args.rounds
    os.environ.pop(THREADS_ENV, None)
    busy = None
    if args.busy:
        busy = subprocess.Popen([sys.executable, "-c", "while True: pass"])
        time.sleep(2.0)
    try:
        settings = {"policy": None, "one thread": "1", "every thread": str(usable_cores())}
        ok = True
        print(f"usable cores {usable_cores()}, free now {free_cores()}, load {os.getloadavg()[0]:.2f}; "
              f"{'one core kept busy by another process' if busy else 'no busy process started'}")
        for name, fn in works(args.tiny).items():
            fn()  # warm-up
            best = dict.fromkeys(settings, float("inf"))
            for _ in range(rounds):
                for label, value in settings.items():  # alternately
                    if value is None:
                        os.environ.pop(THREADS_ENV, None)
                    else:
                        os.environ[THREADS_ENV] = value
                    best[label] = min(best[label], timed(fn))
            os.environ.pop(THREADS_ENV, None)
            ratio = best["policy"] / best["one thread"]
            ok &= ratio <= TARGET
            print(f"{name}: policy {best['policy'] * 1e3:.1f} ms, one thread {best['one thread'] * 1e3:.1f} ms, every "
                  f"thread {best['every thread'] * 1e3:.1f} ms; ratio policy / one thread {ratio:.2f}x (target "
                  f"{TARGET}), every thread / one thread {best['every thread'] / best['one thread']:.2f}x")
    finally:
        if busy is not None:
            busy.kill()
            busy.wait()
    print("targets met" if ok else "TARGETS MISSED")
    return 0 if ok or args.tiny else 1


if __name__ == "__main__":
    raise SystemExit(main())
