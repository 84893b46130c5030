"""rplearn.core.lsq.selection: smoothness penalty, nested statistics, and the choice of order and
smoothing by grouped cross-validation from per-unit statistics (issue 11, item 1)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import make_basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection import nested_columns, penalty_scale, penalty_vector, select_order_and_smoothing, sub_statistics, validation_rmse
from rplearn.core.sh import SphericalHarmonics, sh_index
from rplearn.errors import InputError

RIDGE = 1.0


def synthetic_units(n_units=4, n_per_unit=600, truth_order=3, noise_db=2.0, seed=0):
    """Two nodes linked both ways; a smooth SH-``truth_order`` pattern each, Gaussian noise."""
    rng = np.random.default_rng(seed)
    truth = SphericalHarmonics(truth_order)
    coef = rng.normal(0.0, 3.0, (2, truth.n_coef))
    units = []
    for _ in range(n_units):
        az = rng.uniform(-np.pi, np.pi, (4, n_per_unit))
        el = np.arcsin(rng.uniform(-1, 1, (4, n_per_unit)))
        tx = rng.integers(0, 2, n_per_unit)
        rx = 1 - tx
        g_tx = np.einsum("nc,nc->n", coef[tx], truth.design(az[0], el[0]))
        g_rx = np.einsum("nc,nc->n", coef[rx], truth.design(az[1], el[1]))
        y = g_tx + g_rx + rng.normal(0.0, noise_db, n_per_unit)
        units.append((Directions(az[0], el[0], az[1], el[1]), tx, rx, y))
    return units


def stats_of(units, basis):
    return {f"u{i}": NormalEquations(basis, 2).add(d, tx, rx, y) for i, (d, tx, rx, y) in enumerate(units)}


def test_sh_roughness_is_the_laplacian_eigenvalue_squared():
    w = SphericalHarmonics(5).roughness(2.0)
    assert w[sh_index(0, 0)] == 0.0
    assert w[sh_index(1, -1)] == 4.0 and w[sh_index(3, 2)] == 144.0 and w[sh_index(4, 0)] == 400.0
    assert np.all(make_basis("poly", 3).roughness() == 1.0)  # plain ridge for P and BG
    p = penalty_vector(SphericalHarmonics(3), 2, smoothing=1e-3, scale=50.0)
    assert p.shape == (18,) and p[sh_index(1, 0)] == pytest.approx(2.0**2 * 1e-3 * 50.0)
    np.testing.assert_allclose(p, np.tile(SphericalHarmonics(3).roughness(2.0), 2) * 0.05)
    with pytest.raises(InputError, match="smoothing"):
        penalty_vector(SphericalHarmonics(3), 2, smoothing=-1.0, scale=1.0)


def test_a_smaller_order_is_a_sub_block_of_the_larger_statistics():
    units = synthetic_units(n_units=1)
    big = stats_of(units, SphericalHarmonics(7))["u0"]
    small = stats_of(units, SphericalHarmonics(4))["u0"]
    sub = sub_statistics(big, SphericalHarmonics(4))
    np.testing.assert_allclose(sub.gram, small.gram, rtol=1e-10, atol=1e-8)
    np.testing.assert_allclose(sub.rhs, small.rhs, rtol=1e-10, atol=1e-8)
    assert sub.yty == pytest.approx(small.yty) and sub.n_samples == small.n_samples
    with pytest.raises(InputError):
        nested_columns(SphericalHarmonics(4), SphericalHarmonics(7), 2)


def test_grouped_cv_from_statistics_equals_refitting_from_raw_samples():
    """The validation error of one (order, smoothing) from per-unit statistics is the error of
    refitting without each unit from its raw samples and predicting it: the ridge and the
    penalty shrink toward the learning units' own level (the least-norm constants per node, here
    half the mean joint gain each: every sample sees both nodes), not toward 0 dB."""
    units = synthetic_units(n_units=3, n_per_unit=400)
    order, smoothing = 5, 1e-3
    sel = select_order_and_smoothing(stats_of(units, SphericalHarmonics(order)),
                                     SphericalHarmonics, [order], RIDGE, grid=[smoothing])
    basis = SphericalHarmonics(order)
    p = basis.n_coef

    def design(d, tx, rx):
        x = np.zeros((tx.size, 2 * p))
        ft, fr = basis.design(d.az_tx, d.el_tx), basis.design(d.az_rx, d.el_rx)
        for i in range(tx.size):
            x[i, tx[i] * p:(tx[i] + 1) * p] += ft[i]
            x[i, rx[i] * p:(rx[i] + 1) * p] += fr[i]
        return x

    sse, n = 0.0, 0
    for k in range(3):
        xs = np.vstack([design(*units[j][:3]) for j in range(3) if j != k])
        ys = np.concatenate([units[j][3] for j in range(3) if j != k])
        g = xs.T @ xs
        weights = RIDGE + smoothing * penalty_scale(g) * np.maximum(np.tile(basis.roughness(2.0), 2), 4e-6)
        target = np.zeros(2 * p)
        target[[0, p]] = np.sqrt(4.0 * np.pi) * np.mean(ys) / 2.0  # Y_00 = 1 / sqrt(4 pi)
        c = np.linalg.solve(g + np.diag(weights), xs.T @ ys + weights * target)
        xk = design(*units[k][:3])
        sse += np.sum((units[k][3] - xk @ c) ** 2)
        n += xk.shape[0]
    assert sel.method == "grouped-cv" and sel.rmse_db == pytest.approx(np.sqrt(sse / n), rel=1e-6)


def test_cross_validation_does_not_overfit_a_smooth_pattern():
    units = synthetic_units(n_units=4, n_per_unit=500, truth_order=3, noise_db=2.0, seed=1)
    stats = stats_of(units, SphericalHarmonics(9))
    sel = select_order_and_smoothing(stats, SphericalHarmonics, range(2, 10), RIDGE)
    top_plain = validation_rmse(stats, SphericalHarmonics, [9], 0.0, RIDGE)[0]
    assert sel.rmse_db < top_plain  # better than the unregularised SH-9
    assert sel.rmse_db < 2.0 * 1.15  # near the noise floor (2 dB)
    assert sel.order >= 3  # the truth needs degree 2, order 3
    text = sel.curve_text()
    assert "<- chosen" in text and len(text.splitlines()) == len(sel.curve) + 1


def test_one_unit_is_chosen_by_generalised_cross_validation():
    units = synthetic_units(n_units=1, n_per_unit=1500, truth_order=3, seed=2)
    sel = select_order_and_smoothing(stats_of(units, SphericalHarmonics(8)), SphericalHarmonics, range(2, 9), RIDGE)
    assert sel.method == "gcv" and sel.units == [] and np.isfinite(sel.rmse_db)
    assert 1.5 < sel.rmse_db < 2.6
    assert sel.to_dict()["curve"][0].keys() == {"order", "smoothing", "rmse_db"}


class _Points:
    """The parts of the evaluator the choice among equally good points reads."""

    def __init__(self, fold_sse, n=1000):
        self.cv, self.n = True, n
        self.fold_sse = {k: np.asarray(v, float) for k, v in fold_sse.items()}
        self.folds = [None] * len(next(iter(fold_sse.values())))


def _point(order, smoothing, ev):
    from rplearn.core.lsq.selection import CurvePoint

    return CurvePoint(order, smoothing, float(np.sqrt(ev.fold_sse[(order, smoothing)].sum() / ev.n)))


def test_the_least_smoothing_within_noise_of_the_best_is_chosen():
    """Issue 24, item 5: points the held-out units cannot tell from the best do not loosen the split."""
    from rplearn.core.lsq.selection import _tightest_split

    sse = {(8, 1e-4): [100.0, 100.0, 100.0],   # the best
           (8, 1e-5): [101.0, 99.5, 100.2],    # 0.7 above in total, paired spread 1.3 per unit: noise
           (9, 1e-5): [100.9, 99.6, 100.3],    # as close, and a larger order at the same smoothing
           (8, 0.0): [110.0, 110.0, 110.0]}    # consistently worse in every unit: not noise
    ev = _Points(sse)
    points = [_point(o, s, ev) for o, s in sse]
    best = points[0]
    chosen = _tightest_split(ev, best, points)
    assert (chosen.order, chosen.smoothing) == (9, 1e-5)
    # a cap on what a noisy spread may excuse: 1% of the best mean square
    wide = _Points({(8, 1e-4): [100.0, 100.0, 100.0], (8, 1e-5): [120.0, 90.0, 94.0]})
    pts = [_point(o, s, wide) for o, s in wide.fold_sse]
    assert _tightest_split(wide, pts[0], pts) == pts[0]
    # two held-out units estimate no spread: the best point stays
    two = _Points({(8, 1e-4): [100.0, 100.0], (8, 1e-5): [100.1, 99.95]})
    pts = [_point(o, s, two) for o, s in two.fold_sse]
    assert _tightest_split(two, pts[0], pts) == pts[0]


def test_the_choice_is_within_noise_of_the_best_validation_error():
    units = synthetic_units(n_units=4, n_per_unit=500, truth_order=3, noise_db=2.0, seed=1)
    sel = select_order_and_smoothing(stats_of(units, SphericalHarmonics(9)), SphericalHarmonics, range(2, 10), RIDGE)
    best = min(p.rmse_db for p in sel.curve)
    assert best <= sel.rmse_db <= best * np.sqrt(1.01)
    assert all(p.smoothing >= sel.smoothing for p in sel.curve if p.rmse_db == best)


def test_the_search_leaves_a_coordinate_minimum_along_the_diagonal_valley():
    """Order and smoothing trade off: a validation error whose valley runs along the diagonal
    (a smaller order with less smoothing) has points that no step along one coordinate improves
    on; the search steps along the diagonal to the valley's floor (ground preset, seed 0)."""
    from rplearn.core.lsq.selection import _diagonal_steps

    orders = [3, 4, 5, 6, 7]
    grid = [1e-6, 3e-6, 1e-5, 3e-5, 1e-4]

    class Valley:
        def rmse(self, order, smoothing):
            i, j = orders.index(order), grid.index(smoothing)
            return 4.0 + (i - j) ** 2 + 0.1 * (i + j)  # a valley along i = j, falling toward (3, 1e-6)

    ev = Valley()
    start = (6, 3e-5)  # in the valley: each single-coordinate neighbour is worse
    assert all(ev.rmse(*p) > ev.rmse(*start) for p in [(5, 3e-5), (7, 3e-5), (6, 1e-5), (6, 1e-4)])
    path = _diagonal_steps(ev, orders, *start, grid)
    assert path == [(5, 1e-5), (4, 3e-6), (3, 1e-6)]
    assert all(ev.rmse(*b) < ev.rmse(*a) for a, b in zip([start, *path], path))


