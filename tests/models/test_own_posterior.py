"""rplearn.models.own_posterior (issue 24, acceptance 5): each node's own-pattern spread is read
from the cross-validated prior continued to the largest candidate order, so that a small chosen
order does not hide, as exact zeros, the pattern structure the flight cannot pin down per node."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rplearn.analysis.decoupling import covered_directions, decoupling_certificate
from rplearn.analysis.pattern_error import pattern_errors_db
from rplearn.core.gauge import Gauge
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import nested_columns, penalty_scale
from rplearn.core.threads import one_blas_thread
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.data.tables import link_samples
from rplearn.models import own_posterior
from rplearn.models.auto import fit_auto
from rplearn.models.spec import ModelSpec
from rplearn.sim import simulate


def _ground_fit(seed: int):
    """The ``ground`` preset's flight, its learning units and their automatic fit."""
    sim = simulate("ground", seed=seed)
    ds = synchronise(sim.pose_log, sim.signal_log, SyncOptions()).dataset
    nodes = tuple(sorted(set(ds["tx"]) | set(ds["rx"])))
    learn = ds[~ds["unit"].str.startswith("test")]
    units = {u: link_samples(g, nodes=nodes) for u, g in learn.groupby("unit")}
    fitted, sel = fit_auto(units)
    return sim, units, fitted, sel


@pytest.fixture(scope="module")
def ground():
    """The ``ground`` preset, seed 0: a drone passing a ground station at 15 and 25 m (learning)
    and 35 m (testing); the automatic fit chooses SH-4 of candidates up to SH-15."""
    sim, units, fitted, _ = _ground_fit(0)
    return sim, units, fitted


def _assert_spread_within_criterion(sim, units, fitted):
    """Acceptance 5's criterion: each node's own-pattern spread over the directions the flight
    covered is 0.67-1.5 times its actual pattern error there."""
    model = fitted.model
    errors = pattern_errors_db(model, sim.ground_truth, covered_directions(model))
    cert = decoupling_certificate(model, list(units.values()), posterior=fitted.own_posterior)
    for node, err in errors.items():
        assert 0.67 <= cert.nodes[node].covered_std_db / err <= 1.5, (node, cert.nodes[node], err)


def test_the_own_posterior_continues_the_chosen_prior_to_the_largest_order(ground):
    _, units, fitted = ground
    model, own = fitted.model, fitted.own_posterior
    assert own is not None and own.note == ""
    assert own.basis.n_coef > model.basis.n_coef  # SH-15 against the chosen SH-4
    assert own.covariance.shape == (2 * own.basis.n_coef,) * 2
    with_own = decoupling_certificate(model, list(units.values()), posterior=own)
    chosen_only = decoupling_certificate(model, list(units.values()))
    for node in model.nodes:
        # the higher orders add variance; the sphere spread is the model's (capped) either way
        assert with_own.nodes[node].covered_std_db > 1.5 * chosen_only.nodes[node].covered_std_db
        assert with_own.nodes[node].sphere_std_db == pytest.approx(chosen_only.nodes[node].sphere_std_db)


def test_the_reported_own_spread_matches_the_actual_pattern_error(ground):
    """Acceptance 5's spread criterion on ``ground`` seed 0 (benchmarks/split.py runs seeds 0-2):
    measured 1.71 / 1.30 dB (D) and 1.77 / 1.53 dB (G) at the chosen SH-4 (the posterior
    variance about the chosen pattern, averaged over the five points the two held-out units
    cannot tell apart; 1.88 and 1.94 dB from the chosen point alone); before the order search
    stepped along the diagonal it chose SH-5, whose own SH-5 covariance gave 0.58 / 1.31 and
    0.58 / 1.59 (ratios 0.44 and 0.37)."""
    sim, units, fitted = ground
    _assert_spread_within_criterion(sim, units, fitted)


def test_too_many_columns_fall_back_to_the_chosen_order_and_say_so(ground, monkeypatch):
    _, units, _ = ground
    monkeypatch.setattr(own_posterior, "MAX_OWN_COLUMNS", 100)
    fitted, _ = fit_auto(units)
    own = fitted.own_posterior
    assert own.basis == fitted.model.basis and "a lower bound" in own.note
    cert = decoupling_certificate(fitted.model, list(units.values()), posterior=own)
    assert any("a lower bound" in note for note in cert.notes)


def test_the_own_posterior_is_level_free(ground):
    """A constant added to every RSSI value changes nothing in the own-pattern posterior."""
    _, units, fitted = ground
    moved = {u: dataclasses.replace(s, joint_gain_db=s.joint_gain_db + 63.5) for u, s in units.items()}
    other = fit_auto(moved)[0].own_posterior
    scale = float(np.max(np.abs(fitted.own_posterior.covariance)))
    np.testing.assert_allclose(other.covariance, fitted.own_posterior.covariance, rtol=0, atol=1e-6 * scale)
    before = decoupling_certificate(fitted.model, list(units.values()), posterior=fitted.own_posterior)
    after = decoupling_certificate(fit_auto(moved)[0].model, list(moved.values()), posterior=other)
    for node in fitted.model.nodes:
        assert after.nodes[node].covered_std_db == pytest.approx(before.nodes[node].covered_std_db, abs=1e-6)


