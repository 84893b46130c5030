"""The k-NN model's training samples in a binary sidecar (issue 13, item 5)."""

from __future__ import annotations

import json
import os
import time

import numpy as np
import pytest
from model_file_checks import assert_sidecar_refused_altered_then_missing

from rplearn.core.geometry import Directions
from rplearn.data.tables import LinkSamples
from rplearn.errors import ModelFileError
from rplearn.io.modelfile import named_sidecar, write_model_file
from rplearn.models.baselines import KNNModel
from rplearn.models.load import load_model


def _samples(n, seed=0, links=(("A", "B"),)):
    rng = np.random.default_rng(seed)
    d = Directions(*rng.uniform(-1.0, 1.0, (4, n)))
    nodes = tuple(sorted({x for link in links for x in link}))
    pick = rng.integers(0, len(links), n)
    tx = np.array([nodes.index(links[i][0]) for i in pick])
    rx = np.array([nodes.index(links[i][1]) for i in pick])
    return LinkSamples(d, tx, rx, nodes, rng.normal(size=n), np.full(n, 10.0))


def test_sidecar_round_trip_and_size(tmp_path):
    samples = _samples(150_000)
    model = KNNModel.fit(samples, 400)
    path = tmp_path / "nn.json"
    model.save(path)
    side = named_sidecar(path)
    assert os.path.getsize(path) < 10_000  # the JSON holds no samples
    assert os.path.getsize(side) < 8_000_000  # 150k x 5 float64 and the npz headers
    again = load_model(path)  # its speed: benchmarks/knn_file.py
    probe = _samples(500, seed=1)
    np.testing.assert_array_equal(again.predict_gain(probe), model.predict_gain(probe))
    assert again.n_params == model.n_params


def test_sidecar_bytes_are_reproducible(tmp_path, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "0")
    model = KNNModel.fit(_samples(3000, links=(("A", "B"), ("B", "A"))), 50)
    model.save(tmp_path / "a.json")
    time.sleep(1.1)
    model.save(tmp_path / "b.json")
    assert open(named_sidecar(tmp_path / "a.json"), "rb").read() == open(named_sidecar(tmp_path / "b.json"), "rb").read()
    assert len(load_model(tmp_path / "b.json").train_gain_db) == 2


def test_missing_tampered_or_foreign_sidecars_are_refused(tmp_path):
    model = KNNModel.fit(_samples(2000), 50)
    path = tmp_path / "nn.json"
    model.save(path)
    assert_sidecar_refused_altered_then_missing(path, flip=0xFF)
    # a re-signed model file whose sidecar entry points outside its folder
    doc = json.loads(path.read_text())
    payload = doc["model"]
    payload["sidecar"]["file"] = "../nn.json.npz"
    write_model_file(tmp_path / "evil.json", "knn", payload)
    with pytest.raises(ModelFileError, match="beside the model file"):
        load_model(tmp_path / "evil.json")
    # another model's sidecar under this one's name
    other = KNNModel.fit(_samples(2000, seed=3), 50)
    other.save(tmp_path / "other.json")
    model.save(path)
    side = named_sidecar(path)
    os.replace(named_sidecar(tmp_path / "other.json"), side)
    with pytest.raises(ModelFileError, match="does not belong"):
        load_model(path)


def test_inline_model_files_still_load(tmp_path):
    model = KNNModel.fit(_samples(2000), 50)
    write_model_file(tmp_path / "old.json", "knn", model.to_dict())
    again = load_model(tmp_path / "old.json")
    probe = _samples(100, seed=2)
    np.testing.assert_array_equal(again.predict_gain(probe), model.predict_gain(probe))
