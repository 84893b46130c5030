"""Benchmark and acceptance figures of the flight simulator on the ``paper`` preset.

Prints
- the wall time of ``simulate("paper")`` (median of ``--repeats`` runs) and its ratio to a
  reference measured in the same run: the time numpy takes merely to draw as many standard
  normal numbers as there are numeric cells in the logs it writes (pose log 8 numeric columns,
  signal log 4 numeric columns per row);
- the sample counts, the noise level (nominal and realised), the RMSE of the true patterns on
  the testing unit (true poses, and poses after synchronising the logged estimates), the
  mean and k-NN-400 baselines, an SH-10 fit, and the plan check.

Run: ``.venv/bin/python benchmarks/simulate.py [--repeats 3] [--seed 0]`` (``--tiny``: the
``smoke`` preset once, SH-4 and k-NN-40).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np


def _rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--tiny", action="store_true", help="the smoke preset once, SH-4 and k-NN-40 (seconds)")
    args = parser.parse_args()
    preset, order, k = ("smoke", 4, 40) if args.tiny else ("paper", 10, 400)
    if args.tiny:
        args.repeats = 1

    from rplearn.data.sync import synchronise
    from rplearn.data.tables import link_samples
    from rplearn.models.estimators import JointKNNRegressor, MeanRegressor, PatternRegressor
    from rplearn.plan.check import NominalAttitude, check_plan
    from rplearn.sim.flight import simulate

    times = []
    res = None
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        res = simulate(preset, seed=args.seed)
        times.append(time.perf_counter() - t0)
    assert res is not None
    t_sim = statistics.median(times)
    n_cells = 8 * len(res.pose_log) + 4 * len(res.signal_log)
    ref_times = []
    for _ in range(args.repeats):
        rng = np.random.default_rng(0)
        t0 = time.perf_counter()
        rng.standard_normal(n_cells)
        ref_times.append(time.perf_counter() - t0)
    t_ref = statistics.median(ref_times)
    print(f"simulate({preset!r}): {t_sim:.2f} s (median of {args.repeats}); {len(res.pose_log)} poses, "
          f"{len(res.signal_log)} packets")
    print(f"reference (draw {n_cells} standard normals): {t_ref * 1e3:.1f} ms; ratio {t_sim / t_ref:.0f}x")
    print(f"noise level: nominal {res.noise_std_db:.3f} dB (sqrt(fading^2 + 1/12)), realised {res.realised_noise_std_db:.3f} dB")

    synced = synchronise(res.pose_log, res.signal_log).dataset
    for tx, rx in (("A", "B"), ("B", "A")):
        learn, test = res.matched("learning", tx, rx), res.matched("testing", tx, rx)
        sl, st = link_samples(learn), link_samples(test)
        d = st.directions
        truth = res.ground_truth.predict_joint_gain_db(tx, rx, *d, include_link_offset=True)
        xl, xt = np.column_stack(sl.directions), np.column_stack(d)
        mean = MeanRegressor().fit(xl, sl.joint_gain_db).predict(xt)
        knn = JointKNNRegressor(k).fit(xl, sl.joint_gain_db).predict(xt)
        t0 = time.perf_counter()
        sh = PatternRegressor("sh", order).fit(xl, sl.joint_gain_db)
        t_sh = time.perf_counter() - t0
        print(f"\n{tx}->{rx}: {len(learn)} learning, {len(test)} testing samples")
        rt = _rmse(st.joint_gain_db, truth)
        print(f"  true patterns, true poses:   RMSE {rt:.3f} dB ({100 * (rt / res.noise_std_db - 1):+.2f}% vs noise level)")
        print(f"  mean baseline:               RMSE {_rmse(st.joint_gain_db, mean):.2f} dB (paper 11.15)")
        print(f"  k-NN-{k}:{' ' * (24 - len(str(k)))}RMSE {_rmse(st.joint_gain_db, knn):.2f} dB (paper, k-NN-400: 4.82)")
        print(f"  SH-{order} (lead's solver):{' ' * (8 - len(str(order)))}RMSE {_rmse(st.joint_gain_db, sh.predict(xt)):.2f} dB (paper, SH-10: 4.56), "
              f"rank {sh.report_.rank}/{sh.report_.n_columns}, cond {sh.report_.condition_number:.1f}, {t_sh:.2f} s")
        # the same with the poses the autopilots logged, after synchronisation
        sy = synced[(synced.tx == tx) & (synced.rx == rx)]
        sy_l = link_samples(sy[sy["unit"].isin(res.units("learning"))])
        sy_t = link_samples(sy[sy["unit"].isin(res.units("testing"))])
        dt = sy_t.directions
        truth_est = res.ground_truth.predict_joint_gain_db(tx, rx, *dt, include_link_offset=True)
        knn_est = JointKNNRegressor(k).fit(np.column_stack(sy_l.directions), sy_l.joint_gain_db).predict(np.column_stack(dt))
        print(f"  after sync (logged poses):   true patterns RMSE {_rmse(sy_t.joint_gain_db, truth_est):.3f} dB, "
              f"k-NN-{k} {_rmse(sy_t.joint_gain_db, knn_est):.2f} dB")

    check = check_plan(res.config.campaign, ("sh", order))
    print(f"\nplan check (SH-{order}, learning units, nominal tilt, no wind):")
    print("  " + check.summary().replace("\n", "\n  "))
    windy = check_plan(res.config.campaign, ("sh", order), attitude=NominalAttitude(wind_speed_m_s=10.0))
    print(f"  with a 10 m/s wind: rank {windy.rank}/{windy.n_columns}, condition number {windy.condition_number:.1f}")


if __name__ == "__main__":
    main()
