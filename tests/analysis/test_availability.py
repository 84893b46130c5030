"""Availability of a link and of a swarm (issue 28, items 1 and 2; acceptance 2)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from rplearn.analysis.availability import AvailabilityOptions, connected_draws, link_availability_column, residual_std_db, swarm_availability
from rplearn.analysis.radios import RADIO_PRESETS, sensitivity_dbm
from rplearn.analysis.swarm import SwarmOptions, connectivity_over_time, predict_swarm
from rplearn.core.bases import SphericalHarmonics
from rplearn.core.geometry import quat_wxyz_from_yaw
from rplearn.errors import InputError
from rplearn.models.patterns import PatternSet
from rplearn.models.training import TrainingSummary

NOISE_DB, LEVEL_DB = 2.0, 1.5
PATTERN_OF = {"C": "A", "D": "B"}


def posterior_model(seed=0, scale=1.0):
    """Two SH-3 patterns with a dense posterior covariance (about 1.5 dB of gain spread per end),
    a packet noise and a new flight's level spread."""
    rng = np.random.default_rng(seed)
    b = SphericalHarmonics(3)
    coef = rng.normal(0, 2.0, (2, b.n_coef))
    coef[:, 0] = 0.0
    root = rng.normal(0, 0.25 * scale, (2 * b.n_coef, 2 * b.n_coef))
    training = TrainingSummary(frequency_hz=2.4e9, rmse_db=3.0, noise_std_db=NOISE_DB, new_flight_level_std_db=LEVEL_DB)
    return PatternSet(basis=b, nodes=("A", "B"), coef=coef, covariance=root @ root.T / b.n_coef, training=training)


def formation(n_t=12):
    """Four drones: A, B, C in a triangle about 150 m apart, D drifting away from C."""
    rows = []
    places = {"A": (0.0, 0.0, 20.0, 30.0), "B": (150.0, 0.0, 25.0, 200.0), "C": (70.0, 130.0, 22.0, -60.0)}
    for ti in range(n_t):
        for node, (x, y, z, yaw) in places.items():
            rows.append((float(ti), node, x, y, z, *quat_wxyz_from_yaw(np.radians(yaw + 5.0 * ti))))
        rows.append((float(ti), "D", 70.0 + 12.0 * ti, 260.0 + 10.0 * ti, 21.0, *quat_wxyz_from_yaw(np.radians(120.0))))
    return pd.DataFrame(rows, columns=["t", "node", "x", "y", "z", "qw", "qx", "qy", "qz"])


def simulated_swarms(model, poses, n_swarms, sensitivity, seed):
    """Connectivity of swarms whose patterns are drawn from the model's posterior, each with its
    own flight level and every link its own fading, by a separate path: numpy's multivariate
    normal, a PatternSet per swarm, predict_swarm and scipy-free connectivity_over_time."""
    rng = np.random.default_rng(seed)
    mean = model.coef.ravel()
    out = []
    for _ in range(n_swarms):
        coef = rng.multivariate_normal(mean, model.covariance).reshape(model.coef.shape)
        drawn = PatternSet(basis=model.basis, nodes=model.nodes, coef=coef, training=model.training)
        pred = predict_swarm(drawn, poses, 20.0, SwarmOptions(pattern_of=PATTERN_OF, min_rssi_dbm=sensitivity))
        links = pred.links.copy()
        links["rssi_pred_dbm"] += rng.normal(0, LEVEL_DB) + rng.normal(0, NOISE_DB, len(links))
        c = connectivity_over_time(links, pred.connectivity["t"].to_numpy(), sorted(pred.pattern_of), sensitivity)
        out.append(c["connected"].to_numpy())
    return np.array(out)


