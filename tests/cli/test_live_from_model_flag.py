"""``rplearn live --from-model EARLIER.json``: the session says it ranks the next-best manoeuvres
with the earlier flight's hyper-parameters; a bad file, or the flag with ``--no-advice``, is one
line naming ``--from-model``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_helpers import invoke
from simulated_flights import synced

from rplearn.models import ModelSpec
from rplearn.models.options import FitOptions
from rplearn.workflows.learning import fit_dataset


def _source(d: Path, n: int = 300) -> str:
    """A drone circling a station at 40 m, yawing; 10 Hz poses, a packet each way per 0.1 s."""
    t = np.arange(n) * 0.1
    a = 2 * np.pi * t / 20.0
    yaw = a * 3.0
    drone = pd.DataFrame({"t": t, "node": "D", "x": 40 * np.cos(a), "y": 40 * np.sin(a), "z": 20.0 + 5 * np.sin(a * 2),
                          "qw": np.cos(yaw / 2), "qx": 0.0, "qy": 0.0, "qz": np.sin(yaw / 2)})
    station = pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [1.5], "qw": [1.0], "qx": [0.0],
                            "qy": [0.0], "qz": [0.0]})
    rng = np.random.default_rng(3)
    sig = pd.DataFrame({"t": t + 0.05, "tx": "D", "rx": "G", "rssi_dbm": -60.0 + rng.normal(0, 2, n),
                        "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})
    pd.concat([drone, station], ignore_index=True).to_csv(d / "pose.csv", index=False)
    sig.to_csv(d / "signal.csv", index=False)
    return f"{d / 'pose.csv'},{d / 'signal.csv'}"


@pytest.fixture(scope="module")
def earlier(tmp_path_factory):
    path = tmp_path_factory.mktemp("earlier") / "earlier.json"
    fit_dataset(str(synced("smoke", 5).folder / "m.parquet"), ModelSpec.parse("sh"), options=FitOptions(auto=True), output=str(path))
    return path


def _live(d: Path, *flags: object, ok: bool = True):
    return invoke(["live", _source(d), "-o", d / "m.json", "--quiet", "--idle", "0.2", "--order", "2", "--fixed", "G", *flags], ok)


def test_live_ranks_with_the_earlier_models_hyper_parameters(tmp_path, earlier):
    res = _live(tmp_path, "--from-model", earlier)
    assert "manoeuvres ranked with " in res.output and "earlier.json's noise" in res.output
    assert "then with the session's own" in res.output and (tmp_path / "m.json").exists()


@pytest.mark.parametrize("flags, text", [
    (["--from-model", "nowhere.json"], "nowhere.json: no such"),
    (["--from-model", "EARLIER", "--model", "bg"], "the session learns bg"),
    (["--from-model", "EARLIER", "--no-advice"], "drop --no-advice"),
])
def test_a_bad_from_model_is_one_line_naming_the_flag(tmp_path, earlier, flags, text):
    res = _live(tmp_path, *[earlier if f == "EARLIER" else tmp_path / f if f.endswith(".json") else f for f in flags], ok=False)
    lines = [line for line in res.output.splitlines() if line.strip()]
    assert res.exit_code == 1 and len(lines) == 1 and lines[0].startswith("error: --from-model: "), res.output
    assert text in lines[0] and not (tmp_path / "m.json").exists()
