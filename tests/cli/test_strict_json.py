"""Every JSON file a command writes is strict JSON (issue 26): no NaN or Infinity, which
``JSON.parse`` and strict parsers refuse; a non-finite number is written as null."""

from __future__ import annotations

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


def test_every_command_that_writes_json_writes_strict_json(tmp_path):
    """simulate (ground truth; a fleet's index), fit (fixed order, automatic, a baseline), reference,
    evaluate --json, headings -o .json, report (its model, Table I) and demo (Table I, the
    identifiability study, the models): every JSON file parses with a parser that refuses NaN."""
    d = tmp_path
    invoke(["simulate", "--preset", "smoke", "--seed", "1", "-o", d / "flight"])
    invoke(["simulate", "--preset", "fleet", "--flights", "1", "--drones", "2", "--seed", "1", "-o", d / "fleet"])
    invoke(["sync", "--poses", LOG, "--signals", LOG, "--tx-power", "20", "--frequency", "915e6", "--link", "all",
            "--max-gap", "1.0", "-o", d / "matched.parquet"])
    data = d / "matched.parquet"
    units = "flight[1/5],flight[2/5],flight[3/5],flight[4/5]"
    invoke(["fit", data, "--units", units, "-o", d / "auto.json"])
    invoke(["fit", data, "--model", "sh", "--degree", "3", "--units", units, "-o", d / "sh3.json"])
    invoke(["fit", data, "--model", "mean", "--units", units, "-o", d / "mean.json"])  # no condition number: NaN before
    invoke(["evaluate", d / "sh3.json", d / "mean.json", data, "--json", d / "table.json"])
    (d / "ref.csv").write_text("az_deg,el_deg,gain_dbi\n" + "".join(
        f"{az},{el},{2.0 * math.cos(math.radians(el))}\n" for az in range(-180, 181, 30) for el in range(-90, 91, 30)))
    invoke(["reference", "gcs=" + str(d / "ref.csv"), "-o", d / "reference.json"])
    invoke(["headings", d / "sh3.json", "--pos", "gcs=0,0,2", "--pos", "sys1=50,20,30", "--tx-power", "20",
            "-o", d / "yaws.json"])
    invoke(["report", data, "--paper-models", "m,sh-3", "--repeats", "1", "-o", d / "report"])
    invoke(["demo", "--preset", "smoke", "--seed", "1", "-o", d / "demo"])
    written = sorted(p for p in d.rglob("*.json"))
    names = {p.relative_to(d).as_posix() for p in written}
    for expected in ("flight/ground_truth.json", "fleet/_fleet.json", "auto.json", "sh3.json", "mean.json", "table.json",
                     "reference.json", "yaws.json", "report/model.json", "report/table1.json", "demo/table1.json",
                     "demo/identifiability.json", "demo/models/M.json"):
        assert expected in names, (expected, sorted(names))
    for path in written:
        text = path.read_text(encoding="utf-8")
        assert "NaN" not in text.replace('"NaN"', "") and "Infinity" not in text, path
        strict_loads(text)
    # where a number is not defined it is null, not dropped: the mean model has no condition number
    rows = strict_loads((d / "table.json").read_text(encoding="utf-8"))["rows"]
    assert [r["model"] for r in rows] == ["SH-3", "M"] and rows[1]["condition_number"] is None
