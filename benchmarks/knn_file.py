"""Benchmark of the k-NN model file (issue 13, item 5): training samples in a binary sidecar.

Saves and loads an NN-400 model of 150,000 training samples (a campaign's worth) both ways, alternately, best of
several: the model file with its sidecar (``model.json`` + ``model.json.<sha>.npz``, what ``save``
writes) and the same payload as JSON text (what the files held before). Prints the times,
the sizes and the ratios. Target: loading well under a second.

Run: ``.venv/bin/python benchmarks/knn_file.py`` (``--tiny``: NN-40 of 5,000 samples, once).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

from rplearn.core.geometry import Directions
from rplearn.data.tables import LinkSamples
from rplearn.io.modelfile import named_sidecar, write_model_file
from rplearn.models.baselines import KNNModel
from rplearn.models.load import load_model

N = 150_000


def best(fn, repeats=3):
    out = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out = min(out, time.perf_counter() - t0)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="NN-40 of 5,000 samples, one round (seconds)")
    args = parser.parse_args()
    n, k, rounds = (5_000, 40, 1) if args.tiny else (N, 400, 3)
    rng = np.random.default_rng(0)
    samples = LinkSamples(Directions(*rng.uniform(-1.0, 1.0, (4, n))), np.zeros(n, int), np.ones(n, int), ("A", "B"),
                          rng.normal(size=n), np.full(n, 10.0))
    model = KNNModel.fit(samples, k)
    with tempfile.TemporaryDirectory() as d:
        new, old = os.path.join(d, "nn.json"), os.path.join(d, "nn_text.json")
        t_save_new = t_save_old = t_load_new = t_load_old = float("inf")
        for _ in range(rounds):
            t_save_new = min(t_save_new, best(lambda: model.save(new), 1))
            t_save_old = min(t_save_old, best(lambda: write_model_file(old, "knn", model.to_dict()), 1))
            t_load_new = min(t_load_new, best(lambda: load_model(new), 1))
            t_load_old = min(t_load_old, best(lambda: load_model(old), 1))
        size_new = os.path.getsize(new) + os.path.getsize(named_sidecar(new))
        size_old = os.path.getsize(old)
    print(f"NN-{k}, {n:,} training samples")
    print(f"  save: sidecar {t_save_new:.3f} s, JSON text {t_save_old:.3f} s ({t_save_old / t_save_new:.0f}x)")
    print(f"  load: sidecar {t_load_new:.3f} s, JSON text {t_load_old:.3f} s ({t_load_old / t_load_new:.0f}x)")
    print(f"  size: sidecar + model file {size_new / 2**20:.1f} MiB, JSON text {size_old / 2**20:.1f} MiB")
    ok = t_load_new < 0.5
    print("targets met" if ok else "TARGETS MISSED")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
