"""The pattern misfit per direction cell in the manoeuvre posterior (rplearn.analysis.manoeuvre_cells)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.analysis.manoeuvre_cells import DirectionCells, cell_grid, cell_index, cell_sums
from rplearn.analysis.manoeuvre_posterior import ManoeuvrePosterior
from rplearn.analysis.manoeuvres import ManoeuvreOptions, pattern_spreads, target_metrics
from rplearn.core.geometry import Directions
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.errors import InputError
from rplearn.models.spec import ModelSpec

SPEC = ModelSpec("sh", 3)
NODES = ("A", "B")


def _samples(rng: np.random.Generator, n: int, spread: float = 1.0) -> tuple[Directions, np.ndarray, np.ndarray]:
    az = rng.uniform(-np.pi, np.pi, (n, 2)) * spread
    el = np.arcsin(rng.uniform(-1, 1, (n, 2)) * spread)
    tx = rng.integers(0, 2, n)
    return Directions(az[:, 0], el[:, 0], az[:, 1], el[:, 1]), tx, 1 - tx


def _rows(d: Directions, tx: np.ndarray, rx: np.ndarray) -> np.ndarray:
    basis = SPEC.basis()
    p = basis.n_coef
    rows = np.zeros((tx.size, 2 * p))
    ft, fr = basis.design(d.az_tx, d.el_tx), basis.design(d.az_rx, d.el_rx)
    for i in range(tx.size):
        rows[i, tx[i] * p:(tx[i] + 1) * p] += ft[i]
        rows[i, rx[i] * p:(rx[i] + 1) * p] += fr[i]
    return rows


def test_the_cell_sums_are_each_node_and_cell_s_features_summed_by_brute_force() -> None:
    rng = np.random.default_rng(1)
    d, tx, rx = _samples(rng, 300)
    cells = DirectionCells(SPEC.basis(), 2).add(d, tx, rx)
    grid = cell_grid(SPEC.basis().n_coef)
    rows = _rows(d, tx, rx)
    want = np.zeros_like(cells.sums)
    n_cells = grid.shape[0]
    for i in range(tx.size):  # nearest centre by angle, one end at a time
        for node, az, el in ((tx[i], d.az_tx[i], d.el_tx[i]), (rx[i], d.az_rx[i], d.el_rx[i])):
            u = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
            want[node * n_cells + int(np.argmin(np.arccos(np.clip(grid @ u, -1, 1))))] += rows[i]
    assert np.allclose(cells.sums, want)
    assert cells.factor().shape[1] == int(np.sum(np.any(want != 0, axis=1)))
    assert np.allclose(cell_sums(rows, ((tx, d.az_tx, d.el_tx), (rx, d.az_rx, d.el_rx)), grid, 2.0) @
                       cell_sums(rows, ((tx, d.az_tx, d.el_tx), (rx, d.az_rx, d.el_rx)), grid, 2.0).T,
                       4.0 * cells.factor() @ cells.factor().T)


def test_the_misfit_term_is_a_monte_carlo_over_offsets_drawn_per_node_and_cell() -> None:
    """Truth drawn from the prior, an offset per (node, cell) and white noise: the spread of
    the fit's error over the targets matches the posterior with the misfit term."""
    rng = np.random.default_rng(2)
    basis = SPEC.basis()
    p = basis.n_coef
    d, tx, rx = _samples(rng, 400, spread=0.5)  # few cells, many samples each: the misfit dominates
    x = _rows(d, tx, rx)
    noise_var, misfit_var, prior = 4.0, 0.8, 0.5
    a = x.T @ x + prior * np.eye(2 * p)
    grid = cell_grid(p)
    ends = ((tx, d.az_tx, d.el_tx), (rx, d.az_rx, d.el_rx))
    metrics = target_metrics(basis, NODES, ManoeuvreOptions())
    post = ManoeuvrePosterior(a / noise_var, metrics, noise_var).with_misfit(misfit_var, cell_sums(x, ends, grid), grid)
    white = ManoeuvrePosterior(a / noise_var, metrics, noise_var).spreads()
    keys = [k * grid.shape[0] + cell_index(az, el, grid) for k, az, el in ends]
    draws = 4000
    beta = rng.standard_normal((draws, 2 * p)) * np.sqrt(noise_var / prior)
    offsets = rng.standard_normal((draws, 2 * grid.shape[0])) * np.sqrt(misfit_var)
    y = beta @ x.T + offsets[:, keys[0]] + offsets[:, keys[1]] + rng.standard_normal((draws, tx.size)) * np.sqrt(noise_var)
    err = np.linalg.solve(a, x.T @ y.T).T - beta
    mc = np.sqrt([np.mean(np.einsum("ij,jk,ik->i", err[:, k * p:(k + 1) * p], m, err[:, k * p:(k + 1) * p]))
                  for k, m in enumerate(metrics)])
    assert np.all(post.spreads() > 1.2 * white)  # the term matters here
    assert np.allclose(post.spreads(), mc, rtol=0.05)


