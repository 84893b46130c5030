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