def test_the_spread_is_centred_on_the_chosen_pattern_unless_a_mean_is_given(ground):
    """The automatic fit's own posterior carries no mean: the covered spread is the posterior
    variance about the chosen pattern (the wide fit's mean validates worse and is no better a
    centre). A posterior given *with* a mean adds the square of the chosen pattern's offset
    from it to the variance."""
    _, units, fitted = ground
    model, own = fitted.model, fitted.own_posterior
    assert own.mean is None and own.basis.n_coef > model.basis.n_coef
    covered = covered_directions(model)
    cert = decoupling_certificate(model, list(units.values()), posterior=own)
    q = own.basis.n_coef
    for k, node in enumerate(model.nodes):
        az, el = covered[node]
        x = own.basis.design(az, el)
        x = x - x.mean(axis=0)  # both nodes' constants are gauged on this two-node flight
        block = own.covariance[k * q:(k + 1) * q, k * q:(k + 1) * q]
        variance = float(np.mean(np.einsum("ij,jk,ik->i", x, block, x)))
        assert cert.nodes[node].covered_std_db == pytest.approx(np.sqrt(variance), rel=1e-9)
    rng = np.random.default_rng(3)
    mean = np.zeros((len(model.nodes), q))
    mean[:, :model.basis.n_coef] = model.coef
    mean += rng.normal(0.0, 0.3, mean.shape)
    shifted = decoupling_certificate(model, list(units.values()), posterior=dataclasses.replace(own, mean=mean))
    for k, node in enumerate(model.nodes):
        az, el = covered[node]
        padded = np.zeros(q)
        padded[:model.basis.n_coef] = model.coef[k]
        offset = own.basis.design(az, el) @ (mean[k] - padded)
        offset = offset - offset.mean()
        expected = cert.nodes[node].covered_std_db**2 + float(np.mean(offset**2))
        assert shifted.nodes[node].covered_std_db == pytest.approx(np.sqrt(expected), rel=1e-9)
        assert shifted.nodes[node].covered_std_db > cert.nodes[node].covered_std_db


def test_fit_stores_the_own_spread_map_and_plot_draws_it(ground):
    """``certify`` stores the own-pattern std on the coverage grid; ``plot --spread`` draws that
    map (not the chosen order's smaller covariance) when present."""
    import copy

    from rplearn.analysis.decoupling import OWN_MAP_POINTS, certify
    from rplearn.core.bases import fibonacci_grid_nodes
    from rplearn.viz.plot import _own_std_map

    _, units, fitted = ground
    model = copy.deepcopy(fitted.model)
    certify(model, list(units.values()), fitted.own_posterior)
    stored = model.training["decoupling"]["own_std_db"]
    for node in model.nodes:
        az, el = fibonacci_grid_nodes(OWN_MAP_POINTS)
        assert len(stored[node]) == OWN_MAP_POINTS
        drawn = _own_std_map(model, node, az, el)
        np.testing.assert_allclose(drawn, stored[node], atol=1e-12)
        near = model.coverage_deg(node, az, el) <= 10.0
        assert near.sum() > 50
        assert np.mean(drawn[near]) > 1.5 * np.mean(model.standard_error(node, az[near], el[near]))
    del model.training["decoupling"]["own_std_db"]  # an older model file: the model's covariance
    node = model.nodes[0]
    az, el = fibonacci_grid_nodes(64)
    np.testing.assert_allclose(_own_std_map(model, node, az, el), model.standard_error(node, az, el))


def test_the_spread_does_not_hang_on_a_near_tie_of_the_validation():
    """``ground`` seed 1: SH-5 at smoothing 3.2e-5 validates 4.524 dB, SH-4 at 1e-5 4.532 dB (two
    held-out units cannot tell them apart), and the chosen point's own posterior alone gave
    1.20 dB against errors of 1.39 (D) and 1.93 dB (G): G's ratio 0.62. Averaged over the tied
    points' posteriors: 1.41 and 1.42 dB (ratios 1.02 and 0.73); the pattern is the chosen one."""
    sim, units, fitted, sel = _ground_fit(1)
    assert len(sel.ties) >= 2 and sel.ties[0][:2] == (sel.order, sel.smoothing)
    assert (sel.order, sel.smoothing) == (5, pytest.approx(10**-4.5))
    assert any(o == 4 and s == pytest.approx(1e-5) for o, s, _ in sel.ties)
    _assert_spread_within_criterion(sim, units, fitted)


