"""Model files own their sidecars (issue 29, class 1; acceptance 3): a save writes and removes
only the sidecar its own model file names, and concurrent saves of different models to one path
leave one whole model with its own sidecar."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import textwrap
import time

import numpy as np

from rplearn.io.modelfile import named_sidecar, owned_sidecar
from rplearn.models.load import load_model

#: Builds model ``i`` of a kind (distinct nodes, so the final file says whose it is); saved by
#: the processes of the concurrency test and rebuilt by the test to compare.
BUILD = textwrap.dedent("""
    import numpy as np

    def build(kind, i):
        rng = np.random.default_rng(i)
        if kind == "knn":
            from rplearn.core.geometry import Directions
            from rplearn.data.tables import LinkSamples
            from rplearn.models.baselines import KNNModel
            n = 3000 + 100 * i
            d = Directions(*rng.uniform(-1.0, 1.0, (4, n)))
            samples = LinkSamples(d, np.zeros(n, int), np.ones(n, int), (f"A{i}", f"B{i}"), rng.normal(size=n),
                                  np.full(n, 10.0))
            return KNNModel.fit(samples, 20)
        from rplearn.core.sh import SphericalHarmonics
        from rplearn.models.patterns import PatternSet
        basis = SphericalHarmonics(10)
        a = rng.standard_normal((6 * basis.n_coef, 6 * basis.n_coef)) * 1e-2
        return PatternSet(basis=basis, nodes=tuple(f"s{i}d{k}" for k in range(6)),
                          coef=rng.standard_normal((6, basis.n_coef)), covariance=a @ a.T)
""")

SAVER = BUILD + textwrap.dedent("""
    import os, sys, time
    from rplearn.errors import RplearnError
    kind, i, path, go = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
    model = build(kind, i)
    open(f"{go}.{i}.ready", "w").close()
    while not os.path.exists(go):
        time.sleep(0.0005)
    try:
        for _ in range(3):
            model.save(path)
    except RplearnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(1)
""")


def _build(kind, i):
    scope: dict = {}
    exec(BUILD, scope)
    return scope["build"](kind, i)


def _digest(path):
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def test_a_save_removes_no_file_its_model_file_does_not_name(tmp_path):
    """Saving ``nn.json`` removed the user's ``nn.json.npz`` and ``nn.json.0123456789ab.npz``."""
    path = tmp_path / "nn.json"
    theirs = {name: os.urandom(64) for name in ("nn.json.npz", "nn.json.0123456789ab.npz", "nn.json.bak",
                                                "nn.json.0123456789ab.1.npz")}
    for name, data in theirs.items():
        (tmp_path / name).write_bytes(data)
    for kind, i in (("knn", 0), ("knn", 1), ("patterns", 2), ("knn", 1)):
        _build(kind, i).save(path)
        ours = os.path.basename(named_sidecar(path))
        assert sorted(os.listdir(tmp_path)) == sorted([*theirs, "nn.json", ours])
        for name, data in theirs.items():
            assert (tmp_path / name).read_bytes() == data
        assert load_model(path).nodes == _build(kind, i).nodes
    from rplearn.models.baselines import MeanModel

    MeanModel({("A", "B"): -50.0}).save(path)  # no sidecar: the previous one goes, theirs stay
    assert sorted(os.listdir(tmp_path)) == sorted([*theirs, "nn.json"])


def test_a_model_file_owns_only_the_sidecar_named_after_it(tmp_path):
    path = tmp_path / "m.json"
    _build("knn", 0).save(path)
    assert owned_sidecar(path) == named_sidecar(path)
    assert owned_sidecar(tmp_path / "missing.json") is None
    (tmp_path / "not.json").write_text("{")
    assert owned_sidecar(tmp_path / "not.json") is None
    import json

    from rplearn.io.modelfile import digest

    doc = json.loads(path.read_text())
    doc["model"]["sidecar"]["file"] = "data.parquet"  # a tampered (re-checksummed) model file names another file
    doc["sha256"] = digest(doc["model"])
    path.write_text(json.dumps(doc))
    assert owned_sidecar(path) is None


