"""Every JSON file a command writes is strict JSON (issue 26): no NaN or Infinity, which
``JSON.parse`` and strict parsers refuse; a non-finite number is written as null."""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import pytest

from rplearn._atomic import dump_json, strict_json

LOG = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_16-58-51.tlog"


def _refuse(name: str) -> None:
    raise ValueError(f"{name} is not JSON")


def strict_loads(text: str) -> object:
    return json.loads(text, parse_constant=_refuse)


def invoke(args) -> str:
    from typer.testing import CliRunner

    from rplearn.cli import app

    res = CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
    assert res.exit_code == 0, f"{args}: {res.output}"
    return res.output


def test_strict_json_writes_null_for_non_finite_numbers():
    import io

    import numpy as np

    value = {"a": float("nan"), "b": [1.0, float("inf"), -float("inf")], "c": np.array([1.0, np.nan]),
             "d": np.float32("nan"), "e": (1, 2), 3: np.int64(4), "f": "NaN"}
    assert strict_json(value) == {"a": None, "b": [1.0, None, None], "c": [1.0, None], "d": None, "e": [1, 2],
                                  "3": 4, "f": "NaN"}
    fh = io.StringIO()
    dump_json(value, fh)
    assert strict_loads(fh.getvalue())["a"] is None
    with pytest.raises(ValueError):  # the parser of this test has teeth
        strict_loads(json.dumps({"x": math.nan}))


def _strict_files(folder: Path, expected: tuple[str, ...]) -> None:
    """Every ``expected`` JSON file (relative to ``folder``) is written, and every JSON file under ``folder``
    parses with a parser that refuses NaN (no NaN, no Infinity in its text)."""
    written = sorted(folder.rglob("*.json"))
    names = {p.relative_to(folder).as_posix() for p in written}
    for name in expected:
        assert name in names, (name, sorted(names))
    for path in written:
        text = path.read_text(encoding="utf-8")
        assert "NaN" not in text.replace('"NaN"', "") and "Infinity" not in text, path
        strict_loads(text)


@pytest.fixture(scope="module")
def matched(tmp_path_factory) -> Path:
    """The tlog's matched dataset (``sync``), in a folder of its own: read-only."""
    d = tmp_path_factory.mktemp("strict_json")
    invoke(["sync", "--poses", LOG, "--signals", LOG, "--tx-power", "20", "--frequency", "915e6", "--link", "all",
            "--max-gap", "1.0", "-o", d / "matched.parquet"])
    return d / "matched.parquet"


def test_simulate_writes_strict_json(tmp_path, monkeypatch):
    """simulate: the ground truth; a fleet's index (its flights the smoke campaign's, as the library offers for
    tests: the command and its ``_fleet.json`` are the same, the paper's flights only take longer)."""
    from rplearn.sim import fleet

    monkeypatch.setattr(fleet, "simulate_fleet", functools.partial(fleet.simulate_fleet, preset="smoke"))
    invoke(["simulate", "--preset", "smoke", "--seed", "1", "-o", tmp_path / "flight"])
    invoke(["simulate", "--preset", "fleet", "--flights", "1", "--drones", "2", "--seed", "1", "-o", tmp_path / "fleet"])
    _strict_files(tmp_path, ("flight/ground_truth.json", "fleet/_fleet.json"))


def test_fit_evaluate_reference_and_headings_write_strict_json(matched, tmp_path):
    """fit (fixed order, automatic, a baseline), evaluate --json, reference, headings -o .json."""
    d = tmp_path
    units = "flight[1/5],flight[2/5],flight[3/5],flight[4/5]"
    invoke(["fit", matched, "--units", units, "-o", d / "auto.json"])
    invoke(["fit", matched, "--model", "sh", "--degree", "3", "--units", units, "-o", d / "sh3.json"])
    invoke(["fit", matched, "--model", "mean", "--units", units, "-o", d / "mean.json"])  # no condition number: NaN before
    invoke(["evaluate", d / "sh3.json", d / "mean.json", matched, "--json", d / "table.json"])
    (d / "ref.csv").write_text("az_deg,el_deg,gain_dbi\n" + "".join(
        f"{az},{el},{2.0 * math.cos(math.radians(el))}\n" for az in range(-180, 181, 30) for el in range(-90, 91, 30)))
    invoke(["reference", "gcs=" + str(d / "ref.csv"), "-o", d / "reference.json"])
    invoke(["headings", d / "sh3.json", "--pos", "gcs=0,0,2", "--pos", "sys1=50,20,30", "--tx-power", "20",
            "-o", d / "yaws.json"])
    _strict_files(d, ("auto.json", "sh3.json", "mean.json", "table.json", "reference.json", "yaws.json"))
    # where a number is not defined it is null, not dropped: the mean model has no condition number
    rows = strict_loads((d / "table.json").read_text(encoding="utf-8"))["rows"]
    assert [r["model"] for r in rows] == ["SH-3", "M"] and rows[1]["condition_number"] is None


def test_report_writes_strict_json(matched, tmp_path):
    """report: its model and Table I."""
    invoke(["report", matched, "--paper-models", "m,sh-3", "--repeats", "1", "-o", tmp_path / "report"])
    _strict_files(tmp_path, ("report/model.json", "report/table1.json"))


def test_demo_writes_strict_json(tmp_path):
    """demo: Table I, the identifiability study, the models."""
    invoke(["demo", "--preset", "smoke", "--seed", "1", "-o", tmp_path / "demo"])
    _strict_files(tmp_path, ("demo/table1.json", "demo/identifiability.json", "demo/models/M.json"))