def test_folds_solved_on_the_workers_give_the_search_of_one_thread(monkeypatch):
    """The folds of each batch of points are solved on the statistics' workers at once
    (``FoldEvaluator.prefetch``); with the workers busy (their lock held) the same search runs in
    this thread, point by point: the same points in the same order, the same errors, choice,
    inflation and ties (up to the rounding of one BLAS thread against the policy's)."""
    from rplearn.core.lsq import runtime as runtime_module

    monkeypatch.setenv("RPLEARN_THREADS", "1")
    units = stats_of(synthetic_units(n_units=3, n_per_unit=700, truth_order=4, seed=8), SphericalHarmonics(7))
    basis = lambda k: SphericalHarmonics(k)  # noqa: E731
    calls: list[int] = []
    original = runtime_module.StatisticsRuntime.in_order

    def counted(self, work, starts, **kwargs):
        starts = list(starts)
        calls.append(len(starts))
        return original(self, work, starts, **kwargs)

    monkeypatch.setattr(runtime_module.StatisticsRuntime, "in_order", counted)
    parallel = select_order_and_smoothing(units, basis, range(2, 8), RIDGE)
    assert max(calls) > 3  # batches of several points' folds
    lock = runtime_module.DEFAULT_RUNTIME._lock
    assert lock.acquire(blocking=False)
    try:
        alone = select_order_and_smoothing(units, basis, range(2, 8), RIDGE)
    finally:
        lock.release()
    assert [(p.order, p.smoothing) for p in parallel.curve] == [(p.order, p.smoothing) for p in alone.curve]
    np.testing.assert_allclose([p.rmse_db for p in parallel.curve], [p.rmse_db for p in alone.curve], rtol=1e-12)
    assert (parallel.order, parallel.smoothing) == (alone.order, alone.smoothing)
    assert parallel.variance_inflation == pytest.approx(alone.variance_inflation, rel=1e-10)
    assert [t[:2] for t in parallel.ties] == [t[:2] for t in alone.ties]
    np.testing.assert_allclose([t[2] for t in parallel.ties], [t[2] for t in alone.ties], rtol=1e-10)