def test_concurrent_saves_of_different_models_to_one_path_leave_one_whole_model(tmp_path):
    """8 processes (4 k-NN, 4 swarm models with a covariance sidecar) save 3 times each to one
    path at once: every run succeeds, the file is one run's model with its own sidecar, no stray
    or temporary file is left, and the user's files beside it are untouched."""
    (tmp_path / "sync").mkdir()
    path, go, tmp_path = tmp_path / "models" / "nn.json", tmp_path / "sync" / "go", tmp_path / "models"
    tmp_path.mkdir()
    mine = {"nn.json.npz": os.urandom(32), "nn.json.0123456789ab.npz": os.urandom(32)}
    for name, data in mine.items():
        (tmp_path / name).write_bytes(data)
    runs = [("knn", i) if i % 2 == 0 else ("patterns", i) for i in range(8)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    procs = [subprocess.Popen([sys.executable, "-c", SAVER, kind, str(i), str(path), str(go)], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for kind, i in runs]
    deadline = time.monotonic() + 300
    while len(os.listdir(go.parent)) < len(runs) and time.monotonic() < deadline:  # every process has built its model
        time.sleep(0.01)
    go.write_text("")
    results = [(p.wait(timeout=600), p.communicate()) for p in procs]
    for code, (_, err) in results:
        lines = [line for line in err.splitlines() if line.strip()]
        assert code == 0 or (code == 1 and len(lines) == 1 and lines[0].startswith("error:")), err
    assert [code for code, _ in results] == [0] * 8
    final = load_model(path)  # checksums of the model file and of its sidecar verified
    kind, i = next((k, j) for k, j in runs if _build(k, j).nodes == final.nodes)
    expected = _build(kind, i)
    if kind == "knn":
        np.testing.assert_array_equal(final.train_gain_db[(f"A{i}", f"B{i}")], expected.train_gain_db[(f"A{i}", f"B{i}")])
    else:
        np.testing.assert_array_equal(final.covariance, expected.covariance)
    side = os.path.basename(named_sidecar(path))
    assert sorted(os.listdir(tmp_path)) == sorted([*mine, "nn.json", side])  # no stray, no temporary file
    for name, data in mine.items():
        assert (tmp_path / name).read_bytes() == data


def test_saving_the_same_arrays_again_by_a_relative_path_keeps_their_sidecar(tmp_path, monkeypatch):
    """Two k-NN models of the same samples share the sidecar's name: the second save must not
    remove it as the first model file's (found by tests/cli/test_hostile_paths.py)."""
    from dataclasses import replace

    monkeypatch.chdir(tmp_path)
    model = _build("knn", 0)
    model.save("nn.json")
    replace(model, n_neighbors=30).save("nn.json")
    assert load_model("nn.json").n_neighbors == 30  # its sidecar is there and verified
    assert sorted(os.listdir(tmp_path)) == sorted(["nn.json", os.path.basename(named_sidecar("nn.json"))])


def test_a_model_file_is_checked_from_its_written_text_or_from_its_payload(tmp_path):
    """The checksum is verified from the payload's text as written (no second encoding), and a
    file laid out otherwise (re-indented) still loads through its payload's canonical text; a
    change in the written text or in the re-indented one is refused either way."""
    import json

    import pytest

    from rplearn.errors import ModelFileError
    from rplearn.io.modelfile import read_model_file, write_model_file

    payload = {"coefficients": {"A": [0.1, 2.5e-3, -7.0]}, "nodes": ["A"], "note": "x"}
    path = tmp_path / "m.json"
    write_model_file(path, "patterns", payload)
    assert read_model_file(path) == ("patterns", payload)
    indented = tmp_path / "indented.json"
    indented.write_text(json.dumps(json.loads(path.read_text()), indent=4))
    assert read_model_file(indented) == ("patterns", payload)
    for name, text in {"in place": path.read_text().replace("2.5e-3", "2.6e-3").replace("0.0025", "0.0026"),
                       "re-indented": indented.read_text().replace("0.0025", "0.0026")}.items():
        assert "0.0026" in text or "2.6e-3" in text, name
        bad = tmp_path / f"{name.replace(' ', '_')}.json"
        bad.write_text(text)
        with pytest.raises(ModelFileError, match="checksum mismatch"):
            read_model_file(bad)
