"""Every fit records the flight's layout, whatever way it reads the rows: the nodes that held still
and the radio's packet rate (``training.fixed_nodes``, ``training.packet_rate_hz``) of a fit
streamed in chunks, of a dataset in two parts (in this process and on Dask) equal those of the
fit of the same rows in memory. Before, only the fit in memory recorded them, and a plan from the
others' model files was for two drones at 80 packets/s ("the earlier flight's layout is not recorded")."""

from __future__ import annotations

import importlib.util
import os

import pandas as pd
import pytest
from simulated_flights import synced

from rplearn.models import ModelSpec
from rplearn.models import streamed as streamed_module
from rplearn.models.options import FitOptions
from rplearn.workflows import fleet, learning
from rplearn.workflows.calibration_plan import OptimizeOptions, optimize_plan
from rplearn.workflows.learning import fit_dataset

#: Rows a chunk of the streamed fits: the 29,959 learning rows of the ``ground`` flights in 31 chunks.
CHUNK_ROWS = 997


def _need_dask() -> None:
    """Skip without dask[distributed], except under CI=true, where it must be installed."""
    if importlib.util.find_spec("distributed") is None:
        if os.environ.get("CI") == "true":
            pytest.fail("CI=true but dask[distributed] is not installed (.ci/run installs rplearn[dask])")
        pytest.skip("dask[distributed] not installed (pip install 'rplearn[dask]')")


def _streamed(path: str, spec: ModelSpec, options: FitOptions, **kw):
    """``fit_dataset`` with every file streamed in chunks of :data:`CHUNK_ROWS` rows."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(learning, "STREAM_FIT_ROWS", 0)
        mp.setattr(learning, "STREAM_FIT_BYTES", 0)
        mp.setattr(fleet, "PART_CHUNK_ROWS", CHUNK_ROWS)
        mp.setattr(streamed_module, "PART_CHUNK_ROWS", CHUNK_ROWS)
        return fit_dataset(path, spec, options=options, **kw)


@pytest.fixture(scope="module")
def ground(tmp_path_factory):
    """The ``ground`` flights (a static station G, a drone D): the dataset, the same rows in two
    files (cut inside the second learning flight), and the layout the fit in memory records."""
    flight = synced("ground", 0)
    path = str(flight.folder / "m.parquet")
    rows = pd.read_parquet(path)
    parts = tmp_path_factory.mktemp("ground-parts")
    half = len(rows) // 2
    rows.iloc[:half].to_parquet(parts / "part-0.parquet", index=False)
    rows.iloc[half:].to_parquet(parts / "part-1.parquet", index=False)
    training = fit_dataset(path, ModelSpec.parse("sh", order=4)).fitted.model.training
    assert training.fixed_nodes == ("G",) and training.packet_rate_hz == pytest.approx(78.64, rel=1e-3)
    return path, str(parts), training


def _same_layout(got, memory, how: str) -> None:
    assert got.fixed_nodes == memory.fixed_nodes and got.packet_rate_hz is not None
    print(f"{how}: fixed {got.fixed_nodes}, {got.packet_rate_hz:.4f} packets/s; in memory: fixed "
          f"{memory.fixed_nodes}, {memory.packet_rate_hz:.4f} packets/s")
    assert got.packet_rate_hz == pytest.approx(memory.packet_rate_hz, rel=0.01)


@pytest.mark.parametrize("auto", [False, True], ids=["sh-4", "auto"])
def test_a_streamed_fit_records_the_layout_of_the_fit_in_memory(ground, auto):
    path, _, memory = ground
    spec = ModelSpec.parse("sh") if auto else ModelSpec.parse("sh", order=4)
    outcome = _streamed(path, spec, FitOptions(auto=auto))
    assert outcome.n_samples == 29_959
    _same_layout(outcome.fitted.model.training, memory, f"streamed in chunks of {CHUNK_ROWS} rows ({'auto' if auto else 'sh-4'})")


def test_a_dataset_in_two_parts_records_the_layout_of_the_fit_in_memory(ground):
    _, parts, memory = ground
    outcome = fit_dataset(parts, ModelSpec.parse("sh", order=4))  # a folder: part by part
    _same_layout(outcome.fitted.model.training, memory, "two parts")


def test_a_dask_fit_of_two_parts_records_the_layout_of_the_fit_in_memory(ground):
    _need_dask()
    _, parts, memory = ground
    outcome = fit_dataset(parts, ModelSpec.parse("sh", order=4), dask="local:2")
    _same_layout(outcome.fitted.model.training, memory, "Dask, two parts")


def test_a_streamed_fit_of_two_drones_records_no_fixed_node():
    flight = synced("smoke", 0)
    training = _streamed(str(flight.folder / "m.parquet"), ModelSpec.parse("sh", order=3), FitOptions()).fitted.model.training
    assert training.fixed_nodes == ()  # recorded: nobody held still (None would be "not recorded")
    assert training.packet_rate_hz == pytest.approx(19.56, rel=1e-3)  # the preset's 20 packets/s, each way


def test_a_plan_from_a_streamed_model_is_for_its_station_and_drone(ground, tmp_path):
    path, _, memory = ground
    model = str(tmp_path / "streamed.json")
    _streamed(path, ModelSpec.parse("sh"), FitOptions(auto=True), output=model)
    plan = optimize_plan(str(tmp_path / "plan"), OptimizeOptions(model="sh-5", target_spread_db=2.5, budget_s=40.0,
                                                                 from_model=model))
    assert "a ground station G, held still in the earlier flight, and a drone D" in plan.prior
    assert "not recorded" not in plan.prior and "two drones" not in plan.prior.split("(")[0]
    assert tuple(plan.start_spread_db) == ("D", "G")
    assert plan.steps and not any(" of G" in s.manoeuvre.name or "G turning" in s.manoeuvre.name for s in plan.steps)


def test_every_fit_of_relative_power_records_it_as_the_fit_in_memory_does(ground, tmp_path):
    """Rows of uncalibrated power (``sync --rssi-scale relative``) fitted streamed in chunks or in
    two parts record ``training.rssi_scale`` = relative as the fit in memory does (they recorded
    nothing: their levels would be printed as dBm)."""
    path, _, _ = ground
    rows = pd.read_parquet(path).assign(rssi_scale="relative")
    whole = tmp_path / "relative.parquet"
    rows.to_parquet(whole, index=False)
    parts = tmp_path / "relative-parts"
    parts.mkdir()
    half = len(rows) // 2
    rows.iloc[:half].to_parquet(parts / "part-0.parquet", index=False)
    rows.iloc[half:].to_parquet(parts / "part-1.parquet", index=False)
    spec = ModelSpec.parse("sh", order=4)
    memory = fit_dataset(str(whole), spec).fitted.model
    assert memory.training.get("rssi_scale") == "relative"
    for how, model in (("streamed", _streamed(str(whole), spec, FitOptions()).fitted.model),
                       ("two parts", fit_dataset(str(parts), spec).fitted.model)):
        assert model.training.get("rssi_scale") == "relative", how
    calibrated = _streamed(path, spec, FitOptions()).fitted.model
    assert calibrated.training.get("rssi_scale") is None
