"""rplearn.analysis.decoupling (issue 24, item 5): each node's own-pattern spread and the
components a flight cannot split between nodes; acceptance 5 on a reduced case
(benchmarks/split.py --tiny) is checked by tests/test_benchmarks.py."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rplearn.analysis.decoupling import UNSPLIT_JOINT_FRACTION, certify, covered_directions, decoupling_certificate
from rplearn.core.geometry import Directions
from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.models import ModelSpec
from rplearn.models.auto import fit_auto
from rplearn.models.fit import fit_model

ROOT = Path(__file__).resolve().parents[2]


def lobe(az, el, az0, el0):
    return 6.0 * (np.cos(el) * np.cos(el0) * np.cos(az - az0) + np.sin(el) * np.sin(el0))


def units(mirror: bool, n: int = 600, k: int = 3, seed: int = 0) -> dict[str, LinkSamples]:
    """Three units of random directions; with ``mirror`` both ends always see each other in the
    same body direction, so that ``+f`` on A and ``-f`` on B never shows in a joint gain."""
    rng = np.random.default_rng(seed)
    out = {}
    for u in range(k):
        az, el = rng.uniform(-np.pi, np.pi, n), np.arcsin(rng.uniform(-1, 1, n))
        az2, el2 = (az, el) if mirror else (rng.uniform(-np.pi, np.pi, n), np.arcsin(rng.uniform(-1, 1, n)))
        y = lobe(az, el, 0.5, 0.3) + lobe(az2, el2, -2.0, -0.2) + rng.normal(0, 2.0, n)
        out[f"u{u}"] = LinkSamples(Directions(az, el, az2, el2), np.zeros(n, int), np.ones(n, int), ("A", "B"), y,
                                   np.full(n, 10.0))
    return out


@pytest.fixture(scope="module")
def fits():
    out = {}
    for mirror in (True, False):
        us = units(mirror)
        out[mirror] = (fit_auto(us)[0].model, list(us.values()))
    return out


def test_mirror_geometry_leaves_the_difference_unsplit(fits):
    model, samples = fits[True]
    cert = decoupling_certificate(model, samples)
    assert cert.n_unsplit >= 3 and cert.unsplit_db >= 0.9 * cert.covered_db > 0
    for comp in cert.components:
        assert comp.joint_db ** 2 < UNSPLIT_JOINT_FRACTION * comp.per_node_db ** 2
        (az_a, el_a, sign_a, share_a), (az_b, el_b, sign_b, _share_b) = comp.peaks["A"], comp.peaks["B"]
        assert sign_a == -sign_b and abs(share_a - 0.5) < 0.05  # +f on A, -f on B, where both look alike
        assert abs(el_a - el_b) < 5 and (abs(el_a) > 80 or abs((az_a - az_b + 180) % 360 - 180) < 5)
    assert "not split between nodes by this flight: " in cert.summary()
    free, free_samples = fits[False]
    other = decoupling_certificate(free, free_samples)
    assert other.n_unsplit == 0 and "no component above" in other.summary()
    assert max(s.covered_std_db for s in other.nodes.values()) < 0.5 * min(s.covered_std_db for s in cert.nodes.values())


def test_covered_spread_is_the_posterior_of_the_node_shape(fits):
    """The covered spread equals the RMS (mean removed) of draws from the model's covariance."""
    model, samples = fits[True]
    cert = decoupling_certificate(model, samples)
    p = model.basis.n_coef
    cov = np.asarray(model.covariance)[:2 * p, :2 * p]
    draws = np.random.default_rng(1).multivariate_normal(np.zeros(2 * p), cov, size=4000, method="eigh")
    for k, node in enumerate(model.nodes):
        az, el = covered_directions(model)[node]
        g = draws[:, k * p:(k + 1) * p] @ model.basis.design(az, el).T
        g -= g.mean(axis=1, keepdims=True)  # the gauge fixes the constant of a two-node link
        assert np.sqrt(np.mean(g ** 2)) == pytest.approx(cert.nodes[node].covered_std_db, rel=0.05)
        assert cert.nodes[node].covered_fraction > 0.99  # random directions cover the sphere


def test_components_add_up_to_the_whole_spread(fits):
    model, samples = fits[True]
    cert = decoupling_certificate(model, samples)
    mean_var = np.mean([s.covered_std_db ** 2 for s in cert.nodes.values()])
    assert cert.covered_db == pytest.approx(np.sqrt(mean_var), rel=1e-6)
    joint = decoupling_certificate(model, gram=sum(_gram(model, s) for s in samples), n_samples=sum(len(s) for s in samples))
    assert joint.unsplit_db == pytest.approx(cert.unsplit_db, rel=1e-6)