def test_without_room_for_the_factors_the_inflation_solves_again(monkeypatch):
    """Past ``_PENDING_FACTOR_BYTES`` a batch keeps only its solutions (a swarm's factors are
    large): the best point's inflation then factorises again, to the same figures."""
    from rplearn.core.lsq import selection_evaluator as selection_module

    monkeypatch.setenv("RPLEARN_THREADS", "1")
    units = stats_of(synthetic_units(n_units=3, n_per_unit=600, truth_order=3, seed=9), SphericalHarmonics(6))
    kept = select_order_and_smoothing(units, SphericalHarmonics, range(2, 7), RIDGE)
    monkeypatch.setattr(selection_module, "_PENDING_FACTOR_BYTES", 0)
    dropped = select_order_and_smoothing(units, SphericalHarmonics, range(2, 7), RIDGE)
    assert [(p.order, p.smoothing) for p in kept.curve] == [(p.order, p.smoothing) for p in dropped.curve]
    assert (kept.order, kept.smoothing) == (dropped.order, dropped.smoothing)
    assert dropped.variance_inflation == pytest.approx(kept.variance_inflation, rel=1e-12)
    assert dropped.flight_level_std_db == pytest.approx(kept.flight_level_std_db, rel=1e-9, abs=1e-12)


def test_the_tied_points_inflations_reuse_the_kept_factors(monkeypatch):
    """The folds' factors of the best points are kept (``_KEPT_FACTOR_BYTES``): the inflations of
    the chosen and tied points solve nothing again; without room for them (the best point's
    alone) the tied points solve again, from the factor of the order they were read from, to the
    same inflations."""
    from rplearn.core.lsq import selection_evaluator as selection_module
    from rplearn.core.lsq.selection_lead import LeadFolds

    monkeypatch.setenv("RPLEARN_THREADS", "1")
    units = stats_of(synthetic_units(n_units=3, n_per_unit=600, truth_order=3, seed=9), SphericalHarmonics(6))
    solves: list[int] = []
    original = LeadFolds.resolve

    def counted(self, *args, **kwargs):
        solves.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(LeadFolds, "resolve", counted)
    kept = select_order_and_smoothing(units, SphericalHarmonics, range(2, 7), RIDGE)
    assert len(kept.ties) >= 2  # else nothing to reuse: the test would not test
    assert solves == []
    monkeypatch.setattr(selection_module, "_KEPT_FACTOR_BYTES", 0)
    again = select_order_and_smoothing(units, SphericalHarmonics, range(2, 7), RIDGE)
    assert solves
    assert [t[:2] for t in again.ties] == [t[:2] for t in kept.ties]
    np.testing.assert_array_equal([t[2] for t in again.ties], [t[2] for t in kept.ties])
    assert again.variance_inflation == kept.variance_inflation


