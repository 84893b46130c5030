"""Benchmark of pattern evaluation for planners: gain of one node toward many directions.

Prints, for SH-10 and one million body-frame directions, the time and peak memory of
:meth:`rplearn.models.patterns.PatternSet.evaluate` (chunked, never forms the design matrix) as ratios
against a reference measured in the same run: numpy's matrix-vector product ``F @ c`` of the
already-built float64 design matrix ``F`` (1,000,000 x 100, 0.8 GB), i.e. the cost of merely
reading the features. Building ``F`` is not counted in the reference.

Run: ``.venv/bin/python benchmarks/predict.py`` (``--tiny``: 20,000 directions).
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np

from rplearn.core.bases import SphericalHarmonics
from rplearn.models.patterns import PatternSet

N_DIRECTIONS = 1_000_000


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="20,000 directions, 2 rounds (seconds)")
    args = parser.parse_args()
    n, rounds = (20_000, 2) if args.tiny else (N_DIRECTIONS, 7)
    rng = np.random.default_rng(0)
    basis = SphericalHarmonics(10)
    model = PatternSet(basis=basis, nodes=("A", "B"), coef=rng.normal(0, 2, (2, basis.n_coef)))
    az = rng.uniform(-np.pi, np.pi, n)
    el = np.arcsin(rng.uniform(-1, 1, n))
    model.evaluate("A", az[:1000], el[:1000])  # warm-up: tables, scratch buffers
    tracemalloc.start()
    gain = model.evaluate("A", az, el)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    F = basis.design(az, el)
    c = model.coef[0]
    t_ours = t_ref = float("inf")
    for _ in range(rounds):  # alternately: this machine's speed drifts within a minute
        t0 = time.perf_counter()
        gain = model.evaluate("A", az, el)
        t_ours = min(t_ours, time.perf_counter() - t0)
        t0 = time.perf_counter()
        ref = F @ c
        t_ref = min(t_ref, time.perf_counter() - t0)
    err = float(np.max(np.abs(gain - ref)))
    print(f"SH-10 gain toward {n:,} directions")
    print(f"  PatternSet.evaluate:         {t_ours * 1e3:7.1f} ms   ({n / t_ours / 1e6:.1f} M directions/s)")
    print(f"  F @ c, F already built:      {t_ref * 1e3:7.1f} ms   ratio ours/ref = {t_ours / t_ref:.2f}")
    print(f"  peak traced memory of evaluate: {peak / 2**20:.1f} MiB (the design matrix alone: {F.nbytes / 2**20:.0f} MiB)")
    print(f"  max |difference|: {err:.1e} dB")
    return 0 if err < 1e-9 else 1


if __name__ == "__main__":
    raise SystemExit(main())
