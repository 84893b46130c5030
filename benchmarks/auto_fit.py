"""Benchmark: ``fit --degree auto`` against one plain SH-10 fit on the paper's data (issue 11, acceptance 5).

The `paper` preset (seed 0) is simulated and synchronised (the A->B link, three learning units,
56,005 samples). Then, alternating, best of ``repeats`` each:

- **SH-10**: ``fit_model`` of a plain SH-10 (the reference; like every pattern fit it also
  stores its coverage grid, which auto fits store too);
- **auto**: ``fit_auto`` (per-unit statistics at the largest candidate order, grouped
  cross-validation from them, the final solve from the same statistics);
- **accumulation alone** at the largest candidate order (SH-15): the floor of any selection
  that considers SH-15, since its statistics must be accumulated once.

Printed: the times and the ratios auto / SH-10 (target 3) and floor / SH-10, by the wall clock
and by process CPU time (steadier on a shared machine).

Usage: ``python benchmarks/auto_fit.py [--repeats 5]``; ``--tiny``: the ``smoke`` preset, one
repeat (the smoke test of tests/test_benchmarks.py).
"""

from __future__ import annotations

import argparse
import tempfile
import time

from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.data.sync import SyncOptions
from rplearn.data.units import samples_of, split_units
from rplearn.io.files import read_dataset
from rplearn.models import ModelSpec, fit_model
from rplearn.models.auto import auto_orders, fit_auto
from rplearn.sim import simulate
from rplearn.workflows.logs import sync_logs


def timed(fn) -> tuple[float, float]:
    """Wall-clock and process CPU time of ``fn()`` [s]."""
    t0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - t0, time.process_time() - c0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--tiny", action="store_true", help="the smoke preset, one repeat (seconds)")
    args = ap.parse_args()
    preset = "smoke" if args.tiny else "paper"
    if args.tiny:
        args.repeats = 1
    with tempfile.TemporaryDirectory() as d:
        simulate(preset, seed=0, out_dir=f"{d}/f")
        sync_logs([f"{d}/f/pose_log.parquet"], [f"{d}/f/signal_log.parquet"], f"{d}/m.parquet",
                  sync_options=SyncOptions(link=("A", "B")))
        df = read_dataset(f"{d}/m.parquet")
    learn, _ = split_units(df, None, None)
    nodes = sorted(set(df["tx"]) | set(df["rx"]))
    per_unit = {u: samples_of(df, [u], "d", nodes=nodes) for u in learn}
    everything = samples_of(df, learn, "d", nodes=nodes)
    top = auto_orders("sh", len(everything), len(nodes))[-1]
    basis = ModelSpec("sh", top).basis()

    def accumulate():
        for s in per_unit.values():
            NormalEquations(basis, len(nodes)).add(s.directions, s.tx_index, s.rx_index, s.joint_gain_db)

    spec10 = ModelSpec("sh", 10)
    fit_model(everything, spec10), fit_auto(per_unit), accumulate()  # warm-up
    best = {"SH-10": float("inf"), "auto": float("inf"), "floor": float("inf")}
    cpu = dict(best)  # process CPU time: steadier than the wall clock on a shared machine
    for _ in range(args.repeats):
        for key, fn in (("SH-10", lambda: fit_model(everything, spec10)), ("auto", lambda: fit_auto(per_unit)),
                        ("floor", accumulate)):
            wall, used = timed(fn)
            best[key], cpu[key] = min(best[key], wall), min(cpu[key], used)
    _, sel = fit_auto(per_unit)
    print(f"{preset} data: {len(everything):,} learning samples in {len(per_unit)} units; candidates SH-2..SH-{top}")
    print(f"chosen: SH-{sel.order}, smoothing {sel.smoothing:.1e} ({len(sel.curve)} points of the validation curve)")
    print(f"best of {args.repeats}: SH-10 fit {best['SH-10'] * 1e3:.0f} ms, auto {best['auto'] * 1e3:.0f} ms, "
          f"accumulation at SH-{top} alone {best['floor'] * 1e3:.0f} ms")
    print(f"ratio auto / SH-10 = {best['auto'] / best['SH-10']:.2f} (target 3); "
          f"floor / SH-10 = {best['floor'] / best['SH-10']:.2f}")
    print(f"CPU time: SH-10 fit {cpu['SH-10'] * 1e3:.0f} ms, auto {cpu['auto'] * 1e3:.0f} ms, accumulation "
          f"{cpu['floor'] * 1e3:.0f} ms; ratio auto / SH-10 = {cpu['auto'] / cpu['SH-10']:.2f}, floor / SH-10 = "
          f"{cpu['floor'] / cpu['SH-10']:.2f}")


if __name__ == "__main__":
    main()