def _count_factorisations(monkeypatch) -> list[int]:
    """The size of every Cholesky factorisation the selection makes (its modules' ``spd_factor``)."""
    import importlib

    calls: list[int] = []
    for name in ("selection_evaluator", "selection_lead"):
        try:
            module = importlib.import_module(f"rplearn.core.lsq.{name}")
        except ImportError:
            continue
        original = module.spd_factor

        def counted(matrix, *args, _original=original, **kwargs):
            calls.append(matrix.shape[0])
            return _original(matrix, *args, **kwargs)

        monkeypatch.setattr(module, "spd_factor", counted)
    return calls


def test_one_factorisation_per_fold_and_smoothing_serves_the_smaller_orders(monkeypatch):
    """The points of one smoothing are solved from one Cholesky factor per fold, at the largest
    order asked there (a smaller order's system is a leading block in the lead layout): fewer
    factorisations than points times folds (before: one per point and fold), and every point
    validates as its order factorised alone does, to rounding."""
    from rplearn.core.lsq.selection_evaluator import FoldEvaluator

    monkeypatch.setenv("RPLEARN_THREADS", "1")
    units = stats_of(synthetic_units(n_units=3, n_per_unit=700, truth_order=4, seed=5), SphericalHarmonics(8))
    calls = _count_factorisations(monkeypatch)
    sel = select_order_and_smoothing(units, SphericalHarmonics, range(2, 9), RIDGE)
    searched = len(calls)
    assert searched < 3 * len(sel.curve)
    by_smoothing: dict[float, list[int]] = {}
    for p in sel.curve:
        by_smoothing.setdefault(p.smoothing, []).append(p.order)
    assert any(len(v) > 1 for v in by_smoothing.values())  # else nothing to share: the test would not test
    for p in sel.curve:  # each point alone: a new evaluator factorises its own order
        alone = FoldEvaluator(units, SphericalHarmonics, RIDGE, 2.0).rmse(p.order, p.smoothing)
        assert p.rmse_db == pytest.approx(alone, rel=1e-11)


