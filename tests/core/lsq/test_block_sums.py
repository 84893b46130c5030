"""Per-time-block sums and the drifting error's estimate (rplearn.core.lsq.block_sums)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import make_basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq import link_statistics
from rplearn.core.lsq.block_sums import MIN_BLOCKS, BlockSums, correlated_ratio, time_block_sums
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import sub_statistics
from rplearn.errors import InputError

RATE_HZ = 50.0
BLOCK_S = 5.0


def _flight(seconds: float, seed: int) -> tuple[np.ndarray, Directions, np.ndarray]:
    """Times, directions of a drone turning and bobbing in front of a peer, node 0 -> 1."""
    t = np.arange(0.0, seconds, 1.0 / RATE_HZ)
    rng = np.random.default_rng(seed)
    az_tx = np.angle(np.exp(1j * (2.0 * np.pi * t / 12.0 + rng.uniform(0, 6.3))))
    el_tx = 0.6 * np.sin(2.0 * np.pi * t / 47.0)
    az_rx = np.angle(np.exp(1j * (2.0 * np.pi * t / 29.0)))
    el_rx = -0.4 * np.sin(2.0 * np.pi * t / 31.0)
    return t, Directions(az_tx, el_tx, az_rx, el_rx), np.zeros(t.size, np.int_)


def _accumulate(seconds: float, white_db: float, drift_db: float, seed: int) -> tuple[NormalEquations, BlockSums]:
    basis = make_basis("sh", 3)
    t, d, tx = _flight(seconds, seed)
    rng = np.random.default_rng(seed + 1)
    coef = rng.normal(0.0, 2.0, 2 * basis.n_coef)
    truth = basis.design(d.az_tx, d.el_tx) @ coef[:basis.n_coef] + basis.design(d.az_rx, d.el_rx) @ coef[basis.n_coef:]
    block = np.floor(t / BLOCK_S).astype(int)
    y = truth + rng.normal(0.0, white_db, t.size) + rng.normal(0.0, drift_db, block.max() + 1)[block]
    normal = NormalEquations(basis, 2)
    blocks = BlockSums(2, basis.n_coef, BLOCK_S)
    for s in range(int(seconds)):  # 1-s batches, as a live session learns
        m = (t >= s) & (t < s + 1)
        normal.add(Directions(d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m]), tx[m], 1 - tx[m], y[m])
        blocks.follow(normal, float(t[m][-1]) + 1.0 / RATE_HZ - 1e-9)
    return normal, blocks


def _prior(normal: NormalEquations) -> np.ndarray:
    return np.full(normal.n_pattern_columns, 1e-6 * float(np.mean(np.diag(normal.gram))))


@pytest.mark.parametrize("seed", [0, 1])
def test_the_drifting_error_is_estimated_from_the_blocks(seed: int) -> None:
    white, drift = 2.0, 0.6
    normal, blocks = _accumulate(600.0, white, drift, seed)
    kappa = correlated_ratio(normal, blocks.closed(), _prior(normal))
    assert np.sqrt(kappa) * white == pytest.approx(drift, rel=0.3)


def test_white_noise_alone_gives_a_small_drift() -> None:
    normal, blocks = _accumulate(600.0, 2.0, 0.0, 3)
    kappa = correlated_ratio(normal, blocks.closed(), _prior(normal))
    assert np.sqrt(kappa) * 2.0 < 0.15  # against 0.6 dB above: the estimate tells them apart


def test_blocks_close_every_block_s_and_closed_copies() -> None:
    normal, blocks = _accumulate(60.0, 1.0, 0.0, 0)
    assert blocks.n_blocks == 11  # 60 s of 1-s batches, 5 s each: the twelfth still open
    closed = blocks.closed()
    assert closed.n_blocks == 12 and blocks.n_blocks == 11
    assert closed.sum_n == pytest.approx(normal.n_samples)
    assert closed.sum_nn == pytest.approx(12 * 250.0**2)  # 5 s at 50 Hz per block
    assert np.all(np.linalg.eigvalsh(closed.cross) > -1e-6 * np.max(closed.cross))


def test_batches_and_the_cumulative_statistics_give_the_same_sums() -> None:
    basis = make_basis("sh", 2)
    t, d, tx = _flight(30.0, 0)
    y = np.random.default_rng(0).normal(0.0, 1.0, t.size)
    total, a, b = NormalEquations(basis, 2), BlockSums(2, basis.n_coef, 5.0), BlockSums(2, basis.n_coef, 5.0)
    for s in range(30):
        m = (t >= s) & (t < s + 1)
        rows = (Directions(d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m]), tx[m], 1 - tx[m], y[m])
        total.add(*rows)
        a.follow(total, s + 0.5)
        b.add_batch(NormalEquations(basis, 2).add(*rows), s + 0.5)
    ca, cb = a.closed(), b.closed()
    assert ca.n_blocks == cb.n_blocks == 6
    assert np.allclose(ca.cross, cb.cross) and np.allclose(ca.sum_yv, cb.sum_yv) and ca.sum_yy == pytest.approx(cb.sum_yy)


def test_too_few_blocks_estimate_nothing() -> None:
    normal, blocks = _accumulate(5.0 * (MIN_BLOCKS - 1), 1.0, 1.0, 0)
    assert correlated_ratio(normal, blocks.closed(), _prior(normal)) == 0.0


def test_bad_block_lengths_and_mismatched_statistics_are_refused() -> None:
    with pytest.raises(InputError, match="block_s"):
        BlockSums(2, 4, 0.0)
    with pytest.raises(InputError, match="block sums"):
        BlockSums(2, 4).follow(NormalEquations(make_basis("sh", 3), 2), 1.0)


def test_a_late_batch_joins_the_open_block_and_never_reopens_a_closed_one() -> None:
    """Batches out of time order: a block is closed once (it was closed again as a new block,
    so the sums hung on how rows were batched)."""
    basis = make_basis("sh", 2)
    t, d, tx = _flight(30.0, 1)
    y = np.random.default_rng(1).normal(0.0, 1.0, t.size)
    blocks = BlockSums(2, basis.n_coef, 5.0)
    order = [s for s in range(30) if s != 3]
    order.insert(order.index(8), 3)  # the batch of 3-4 s arrives after the one of 7-8 s
    for s in order:
        m = (t >= s) & (t < s + 1)
        rows = (Directions(d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m]), tx[m], 1 - tx[m], y[m])
        blocks.add_batch(NormalEquations(basis, 2).add(*rows), s + 0.5)
    closed = blocks.closed()
    assert closed.n_blocks == 6 and closed.sum_n == pytest.approx(t.size)


def _links(rng: np.random.Generator, n_nodes: int, n: int, one_link: bool) -> tuple[Directions, np.ndarray, np.ndarray]:
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = np.arcsin(rng.uniform(-1.0, 1.0, (2, n)))
    tx = np.zeros(n, np.int_) if one_link else rng.integers(0, n_nodes, n)
    rx = np.ones(n, np.int_) if one_link else (tx + rng.integers(1, n_nodes, n)) % n_nodes
    return Directions(az[0], el[0], az[1], el[1]), tx, rx


@pytest.mark.parametrize(("kind", "n_nodes", "one_link", "environment"),
                         [("sh", 2, False, False), ("sh", 4, False, True), ("sh", 2, True, False), ("bg", 3, False, False),
                          ("bg", 2, True, True)])
def test_time_blocks_kept_in_the_pass_equal_each_blocks_own_statistics(monkeypatch, kind, n_nodes, one_link, environment):
    """Statistics given each sample's time block keep every block's sums per directed link, the
    same as each block accumulated alone (many links at once, one link in pipelined blocks, a
    basis without Gram moments; runs split between blocks of samples), the rest unchanged; their
    block sums, also at a nested smaller order, those a live session's batches give."""
    monkeypatch.setattr(link_statistics, "BLOCK_SAMPLES", 700)
    monkeypatch.setattr(link_statistics, "PIPELINE_MIN_BLOCK", 300)
    rng = np.random.default_rng(n_nodes)
    basis = make_basis(kind, 5 if kind == "sh" else 3)
    small = make_basis("sh", 3) if kind == "sh" else basis
    n = 4000
    d, tx, rx = _links(rng, n_nodes, n, one_link)
    y, e = rng.normal(0.0, 3.0, n), (rng.normal(size=n) if environment else None)
    t = np.sort(rng.uniform(0.0, 80.0, n))
    label = np.floor(t / BLOCK_S).astype(np.int64)
    kept = NormalEquations(basis, n_nodes, environment).add(d, tx, rx, y, e, time_block=label)
    plain = NormalEquations(basis, n_nodes, environment).add(d, tx, rx, y, e)
    np.testing.assert_allclose(kept.gram, plain.gram, rtol=0, atol=1e-9 * np.abs(plain.gram).max())
    np.testing.assert_allclose(kept.rhs, plain.rhs, atol=1e-8)
    for k, v in plain.directed.items():
        np.testing.assert_allclose(kept.directed[k], v, atol=1e-8)
    assert not plain.block_directed and sorted(kept.block_directed) == sorted(np.unique(label).tolist())
    want, want_small = BlockSums(n_nodes, basis.n_coef, BLOCK_S), BlockSums(n_nodes, small.n_coef, BLOCK_S)
    for k in np.unique(label):
        m = label == k
        alone = NormalEquations(basis, n_nodes, environment).add(Directions(*(a[m] for a in d)), tx[m], rx[m], y[m],
                                                                 None if e is None else e[m])
        assert set(kept.block_directed[int(k)]) == set(alone.directed)
        for key, v in alone.directed.items():
            np.testing.assert_allclose(kept.block_directed[int(k)][key], v, atol=1e-8)
        want.add_batch(alone, (k + 0.5) * BLOCK_S)
        want_small.add_batch(sub_statistics(alone, small), (k + 0.5) * BLOCK_S)
    halves = [NormalEquations(basis, n_nodes, environment) for _ in range(2)]  # merged: one unit in two pieces
    for half, part in zip(halves, (slice(0, n // 2), slice(n // 2, n))):
        half.add(Directions(*(a[part] for a in d)), tx[part], rx[part], y[part], None if e is None else e[part],
                 time_block=label[part])
    merged = halves[0].merge(halves[1])
    # only the nested smaller order's coefficients kept per block (block_coefs): its sums, less memory
    trimmed = NormalEquations(basis, n_nodes, environment, block_coefs=small.n_coef).add(d, tx, rx, y, e, time_block=label)
    np.testing.assert_array_equal(trimmed.gram, kept.gram)
    assert {v.size for links in trimmed.block_directed.values() for v in links.values()} == {2 * small.n_coef + 3}
    if small.n_coef < basis.n_coef:  # sums of different widths do not merge
        with pytest.raises(InputError, match="block_coefs"):
            NormalEquations(basis, n_nodes, environment).add(d, tx, rx, y, e, time_block=label).merge(trimmed)
    with pytest.raises(InputError, match="block_coefs"):
        NormalEquations(basis, n_nodes, environment, block_coefs=basis.n_coef + 1)
    with pytest.raises(InputError, match="n_coef"):
        time_block_sums([trimmed], BLOCK_S, small.n_coef + 1)
    assert NormalEquations(basis, n_nodes, environment).merge(trimmed).n_block_coefs == small.n_coef  # none kept: takes them
    for got, ref in ((time_block_sums([kept], BLOCK_S), want.closed()), (time_block_sums([merged], BLOCK_S), want.closed()),
                     (time_block_sums([kept], BLOCK_S, small.n_coef), want_small.closed()),
                     (time_block_sums([trimmed], BLOCK_S), want_small.closed())):
        assert got is not None and got.n_blocks == ref.n_blocks
        for name in ("cross", "cross_n", "sum_yv"):
            np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-10, atol=1e-8)
        for name in ("sum_yy", "sum_n", "sum_nn"):
            assert getattr(got, name) == pytest.approx(getattr(ref, name), rel=1e-12)


def test_time_blocks_of_two_units_stay_apart_and_bad_labels_are_refused() -> None:
    basis = make_basis("sh", 3)
    rng = np.random.default_rng(4)
    d, tx, rx = _links(rng, 2, 600, False)
    y = rng.normal(size=600)
    label = np.repeat(np.arange(6), 100)
    units = [NormalEquations(basis, 2).add(d, tx, rx, y, time_block=label) for _ in range(2)]
    both = time_block_sums(units, BLOCK_S)
    one = time_block_sums(units[:1], BLOCK_S)
    assert both is not None and one is not None and both.n_blocks == 2 * one.n_blocks == 12
    np.testing.assert_allclose(both.cross, 2.0 * one.cross)
    assert time_block_sums([NormalEquations(basis, 2).add(d, tx, rx, y)], BLOCK_S) is None
    with pytest.raises(InputError, match="time_block"):
        NormalEquations(basis, 2).add(d, tx, rx, y, time_block=label.astype(float))
    with pytest.raises(InputError, match="time_block has 5 values"):
        NormalEquations(basis, 2).add(d, tx, rx, y, time_block=label[:5])
    with pytest.raises(InputError, match="n_coef"):
        time_block_sums(units, BLOCK_S, 99)


def _three_links(seconds: float, seed: int) -> tuple[NormalEquations, BlockSums, list[NormalEquations]]:
    """Three nodes (links 0-1, 0-2, 1-2) seen at 50 Hz for ``seconds``, white noise plus an
    offset per link and 5-s block: their statistics, live block sums (1-s batches) and each
    block's statistics kept in two pieces (a flight cut into stretches)."""
    basis = make_basis("sh", 2)
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / RATE_HZ)
    d, tx, rx = _links(rng, 3, t.size, False)
    coef = rng.normal(0.0, 2.0, 3 * basis.n_coef)
    p = basis.n_coef
    truth = np.array([basis.design(d.az_tx[i:i + 1], d.el_tx[i:i + 1])[0] @ coef[tx[i] * p:(tx[i] + 1) * p]
                      + basis.design(d.az_rx[i:i + 1], d.el_rx[i:i + 1])[0] @ coef[rx[i] * p:(rx[i] + 1) * p]
                      for i in range(t.size)])
    label = np.floor(t / BLOCK_S).astype(np.int64)
    link = np.minimum(tx, rx) + np.maximum(tx, rx)  # 1, 2, 3: one code per link
    offsets = rng.normal(0.0, 3.0, (4, label.max() + 1))
    y = truth + rng.normal(0.0, 1.0, t.size) + offsets[link, label]
    normal, blocks = NormalEquations(basis, 3), BlockSums(3, p, BLOCK_S)
    for s in range(int(seconds)):
        m = (t >= s) & (t < s + 1)
        batch = NormalEquations(basis, 3).add(Directions(*(a[m] for a in d)), tx[m], rx[m], y[m])
        normal.merge(batch)
        blocks.add_batch(batch, s + 0.5)
    half = t.size // 2 + 7  # within a block: its samples in both pieces
    pieces = [NormalEquations(basis, 3).add(Directions(*(a[part] for a in d)), tx[part], rx[part], y[part],
                                            time_block=label[part]) for part in (slice(0, half), slice(half, t.size))]
    return normal, blocks, pieces


def test_three_links_in_two_blocks_estimate_no_drift() -> None:
    """Three links in 2 time blocks are 6 block vectors but no link is seen in MIN_BLOCKS
    distinct blocks: no drift (the 6 vectors passed for 6 blocks, and a drift was estimated
    from two blocks)."""
    normal, blocks, pieces = _three_links(10.0, 5)
    closed = blocks.closed()
    assert closed.n_blocks == 6 and closed.link_blocks == 2
    assert correlated_ratio(normal, closed, _prior(normal)) == 0.0
    summed = time_block_sums(pieces, BLOCK_S)
    assert summed is not None and summed.n_blocks == 9 and summed.link_blocks == 2  # the cut block once per link
    assert correlated_ratio(normal, summed, _prior(normal)) == 0.0


def test_three_links_in_four_blocks_estimate_the_drift() -> None:
    normal, blocks, pieces = _three_links(20.0, 5)
    closed = blocks.closed()
    assert closed.n_blocks == 12 and closed.link_blocks == 4 == MIN_BLOCKS
    # offsets of 3 dB over a 1-dB white noise; the estimates of before (counting vectors)
    assert correlated_ratio(normal, closed, _prior(normal)) == pytest.approx(13.824419254506136, rel=1e-9)
    summed = time_block_sums(pieces, BLOCK_S)
    assert summed is not None and summed.n_blocks == 15 and summed.link_blocks == 4
    assert correlated_ratio(normal, summed, _prior(normal)) == pytest.approx(15.718238763156771, rel=1e-9)
    summed.add_vectors(np.zeros((1, summed.cross.shape[0] + 2)) + 1.0, -1.0, links=[(2, 1)], labels=[0])
    assert summed.link_blocks == 4  # link 1-2's block 0 still held by another vector
    with pytest.raises(InputError, match="links"):
        summed.add_vectors(np.ones((2, summed.cross.shape[0] + 2)), links=[(0, 1)], labels=[0, 1])


@pytest.mark.parametrize(("seed", "want"), [(0, 0.09741237012759629), (1, 0.1145297827563708)])
def test_two_nodes_estimate_the_same_drift_as_before(seed: int, want: float) -> None:
    """One link: its blocks are the block vectors, the estimate unchanged to the bit (the blocks
    per link counted up to MIN_BLOCKS: all a drift needs, and no memory that grows with the flight)."""
    normal, blocks = _accumulate(600.0, 2.0, 0.6, seed)
    closed = blocks.closed()
    assert closed.n_blocks == 120 and closed.link_blocks == MIN_BLOCKS
    assert sum(len(labels) for labels in closed.link_labels.values()) == MIN_BLOCKS
    assert correlated_ratio(normal, closed, _prior(normal)) == want