def test_one_tied_point_leaves_the_own_posterior_as_it_is(ground):
    _, units, fitted = ground
    own = fitted.own_posterior
    sel = fitted.model.training["selection"]
    assert len(sel["ties"]) >= 2  # this flight's ties (the average is what fit reports)
    same = own_posterior.tied_own_posterior(own, None, fitted.model.nodes, None, sel["ties"][:1], 1.0, None)
    assert same is own


def test_the_continued_posteriors_computed_beforehand_are_those_computed_here(ground):
    """``continued_jobs`` (run beside the final solve) give the own posterior and its average over
    the tied points to the last bit of those computed by the two functions themselves (one BLAS
    thread everywhere: another count rounds differently)."""
    _, units, fitted = ground
    model = fitted.model
    sel = model.training["selection"]
    nodes = [str(n) for n in model.nodes]
    big = ModelSpec("sh", 15).basis()
    total = NormalEquations(big, len(nodes))
    for s in units.values():
        total.add(s.directions, s.tx_index, s.rx_index, s.joint_gain_db)
    chosen = ModelSpec("sh", int(sel["order"])).basis()
    idx = nested_columns(big, chosen, len(nodes))
    prior = own_posterior.OwnPrior(float(sel["smoothing"]), penalty_scale(total.gram[np.ix_(idx, idx)], idx.size), 2.0,
                                   1e-6, Gauge(), None)
    ties = [tuple(t) for t in sel["ties"]]
    assert len(ties) >= 2 and chosen != big
    make = lambda k: ModelSpec("sh", k).basis()  # noqa: E731
    own_first, jobs = own_posterior.continued_jobs(total, chosen, nodes, prior, ties, make)
    assert own_first and len(jobs) == 1 + len(own_posterior.tied_groups(total, prior, ties, make))
    with one_blas_thread():  # as beside the final solve, and as tied_own_posterior's workers
        parts = [job() for job in jobs]
        here = own_posterior.own_pattern_posterior(total, chosen, nodes, prior, 0.7, None)
    given = own_posterior.own_pattern_posterior(total, chosen, nodes, prior, 0.7, None, lambda: parts[0])
    assert here is not None and given is not None and np.array_equal(here.covariance, given.covariance)
    tied_here = own_posterior.tied_own_posterior(here, total, nodes, prior, ties, 0.5, make)
    tied_given = own_posterior.tied_own_posterior(given, total, nodes, prior, ties, 0.5, make, parts[1:])
    assert tied_here is not here, np.max(np.abs(tied_here.covariance - tied_given.covariance))
    assert np.array_equal(tied_here.covariance, tied_given.covariance), np.max(np.abs(tied_here.covariance - tied_given.covariance))
    none_first, none_jobs = own_posterior.continued_jobs(total, big, nodes, prior, ties[:1], make)
    assert not none_first and none_jobs == []  # the largest basis chosen, one point: nothing to continue


def test_the_final_solves_own_system_is_read_off_the_solve():
    """``solved_parts``: the continued posterior of the chosen point at the largest basis is the
    final solve's own covariance over its residual variance (the constrained inverse that
    ``continued_parts`` forms again), to the rounding of two factorisations of a system whose
    gauge direction is held by a ridge of 1e-6 alone (1.2e-8 of the largest entry on this
    noise-only flight; the ``--record`` fits: own-pattern spreads within 4e-13); another point
    is not read off it."""
    from rplearn.core.geometry import Directions
    from rplearn.core.lsq.selection import penalty_vector
    from rplearn.core.lsq.solver import solve
    from rplearn.core.sh import SphericalHarmonics

    rng = np.random.default_rng(5)
    basis, n = SphericalHarmonics(5), 3000
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), np.arcsin(rng.uniform(-1, 1, (2, n)))
    tx = rng.integers(0, 2, n)
    total = NormalEquations(basis, 2).add(Directions(az[0], el[0], az[1], el[1]), tx, 1 - tx, rng.normal(0.0, 2.0, n))
    nodes = ["A", "B"]
    prior = own_posterior.OwnPrior(1e-4, penalty_scale(total.gram, total.n_pattern_columns), 2.0, 1e-6, Gauge(), None)
    sol = solve(total, nodes, ridge=prior.ridge, gauge=prior.gauge,
                penalty=penalty_vector(basis, 2, prior.smoothing, prior.scale, prior.power))
    pat = 2 * basis.n_coef
    known = own_posterior.solved_parts(prior, prior, sol.covariance, sol.residual_variance_db2, pat)
    assert known is not False
    direct = own_posterior.read_continued(own_posterior.continued_parts(total, nodes, prior), 1.0)
    read = own_posterior.read_continued(known, 1.0)
    assert direct is not None and read is not None
    assert np.max(np.abs(read - direct)) <= 1e-7 * np.max(np.abs(direct))
    other = dataclasses.replace(prior, smoothing=2e-4)
    assert own_posterior.solved_parts(prior, other, sol.covariance, sol.residual_variance_db2, pat) is False
    assert own_posterior.solved_parts(prior, prior, None, 1.0, pat) is False
