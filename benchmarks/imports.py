"""Benchmark of what ``rplearn fit`` spends importing (issue 13, item 4).

Runs ``python -X importtime -m rplearn.cli fit DATA --degree 6 -o M.json`` on a small
simulated dataset, alternating with the reference ``python -X importtime -c "import numpy,
pandas, pyarrow.parquet"`` (the floor of any command that reads a Parquet table into pandas),
best of ``--repeats``, and prints the sum of the top-level imports of each, their ratio and the
largest top-level imports of the fit. Target: under 0.5 s.

Run: ``.venv/bin/python benchmarks/imports.py`` (``--tiny``: one repeat, the target not enforced).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile


def import_times(args: list[str], cwd: str) -> tuple[float, list[tuple[float, str]]]:
    """Sum of the top-level imports [s] of a Python run, and each top-level import [s]."""
    # as a user runs it: modules load from their bytecode caches (a session that sets
    # PYTHONDONTWRITEBYTECODE would compile rplearn's modules from source at every start)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    proc = subprocess.run([sys.executable, "-X", "importtime", *args], cwd=cwd, capture_output=True, text=True, env=env)
    if proc.returncode:
        raise SystemExit(proc.stderr[-2000:])
    top = []
    for line in proc.stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        _, cumulative, name = line[len("import time:"):].split("|")
        if not name.startswith("  ") and name.strip():
            top.append((int(cumulative) / 1e6, name.strip()))
    return sum(t for t, _ in top), sorted(top, reverse=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--tiny", action="store_true", help="one repeat; the target is printed, not enforced")
    args = parser.parse_args()
    if args.tiny:
        args.repeats = 1
    from rplearn.sim.flight import simulate

    with tempfile.TemporaryDirectory() as d:
        simulate("smoke", seed=1).matched_truth.to_parquet(os.path.join(d, "m.parquet"))
        fit = ["-m", "rplearn.cli", "fit", "m.parquet", "--degree", "6", "-o", "m.json"]
        floor = ["-c", "import numpy, pandas, pyarrow.parquet"]
        best_fit, best_floor, detail = float("inf"), float("inf"), []
        if not args.tiny:  # (a tiny run times nothing it enforces)
            import_times(fit, d)  # writes the bytecode caches of an editable install
        for _ in range(args.repeats):
            t, top = import_times(fit, d)
            if t < best_fit:
                best_fit, detail = t, top
            best_floor = min(best_floor, import_times(floor, d)[0])
    print(f"imports of `rplearn fit` (sum of top-level imports, best of {args.repeats}): {best_fit:.3f} s")
    print(f"  reference, numpy + pandas + pyarrow.parquet alone: {best_floor:.3f} s; ratio {best_fit / best_floor:.2f}x")
    print("  largest top-level imports: " + ", ".join(f"{n} {t * 1e3:.0f} ms" for t, n in detail[:8]))
    ok = best_fit < 0.5
    print("target met (under 0.5 s)" if ok else "TARGET MISSED (0.5 s)")
    return 0 if ok or args.tiny else 1


if __name__ == "__main__":
    raise SystemExit(main())
