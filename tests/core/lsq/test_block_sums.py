"""Per-time-block sums and the drifting error's estimate (rplearn.core.lsq.block_sums)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import make_basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq.block_sums import MIN_BLOCKS, BlockSums, correlated_ratio
from rplearn.core.lsq.normal_equations import NormalEquations
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
