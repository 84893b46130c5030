"""Fleets of flights: fit and evaluate a partitioned dataset in one process and on Dask
(issue 13, item 3)."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.files import write_table
from rplearn.models.load import load_model
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.sim.fleet import drone_ids, fleet_pairs, simulate_fleet
from rplearn.workflows.fleet import dask_client, parse_dask
from rplearn.workflows.learning import evaluate_model_files, fit_dataset

RPLEARN = [sys.executable, "-m", "rplearn.cli"]
FLIGHTS = 8


def need_dask():
    """Skip without dask[distributed], except under CI=true, where it must be installed."""
    if importlib.util.find_spec("distributed") is None:
        if os.environ.get("CI") == "true":
            pytest.fail("CI=true but dask[distributed] is not installed (.ci/run installs rplearn[dask])")
        pytest.skip("dask[distributed] not installed (pip install 'rplearn[dask]')")


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    root = tmp_path_factory.mktemp("fleet") / "flights"
    result = simulate_fleet(str(root), flights=FLIGHTS, drones=4, seed=5, preset="smoke")
    return root, result


@pytest.fixture(scope="module")
def sh6(fleet, tmp_path_factory):
    """SH-6 learned in one process from the fleet's folder (streamed, part by part), saved: the
    reference the Dask fits and evaluations are compared with, learned once for the module
    (its tests only read the result and the file)."""
    root, _ = fleet
    path = tmp_path_factory.mktemp("sh6") / "sh6.json"
    return fit_dataset(str(root), ModelSpec.parse("sh", order=6), output=str(path)), path


@pytest.fixture(scope="module")
def client():
    need_dask()
    with dask_client("local:2") as c:
        yield c


def coef(model):
    return np.concatenate([np.ravel(model.coef), np.ravel(model.shared_coef)])


def test_the_fleet_preset_writes_one_file_per_flight_and_links_every_drone(fleet):
    root, result = fleet
    assert len(result.files) == FLIGHTS and all(os.path.isfile(f) for f in result.files)
    assert result.pairs[:4] == fleet_pairs(4)[:4]
    df = pd.concat([pd.read_parquet(f) for f in result.files])
    assert len(df) == result.samples
    assert set(df["tx"]) == set(drone_ids(4))
    assert df["unit"].str.endswith("@f0007").sum() > 0 and df["unit"].str.startswith("test").sum() > 0
    meta = json.loads((root / "_fleet.json").read_text())
    assert meta["flights"] == FLIGHTS and meta["samples"] == result.samples
    with pytest.raises(InputError, match="already holds flight"):
        simulate_fleet(str(root), flights=1, preset="smoke")
    with pytest.raises(InputError, match="preset"):
        simulate_fleet(str(root.parent / "other"), flights=1, preset="tworay")


def test_a_folder_fit_equals_the_fit_of_the_same_rows_in_one_file(fleet, sh6, tmp_path):
    _, result = fleet
    whole = pd.concat([pd.read_parquet(f) for f in result.files], ignore_index=True)
    write_table(whole, str(tmp_path / "all.parquet"))
    parts, _ = sh6
    one = fit_dataset(str(tmp_path / "all.parquet"), ModelSpec.parse("sh", order=6), output=str(tmp_path / "one.json"))
    assert parts.n_samples == one.n_samples
    assert np.max(np.abs(coef(parts.fitted.model) - coef(one.fitted.model))) < 1e-9
    assert parts.wall_s is not None and "samples/s" in parts.summary()


def test_dask_fit_and_automatic_choice_equal_the_single_process(fleet, sh6, client, tmp_path):
    from rplearn.workflows.learning import _fit_streamed

    root, result = fleet
    here, _ = sh6  # fit_dataset's streamed fit of the folder (_fit_streamed without a client)
    there = _fit_streamed(str(root), ModelSpec.parse("sh", order=6), None, FitOptions(), None, client=client)
    assert there.n_samples == here.n_samples
    assert np.max(np.abs(coef(there.fitted.model) - coef(here.fitted.model))) < 1e-9
    auto_here = _fit_streamed(str(root), ModelSpec.parse("sh"), None, FitOptions(auto=True), None)
    auto_there = _fit_streamed(str(root), ModelSpec.parse("sh"), None, FitOptions(auto=True), None, client=client)
    assert auto_there.selection.order == auto_here.selection.order
    assert auto_there.selection.smoothing == auto_here.selection.smoothing
    assert np.max(np.abs(coef(auto_there.fitted.model) - coef(auto_here.fitted.model))) < 1e-9
    # the next plan's prior and drift (trajectory --optimize --from-model): those of the in-memory
    # fit of the same rows in one file, here and on the cluster
    whole = pd.concat([pd.read_parquet(f) for f in result.files], ignore_index=True)
    write_table(whole, str(tmp_path / "all.parquet"))
    memory = fit_dataset(str(tmp_path / "all.parquet"), ModelSpec.parse("sh"), options=FitOptions(auto=True))
    _same_plan_prior(memory, auto_here, auto_there)


def _same_plan_prior(memory, *others):
    """The drifting error and the planning penalty weight of ``others``' models are ``memory``'s
    (an in-memory ``fit --order auto``), to 1e-9 relative."""
    want = memory.fitted.model.training
    assert want.drift_std_db is not None and want.drift_std_db > 0 and want.planning_penalty_weight > 0
    for other in others:
        got = other.fitted.model.training
        assert got.drift_std_db == pytest.approx(want.drift_std_db, rel=1e-9)
        assert got.planning_penalty_weight == pytest.approx(want.planning_penalty_weight, rel=1e-9)


def test_one_flight_cut_into_time_blocks_across_files_matches_on_dask(fleet, client, tmp_path):
    from rplearn.workflows.learning import _fit_streamed

    _, result = fleet
    one = pd.read_parquet(result.files[0])
    one = one[one["unit"].str.startswith("learn")].drop(columns="unit").sort_values("t", kind="stable")
    folder = tmp_path / "one"
    folder.mkdir()
    n = len(one)
    for i in range(8):  # the time blocks (5) straddle the files (8)
        write_table(one.iloc[i * n // 8:(i + 1) * n // 8], str(folder / f"p{i}.parquet"))
    here = _fit_streamed(str(folder), ModelSpec.parse("sh"), None, FitOptions(auto=True), None)
    there = _fit_streamed(str(folder), ModelSpec.parse("sh"), None, FitOptions(auto=True), None, client=client)
    assert len(here.selection.units) == 5
    assert np.max(np.abs(coef(there.fitted.model) - coef(here.fitted.model))) < 1e-9
    # the folds are the stretches of time the whole flight names (flight[1/5] .. test[5/5]), cut at instants
    assert here.selection.units == ["flight[1/5]", "flight[2/5]", "flight[3/5]", "flight[4/5]", "test[5/5]"]
    # the same files listed out of time order: the same stretches, the same model
    shuffled = ",".join(str(folder / f"p{i}.parquet") for i in (1, 0, *range(2, 8)))
    again = _fit_streamed(shuffled, ModelSpec.parse("sh"), None, FitOptions(auto=True), None)
    assert again.selection.order == here.selection.order
    assert np.max(np.abs(coef(again.fitted.model) - coef(here.fitted.model))) < 1e-9
    # the drift from 5-s blocks that straddle the files: the in-memory fit's, whatever the files' order
    write_table(one, str(tmp_path / "one.parquet"))
    memory = fit_dataset(str(tmp_path / "one.parquet"), ModelSpec.parse("sh"), options=FitOptions(auto=True))
    t = one["t"].to_numpy(np.float64)
    cuts = [i * n // 8 for i in range(1, 8)]
    assert any(np.floor(t[c - 1] / 5.0) == np.floor(t[c] / 5.0) for c in cuts)  # a block in two files
    _same_plan_prior(memory, here, there, again)


def test_dask_evaluation_equals_the_single_process(fleet, sh6, client):
    from rplearn.io.partitions import dataset_parts
    from rplearn.workflows.fleet import predict_parts

    root, _ = fleet
    model_path = str(sh6[1])
    here = evaluate_model_files([model_path], str(root))
    model = load_model(model_path)
    observed, predictions, _ = predict_parts(dataset_parts(str(root)), [model], ["test_90@f0003"], client)
    assert observed.size > 0 and np.all(np.isfinite(predictions[0]))
    units = sorted({u for u in here.units.units})
    assert all(u.startswith("test") for u in units)
    from rplearn.workflows import fleet as fleet_module

    observed_all, pred_all, _ = fleet_module.predict_parts(dataset_parts(str(root)), [model], units, client)
    rmse = float(np.sqrt(np.mean((observed_all - pred_all[0]) ** 2)))
    assert abs(rmse - here.rows[0].rmse_db) < 1e-9
    assert here.rows[0].n_samples == observed_all.size


def test_fit_and_evaluate_dask_local_2_from_the_command_line(fleet, sh6, tmp_path):
    """Acceptance 3: ``fit --dask local:2`` on 8 files gives the single-process coefficients
    (those of ``rplearn fit FOLDER --degree 6``: fit_dataset's SH-6, the fixture ``sh6``); its
    evaluation on the cluster the single process's scores (evaluate_model_files)."""
    need_dask()
    root, _ = fleet
    run = lambda *a: subprocess.run(RPLEARN + list(a), cwd=tmp_path, capture_output=True, text=True, timeout=300)
    dask = run("fit", str(root), "--degree", "6", "--dask", "local:2", "-o", "dask.json")
    assert dask.returncode == 0, dask.stderr
    assert "distributed" not in dask.stderr  # the cluster's logs stay quiet
    a, b = load_model(str(sh6[1])), load_model(str(tmp_path / "dask.json"))
    assert a.label == b.label == "SH-6" and np.max(np.abs(coef(a) - coef(b))) < 1e-9
    ev = run("evaluate", "dask.json", str(root), "--dask", "local:2", "--json", "t.json")
    assert ev.returncode == 0, ev.stderr
    r = json.loads((tmp_path / "t.json").read_text())["rows"][0]
    r1 = evaluate_model_files([str(tmp_path / "dask.json")], str(root)).rows[0]
    assert abs(r["rmse_db"] - r1.rmse_db) < 1e-9 and r["n_samples"] == r1.n_samples


def test_dask_option_errors_are_one_line():
    for bad in ("locl", "local:0", "local:x", "tcp://", ""):
        with pytest.raises(InputError, match="--dask"):
            parse_dask(bad)
    assert parse_dask("local") == ("local", 2) and parse_dask("local:3") == ("local", 3)
    assert parse_dask("tcp://10.0.0.1:8786") == ("remote", "tcp://10.0.0.1:8786")
    with pytest.raises(InputError, match="pattern models"):
        fit_dataset("x.parquet", ModelSpec.parse("mean"), dask="local")


def test_a_missing_dask_says_how_to_install_it(monkeypatch):
    import builtins

    real = builtins.__import__

    def no_dask(name, *args, **kwargs):
        if name.split(".")[0] in ("dask", "distributed"):
            raise ImportError(name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dask)
    with pytest.raises(InputError, match=r"pip install 'rplearn\[dask\]'"):
        with dask_client("local"):
            pass


def test_files_with_and_without_units_are_refused_naming_one(fleet, tmp_path):
    _, result = fleet
    df = pd.read_parquet(result.files[0])
    write_table(df, str(tmp_path / "a.parquet"))
    write_table(df.drop(columns="unit"), str(tmp_path / "b.parquet"))
    with pytest.raises(InputError, match=r"b\.parquet: field unit is missing.*a\.parquet"):
        fit_dataset(str(tmp_path), ModelSpec.parse("sh", order=4))


def test_a_merge_task_leaves_its_inputs_unchanged(fleet):
    """Dask may recompute from stored results: merging must not change them (found by review)."""
    from rplearn.io.partitions import dataset_parts
    from rplearn.models.streamed import part_statistics
    from rplearn.workflows.fleet import _merge_accumulated

    root, _ = fleet
    parts = dataset_parts(str(root))[:2]
    kwargs = dict(spec=ModelSpec.parse("sh", order=4), nodes=drone_ids(4), units=None, by_unit=True, stretches=None,
                  options=None)
    a, b = (part_statistics(p, **kwargs) for p in parts)
    before = (a.n_samples, b.n_samples, a.non_unit, {k: v.gram.copy() for k, v in a.stats.items()})
    merged = _merge_accumulated(a, b)
    assert merged.n_samples == before[0] + before[1]
    assert (a.n_samples, b.n_samples, a.non_unit) == before[:3]
    assert all(np.array_equal(a.stats[k].gram, g) for k, g in before[3].items())


def test_parts_add_up_in_one_process_to_one_pass_over_their_rows(fleet):
    """models.streamed.accumulate_parts (no Dask) is the sum of each part's statistics, in order,
    and equals accumulating every part's chunks in one pass."""
    from rplearn.io.files import iter_parts
    from rplearn.io.partitions import dataset_parts
    from rplearn.models.streamed import accumulate, accumulate_parts, part_statistics

    root, _ = fleet
    parts = dataset_parts(str(root))[:3]
    kwargs = dict(spec=ModelSpec.parse("sh", order=3), nodes=drone_ids(4), units=None, by_unit=False)
    seen = []
    total = accumulate_parts(parts, **kwargs, progress=lambda done, n: seen.append((done, n)))
    assert seen == [(1, 3), (2, 3), (3, 3)]
    each = [part_statistics(p, **kwargs) for p in parts]
    assert total.n_samples == sum(a.n_samples for a in each) > 0
    one_pass = accumulate(iter_parts(parts, 97), source="all", **kwargs)
    np.testing.assert_allclose(total.stats["all"].gram, one_pass.stats["all"].gram, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(total.stats["all"].rhs, one_pass.stats["all"].rhs, rtol=1e-12, atol=1e-9)
    assert total.non_unit == one_pass.non_unit and total.freq == one_pass.freq
    assert accumulate_parts([], **kwargs).n_samples == 0


def test_parts_holding_the_same_rows_are_refused_alike_here_and_on_dask(fleet, client, tmp_path):
    """Copies in other files, met only when the parts' statistics are merged (on the workers),
    are refused with the message of the single process: one line naming both files."""
    from rplearn.workflows.learning import _fit_streamed

    _, result = fleet
    folder = tmp_path / "copies"
    folder.mkdir()
    for k, f in enumerate(result.files[:5]):
        write_table(pd.read_parquet(f), str(folder / f"p{k}.parquet"))
    write_table(pd.read_parquet(result.files[2]).iloc[10:40], str(folder / "p5.parquet"))  # a later file repeats rows
    spec = ModelSpec.parse("sh", order=4)
    with pytest.raises(InputError) as here:
        _fit_streamed(str(folder), spec, None, FitOptions(), None)
    with pytest.raises(InputError) as there:
        _fit_streamed(str(folder), spec, None, FitOptions(), None, client=client)
    message = str(here.value)
    assert message == str(there.value) and "\n" not in message
    assert message.startswith(f"{folder / 'p5.parquet'}: 30 row(s) repeat an earlier row in every column "
                              f"(first at row 0, a copy of row 10 of {folder / 'p2.parquet'}")
    with pytest.raises(InputError) as auto:
        _fit_streamed(str(folder), ModelSpec.parse("sh"), None, FitOptions(auto=True), None, client=client)
    assert str(auto.value) == message
    copied = pd.read_parquet(folder / "p5.parquet")
    (folder / "p5.parquet").unlink()  # the clean files: learned, the same here and on the cluster
    model_path = str(tmp_path / "clean.json")
    clean = _fit_streamed(str(folder), spec, None, FitOptions(), model_path, client=client)
    assert clean.n_samples == _fit_streamed(str(folder), spec, None, FitOptions(), None).n_samples
    write_table(copied, str(folder / "p5.parquet"))  # scored part by part: refused alike, not scored twice
    from rplearn.io.partitions import dataset_parts
    from rplearn.workflows.fleet import predict_parts

    with pytest.raises(InputError) as scored:
        predict_parts(dataset_parts(str(folder)), [load_model(model_path)], None, client)
    assert str(scored.value) == message


def test_a_local_cluster_leaves_this_processs_environment_as_it_was(monkeypatch):
    """distributed's nanny sets its pre-spawn variables (OMP_NUM_THREADS=1, OPENBLAS_NUM_THREADS=1,
    MKL_NUM_THREADS=1, PYTHONHASHSEED) in the spawning process's own environment and never undoes
    it: every process started after a Dask fit ran single-threaded BLAS (a test's subprocess found
    numpy's and scipy's OpenBLAS at one thread). The environment is now as it was."""
    need_dask()
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "PYTHONHASHSEED"):
        monkeypatch.delenv(name, raising=False)
    before = dict(os.environ)
    with dask_client("local:1") as c:
        assert c.submit(lambda: os.environ.get("OPENBLAS_NUM_THREADS")).result() == "1"  # the worker's is set
    assert dict(os.environ) == before
