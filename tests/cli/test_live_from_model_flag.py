"""``rplearn live --from-model EARLIER.json``: the session says it ranks the next-best manoeuvres
with the earlier flight's hyper-parameters; a bad file, or the flag with ``--no-advice``, is one
line naming ``--from-model``."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_helpers import invoke
from simulated_flights import synced

from rplearn.models import ModelSpec, load_model
from rplearn.models.options import FitOptions
from rplearn.workflows.learning import fit_dataset


def _source(d: Path, n: int = 300, drone: str = "A", station: str = "B", frequency_hz: float = 2.4e9) -> str:
    """A drone circling a station at 40 m, yawing; 10 Hz poses, a packet each way per 0.1 s (by default the earlier
    model's nodes, A and B, in its band)."""
    t = np.arange(n) * 0.1
    a = 2 * np.pi * t / 20.0
    yaw = a * 3.0
    poses = pd.DataFrame({"t": t, "node": drone, "x": 40 * np.cos(a), "y": 40 * np.sin(a), "z": 20.0 + 5 * np.sin(a * 2),
                          "qw": np.cos(yaw / 2), "qx": 0.0, "qy": 0.0, "qz": np.sin(yaw / 2)})
    still = pd.DataFrame({"t": [0.0], "node": [station], "x": [0.0], "y": [0.0], "z": [1.5], "qw": [1.0], "qx": [0.0],
                          "qy": [0.0], "qz": [0.0]})
    rng = np.random.default_rng(3)
    sig = pd.DataFrame({"t": t + 0.05, "tx": drone, "rx": station, "rssi_dbm": -60.0 + rng.normal(0, 2, n),
                        "tx_power_dbm": 20.0, "frequency_hz": frequency_hz})
    pd.concat([poses, still], ignore_index=True).to_csv(d / "pose.csv", index=False)
    sig.to_csv(d / "signal.csv", index=False)
    return f"{d / 'pose.csv'},{d / 'signal.csv'}"


@pytest.fixture(scope="module")
def earlier(tmp_path_factory):
    path = tmp_path_factory.mktemp("earlier") / "earlier.json"
    fit_dataset(str(synced("smoke", 5).folder / "m.parquet"), ModelSpec.parse("sh"), options=FitOptions(auto=True), output=str(path))
    return path


def _live(d: Path, *flags: object, ok: bool = True, **source: object):
    return invoke(["live", _source(d, **source), "-o", d / "m.json", "--quiet", "--idle", "0.2", "--order", "2",
                   "--fixed", source.get("station", "B"), *flags], ok)


def test_live_ranks_with_the_earlier_models_hyper_parameters(tmp_path, earlier):
    res = _live(tmp_path, "--from-model", earlier)
    assert "manoeuvres ranked with " in res.output and "earlier.json's noise" in res.output
    assert "then with the session's own" in res.output and (tmp_path / "m.json").exists()
    assert "--from-model " not in res.output  # the session's nodes and band are the earlier model's: no fallback note


@pytest.mark.parametrize("source, text", [
    ({"drone": "D", "station": "G"}, "learned the nodes A, B (its model's nodes), the session learns D, G: D, G not among them"),
    ({"frequency_hz": 433e6}, "learned at 2.412 GHz (training.frequency_hz), the session's rows are at 433 MHz"),
])
def test_a_model_of_other_nodes_or_band_is_not_ranked_with_and_the_summary_says_so(tmp_path, earlier, source, text):
    """Known only once rows arrive (a CSV source without --nodes): the session goes on, ranking with its own
    hyper-parameters, and its summary names the file, the field and the flag (was: ranked with them, not a word)."""
    res = _live(tmp_path, "--from-model", earlier, **source)
    [note] = [line.strip() for line in res.output.splitlines() if line.strip().startswith("--from-model ")]
    assert text in note and note.startswith(f"--from-model {earlier} ")
    assert note.endswith("the manoeuvres are ranked with the session's own instead")


def test_a_model_of_nodes_other_than_nodes_is_refused_before_the_session(tmp_path, earlier):
    res = _live(tmp_path, "--from-model", earlier, "--nodes", "D,G", ok=False, drone="D", station="G")
    line = _one_line(res)
    assert "earlier.json learned the nodes A, B (its model's nodes), the session learns D, G" in line
    assert not (tmp_path / "m.json").exists()


def test_a_model_of_another_band_than_a_mavlink_frequency_is_refused_before_connecting(tmp_path, earlier):
    res = invoke(["live", "udpin:127.0.0.1:9", "-o", tmp_path / "m.json", "--quiet", "--tx-power", "20", "--frequency",
                  "433e6", "--duration", "3", "--from-model", earlier], ok=False)
    line = _one_line(res)
    assert "learned at 2.412 GHz (training.frequency_hz), the session's rows are at 433 MHz" in line


@pytest.mark.parametrize("flag", ["-o", "--html", "--record"])
def test_an_output_that_is_the_earlier_model_is_refused_before_any_work(tmp_path, earlier, flag):
    """-o EARLIER.json overwrote the earlier model at the first refit (was: accepted without a word)."""
    copy = tmp_path / ("earlier.html" if flag == "--html" else "earlier.json")
    shutil.copyfile(earlier, copy)
    source = "udpin:127.0.0.1:9" if flag == "--record" else _source(tmp_path)
    out = [] if flag == "-o" else ["-o", tmp_path / "m.json"]
    res = invoke(["live", source, *out, flag, copy, "--quiet", "--tx-power", "20", "--frequency", "2.4e9", "--duration", "3", "--from-model",
                  copy], ok=False)
    line = _one_line(res)
    name = {"-o": "--out"}.get(flag, flag)
    assert line.startswith(f"error: {name}: {copy} is also given as --from-model"), line
    assert "manoeuvres ranked with" not in res.output
    assert copy.read_bytes() == Path(earlier).read_bytes() and not (tmp_path / "m.json").exists()


@pytest.mark.parametrize("flags, text", [
    (["--from-model", "nowhere.json"], "nowhere.json: no such"),
    (["--from-model", "EARLIER", "--model", "bg"], "the session learns bg"),
    (["--from-model", "EARLIER", "--no-advice"], "drop --no-advice"),
])
def test_a_bad_from_model_is_one_line_naming_the_flag(tmp_path, earlier, flags, text):
    res = _live(tmp_path, *[earlier if f == "EARLIER" else tmp_path / f if f.endswith(".json") else f for f in flags], ok=False)
    line = _one_line(res)
    assert line.startswith("error: --from-model: ") and text in line and not (tmp_path / "m.json").exists()


def _one_line(res) -> str:
    lines = [line for line in res.output.splitlines() if line.strip()]
    assert res.exit_code == 1 and len(lines) == 1 and lines[0].startswith("error: "), res.output
    return lines[0]


def _saved(model: Path, path: Path, **changes: object) -> Path:
    out = load_model(str(model))
    out.training = out.training.replace(**changes)
    out.save(str(path))
    return path


def _reference(d: Path) -> Path:
    """``rplearn reference`` of a dipole-like pattern for A and B: a model learned from no flight."""
    rows = [(az, el, 2.15 * np.cos(np.radians(el)) ** 2) for az in range(0, 360, 10) for el in range(-90, 91, 10)]
    pd.DataFrame(rows, columns=["az_deg", "el_deg", "gain_dbi"]).to_csv(d / "dipole.csv", index=False)
    invoke(["reference", f"A={d / 'dipole.csv'}", f"B={d / 'dipole.csv'}", "-o", d / "ref.json"])
    return d / "ref.json"


@pytest.mark.parametrize("make, text", [
    (lambda d, e: _reference(d), "ref.json is a reference-pattern model (training.reference: rplearn reference)"),
    (lambda d, e: _saved(e, d / "rel.json", rssi_scale="relative"), "rel.json learned from relative RSSI (training.rssi_scale"),
    (lambda d, e: _saved(e, d / "zero.json", n_samples=0), "zero.json: training.n_samples: expected a positive count"),
    (lambda d, e: _saved(e, d / "noweight.json", planning_penalty_weight=None), "has no training.planning_penalty_weight"),
    (lambda d, e: _knn(d), "knn.json is a knn baseline"),
    (lambda d, e: _cut(e, d / "cut.json"), "cut.json: not a valid JSON model file (truncated or corrupt"),
    (lambda d, e: (d / "folder.json").mkdir() or d / "folder.json", "folder.json: cannot read"),
    (lambda d, e: Path(_source(d).split(",")[0]), "pose.csv: a table (a dataset?), not a model file"),
])
def test_a_hostile_model_file_is_one_line_naming_the_file_and_field(tmp_path, earlier, make, text):
    """Each before the session starts (no model written, nothing said of a ranking); was: a reference model called a
    fixed-order fit, a relative-RSSI fit and a count of 0 samples (never used) accepted without a word."""
    res = _live(tmp_path, "--from-model", make(tmp_path, earlier), ok=False)
    line = _one_line(res)
    assert line.startswith("error: --from-model: ") and text in line, line
    assert not (tmp_path / "m.json").exists()


def test_a_figure_out_of_range_names_no_flag_live_lacks(tmp_path, earlier):
    """live has no --noise or --drift: a model figure out of range is refused without advising them (was: 'give
    --noise instead')."""
    for field, value in (("noise_std_db", 0.001), ("drift_std_db", 200.0), ("variance_inflation", 2e4)):
        res = _live(tmp_path, "--from-model", _saved(earlier, tmp_path / f"{field}.json", **{field: value}), ok=False)
        line = _one_line(res)
        assert line.startswith("error: --from-model: ") and f"training.{field} is " in line, line
        assert "--noise" not in line and "--drift" not in line, line


def test_an_inflation_in_the_hundreds_is_an_earlier_model_live_ranks_with(tmp_path, earlier):
    """A fast radio's errors correlated over many packets inflate the variance by hundreds: noise x sqrt(inflation)
    above 90 dB is no refusal (was: 'not a radio's RSSI scatter')."""
    res = _live(tmp_path, "--from-model", _saved(earlier, tmp_path / "inflated.json", variance_inflation=600.0))
    assert "manoeuvres ranked with " in res.output and "inflated.json's noise" in res.output, res.output


def _knn(d: Path) -> Path:
    invoke(["fit", synced("smoke", 5).folder / "m.parquet", "--model", "knn", "-o", d / "knn.json"])
    return d / "knn.json"


def _cut(model: Path, path: Path) -> Path:
    text = Path(model).read_text()
    path.write_text(text[: len(text) // 2])
    return path
