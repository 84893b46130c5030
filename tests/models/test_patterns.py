"""PatternSet: evaluation, prediction for poses, model files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rplearn.core.bases import BasisGrid, SphericalHarmonics
from rplearn.core.geometry import link_directions, quat_wxyz_from_yaw
from rplearn.core.link import free_space_path_loss_db
from rplearn.errors import InputError, ModelFileError
from rplearn.models.patterns import PatternSet
from rplearn.models.training import TrainingSummary


@pytest.fixture
def pattern_set():
    rng = np.random.default_rng(0)
    b = SphericalHarmonics(4)
    return PatternSet(
        basis=b,
        nodes=("A", "B"),
        coef=rng.normal(0, 2, (2, 16)),
        covariance=np.eye(32) * 0.01,
        gauge=[{"rule": "equal-mean"}],
        training=TrainingSummary(n_samples=10, condition_number=3.5),
        provenance={"command": "test"},
    )


def test_evaluate_and_joint_gain(pattern_set):
    az = np.array([0.1, 1.0, -1.5])  # also used as elevations below: within [-pi/2, pi/2]
    el = np.array([0.0, 0.5, -1.2])
    ga = pattern_set.evaluate("A", az, el)
    np.testing.assert_allclose(ga, pattern_set.basis.design(az, el) @ pattern_set.coef[0])
    joint = pattern_set.predict_joint_gain_db("A", "B", az, el, el, az)
    np.testing.assert_allclose(joint, ga + pattern_set.evaluate("B", el, az))
    mixed = pattern_set.predict_joint_gain_db(["A", "B", "A"], ["B", "A", "B"], az, el, el, az)
    assert mixed[1] == pytest.approx(pattern_set.evaluate("B", az[1], el[1]) + pattern_set.evaluate("A", el[1], az[1]))
    se = pattern_set.standard_error("A", az, el)
    np.testing.assert_allclose(se, 0.1 * np.linalg.norm(pattern_set.basis.design(az, el), axis=1))


def test_predict_for_poses_is_friis(pattern_set):
    tx_p, rx_p = np.array([[0, 0, 20.0]]), np.array([[10.0, 0, 20.0]])
    tx_q, rx_q = quat_wxyz_from_yaw([0.0]), quat_wxyz_from_yaw([np.pi])
    out = pattern_set.predict_for_poses("A", "B", tx_p, tx_q, rx_p, rx_q, tx_power_dbm=20.0, frequency_hz=2.4e9)
    d = link_directions(tx_p, tx_q, rx_p, rx_q)
    g = pattern_set.evaluate("A", d.az_tx, d.el_tx) + pattern_set.evaluate("B", d.az_rx, d.el_rx)
    np.testing.assert_allclose(out["gain_db"], g)
    np.testing.assert_allclose(out["rssi_dbm"], 20.0 + g - free_space_path_loss_db(10.0, 2.4e9))


def test_unknown_node(pattern_set):
    with pytest.raises(InputError, match="unknown node 'Z'; the model knows A, B"):
        pattern_set.evaluate("Z", 0.0, 0.0)


def test_model_file_round_trip(pattern_set, tmp_path):
    path = tmp_path / "m.json"
    pattern_set.save(path)
    back = PatternSet.load(path)
    assert back.nodes == pattern_set.nodes and back.basis == pattern_set.basis
    np.testing.assert_array_equal(back.coef, pattern_set.coef)
    np.testing.assert_array_equal(back.covariance, pattern_set.covariance)
    assert back.training["condition_number"] == 3.5
    assert back.provenance["rplearn_version"]


def test_bad_model_files_are_refused(pattern_set, tmp_path):
    path = tmp_path / "m.json"
    pattern_set.save(path)
    text = path.read_text()
    cases = {
        "truncated": text[: len(text) // 2],
        "not json": "\x00\x01garbage",
        "other schema": json.dumps({"schema": "something", "schema_version": 1}),
        "future version": text.replace('"schema_version": 1', '"schema_version": 99'),
    }
    doc = json.loads(text)
    doc["model"]["coefficients"]["A"][0] += 1.0
    cases["tampered"] = json.dumps(doc)
    messages = {
        "truncated": "truncated or corrupt",
        "not json": "truncated or corrupt",
        "other schema": "not an rplearn model file",
        "future version": "schema_version 99",
        "tampered": "checksum mismatch",
    }
    for name, content in cases.items():
        bad = tmp_path / f"{name.replace(' ', '_')}.json"
        bad.write_text(content)
        with pytest.raises(ModelFileError, match=messages[name]) as info:
            PatternSet.load(bad)
        assert str(bad) in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(ModelFileError, match="no such model file"):
        PatternSet.load(tmp_path / "missing.json")
    # a wrong-shaped but correctly checksummed file is refused on its content
    doc = json.loads(text)
    doc["model"]["coefficients"]["A"] = [1.0, 2.0]
    from rplearn.io.modelfile import digest as _digest

    doc["sha256"] = _digest(doc["model"])
    bad = tmp_path / "shape.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="coefficients must be"):
        PatternSet.load(bad)


def test_prediction_standard_error_is_calibrated():
    """Joint-gain errors divided by the reported standard error are ~N(0, 1), two-node gauge or not."""
    from rplearn.core.geometry import Directions
    from rplearn.data.tables import LinkSamples
    from rplearn.models.fit import fit_patterns
    from rplearn.models.spec import ModelSpec

    rng = np.random.default_rng(9)
    b = SphericalHarmonics(3)
    true = rng.normal(0, 3, (2, b.n_coef))

    def samples(n, noise):
        az = rng.uniform(-np.pi, np.pi, (2, n))
        el = np.arcsin(rng.uniform(-1, 1, (2, n)))
        y = b.design(az[0], el[0]) @ true[0] + b.design(az[1], el[1]) @ true[1]
        return LinkSamples(Directions(az[0], el[0], az[1], el[1]), np.zeros(n, int), np.ones(n, int), ("A", "B"),
                           y + noise * rng.normal(size=n), np.full(n, 10.0))

    z = []
    probe = samples(300, 0.0)
    for _ in range(40):
        model = fit_patterns(samples(400, 2.0), ModelSpec("sh", 3, ridge=0.0))
        z.append((model.predict_gain(probe) - probe.joint_gain_db) / model.predict_gain_std(probe))
    z = np.concatenate(z)
    assert 0.85 < np.std(z) < 1.15


@pytest.mark.parametrize("basis", [SphericalHarmonics(5), BasisGrid(3, 0.3)], ids=["SH", "BG"])
def test_joint_gain_std_equals_the_explicit_quadratic_form(basis):
    """sqrt(x^T C x) with x the sample's full design row, three nodes, both link directions."""
    from rplearn.core.geometry import Directions
    from rplearn.data.tables import LinkSamples

    rng = np.random.default_rng(0)
    p = basis.n_coef
    a = rng.normal(size=(3 * p, 3 * p))
    model = PatternSet(basis=basis, nodes=("A", "B", "C"), coef=rng.normal(size=(3, p)), covariance=a @ a.T / 100)
    n = 20000  # several steps and a partial one
    az = rng.uniform(-3, 3, (2, n))
    el = rng.uniform(-1.5, 1.5, (2, n))
    tx = rng.integers(0, 3, n)
    rx = (tx + rng.integers(1, 3, n)) % 3
    samples = LinkSamples(Directions(az[0], el[0], az[1], el[1]), tx, rx, ("A", "B", "C"), np.zeros(n), np.ones(n), None)
    x = np.zeros((n, 3 * p))
    ft, fr = basis.design(az[0], el[0]), basis.design(az[1], el[1])
    for k in range(3):
        x[:, k * p : (k + 1) * p] += np.where((tx == k)[:, None], ft, 0.0) + np.where((rx == k)[:, None], fr, 0.0)
    expected = np.sqrt(np.einsum("ni,ij,nj->n", x, model.covariance, x))
    np.testing.assert_allclose(model.predict_gain_std(samples), expected, rtol=1e-12, atol=1e-12)