def test_a_manoeuvre_s_own_cells_update_is_the_posterior_formed_whole() -> None:
    rng = np.random.default_rng(3)
    basis = SPEC.basis()
    p = basis.n_coef
    d1, t1, r1 = _samples(rng, 80)
    d2, t2, r2 = _samples(rng, 30, spread=0.3)
    x1, x2 = _rows(d1, t1, r1), _rows(d2, t2, r2)
    grid = cell_grid(p)
    e1, e2 = ((t1, d1.az_tx, d1.el_tx), (r1, d1.az_rx, d1.el_rx)), ((t2, d2.az_tx, d2.el_tx), (r2, d2.az_rx, d2.el_rx))
    noise_var, misfit_var, weight = 9.0, 0.6, 3.0
    metrics = target_metrics(basis, NODES, ManoeuvreOptions())
    a = x1.T @ x1 + np.eye(2 * p)
    post = ManoeuvrePosterior(a / noise_var, metrics, noise_var).with_misfit(misfit_var, cell_sums(x1, e1, grid), grid)
    v = np.hstack([cell_sums(x1, e1, grid), cell_sums(x2, e2, grid, weight)])  # the manoeuvre's cells taken as new
    inv = np.linalg.inv(a + weight * x2.T @ x2)
    cov = noise_var * inv + misfit_var * inv @ v @ v.T @ inv
    want = np.sqrt([np.sum(m * cov[k * p:(k + 1) * p, k * p:(k + 1) * p]) for k, m in enumerate(metrics)])
    assert np.allclose(post.spreads_after(x2, weight, e2), want, rtol=1e-8)
    post.update(x2, weight, e2)
    assert np.allclose(post.spreads(), want, rtol=1e-8)


def test_the_same_packets_in_one_cell_teach_less_than_spread_over_many() -> None:
    rng = np.random.default_rng(4)
    basis = SPEC.basis()
    p = basis.n_coef
    d, tx, rx = _samples(rng, 200)
    x = _rows(d, tx, rx)
    grid = cell_grid(p)
    metrics = target_metrics(basis, NODES, ManoeuvreOptions())
    a = x.T @ x + np.eye(2 * p)
    one = np.full(5, 0.3), np.full(5, 0.2)  # five rows, one direction each end
    rows_one = _rows(Directions(one[0], one[1], one[0], one[1]), np.zeros(5, int), np.ones(5, int))
    spread = np.linspace(-2.5, 2.5, 5), np.linspace(-1.0, 1.0, 5)
    rows_many = _rows(Directions(spread[0], spread[1], spread[0], spread[1]), np.zeros(5, int), np.ones(5, int))
    past = cell_sums(x, ((tx, d.az_tx, d.el_tx), (rx, d.az_rx, d.el_rx)), grid)
    base = ManoeuvrePosterior(a / 9.0, metrics, 9.0).with_misfit(1.0, past, grid)
    gain_one = base.spreads() - base.spreads_after(rows_one, 2.0, ((np.zeros(5, int), *one), (np.ones(5, int), *one)))
    gain_many = base.spreads() - base.spreads_after(rows_many, 2.0, ((np.zeros(5, int), *spread), (np.ones(5, int), *spread)))
    white = ManoeuvrePosterior(a / 9.0, metrics, 9.0)
    assert np.all(white.spreads_after(rows_one, 2.0) < white.spreads())  # white noise: repeated looks still teach
    assert np.all(gain_one < gain_many) and np.all(gain_many > 0)


def test_pattern_spreads_read_the_flight_s_cells_and_refuse_cells_of_other_statistics() -> None:
    rng = np.random.default_rng(5)
    d, tx, rx = _samples(rng, 500)
    normal = NormalEquations(SPEC.basis(), 2)
    normal.add(d, tx, rx, rng.standard_normal(tx.size))
    cells = DirectionCells(SPEC.basis(), 2).add(d, tx, rx)
    opts = ManoeuvreOptions(penalty_weight=1e-3)
    plain = pattern_spreads(normal, SPEC, NODES, opts)
    assert pattern_spreads(normal, SPEC, NODES, opts, cells=cells) == plain  # no misfit size: no term
    more = pattern_spreads(normal, SPEC, NODES, ManoeuvreOptions(penalty_weight=1e-3, misfit_std_db=1.0), cells=cells)
    assert all(more[n] > plain[n] for n in NODES)
    with pytest.raises(InputError, match="cells"):
        pattern_spreads(normal, SPEC, NODES, ManoeuvreOptions(misfit_std_db=1.0), cells=DirectionCells(ModelSpec("sh", 2).basis(), 2))


def test_cells_of_another_basis_with_as_many_coefficients_are_refused() -> None:
    """SH-6 and P-7 both have 36 coefficients a node: the cells' basis itself must be the statistics'."""
    from rplearn.core.bases import Polynomial

    rng = np.random.default_rng(6)
    d, tx, rx = _samples(rng, 300)
    sh6 = ModelSpec("sh", 6)
    normal = NormalEquations(sh6.basis(), 2)
    normal.add(d, tx, rx, rng.standard_normal(tx.size))
    assert Polynomial(order=7).n_coef == sh6.basis().n_coef
    opts = ManoeuvreOptions(penalty_weight=1e-3, misfit_std_db=1.0)
    assert pattern_spreads(normal, sh6, NODES, opts, cells=DirectionCells(sh6.basis(), 2).add(d, tx, rx))
    with pytest.raises(InputError, match=r"^cells: .*P-7.*SH-6"):
        pattern_spreads(normal, sh6, NODES, opts, cells=DirectionCells(Polynomial(order=7), 2).add(d, tx, rx))


def test_bad_input_is_refused_with_the_parameter_named() -> None:
    with pytest.raises(InputError, match="misfit_std_db"):
        ManoeuvreOptions(misfit_std_db=-1.0)
    with pytest.raises(InputError, match="n_nodes"):
        DirectionCells(SPEC.basis(), 1)
    d = Directions(np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2))
    with pytest.raises(InputError, match="tx_index"):
        DirectionCells(SPEC.basis(), 2).add(d, np.array([0, 2]), np.array([1, 0]))
    with pytest.raises(InputError, match="one entry per sample"):
        DirectionCells(SPEC.basis(), 2).add(d, np.array([0]), np.array([1]))