def test_monte_carlo_connectivity_agrees_with_200_simulated_swarms():
    """Acceptance 2: the Monte Carlo's P(connected) over time agrees within 0.05 with the share
    of 200 swarms (patterns drawn from the same posterior) that are connected, at a sensitivity
    where it is neither 0 nor 1."""
    model, poses = posterior_model(), formation()
    ref = predict_swarm(model, poses, 20.0, SwarmOptions(pattern_of=PATTERN_OF))
    sensitivity = float(ref.connectivity["bottleneck_rssi_dbm"].median())
    mc = swarm_availability(model, poses, 20.0, AvailabilityOptions(sensitivity, n_draws=4000, seed=1,
                                                                      pairs=[("A", "D")]),
                            SwarmOptions(pattern_of=PATTERN_OF))
    observed = simulated_swarms(model, poses, 200, sensitivity, seed=2)
    p = mc.connectivity["p_connected"].to_numpy()
    freq = observed.mean(axis=0)
    assert 0.2 < p.mean() < 0.8, p
    assert abs(p.mean() - freq.mean()) <= 0.05, (p.mean(), freq.mean())
    se = np.sqrt(freq * (1 - freq) / 200 + p * (1 - p) / 4000) + 1e-3
    assert np.all(np.abs(p - freq) <= 4 * se), np.c_[p, freq]
    # measured: P(connected) 0.974 .. 0.050 over the 12 times, the 200 swarms' share within 0.05
    # of it at every time (time means 0.449 and 0.432); D's links fail the swarm
    assert mc.weakest["share"].sum() == pytest.approx(1.0) and mc.weakest["pair"].iloc[0] in {"C-D", "A-D", "B-D"}
    assert (mc.connectivity["p_path_A-D"] >= p - 1e-12).all()  # a connected swarm joins every pair


def test_without_spread_the_monte_carlo_is_the_deterministic_connectivity():
    model, poses = posterior_model(), formation()
    model.covariance = np.zeros_like(model.covariance)
    model.training = model.training.replace(new_flight_level_std_db=None)
    ref = predict_swarm(model, poses, 20.0, SwarmOptions(pattern_of=PATTERN_OF, min_rssi_dbm=-88.0))
    mc = swarm_availability(model, poses, 20.0, AvailabilityOptions(-88.0, n_draws=3, fading=False),
                            SwarmOptions(pattern_of=PATTERN_OF))
    np.testing.assert_array_equal(mc.connectivity["p_connected"].to_numpy() == 1.0, ref.connectivity["connected"])


def test_connected_draws_match_scipy_components():
    rng = np.random.default_rng(5)
    n, n_draws, n_times = 6, 40, 3
    k, a, b = np.nonzero(np.ones((n_times, n, n), bool) & ~np.eye(n, dtype=bool))
    margin = rng.normal(-0.8, 1.0, (k.size, n_draws)).astype(np.float32)
    ok, _, _, path = connected_draws(margin, k, a, b, (n_draws, n_times, n), np.array([[0, 5], [1, 2]]))
    for d in range(n_draws):
        for t in range(n_times):
            sel = k == t
            w = np.full((n, n), -np.inf)
            w[a[sel], b[sel]] = margin[sel, d]
            up = np.fmin(w, w.T) >= 0
            count, labels = connected_components(csr_matrix(up), directed=False)
            assert ok[d, t] == (count == 1)
            assert path[0, d, t] == (labels[0] == labels[5]) and path[1, d, t] == (labels[1] == labels[2])


def test_link_availability_column_uses_the_noise_about_the_flight_level():
    model = posterior_model()
    table = pd.DataFrame({"rssi_pred_dbm": [-80.0, -90.0], "gain_pred_std_db": [1.5, 0.0], "near_field": [False, True]})
    p = link_availability_column(table, model, -82.0)
    spread = np.hypot(1.5, NOISE_DB)
    assert residual_std_db(model) == NOISE_DB
    assert p[0] == pytest.approx(0.5 * (1 + math.erf(2.0 / spread / np.sqrt(2)))) and p[1] == 1.0


def test_presets_and_numbers_give_a_sensitivity():
    assert sensitivity_dbm("sik") == -121.0 == RADIO_PRESETS["rfd900"].sensitivity_dbm
    assert sensitivity_dbm(" ESP32-11b ") == -97.0 and sensitivity_dbm("-85.5") == -85.5 and sensitivity_dbm(-70) == -70.0
    for bad in ("wifi", "nan", "12"):
        with pytest.raises(InputError, match="sensitivity"):
            sensitivity_dbm(bad)


def test_bad_options_are_refused_naming_them():
    with pytest.raises(InputError, match="n_draws"):
        AvailabilityOptions(-90.0, n_draws=0)
    with pytest.raises(InputError, match="pairs"):
        AvailabilityOptions(-90.0, pairs=[("A", "A")])
    model, poses = posterior_model(), formation(3)
    with pytest.raises(InputError, match="pairs"):
        swarm_availability(model, poses, 20.0, AvailabilityOptions(-90.0, n_draws=2, pairs=[("A", "Z")]),
                           SwarmOptions(pattern_of=PATTERN_OF))
    model.covariance = None
    with pytest.raises(InputError, match="covariance"):
        swarm_availability(model, poses, 20.0, AvailabilityOptions(-90.0, n_draws=2), SwarmOptions(pattern_of=PATTERN_OF))
