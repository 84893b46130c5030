"""A swarm model's covariance in the model file's binary sidecar: JSON text of the 3,000 x 3,000
covariance of 30 drones at SH-10 was 239 MiB, 20 s to write and 7.6 s to read."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from model_file_checks import assert_sidecar_refused_altered_then_missing

from rplearn.core.sh import SphericalHarmonics
from rplearn.errors import ModelFileError
from rplearn.io import modelfile
from rplearn.io.modelfile import named_sidecar
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
    entry = doc["model"]["sidecar"]
    assert "covariance" not in doc["model"] and entry["file"] == f"swarm.json.{entry['sha256'][:12]}.npz"
    assert doc["schema_version"] == 2  # an rplearn that cannot read sidecars refuses it (not: no covariance)
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
    doc = json.loads(path.read_text())
    assert "covariance" in doc["model"] and doc["schema_version"] == 1
    assert named_sidecar(path) is None and os.listdir(tmp_path) == ["pair.json"]
    np.testing.assert_array_equal(load_model(path).covariance, model.covariance)


def test_a_missing_or_altered_covariance_sidecar_is_refused_by_name(tmp_path):
    path = tmp_path / "swarm.json"
    _model(6).save(path)
    assert_sidecar_refused_altered_then_missing(path, flip=1)


def test_a_failed_save_leaves_the_previous_model_and_its_sidecar_readable(tmp_path, monkeypatch):
    """The new sidecar gets a new name, and earlier ones go only after the model file is
    replaced (found by review: a failed second save left the first unreadable)."""
    path = tmp_path / "swarm.json"
    first = _model(6)
    first.save(path)

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(modelfile, "write_model_file", full_disk)
    with pytest.raises(OSError):
        _model(6, seed=1).save(path)
    monkeypatch.undo()
    np.testing.assert_array_equal(load_model(path).covariance, first.covariance)
    assert sorted(os.listdir(tmp_path)) == sorted(["swarm.json", os.path.basename(named_sidecar(path))])


def test_saving_again_leaves_only_the_sidecar_the_model_file_names(tmp_path):
    path = tmp_path / "swarm.json"
    _model(6).save(path)
    _model(6, seed=1).save(path)
    assert sorted(os.listdir(tmp_path)) == sorted(["swarm.json", os.path.basename(named_sidecar(path))])
    _model(2).save(path)  # inline now: the old sidecar goes
    assert os.listdir(tmp_path) == ["swarm.json"]


def test_a_payload_read_without_its_file_path_says_how_to_read_it(tmp_path):
    path = tmp_path / "swarm.json"
    _model(6).save(path)
    _, payload = modelfile.read_model_file(path)
    with pytest.raises(ModelFileError, match="source=path"):
        PatternSet.from_dict(payload)
    assert PatternSet.from_dict(payload, source=str(path)).covariance.shape == (600, 600)


def test_saving_over_a_folder_writes_nothing(tmp_path):
    (tmp_path / "adir").mkdir()
    with pytest.raises(Exception, match="folder|directory"):
        _model(6).save(tmp_path / "adir")
    assert os.listdir(tmp_path) == ["adir"]
