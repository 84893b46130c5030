"""A swarm model's covariance in the model file's binary sidecar: JSON text of the 3,000 x 3,000
covariance of 30 drones at SH-10 was 239 MiB, 20 s to write and 7.6 s to read."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from rplearn.core.sh import SphericalHarmonics
from rplearn.errors import ModelFileError
from rplearn.io.modelfile import sidecar_path
from rplearn.models import patterns
from rplearn.models.load import load_model
from rplearn.models.patterns import PatternSet


def _model(n_nodes, order=10, seed=0):
    basis = SphericalHarmonics(order)
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((n_nodes * basis.n_coef, n_nodes * basis.n_coef)) * 1e-2
    return PatternSet(basis=basis, nodes=tuple(f"d{i}" for i in range(n_nodes)),
                      coef=rng.standard_normal((n_nodes, basis.n_coef)), covariance=a @ a.T)


def test_a_swarms_covariance_goes_beside_the_model_file(tmp_path):
    model = _model(6)  # 600 x 600: more values than the JSON keeps inline
    assert model.covariance.size > patterns.INLINE_COVARIANCE_VALUES
    path = tmp_path / "swarm.json"
    model.save(path)
    doc = json.loads(path.read_text())
    assert "covariance" not in doc["model"] and doc["model"]["sidecar"]["file"] == "swarm.json.npz"
    assert os.path.getsize(path) < 100_000
    again = load_model(path)
    np.testing.assert_array_equal(again.covariance, model.covariance)
    np.testing.assert_array_equal(again.coef, model.coef)
    az, el = np.array([0.3, -1.0]), np.array([0.1, 0.5])
    np.testing.assert_array_equal(again.standard_error("d2", az, el), model.standard_error("d2", az, el))


def test_the_paper_sized_model_keeps_its_covariance_inline(tmp_path):
    model = _model(2)  # 200 x 200
    path = tmp_path / "pair.json"
    model.save(path)
    assert "covariance" in json.loads(path.read_text())["model"]
    assert not os.path.exists(sidecar_path(path))
    np.testing.assert_array_equal(load_model(path).covariance, model.covariance)


def test_a_missing_or_altered_covariance_sidecar_is_refused_by_name(tmp_path):
    path = tmp_path / "swarm.json"
    _model(6).save(path)
    side = sidecar_path(path)
    data = bytearray(open(side, "rb").read())
    data[-100] ^= 1
    open(side, "wb").write(bytes(data))
    with pytest.raises(ModelFileError, match="checksum mismatch"):
        load_model(path)
    os.remove(side)
    with pytest.raises(ModelFileError, match="sidecar is missing"):
        load_model(path)
