"""Statistics of many short links at once (issue 13, item 1): one feature pass per block of
samples, blocks computed ahead by two worker threads, equal to adding each link alone."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.geometry import Directions
from rplearn.core.lsq import link_statistics
from rplearn.core.lsq.link_statistics import segmented_link_statistics
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.sh import SphericalHarmonics


def _samples(rng: np.random.Generator, n_nodes: int, n: int):
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = np.arcsin(rng.uniform(-1.0, 1.0, (2, n)))
    tx = rng.integers(0, n_nodes, n)
    rx = (tx + rng.integers(1, n_nodes, n)) % n_nodes
    return Directions(az[0], el[0], az[1], el[1]), tx, rx, rng.normal(0, 3.0, n), rng.normal(size=n)


@pytest.mark.parametrize("environment", [False, True])
def test_many_links_in_blocks_equal_each_link_alone(environment, monkeypatch):
    """7 nodes, 42 directed links, blocks of 700 samples (several links per block, links split
    between blocks, more blocks than the threads): every statistic equals the sum of one
    accumulation per link."""
    monkeypatch.setattr(link_statistics, "BLOCK_SAMPLES", 700)
    monkeypatch.setattr(link_statistics, "FEATURE_CHUNK", 250)
    rng = np.random.default_rng(5)
    basis = SphericalHarmonics(6)
    d, tx, rx, y, e = _samples(rng, 7, 9000)
    e = e if environment else None
    together = NormalEquations(basis, 7, environment=environment).add(d, tx, rx, y, e)
    alone = NormalEquations(basis, 7, environment=environment)
    for code in np.unique(tx * 7 + rx):
        s = tx * 7 + rx == code
        alone.add(Directions(*(a[s] for a in d)), tx[s], rx[s], y[s], None if e is None else e[s])
    np.testing.assert_allclose(together.gram, alone.gram, rtol=0, atol=1e-9 * np.abs(alone.gram).max())
    np.testing.assert_allclose(together.gram, together.gram.T, rtol=0, atol=0)
    np.testing.assert_allclose(together.rhs, alone.rhs, atol=1e-8)
    assert together.yty == pytest.approx(alone.yty, rel=1e-12)
    assert together.link_counts == alone.link_counts and together.n_samples == 9000
    assert set(together.directed) == set(alone.directed)
    for k, v in alone.directed.items():
        np.testing.assert_allclose(together.directed[k], v, atol=1e-8)
    np.testing.assert_allclose(together.env_cross, alone.env_cross, atol=1e-8)
    assert together.env_sq == pytest.approx(alone.env_sq, rel=1e-12)
    assert together.env_y == pytest.approx(alone.env_y, rel=1e-12, abs=1e-9)


def test_segmented_statistics_are_each_links_products():
    """Per link: the cross block, X^T y parts and the moments (their Gram is F^T F)."""
    rng = np.random.default_rng(2)
    basis = SphericalHarmonics(4)
    p = basis.n_coef
    n = 500
    az_t, az_r = rng.uniform(-np.pi, np.pi, (2, n))
    el_t, el_r = np.arcsin(rng.uniform(-1, 1, (2, n)))
    y = rng.normal(size=n)
    bounds = np.array([0, 120, 120, 377, 500])  # one empty link
    products, moments = segmented_link_statistics(basis, Directions(az_t, el_t, az_r, el_r), y, np.ones((1, n)), bounds,
                                                  np.argsort(basis.row_order))
    f_t, f_r = basis.design(az_t, el_t), basis.design(az_r, el_r)
    for j in range(4):
        s = slice(bounds[j], bounds[j + 1])
        np.testing.assert_allclose(products[j, :p, 2:], f_t[s].T @ f_r[s], atol=1e-10)
        np.testing.assert_allclose(products[j, :p, 0], f_t[s].T @ y[s], atol=1e-10)
        np.testing.assert_allclose(products[j, p, 2:], y[s] @ f_r[s], atol=1e-10)
        assert products[j, p + 1, 1] == bounds[j + 1] - bounds[j]
        gram_tx = basis.gram_from_moments(moments[0][j])[np.ix_(np.argsort(basis.row_order), np.argsort(basis.row_order))]
        np.testing.assert_allclose(gram_tx, f_t[s].T @ f_t[s], atol=1e-9)


def test_blocks_hold_a_bounded_number_of_samples_and_links():
    """Short links (found by review: thousands of 2-sample links made a block's products GBs)."""
    bounds = np.r_[0, np.cumsum(np.random.default_rng(1).integers(1, 4, 5000))]
    starts = link_statistics.block_starts(bounds, 700, 100)
    stops = [*starts[1:], int(bounds[-1])]
    assert starts[0] == 0 and all(a < b for a, b in zip(starts, stops))
    for a, b in zip(starts, stops):
        links = np.searchsorted(bounds, b, side="left") - (np.searchsorted(bounds, a, side="right") - 1)
        assert b - a <= 700 and links <= 101
    assert link_statistics.max_links_per_block(SphericalHarmonics(10), 1) * 102**2 * 4 <= link_statistics.BLOCK_MAX_VALUES


def _blas_threads() -> list[int]:
    from threadpoolctl import threadpool_info

    return sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")


def test_concurrent_accumulations_are_right_and_leave_the_blas_threads_as_they_were(monkeypatch):
    """Two threads adding at once (found by review: the process-wide one-thread BLAS limit was
    restored by the first to finish, and the second left it at one thread for good)."""
    import threading

    monkeypatch.setattr(link_statistics, "BLOCK_SAMPLES", 700)
    before = _blas_threads()
    basis = SphericalHarmonics(5)
    data = [_samples(np.random.default_rng(k), 6, 20000) for k in range(2)]
    out: dict[int, NormalEquations] = {}

    def run(k: int) -> None:
        d, tx, rx, y, _ = data[k]
        out[k] = NormalEquations(basis, 6).add(d, tx, rx, y)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert _blas_threads() == before
    for k in range(2):
        d, tx, rx, y, _ = data[k]
        alone = NormalEquations(basis, 6).add(d, tx, rx, y)
        np.testing.assert_allclose(out[k].gram, alone.gram, atol=1e-9 * np.abs(alone.gram).max())


def _fit_in_child(seed: int) -> float:
    d, tx, rx, y, _ = _samples(np.random.default_rng(seed), 5, 200_000)
    return float(NormalEquations(SphericalHarmonics(4), 5).add(d, tx, rx, y).yty)


def test_a_forked_child_accumulates_after_the_parent_used_the_worker_threads():
    """Found by review: a forked child inherited the pool object without its threads and hung."""
    import multiprocessing

    assert _fit_in_child(0) > 0  # the parent's pool now exists
    with multiprocessing.get_context("fork").Pool(1) as pool:
        got = pool.apply_async(_fit_in_child, (0,)).get(timeout=60)
    assert got == pytest.approx(_fit_in_child(0), rel=1e-12)


@pytest.mark.parametrize("n", [5_000, 40_000, 70_000])
def test_one_link_split_into_blocks_for_the_workers_equals_the_product_of_its_rows(n):
    """A long link's samples go to the worker threads in blocks (pipelined_block_samples): the
    blocks' products and moments, added in order, are Z^T Z of the whole link."""
    from rplearn.core.lsq.link_statistics import PIPELINE_MIN_BLOCK, pipelined_block_samples
    from rplearn.core.lsq.link_statistics import link_statistics as statistics

    basis = SphericalHarmonics(6)
    rng = np.random.default_rng(3)
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = np.arcsin(rng.uniform(-1.0, 1.0, (2, n)))
    y = rng.normal(0.0, 3.0, n)
    extra = np.stack([np.ones(n), rng.normal(size=n)])
    p = basis.n_coef
    assert (pipelined_block_samples(2 * p + 3, n) < n) == (n >= 2 * PIPELINE_MIN_BLOCK)  # blocks only when worth it
    z = np.vstack([basis.design_t(az[0], el[0])[basis.row_order], y, extra, basis.design_t(az[1], el[1])[basis.row_order]])
    got = statistics(basis, az[0], el[0], az[1], el[1], y, extra)
    np.testing.assert_allclose(got, z @ z.T, rtol=1e-10, atol=1e-9 * n)
