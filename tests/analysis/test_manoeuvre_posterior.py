"""The manoeuvre posterior with an error drifting over seconds (rplearn.analysis.manoeuvre_posterior)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rplearn.analysis.manoeuvre_posterior import ManoeuvrePosterior, psd_factor
from rplearn.analysis.manoeuvres import ManoeuvreOptions, pattern_spreads, prior_penalty_weight, rank_manoeuvres, target_metrics
from rplearn.core.geometry import Directions
from rplearn.core.lsq.block_sums import BlockSums
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.errors import InputError
from rplearn.models.spec import ModelSpec
from rplearn.plan.manoeuvres import CandidateOptions

SPEC = ModelSpec("sh", 3)
NODES = ("A", "B")
NOISE_VAR = 9.0


def _setup(seed: int = 0):
    rng = np.random.default_rng(seed)
    p = SPEC.basis().n_coef
    metrics = target_metrics(SPEC.basis(), NODES, ManoeuvreOptions())
    x = rng.standard_normal((40, 2 * p))
    a = x.T @ x + np.eye(2 * p)
    v = rng.standard_normal((2 * p, 3)) * 4.0
    return rng, p, metrics, a, v @ v.T


def _direct(a, c, rows, weight, block_rows, sc2, metrics, p):
    """The sandwich covariance after the rows, formed whole."""
    a2 = a + weight * rows.T @ rows
    starts = np.arange(0, rows.shape[0], block_rows)
    u = weight * np.add.reduceat(rows, starts, axis=0).T
    inv = np.linalg.inv(a2)
    cov = NOISE_VAR * inv + sc2 * inv @ (c + u @ u.T) @ inv
    return np.sqrt([np.sum(m * cov[k * p:(k + 1) * p, k * p:(k + 1) * p]) for k, m in enumerate(metrics)])


@pytest.mark.parametrize("n_rows", [5, 60])
def test_the_rank_k_update_with_drift_is_the_sandwich_formed_whole(n_rows: int) -> None:
    rng, p, metrics, a, c = _setup()
    sc2, weight, block_rows = 0.7, 2.5, 4
    post = ManoeuvrePosterior(a / NOISE_VAR, metrics, NOISE_VAR).with_drift(sc2, c, block_rows)
    inv = np.linalg.inv(a)
    now = NOISE_VAR * inv + sc2 * inv @ c @ inv
    assert np.allclose(post.spreads(), np.sqrt([np.sum(m * now[k * p:(k + 1) * p, k * p:(k + 1) * p])
                                                for k, m in enumerate(metrics)]), rtol=1e-9)
    rows = rng.standard_normal((n_rows, 2 * p))
    expected = _direct(a, c, rows, weight, block_rows, sc2, metrics, p)
    assert np.allclose(post.spreads_after(rows, weight), expected, rtol=1e-8)
    post.update(rows, weight)  # taken in: the same, and a second manoeuvre after it too
    assert np.allclose(post.spreads(), expected, rtol=1e-8)
    more = rng.standard_normal((7, 2 * p))
    a2 = a + weight * rows.T @ rows
    u = weight * np.add.reduceat(rows, np.arange(0, n_rows, block_rows), axis=0).T
    assert np.allclose(post.spreads_after(more, weight), _direct(a2, c + u @ u.T, more, weight, block_rows, sc2, metrics, p),
                       rtol=1e-8)


def test_without_drift_the_posterior_is_the_white_one_to_the_bit() -> None:
    rng, p, metrics, a, c = _setup(1)
    rows = rng.standard_normal((9, 2 * p))
    white = ManoeuvrePosterior(a / NOISE_VAR, metrics, NOISE_VAR)
    off = ManoeuvrePosterior(a / NOISE_VAR, metrics, NOISE_VAR).with_drift(0.0, c, 4)
    assert np.array_equal(white.spreads_after(rows, 2.0), off.spreads_after(rows, 2.0))
    assert np.array_equal(white.spreads(), off.spreads())


def test_one_look_in_one_block_learns_less_than_the_same_looks_in_separate_blocks() -> None:
    """The point of the drift: repeating a direction within one block does not average its error."""
    rng, p, metrics, a, c = _setup(2)
    rows = np.tile(rng.standard_normal((4, 2 * p)), (6, 1))  # four directions, six times each
    one = ManoeuvrePosterior(a / NOISE_VAR, metrics, NOISE_VAR).with_drift(1.0, None, 24)  # all in one block
    apart = ManoeuvrePosterior(a / NOISE_VAR, metrics, NOISE_VAR).with_drift(1.0, None, 4)  # each visit its own block
    white = ManoeuvrePosterior(a / NOISE_VAR, metrics, NOISE_VAR)
    s_one, s_apart, s_white = (post.spreads_after(rows, 50.0) for post in (one, apart, white))
    assert np.all(s_one > s_apart) and np.all(s_apart > s_white)


def test_psd_factor_rebuilds_the_matrix() -> None:
    rng = np.random.default_rng(3)
    f = rng.standard_normal((6, 2))
    g = psd_factor(f @ f.T)
    assert g.shape == (6, 2) and np.allclose(g @ g.T, f @ f.T)
    assert psd_factor(np.zeros((3, 3))).shape == (3, 0)


def _statistics(seconds: float, drift_db: float):
    basis = SPEC.basis()
    t = np.arange(0.0, seconds, 0.05)
    rng = np.random.default_rng(4)
    d = Directions(np.angle(np.exp(2j * np.pi * t / 12.0)), 0.5 * np.sin(t / 9.0), np.angle(np.exp(2j * np.pi * t / 17.0)),
                   -0.3 * np.sin(t / 5.0))
    blk = (t // 5.0).astype(int)
    y = rng.normal(0.0, 3.0, t.size) + rng.normal(0.0, drift_db, blk.max() + 1)[blk]
    normal, blocks = NormalEquations(basis, 2), BlockSums(2, basis.n_coef, 5.0)
    tx = np.zeros(t.size, np.int_)
    for s in range(int(seconds)):
        m = (t >= s) & (t < s + 1)
        normal.add(Directions(*(v[m] for v in d)), tx[m], 1 - tx[m], y[m])
        blocks.follow(normal, s + 0.5)
    return normal, blocks


def test_the_ranking_reads_the_drift_the_blocks_show_and_is_unchanged_without_it() -> None:
    normal, blocks = _statistics(120.0, 1.5)
    weight = prior_penalty_weight(SPEC.basis(), 3.0, 3.0, SPEC.ridge_weight)
    cands = CandidateOptions(elevations_deg=(0.0, 30.0), library_loops=(1,), anchor_turns=False)
    opts = ManoeuvreOptions(noise_std_db=3.0, packet_rate_hz=20.0, penalty_weight=weight, candidates=cands)
    plain = pattern_spreads(normal, SPEC, NODES, opts)
    assert pattern_spreads(normal, SPEC, NODES, replace(opts, correlated_std_db=0.0), blocks) == plain
    drifting = pattern_spreads(normal, SPEC, NODES, opts, blocks)  # estimated from the blocks
    assert all(drifting[n] > plain[n] for n in NODES)
    poses = {"A": ((-5.0, 0.0, 20.0), 0.0), "B": ((5.0, 0.0, 20.0), 0.0)}
    ranked = rank_manoeuvres(normal, SPEC, NODES, poses, opts, blocks)
    assert ranked and all(r.spread_before_db == drifting for r in ranked)
    assert [r.name for r in rank_manoeuvres(normal, SPEC, NODES, poses, replace(opts, correlated_std_db=0.0), blocks)] == \
        [r.name for r in rank_manoeuvres(normal, SPEC, NODES, poses, opts)]


def test_the_prior_excess_is_a_monte_carlo_over_truths_from_the_larger_prior_and_updates_like_the_whole() -> None:
    """Truth drawn from a prior ``factor`` times what the penalty implies, white noise as stated:
    the fit's error over the targets has the spread of ``sigma^2 A^-1 + sigma^2 (factor - 1) A^-1 P A^-1``,
    and a manoeuvre's rank-k update gives the sandwich formed whole."""
    rng, p, metrics, _, _ = _setup(7)
    x = rng.standard_normal((10, 2 * p))
    prior = np.linspace(0.5, 3.0, 2 * p)
    a = x.T @ x + np.diag(prior)
    factor = 4.0
    post = ManoeuvrePosterior(a / NOISE_VAR, metrics, NOISE_VAR).with_prior_excess(factor - 1.0, prior)
    draws = 6000
    beta = rng.standard_normal((draws, 2 * p)) * np.sqrt(factor * NOISE_VAR / prior)
    y = beta @ x.T + rng.standard_normal((draws, x.shape[0])) * np.sqrt(NOISE_VAR)
    err = np.linalg.solve(a, x.T @ y.T).T - beta
    mc = np.sqrt([np.mean(np.einsum("ij,jk,ik->i", err[:, k * p:(k + 1) * p], m, err[:, k * p:(k + 1) * p]))
                  for k, m in enumerate(metrics)])
    assert np.all(post.spreads() > 1.3 * ManoeuvrePosterior(a / NOISE_VAR, metrics, NOISE_VAR).spreads())
    assert np.allclose(post.spreads(), mc, rtol=0.05)
    rows, weight = rng.standard_normal((50, 2 * p)), 1.5
    inv = np.linalg.inv(a + weight * rows.T @ rows)
    cov = NOISE_VAR * inv + NOISE_VAR * (factor - 1.0) * inv @ np.diag(prior) @ inv
    want = np.sqrt([np.sum(m * cov[k * p:(k + 1) * p, k * p:(k + 1) * p]) for k, m in enumerate(metrics)])
    assert np.allclose(post.spreads_after(rows, weight), want, rtol=1e-8)


def test_psd_factor_falls_back_to_the_svd_when_the_eigensolver_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(8)
    v = rng.standard_normal((12, 5))
    m = v @ v.T

    def fail(*args: object, **kwargs: object) -> None:
        raise np.linalg.LinAlgError("Eigenvalues did not converge")

    monkeypatch.setattr(np.linalg, "eigh", fail)
    f = psd_factor(m)
    assert f.shape == (12, 5) and np.allclose(f @ f.T, m)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_psd_factor_refuses_a_matrix_that_is_not_finite(bad: float) -> None:
    m = np.eye(4)
    m[1, 2] = m[2, 1] = bad
    with pytest.raises(InputError, match="^matrix: .*NaN or infinite"):
        psd_factor(m)