def test_the_lead_layout_puts_every_smaller_order_in_a_leading_block():
    """``lead_columns``: shared columns first, then each coefficient of every node; an order's
    problem is the leading block, its columns those of ``nested_columns`` (with the shared ones)."""
    from rplearn.core.lsq.selection_folds import lead_columns, lead_size

    perm = lead_columns(SphericalHarmonics(4).n_coef, 3, 2)
    assert sorted(perm) == list(range(3 * 16 + 2)) and list(perm[:2]) == [48, 49]
    for order in (1, 2, 3, 4):
        m = lead_size(SphericalHarmonics(order).n_coef, 3, 2)
        wanted = set(nested_columns(SphericalHarmonics(4), SphericalHarmonics(order), 3)) | {48, 49}
        assert set(perm[:m]) == wanted


@pytest.mark.parametrize("threads", [None, "2"])
def test_a_fold_solved_in_the_calling_thread_is_solved_with_one_blas_thread(monkeypatch, threads):
    """With the workers busy, the folds run in the calling thread, still with one BLAS thread
    (whatever the caller's limit): the same bits as on the workers."""
    from threadpoolctl import threadpool_limits

    from rplearn.core.lsq import runtime as runtime_module
    from rplearn.core.threads import _controller

    if threads is None:
        monkeypatch.delenv("RPLEARN_THREADS", raising=False)
    else:
        monkeypatch.setenv("RPLEARN_THREADS", threads)
    units = stats_of(synthetic_units(n_units=3, n_per_unit=500, truth_order=3, seed=11), SphericalHarmonics(6))
    from rplearn.core.lsq import selection_lead

    seen: list[int] = []
    factor = selection_lead.spd_factor

    def counted(*args, **kwargs):
        seen.append(max(lib.num_threads for lib in _controller().select(user_api="blas").lib_controllers))
        return factor(*args, **kwargs)

    monkeypatch.setattr(selection_lead, "spd_factor", counted)
    on_workers = select_order_and_smoothing(units, SphericalHarmonics, range(2, 7), RIDGE)
    lock = runtime_module.DEFAULT_RUNTIME._lock
    with threadpool_limits(2, user_api="blas"):
        assert lock.acquire(blocking=False)
        try:
            seen.clear()
            here = select_order_and_smoothing(units, SphericalHarmonics, range(2, 7), RIDGE)
        finally:
            lock.release()
    assert seen and set(seen) == {1}
    assert [(p.order, p.smoothing, p.rmse_db) for p in here.curve] == [(p.order, p.smoothing, p.rmse_db) for p in on_workers.curve]
    assert (here.order, here.smoothing, here.variance_inflation, here.ties) == (
        on_workers.order, on_workers.smoothing, on_workers.variance_inflation, on_workers.ties)