def _gram(model, s):
    from rplearn.core.lsq.normal_equations import NormalEquations

    return NormalEquations(model.basis, 2).add(s.directions, s.tx_index, s.rx_index).gram


def test_certify_stores_the_certificate_and_skips_baselines(fits):
    model, samples = fits[False]
    cert = certify(model, samples)
    assert model.training["decoupling"]["summary"] == cert.summary()
    assert model.training["decoupling"]["nodes"]["A"]["covered_std_db"] == cert.nodes["A"].covered_std_db
    cat = lambda f: np.concatenate([getattr(s, f) for s in samples])  # noqa: E731
    d = Directions(*(np.concatenate([s.directions[i] for s in samples]) for i in range(4)))
    everything = LinkSamples(d, cat("tx_index"), cat("rx_index"), ("A", "B"), cat("joint_gain_db"), cat("distance_m"))
    assert certify(fit_model(everything, ModelSpec("mean")).model, samples) is None
    fixed = fit_model(everything, ModelSpec("sh", 3)).model
    note = certify(fixed, samples)
    assert not note.components and "fixed-order fit" in note.summary()


def test_an_automatic_fits_kept_gram_gives_the_certificate_of_its_samples():
    """``fit --order auto`` reads the joint metric off the X^T X its selection accumulated
    (``FittedModel.learning_gram``) instead of a second pass over the samples: the same
    certificate; without it or the samples, no components."""
    import copy

    us = units(True, seed=3)
    fitted = fit_auto(us)[0]
    assert fitted.learning_gram is not None and fitted.learning_gram.n_samples == sum(len(s) for s in us.values())
    from_samples = certify(copy.copy(fitted.model), list(us.values()), fitted.own_posterior)
    from_gram = certify(copy.copy(fitted.model), None, fitted.own_posterior, fitted.learning_gram)
    assert from_samples.n_unsplit == from_gram.n_unsplit >= 3
    assert from_gram.unsplit_db == pytest.approx(from_samples.unsplit_db, rel=1e-9)
    assert from_gram.summary() == from_samples.summary()
    alone = certify(copy.copy(fitted.model), None, fitted.own_posterior)
    assert not alone.components and "were not kept" in alone.summary()


def test_certificate_needs_a_covariance_and_a_coverage_grid(fits):
    import copy

    model = copy.copy(fits[False][0])
    model.covariance = None
    with pytest.raises(InputError, match="no covariance"):
        decoupling_certificate(model)
    model = copy.copy(fits[False][0])
    model.training = model.training.replace(coverage_deg=None)
    with pytest.raises(InputError, match="no coverage grid for node A"):
        decoupling_certificate(model)


def test_fit_prints_and_stores_the_certificate_and_plot_draws_it(tmp_path):
    """`rplearn fit` (automatic) prints each node's own-pattern spread and the unsplit
    components, stores them in the model file; `rplearn plot --spread` draws them. The commands
    run in this process (typer's runner); the refusal at the end as a user's process, whose exit
    code and one line of standard error are the point."""
    import os

    from typer.testing import CliRunner

    from rplearn.cli import app
    from rplearn.models import load_model

    def invoke(*args: object):
        res = CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
        assert res.exit_code == 0, (args, res.output)
        return res

    invoke("simulate", "--preset", "smoke", "--seed", "5", "-o", tmp_path / "f")
    invoke("sync", "--poses", tmp_path / "f/pose_log.parquet", "--signals", tmp_path / "f/signal_log.parquet",
           "-o", tmp_path / "m.parquet")
    out = invoke("fit", tmp_path / "m.parquet", "-o", tmp_path / "a.json").stdout
    assert "own-pattern spread (1 sigma" in out and "not split between nodes by this flight" in out
    stored = load_model(str(tmp_path / "a.json")).training["decoupling"]
    assert set(stored["nodes"]) == {"A", "B"} and stored["summary"].splitlines()[0] in out
    plotted = invoke("plot", tmp_path / "a.json", "-o", tmp_path / "p.png", "--spread", tmp_path / "s.png").stdout
    assert f"wrote {tmp_path / 's.png'}" in " ".join(plotted.split())
    assert (tmp_path / "s.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-m", "rplearn.cli", "plot", "a.json", "-o", "p.png", "--spread", "a.json"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 1 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
