"""``fit --path-loss`` and ``--link-offsets`` from the command line (issue 12, items 1 and 2).

The commands that succeed run in this process (:func:`cli_helpers.invoke`: what they print and
store is the point); so do the refusals (:func:`cli_helpers.run_here`: the exit code and standard
error of a user's process), except the first, which runs as a process of its own so that the
process boundary stays covered."""

from __future__ import annotations

import json

import pytest
from cli_helpers import answer, invoke, invoke_in


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """The pathloss flight, synced both ways and A->B only (made in this process: the test's inputs)."""
    d = tmp_path_factory.mktemp("terms")
    invoke_in(d, ["simulate", "--preset", "pathloss", "--seed", "2", "-o", "flight"])
    invoke_in(d, ["sync", "--poses", "flight/pose_log.parquet", "--signals", "flight/signal_log.parquet", "-o", "both.parquet"])
    invoke_in(d, ["sync", "--poses", "flight/pose_log.parquet", "--signals", "flight/signal_log.parquet", "--link", "A:B",
                  "-o", "ab.parquet"])
    return d


@pytest.mark.slow
def test_fit_learns_and_stores_the_exponent_and_offsets_and_names_its_flags(workdir):
    d = workdir
    out = invoke(["fit", d / "both.parquet", "--path-loss", "log-distance", "--degree", "8", "-o", d / "m.json"])
    exponent = float(out.stdout.split("path loss: log-distance, exponent ")[1].split()[0])
    assert abs(exponent - 3.0) < 0.1
    assert "electronics offsets" in out.stdout and "A->B" in out.stdout
    payload = json.loads((d / "m.json").read_text())["model"]
    assert payload["path_loss"]["kind"] == "log-distance"
    assert set(payload["shared"]) == {"exponent", "offset:A->B"}
    assert abs(payload["training"]["path_loss"]["exponent"] - 3.0) < 0.1
    pred = invoke(["predict", d / "m.json", d / "ab.parquet", "-o", d / "p.parquet"])  # the note is checked, not the table
    assert "never learned" not in pred.stderr
    orient = invoke(["orient", d / "m.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "40,0,20"])
    assert "dBm" in orient.stdout
    # one direction: no offset, and predicting the other says what it assumes
    invoke(["fit", d / "ab.parquet", "--model", "sh", "--degree", "6", "-o", d / "ab.json"])
    assert "shared" not in json.loads((d / "ab.json").read_text())["model"]
    pred = invoke(["predict", d / "ab.json", d / "both.parquet", "-o", d / "p2.parquet"])  # SH-6: quick
    assert "B->A were never learned" in pred.stderr
    # reciprocal on request
    out = invoke(["fit", d / "both.parquet", "--degree", "6", "--no-link-offsets", "-o", d / "r.json"])
    assert "electronics offsets" not in out.stdout
    # errors name the flag (one test: the flight is simulated once per worker)
    bad = answer(["fit", "ab.parquet", "--path-loss", "hata", "-o", "x.json"], d, process=True)
    assert bad.returncode == 2 and "--path-loss" in bad.stderr and "log-distance" in bad.stderr  # a usage error
    bad = answer(["fit", "ab.parquet", "--path-loss", "two-ray", "--ground-level", "100", "-o", "x.json"], d)
    assert bad.returncode == 1 and "below the ground level" in bad.stderr and "--ground-level" in bad.stderr
    bad = answer(["fit", "ab.parquet", "--model", "m", "--path-loss", "log-distance", "-o", "x.json"], d)
    assert bad.returncode == 1 and "baselines" in bad.stderr
    bad = answer(["fit", "ab.parquet", "--path-loss", "two-ray", "--permittivity", "0.5", "-o", "x.json"], d)
    assert bad.returncode == 1 and "--permittivity" in bad.stderr
    assert not (d / "x.json").exists()
