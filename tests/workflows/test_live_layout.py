"""A live session's model files record the flight's layout as ``fit`` records it of the same rows:
the nodes that held still and the radio's packet rate (``training.fixed_nodes``,
``training.packet_rate_hz``), from a bounded summary of the batches
(:class:`rplearn.data.flight_layout.LayoutSketch`). Before, they recorded neither, and a plan from
them was for two drones at 80 packets/s."""

from __future__ import annotations

import pandas as pd
import pytest
from simulated_flights import simulated

from rplearn.models.load import load_model
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.workflows.learning import fit_dataset
from rplearn.workflows.live import LiveOptions, replay_session
from rplearn.workflows.logs import sync_logs


@pytest.fixture(scope="module")
def first_flight(tmp_path_factory):
    """The first flight of the ``ground`` preset (a static station G, a drone D), its logs, and
    the layout ``fit`` records of them synced."""
    folder, _ = simulated("ground", 0)
    d = tmp_path_factory.mktemp("ground-live")
    pose = pd.read_parquet(folder / "pose_log.parquet")
    signal = pd.read_parquet(folder / "signal_log.parquet")
    signal = signal[signal["unit"] == "learn_15m"].drop(columns=["unit"])
    pose = pose[pose["t"] <= signal["t"].max() + 1.0]
    pose.to_parquet(d / "pose.parquet", index=False)
    signal.to_parquet(d / "signal.parquet", index=False)
    sync_logs([str(d / "pose.parquet")], [str(d / "signal.parquet")], str(d / "m.parquet"))
    training = fit_dataset(str(d / "m.parquet"), ModelSpec.parse("sh", order=4)).fitted.model.training
    assert training.fixed_nodes == ("G",) and training.packet_rate_hz is not None
    return pose, signal, training


@pytest.mark.parametrize("auto", [False, True], ids=["sh-4", "auto"])
def test_a_live_sessions_model_file_records_the_layout_fit_records(first_flight, tmp_path, auto):
    pose, signal, memory = first_flight
    spec = ModelSpec.parse("sh") if auto else ModelSpec.parse("sh", order=4)
    path = str(tmp_path / "live.json")
    seen = []

    def read_file(status) -> None:  # the model file of a refit in flight
        if status.refits and not seen:
            seen.append(load_model(path).training)

    replay_session(pose, signal, path, LiveOptions(spec=spec, fit=FitOptions(auto=auto), refit_s=20.0), on_update=read_file)
    last = load_model(path).training
    assert last.fixed_nodes == memory.fixed_nodes == ("G",) and last.packet_rate_hz is not None
    print(f"live ({'auto' if auto else 'sh-4'}): fixed {last.fixed_nodes}, {last.packet_rate_hz:.4f} packets/s; in "
          f"memory: fixed {memory.fixed_nodes}, {memory.packet_rate_hz:.4f} packets/s")
    assert last.fixed_nodes == memory.fixed_nodes == ("G",)
    assert last.packet_rate_hz == pytest.approx(memory.packet_rate_hz, rel=0.01)
    assert seen and seen[0].fixed_nodes == ("G",) and seen[0].packet_rate_hz == pytest.approx(memory.packet_rate_hz, rel=0.01)