def test_fold_blocks_built_on_the_workers_and_kept_give_the_same_search(monkeypatch):
    """The blocks of every order the search asks for (generalised cross-validation: one unit)
    are built on the workers at once and kept within ``_CACHE_BYTES``; with room for only
    ``_CACHED_ORDERS`` orders (built again as the search comes back) the search is the same to
    the last bit: the same copies."""
    from rplearn.core.lsq import selection_evaluator as selection_module

    monkeypatch.setenv("RPLEARN_THREADS", "1")
    units = stats_of(synthetic_units(n_units=1, n_per_unit=2100, truth_order=4, seed=11), SphericalHarmonics(8))
    built: list[tuple[int, int]] = []
    original = selection_module.FoldEvaluator._fold_block

    def counted(self, order, fold):
        built.append((order, fold))
        return original(self, order, fold)

    monkeypatch.setattr(selection_module.FoldEvaluator, "_fold_block", counted)
    kept = select_order_and_smoothing(units, SphericalHarmonics, range(2, 9), RIDGE)
    assert built and len(built) == len(set(built))  # every (order, fold) built once
    once = len(built)
    built.clear()
    monkeypatch.setattr(selection_module, "_CACHE_BYTES", 0)
    bounded = select_order_and_smoothing(units, SphericalHarmonics, range(2, 9), RIDGE)
    assert len(built) > once  # orders dropped and built again
    assert [(p.order, p.smoothing, p.rmse_db) for p in kept.curve] == [(p.order, p.smoothing, p.rmse_db) for p in bounded.curve]
    assert (kept.order, kept.smoothing, kept.variance_inflation) == (bounded.order, bounded.smoothing,
                                                                     bounded.variance_inflation)
    assert kept.ties == bounded.ties


def test_work_beside_the_last_step_gets_the_choice_and_changes_nothing():
    """``select_beside``: the caller's jobs are built from the chosen point and the tied points'
    keys, run with the inflations' folds, and come back in order; the selection is that of
    ``select_order_and_smoothing`` to the last bit."""
    from rplearn.core.lsq.selection import select_beside

    units = stats_of(synthetic_units(n_units=3, n_per_unit=600, truth_order=3, seed=12), SphericalHarmonics(6))
    asked: list[tuple[int, float, list[tuple[int, float]]]] = []

    def jobs(order, smoothing, keys):
        asked.append((order, smoothing, keys))
        return [lambda: order * 10, lambda: len(keys)]

    results, with_jobs = select_beside(units, SphericalHarmonics, range(2, 7), RIDGE, beside=jobs)
    plain = select_order_and_smoothing(units, SphericalHarmonics, range(2, 7), RIDGE)
    assert len(asked) == 1 and asked[0][:2] == (plain.order, plain.smoothing)
    assert asked[0][2] == [t[:2] for t in plain.ties] or (not plain.ties and asked[0][2] == [])
    assert results == [plain.order * 10, len(asked[0][2])]
    assert with_jobs.to_dict() == plain.to_dict()
    one_unit = {"u0": units["u0"]}  # GCV: no folds, the jobs run all the same
    results, gcv = select_beside(one_unit, SphericalHarmonics, range(2, 7), RIDGE, beside=jobs)
    assert gcv.method == "gcv" and results == [gcv.order * 10, 0]


