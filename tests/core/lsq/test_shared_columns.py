"""Shared columns of the joint problem: the environment column and link offsets (issue 12, items 1-2)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import make_basis
from rplearn.core.environment import log_distance_column
from rplearn.core.geometry import Directions
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection import sub_statistics
from rplearn.core.lsq.solver import JointFitOptions, fit_joint
from rplearn.errors import IdentifiabilityError, InputError


def _design(basis, d, tx, rx, n_nodes, e, links):
    """The explicit design matrix [patterns | e | offsets] (what the statistics must equal)."""
    p = basis.n_coef
    eye = np.eye(p)
    f_tx = np.array([basis.evaluate(eye[j], d.az_tx, d.el_tx) for j in range(p)]).T
    f_rx = np.array([basis.evaluate(eye[j], d.az_rx, d.el_rx) for j in range(p)]).T
    x = np.zeros((tx.size, n_nodes * p + (e is not None) + len(links)))
    for i in range(tx.size):
        x[i, tx[i] * p:(tx[i] + 1) * p] += f_tx[i]
        x[i, rx[i] * p:(rx[i] + 1) * p] += f_rx[i]
    col = n_nodes * p
    if e is not None:
        x[:, col] = e
        col += 1
    for j, (a, b) in enumerate(links):
        x[(tx == a) & (rx == b), col + j] = 1.0
        x[(tx == b) & (rx == a), col + j] = -1.0
    return x


def _random_samples(rng, n, n_nodes, one_way=()):
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = rng.uniform(-1.5, 1.5, (2, n))
    tx = rng.integers(0, n_nodes, n)
    rx = (tx + rng.integers(1, n_nodes, n)) % n_nodes
    for a, b in one_way:  # keep only a -> b of this link
        back = (tx == b) & (rx == a)
        tx[back], rx[back] = a, b
    return Directions(az[0], el[0], az[1], el[1]), tx, rx


@pytest.mark.parametrize("kind,order", [("sh", 4), ("bg", 3), ("poly", 3)])
def test_with_shared_equals_the_explicit_design(kind, order):
    rng = np.random.default_rng(3)
    basis = make_basis(kind, order)
    d, tx, rx = _random_samples(rng, 2500, 3, one_way=[(1, 2)])
    y, e = rng.normal(size=tx.size), rng.normal(size=tx.size)
    half = tx.size // 2
    ne = NormalEquations(basis, 3, environment=True)
    ne.add(Directions(*(a[:half] for a in d)), tx[:half], rx[:half], y[:half], e[:half])
    ne.add(Directions(*(a[half:] for a in d)), tx[half:], rx[half:], y[half:], e[half:])
    links = ne.two_way_links()
    assert links == [(0, 1), (0, 2)]  # 1 -> 2 only: no offset for that link
    full = ne.with_shared(links)
    x = _design(basis, d, tx, rx, 3, e, links)
    scale = np.abs(x.T @ x).max()
    np.testing.assert_allclose(full.gram, x.T @ x, atol=1e-10 * scale)
    np.testing.assert_allclose(full.rhs, x.T @ y, atol=1e-9 * scale)
    assert full.environment_sum == pytest.approx(e.sum())
    assert full.shared == (("exponent",), ("offset", 0, 1), ("offset", 0, 2))
    with pytest.raises(InputError, match="with_shared"):
        full.add(d, tx, rx, y, e)


def test_merge_and_sub_statistics_keep_the_shared_sums():
    rng = np.random.default_rng(4)
    big, small = make_basis("sh", 5), make_basis("sh", 3)
    d, tx, rx = _random_samples(rng, 1500, 2)
    y, e = rng.normal(size=tx.size), rng.normal(size=tx.size)
    a = NormalEquations(big, 2, environment=True).add(Directions(*(v[:700] for v in d)), tx[:700], rx[:700], y[:700], e[:700])
    b = NormalEquations(big, 2, environment=True).add(Directions(*(v[700:] for v in d)), tx[700:], rx[700:], y[700:], e[700:])
    merged = a.merge(b).with_shared([(0, 1)])
    direct = NormalEquations(small, 2, environment=True).add(d, tx, rx, y, e).with_shared([(0, 1)])
    sub = sub_statistics(merged, small)
    np.testing.assert_allclose(sub.gram, direct.gram, atol=1e-8 * np.abs(direct.gram).max())
    np.testing.assert_allclose(sub.rhs, direct.rhs, atol=1e-8 * np.abs(direct.rhs).max())
    with pytest.raises(InputError, match="environment"):
        NormalEquations(big, 2).add(d, tx, rx, y, e)
    with pytest.raises(InputError, match="environment"):
        NormalEquations(big, 2, environment=True).add(d, tx, rx, y)


def test_exponent_and_offsets_are_recovered_from_exact_data():
    rng = np.random.default_rng(5)
    basis = make_basis("sh", 3)
    d, tx, rx = _random_samples(rng, 6000, 3)
    coef = rng.normal(size=(3, basis.n_coef))
    dist = rng.uniform(5.0, 80.0, tx.size)
    offset = {(0, 1): 1.5, (0, 2): -0.7, (1, 2): 0.4}  # a -> b gets +v, b -> a gets -v
    y = np.array([basis.evaluate(coef[t], [d.az_tx[i]], [d.el_tx[i]])[0] + basis.evaluate(coef[r], [d.az_rx[i]], [d.el_rx[i]])[0]
                  for i, (t, r) in enumerate(zip(tx, rx))])
    y += (3.1 - 2.0) * log_distance_column(dist)
    for (a, b), v in offset.items():
        y[(tx == a) & (rx == b)] += v
        y[(tx == b) & (rx == a)] -= v
    sol = fit_joint(d, tx, rx, y, 3, basis, options=JointFitOptions(ridge=1e-9, environment=log_distance_column(dist), link_offsets=True))
    assert sol.shared[0] == ("exponent",)
    assert 2.0 + sol.shared_coef[0] == pytest.approx(3.1, abs=1e-6)
    np.testing.assert_allclose(sol.shared_coef[1:], [offset[(0, 1)], offset[(0, 2)], offset[(1, 2)]], atol=1e-6)
    np.testing.assert_allclose(sol.coef, coef, atol=1e-6)  # a triangle: absolute gains identified
    assert sol.covariance.shape == (3 * basis.n_coef + 4,) * 2
    assert 0.3 < sol.shared_unexplained[0] <= 1.0


def test_constant_distance_exponent_is_not_identifiable():
    """At constant distance the log-distance column is a constant: the patterns take any exponent."""
    rng = np.random.default_rng(6)
    basis = make_basis("sh", 3)
    d, tx, rx = _random_samples(rng, 3000, 2)
    dist = 10.0 + 0.05 * rng.normal(size=tx.size)  # a flight "at 10 m", tracking error included
    y = rng.normal(size=tx.size) - 1.0 * log_distance_column(dist)
    with pytest.raises(IdentifiabilityError, match="path-loss exponent is not identifiable"):
        fit_joint(d, tx, rx, y, 2, basis, options=JointFitOptions(environment=log_distance_column(dist)))
    # the distance moving with the directions (a drone at constant altitude seen from a station,
    # one direction logged) is refused too
    tx, rx = np.zeros_like(tx), np.ones_like(rx)
    d = Directions(d.az_tx, d.el_tx, d.az_rx, -d.el_tx)
    dist = 20.0 * 10 ** (0.3 * np.sin(d.el_tx))  # 10 log10 d linear in sin(el): within SH-3
    with pytest.raises(IdentifiabilityError, match="directions do not explain"):
        fit_joint(d, tx, rx, rng.normal(size=tx.size), 2, basis, options=JointFitOptions(environment=log_distance_column(dist)))
    # the same directions at distances of their own: identified
    dist = dist * rng.choice([1.0, 2.0], tx.size)
    sol = fit_joint(d, tx, rx, rng.normal(size=tx.size), 2, basis, options=JointFitOptions(environment=log_distance_column(dist)))
    assert sol.shared == (("exponent",),)


def test_the_block_buffer_is_capped_and_blocks_add_up():
    """SH-24: the accumulation buffer stays within BLOCK_MAX_VALUES (issue 13, item 4), and
    statistics over several blocks equal those over one block each."""
    from rplearn.core.lsq import link_statistics as ne_module
    from rplearn.core.lsq.runtime import DEFAULT_RUNTIME

    rng = np.random.default_rng(11)
    basis = make_basis("sh", 24)
    rows = ne_module.block_rows(basis)
    per_block = ne_module.block_samples(rows)
    assert per_block < ne_module.BLOCK_SAMPLES and rows * per_block <= ne_module.BLOCK_MAX_VALUES
    n = per_block + 500  # two blocks
    d, tx, rx = _random_samples(rng, n, 2)
    y = rng.normal(size=n)
    whole = NormalEquations(basis, 2).add(d, tx, rx, y)
    assert DEFAULT_RUNTIME.buffer_size() <= ne_module.BLOCK_MAX_VALUES  # this thread's (the workers hold theirs)
    half = n // 2
    parts = NormalEquations(basis, 2)
    parts.add(Directions(*(a[:half] for a in d)), tx[:half], rx[:half], y[:half])
    parts.add(Directions(*(a[half:] for a in d)), tx[half:], rx[half:], y[half:])
    np.testing.assert_allclose(whole.gram, parts.gram, atol=1e-9 * np.abs(whole.gram).max())
    np.testing.assert_allclose(whole.rhs, parts.rhs, atol=1e-9 * np.abs(whole.rhs).max())


@pytest.mark.parametrize("kind,order", [("sh", 4), ("bg", 3)])
def test_column_sums_are_those_of_the_explicit_design(kind, order):
    """``X^T 1`` and ``1^T y`` from the directed links' sums (each unit's mean residual in the
    selection's between-flight level spread), shared columns included."""
    rng = np.random.default_rng(5)
    basis = make_basis(kind, order)
    d, tx, rx = _random_samples(rng, 1200, 3, one_way=[(1, 2)])
    y, e = rng.normal(size=tx.size), rng.normal(size=tx.size)
    ne = NormalEquations(basis, 3, environment=True).add(d, tx, rx, y, e)
    full = ne.with_shared(ne.two_way_links())
    sums, sum_y = full.column_sums()
    x = _design(basis, d, tx, rx, 3, e, ne.two_way_links())
    np.testing.assert_allclose(sums, x.sum(axis=0), atol=1e-9 * np.abs(x).sum())
    assert sum_y == pytest.approx(y.sum()) and ne.column_sums()[0].size == ne.n_columns
