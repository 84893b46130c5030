"""Benchmark of the joint fit (issue 2, acceptance 5).

Prints, for SH-10 (100 coefficients per node) and 56,164 samples of two nodes (the paper's
learning set size), the whole fit time (features and solve) as ratios against two references
measured in the same run:

(a) BLAS ``dsyrk`` (scipy.linalg.blas) of the same float64 design matrix (56,164 x 200), the
    Gram's one triangle without a copy of the design: the floor of any normal-equations method
    (numpy's ``X.T @ X`` is a full gemm, up to twice as slow); it runs with one BLAS thread and
    with the library's default alternately, and its best is kept (issue 30);
(b) the pipeline a user would write by hand: ``scipy.special.sph_harm_y`` per (l, m) for both
    nodes, then scikit-learn ``Ridge`` with the same ridge weight.

Targets: at most 1.5x (a), at least 30x faster than (b), predictions equal within 1e-6 dB.

Then the figure issue 30 asks for: ``fit_model`` (what ``rplearn fit`` runs: the features, the
Gram, the solve, the standard errors and the coverage grid every pattern model stores, whose
jobs run on the statistics' workers behind the last block of samples) of SH-10
on the paper preset's learning samples (seed 0, 56,005 samples, ``smoke`` with ``--tiny``)
against ``dsyrk`` of the float64 design matrix of the same samples (56,005 x 200), timed
alternately (wall clock, best of each; ``dsyrk`` with one BLAS thread and the default alternately)
and as process CPU time (target <= 1.5 both).
The fit can come under twice the floor although it also builds the features and solves
because, for SH, only the cross block ``X_tx^T X_rx`` (with ``X^T y``) goes through BLAS; the
two diagonal blocks come from (2L+1) x (4L-2) moment sums per node
(:meth:`rplearn.core.bases.SphericalHarmonics.gram_from_moments`), so the BLAS work is half the
floor's.
Then the peak memory of a fit over 10 million samples streamed in chunks (target < 1 GiB).
Then, with ``--swarm``, the many-node rows (issue 13): SH-10 with 10, 30 and 50 drones against
the ``X^T X`` floor of the same columns (``benchmarks/fit_swarm.py``, which also runs alone).

Run: ``.venv/bin/python benchmarks/fit.py [--quick]``. Timings are the best of several runs.
``--tiny`` (the smoke test of tests/test_benchmarks.py) runs a small case and checks the numbers only.
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
import tracemalloc
from contextlib import nullcontext

import numpy as np
from scipy.linalg.blas import dsyrk
from sklearn.linear_model import Ridge
from threadpoolctl import threadpool_limits

from rplearn.core.geometry import Directions
from rplearn.core.lsq.solver import JointFitOptions, NormalEquations, fit_joint, solve
from rplearn.core.sh import SphericalHarmonics, real_sh_reference

N_SAMPLES = 56_164
ORDER = 10
RIDGE = 1e-6


def best_of(fn, repeats: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def random_directions(rng: np.random.Generator, n: int) -> Directions:
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = np.arcsin(rng.uniform(-1.0, 1.0, (2, n)))
    return Directions(az[0], el[0], az[1], el[1])


def paper_samples(tiny: bool):
    """The learning samples of the paper preset (seed 0; ``smoke`` when tiny), link A -> B."""
    import tempfile

    from rplearn.data.sync import SyncOptions
    from rplearn.data.units import samples_of, split_units
    from rplearn.io.files import read_dataset
    from rplearn.sim import simulate
    from rplearn.workflows.logs import sync_logs

    with tempfile.TemporaryDirectory() as d:
        simulate("smoke" if tiny else "paper", seed=0, out_dir=f"{d}/f")
        sync_logs([f"{d}/f/pose_log.parquet"], [f"{d}/f/signal_log.parquet"], f"{d}/m.parquet",
                  sync_options=SyncOptions(link=("A", "B")))
        df = read_dataset(f"{d}/m.parquet")
    learn, _ = split_units(df, None, None)
    return samples_of(df, learn, "d", nodes=sorted(set(df["tx"]) | set(df["rx"])))


def fit_model_against_dsyrk(tiny: bool, repeats: int) -> tuple[float, bool]:
    """``fit_model`` SH-10 against ``dsyrk`` of the same samples' design (see the module
    docstring); returns the wall-clock ratio and whether the numbers agree (the Gram of the
    design equals the fit's statistics, the fit's predictions are those of plain least squares
    but for its small ridge)."""
    from rplearn.core.lsq.normal_equations import NormalEquations
    from rplearn.models import ModelSpec, fit_model

    samples = paper_samples(tiny)
    spec = ModelSpec("sh", 10)
    basis = spec.basis()
    d = samples.directions
    tx, rx = np.asarray(samples.tx_index), np.asarray(samples.rx_index)
    n_nodes = len(samples.nodes)
    p = basis.n_coef
    X = np.zeros((len(samples), n_nodes * p))
    rows = np.arange(len(samples))
    f_tx, f_rx = basis.design(d.az_tx, d.el_tx), basis.design(d.az_rx, d.el_rx)
    for k in range(n_nodes):
        X[rows[tx == k][:, None], k * p + np.arange(p)] += f_tx[tx == k]
        X[rows[rx == k][:, None], k * p + np.arange(p)] += f_rx[rx == k]
    Xt = X.T  # Fortran-ordered (columns, samples): dsyrk forms X^T X without copying the design
    fitted = fit_model(samples, spec)  # warm-up (imports, tables, buffers, BLAS threads)
    gram = dsyrk(1.0, Xt)
    stats = NormalEquations(basis, n_nodes).add(d, tx, rx, samples.joint_gain_db)
    gram_ok = bool(np.allclose(np.triu(gram), np.triu(stats.gram), rtol=1e-9, atol=1e-9 * len(samples)))
    wall = {"fit_model": float("inf"), "dsyrk": float("inf")}
    cpu = dict(wall)
    for r in range(max(2, repeats * 2)):
        t0, c0 = time.perf_counter(), time.process_time()
        fitted = fit_model(samples, spec)
        wall["fit_model"] = min(wall["fit_model"], time.perf_counter() - t0)
        cpu["fit_model"] = min(cpu["fit_model"], time.process_time() - c0)
        with threadpool_limits(1) if r % 2 == 0 else nullcontext():
            t0, c0 = time.perf_counter(), time.process_time()
            dsyrk(1.0, Xt)
            wall["dsyrk"] = min(wall["dsyrk"], time.perf_counter() - t0)
            if r % 2 == 0:  # CPU time of the one-thread runs (a spinning second thread counts too)
                cpu["dsyrk"] = min(cpu["dsyrk"], time.process_time() - c0)
    pred = X @ fitted.model.coef.ravel()
    y = np.asarray(samples.joint_gain_db, np.float64)
    plain = X @ np.linalg.lstsq(X, y, rcond=None)[0]  # unregularised, minimum norm: the same joint predictions
    pred_diff = float(np.max(np.abs(pred - plain)))
    grid = fitted.model.training.coverage_deg
    print(f"fit_model SH-10 on the {'smoke' if tiny else 'paper'} preset's {len(samples):,} learning samples "
          f"({X.shape[0]:,} x {X.shape[1]} design; coverage grid {np.mean(np.asarray(grid[samples.nodes[0]]) == 0):.0%} "
          f"occupied for {samples.nodes[0]})")
    print(f"  fit_model (features, Gram, solve, errors, coverage): {wall['fit_model'] * 1e3:8.1f} ms wall, "
          f"{cpu['fit_model'] * 1e3:8.1f} ms CPU")
    print(f"  dsyrk of its design:                                 {wall['dsyrk'] * 1e3:8.1f} ms wall, "
          f"{cpu['dsyrk'] * 1e3:8.1f} ms CPU (one thread)")
    ratio = wall["fit_model"] / wall["dsyrk"]
    print(f"  ratio fit_model / dsyrk = {ratio:.2f} wall, {cpu['fit_model'] / cpu['dsyrk']:.2f} CPU (target <= 1.5); "
          f"Gram equals the fit's statistics: {gram_ok}; max |prediction - plain least squares| {pred_diff:.1e} dB "
          f"(its ridge; target <= 0.05 dB{'' if not tiny else ', not for the tiny case, where the ridge dominates'})")
    return ratio, gram_ok and (tiny or pred_diff <= 0.05)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and 2 M streamed samples")
    parser.add_argument("--swarm", action="store_true", help="also the many-node rows (benchmarks/fit_swarm.py)")
    parser.add_argument("--tiny", action="store_true",
                        help="a smoke run (2,000 samples, SH-6, one repeat, 20,000 streamed); targets not enforced")
    parser.add_argument("--model-only", action="store_true",
                        help="only fit_model against dsyrk on the paper preset (issue 30)")
    args = parser.parse_args()
    repeats = 1 if args.tiny else 3 if args.quick else 7
    if args.model_only:
        ratio, numbers_ok = fit_model_against_dsyrk(args.tiny, repeats)
        return 0 if numbers_ok and (args.tiny or ratio <= 1.5) else 1
    n_samples, order = (2_000, 6) if args.tiny else (N_SAMPLES, ORDER)
    rng = np.random.default_rng(0)
    basis = SphericalHarmonics(order)
    d = random_directions(rng, n_samples)
    true = rng.normal(0, 2, (2, basis.n_coef))

    # Streaming: 10 million samples in chunks, never materialised at once; first, before any other fit: the solver's reusable block
    # buffer and the feature scratch arrays are then allocated while traced, so the peak counts them.
    total = 20_000 if args.tiny else 2_000_000 if args.quick else 10_000_000
    chunk = 10_000 if args.tiny else 200_000
    tracemalloc.start()
    t0 = time.perf_counter()
    normal = NormalEquations(basis, 2)
    stream_rng = np.random.default_rng(1)
    ones = np.ones(chunk, np.intp)
    zeros = np.zeros(chunk, np.intp)
    for _ in range(total // chunk):
        dc = random_directions(stream_rng, chunk)
        yc = np.concatenate(  # the benchmark's own data, made in small pieces
            [
                basis.design_t(dc.az_tx[s : s + 20_000], dc.el_tx[s : s + 20_000]).T @ true[0]
                + basis.design_t(dc.az_rx[s : s + 20_000], dc.el_rx[s : s + 20_000]).T @ true[1]
                for s in range(0, chunk, 20_000)
            ]
        )
        normal.add(dc, zeros, ones, yc)
        del dc, yc
    sol_stream = solve(normal, ridge=RIDGE)
    elapsed = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss_gib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    err = float(np.max(np.abs(sol_stream.coef[:, 1:] - true[:, 1:])))
    print(f"streamed fit of {total:,} samples in chunks of {chunk:,}: {elapsed:.1f} s")
    print(f"  peak traced memory {peak / 2**20:.0f} MiB (target < 1024 MiB); process max RSS {rss_gib:.2f} GiB")
    print(f"  max coefficient error (noise-free, shapes): {err:.1e}")

    y = basis.design(d.az_tx, d.el_tx) @ true[0] + basis.design(d.az_rx, d.el_rx) @ true[1]
    y += rng.normal(0, 3.0, n_samples)
    tx = np.zeros(n_samples, np.intp)
    rx = np.ones(n_samples, np.intp)

    X = np.hstack([basis.design(d.az_tx, d.el_tx), basis.design(d.az_rx, d.el_rx)])
    X = np.ascontiguousarray(X)
    Xt = X.T  # Fortran-ordered (columns, samples): dsyrk forms Xt Xt^T = X^T X without copying it
    fit_joint(d, tx, rx, y, 2, basis, options=JointFitOptions(ridge=RIDGE))  # warm-up (caches, BLAS threads)
    gram = dsyrk(1.0, Xt)
    floor_ok = np.allclose(np.triu(gram), np.triu(X.T @ X), rtol=1e-10, atol=1e-8 * n_samples)
    # Interleaved: this machine's speed drifts by tens of percent within a minute, so the fit
    # and its reference are timed alternately and the best of each is kept.
    t_ours = t_floor = float("inf")
    for r in range(repeats * 2):
        t, sol = best_of(lambda: fit_joint(d, tx, rx, y, 2, basis, options=JointFitOptions(ridge=RIDGE)), 1)
        t_ours = min(t_ours, t)
        with threadpool_limits(1) if r % 2 == 0 else nullcontext():
            t, _ = best_of(lambda: dsyrk(1.0, Xt), 1)
        t_floor = min(t_floor, t)

    def by_hand():
        Xs = np.hstack([real_sh_reference(order, d.az_tx, d.el_tx), real_sh_reference(order, d.az_rx, d.el_rx)])
        return Ridge(alpha=RIDGE, fit_intercept=False).fit(Xs, y), Xs

    # Also interleaved with runs of ours, so that both can meet the machine in the same mood.
    t_hand = t_ours_b = float("inf")
    for _ in range(max(2, repeats // 3)):
        t, sol = best_of(lambda: fit_joint(d, tx, rx, y, 2, basis, options=JointFitOptions(ridge=RIDGE)), 3)
        t_ours_b = min(t_ours_b, t)
        t, (ridge_model, Xs) = best_of(by_hand, 1)
        t_hand = min(t_hand, t)
    pred_ours = X @ sol.coef.ravel()
    pred_hand = ridge_model.predict(Xs)
    max_diff = float(np.max(np.abs(pred_ours - pred_hand)))

    print(f"SH-{order}, 2 nodes, {n_samples} samples, {2 * basis.n_coef} columns")
    print(f"  rplearn fit (features + solve): {t_ours * 1e3:8.1f} ms")
    print(f"  (a) BLAS dsyrk floor:           {t_floor * 1e3:8.1f} ms   ratio ours/(a) = {t_ours / t_floor:5.2f}x (target <= 1.5;"
          f" its Gram equals numpy's X.T @ X: {floor_ok})")
    print(
        f"  (b) sph_harm_y + sklearn Ridge: {t_hand * 1e3:8.1f} ms   speed-up (b)/ours = {t_hand / t_ours_b:5.1f}x (target >= 30;"
        f" ours {t_ours_b * 1e3:.1f} ms in the rounds alternating with (b))"
    )
    print(f"  max |prediction difference| vs (b): {max_diff:.2e} dB (target <= 1e-6)")
    print(f"  rank {sol.report.rank} of {sol.report.n_columns}, condition number {sol.report.condition_number:.2f}")

    model_ratio, model_ok = fit_model_against_dsyrk(args.tiny, repeats)
    ok = t_ours / t_floor <= 1.5 and t_hand / t_ours_b >= 30 and max_diff <= 1e-6 and peak < 2**30 and model_ratio <= 1.5
    print("targets met" if ok else "TARGETS MISSED")
    if args.tiny:  # a smoke run: the timings of so small a case say nothing; the numbers must still agree
        return 0 if max_diff <= 1e-6 and err < 1e-6 and floor_ok and model_ok else 1
    if args.swarm:  # a fresh process: its peak memory is the swarm fits' own
        import subprocess

        swarm = [sys.executable, __file__.replace("fit.py", "fit_swarm.py")] + (["--quick"] if args.quick else [])
        ok = subprocess.run(swarm).returncode == 0 and ok
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