def test_permuted_is_the_lead_layouts_fancy_index():
    """``permuted``: block by block, the same matrix as ``matrix[perm][:, perm]``."""
    from rplearn.core.lsq.selection_folds import lead_columns, permuted

    for layout in ((9, 2, 0), (4, 3, 2), (1, 2, 1)):
        n = layout[0] * layout[1] + layout[2]
        matrix = np.random.default_rng(n).normal(size=(n, n))
        perm = lead_columns(*layout)
        np.testing.assert_array_equal(permuted(matrix, layout), matrix[np.ix_(perm, perm)])


def test_the_penalty_unit_is_the_same_at_every_sh_order():
    """The folds' penalty unit is read at the largest order for every order (``selection_lead``):
    the mean diagonal of ``X^T X`` over the pattern columns is ``samples / (4 pi)`` per node end
    at every SH order (Unsöld's theorem), to rounding."""
    units = synthetic_units(n_units=1, n_per_unit=900, seed=4)
    big = stats_of(units, SphericalHarmonics(9))["u0"]
    scales = [penalty_scale(sub_statistics(big, SphericalHarmonics(o)).gram) for o in range(1, 10)]
    np.testing.assert_allclose(scales, 2 * 900 / (2 * 4 * np.pi), rtol=1e-12)


def test_a_smaller_order_is_solved_alone_when_the_larger_system_is_not_positive_definite():
    """When the largest order's system at a smoothing has no Cholesky factor, a smaller order
    asked with it is factorised alone (as a point asked by itself), not left to least squares;
    solved again it reads the same factor: the same bits."""
    from rplearn.core.lsq.selection_evaluator import FoldEvaluator

    units = stats_of(synthetic_units(n_units=3, n_per_unit=300, truth_order=2, seed=2), SphericalHarmonics(6))
    lead = FoldEvaluator(units, SphericalHarmonics, RIDGE, 2.0).lead()
    lead.order(6), lead.order(3)
    c, upper, source = lead.solve(0, 3, 1e-4, (6, None))  # as when the factor at SH-6 failed
    assert source == 3 and upper is not None and upper.shape == (18, 18)
    alone, _, _ = lead.solve(0, 3, 1e-4, (3, lead.factor(0, 3, 1e-4)))
    np.testing.assert_array_equal(c, alone)
    np.testing.assert_array_equal(lead.resolve(0, 3, 1e-4, source)[0], c)
    shared, _, read = lead.solve(0, 3, 1e-4, (6, lead.factor(0, 6, 1e-4)))  # from SH-6's factor
    assert read == 6
    np.testing.assert_allclose(shared, c, rtol=1e-10, atol=1e-12)


def test_the_lead_folds_are_the_natural_folds_reordered_to_the_bit():
    """``LeadFolds``: each fold's learning block (all units' reordered, less its held-out unit's
    reordered) is the natural fold's reordered, to the bit, and so is its held-out block."""
    from rplearn.core.lsq.selection_evaluator import FoldEvaluator

    units = stats_of(synthetic_units(n_units=3, n_per_unit=300, seed=2), SphericalHarmonics(6))
    ev = FoldEvaluator(units, SphericalHarmonics, RIDGE, 2.0)
    lead = ev.lead()
    cols = np.ix_(lead.perm, lead.perm)
    for mine, natural in zip(lead.folds, ev.folds):
        np.testing.assert_array_equal(mine.gram, natural.gram[cols])
        np.testing.assert_array_equal(mine.held_gram, natural.held_gram[cols])
        np.testing.assert_array_equal(mine.rhs, natural.rhs[lead.perm])
