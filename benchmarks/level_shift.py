"""Benchmark: does a constant added to every RSSI value change a fit (issue 24, item 3)?

With uncalibrated power (``sync --rssi-scale relative``) the level of the RSSI values is
arbitrary: adding a constant to all of them must shift every prediction by that constant and
change nothing else. A simulated flight (preset ``ground`` by default, seed 0) is synchronised
with ``rssi_scale="relative"``; for every shift its RSSI values (the joint gains) are moved by the shift, the
default automatic fit (``fit_auto``) and the automatic fit with a reference prior (the true
patterns with 2 dB RMS smooth error, mounted 10 degrees off, as ``tests/models/test_prior.py``)
are learned on the learning units, and the held-out RMSE on the test unit is printed with the
chosen order and smoothing.

Then the ratio of the largest to the smallest held-out RMSE over the shifts (1 when a shift
changes nothing).

Usage: ``python benchmarks/level_shift.py [--preset ground] [--seed 0] [--shifts -100 -50 0 50 100]``
(``--tiny``: the ``smoke`` preset, shifts 0 and 50).
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path

import numpy as np

from rplearn.data.sync import SyncOptions
from rplearn.data.tables import LinkSamples
from rplearn.data.units import samples_of, split_units
from rplearn.io.files import read_dataset
from rplearn.io.reference import read_reference_pattern
from rplearn.models import ModelSpec
from rplearn.models.auto import fit_auto
from rplearn.models.fit import FittedModel, evaluate_models
from rplearn.models.options import FitOptions
from rplearn.models.reference import reference_model
from rplearn.sim import imperfect_reference, simulate
from rplearn.workflows.logs import sync_logs


def shifted(samples: LinkSamples, shift_db: float) -> LinkSamples:
    """The samples with ``shift_db`` added to every RSSI value (so to every joint gain; shifting the
    table's ``rssi_dbm`` could land a value on a reader's sentinel)."""
    return dataclasses.replace(samples, joint_gain_db=np.asarray(samples.joint_gain_db, np.float64) + shift_db)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="ground")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--shifts", type=float, nargs="+", default=[-100.0, -50.0, 0.0, 50.0, 100.0])
    parser.add_argument("--tiny", action="store_true", help="the smoke preset, shifts 0 and 50 (seconds)")
    args = parser.parse_args()
    if args.tiny:
        args.preset, args.shifts = "smoke", [0.0, 50.0]
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        sim = simulate(args.preset, seed=args.seed, out_dir=str(d / "f"))
        sync_logs([str(d / "f" / "pose_log.parquet")], [str(d / "f" / "signal_log.parquet")], str(d / "m.parquet"),
                  sync_options=SyncOptions(rssi_scale="relative"))
        df = read_dataset(str(d / "m.parquet"))
        nodes = sorted(set(df["tx"]) | set(df["rx"]))
        refs = {}
        for n in nodes:
            imperfect_reference(sim.ground_truth, n, 2.0, 10.0, seed=args.seed).to_csv(d / f"ref_{n}.csv", index=False)
            refs[n] = read_reference_pattern(d / f"ref_{n}.csv")
        prior = reference_model(refs)
        learn, test = split_units(df, None, None)
        base = {u: samples_of(df, [u], "d", nodes=nodes) for u in learn}
        base_test = samples_of(df, test, "d", nodes=nodes)
        print(f"preset {args.preset}, seed {args.seed}: {len(df):,} samples, learning {', '.join(learn)}, test {', '.join(test)}")
        print(f"{'shift_db':>8} {'auto_rmse':>9} {'order':>5} {'smoothing':>9} {'prior_rmse':>10} {'order':>5} {'smoothing':>9}")
        rmses: dict[str, list[float]] = {"auto": [], "prior": []}
        for shift in args.shifts:
            per_unit = {u: shifted(s, shift) for u, s in base.items()}
            held = shifted(base_test, shift)
            row = [f"{shift:>8g}"]
            for name, options in (("auto", FitOptions(auto=True)), ("prior", FitOptions(auto=True, priors={n: prior for n in nodes}))):
                fitted, sel = fit_auto(per_unit, options=options)
                rmse = evaluate_models([FittedModel(ModelSpec("sh", sel.order), fitted.model, 0.0)], held)[0].rmse_db
                rmses[name].append(rmse)
                row += [f"{rmse:>9.3f}", f"{sel.order:>5d}", f"{sel.smoothing:>9.1e}"]
            print(" ".join(row))
        print("ratio of the largest to the smallest held-out RMSE over the shifts: "
              + ", ".join(f"{k} {max(v) / min(v):.4f}" for k, v in rmses.items()))


if __name__ == "__main__":
    main()
