"""The paper's LTD: one-off costs of a process stay out of the learning time."""

import time

import numpy as np

import rplearn.models.fit as learn
from rplearn.core.geometry import Directions
from rplearn.data.tables import LinkSamples
from rplearn.models.fit import fit_model
from rplearn.models.spec import ModelSpec


def test_warm_up_is_not_timed(monkeypatch):
    rng = np.random.default_rng(0)
    n = 2000
    az = rng.uniform(-np.pi, np.pi, (2, n))
    el = np.arcsin(rng.uniform(-1, 1, (2, n)))
    samples = LinkSamples(
        Directions(az[0], el[0], az[1], el[1]), np.zeros(n, np.intp), np.ones(n, np.intp), ("A", "B"),
        rng.normal(0, 3, n), np.full(n, 20.0), np.full(n, 2.4e9),
    )
    original = learn._warm_up
    calls = []

    def slow_warm_up(spec, n_samples=1, options=None):
        calls.append(spec.label)
        time.sleep(0.5)
        original(spec, n_samples, options)

    monkeypatch.setattr(learn, "_warm_up", slow_warm_up)
    for name in ("sh-4", "nn-10", "m", "bg-3"):
        fitted = fit_model(samples, ModelSpec.parse(name))
        assert fitted.ltd_s < 0.5, (name, fitted.ltd_s)
    assert calls == ["SH-4", "NN-10", "M", "BG-3"]


def test_coverage_grids_on_the_worker_threads_equal_each_node_alone():
    """Many directions: the nodes' grids are computed on the runtime's workers; each is the grid of
    that node's directions alone (tx and rx ends pooled), in node order."""
    from rplearn.core.coverage import coverage_grid
    from rplearn.models.fit import PARALLEL_COVERAGE_DIRECTIONS, node_coverage_grids

    rng = np.random.default_rng(4)
    n = PARALLEL_COVERAGE_DIRECTIONS
    tx = rng.integers(0, 3, n)
    rx = (tx + rng.integers(1, 3, n)) % 3
    az = rng.normal(0.0, 0.7, (2, n))
    el = rng.uniform(-0.6, 0.3, (2, n))
    samples = LinkSamples(Directions(az[0], el[0], az[1], el[1]), tx, rx, ("A", "B", "C"), np.zeros(n), np.ones(n))
    grids = node_coverage_grids(samples)
    assert list(grids) == ["A", "B", "C"]
    for k, node in enumerate(grids):
        alone = coverage_grid(np.r_[az[0][tx == k], az[1][rx == k]], np.r_[el[0][tx == k], el[1][rx == k]])
        assert grids[node] == np.round(alone, 1).tolist()
