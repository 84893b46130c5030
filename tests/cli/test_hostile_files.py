"""Session 46's audit of the command line on hostile files: model files with a checksum that
matches but fields no fit writes (a writer's bug, or a hand edit whose checksum was made again),
JSON nested past the decoder's recursion, and matched datasets whose rows no ``sync`` writes
(positions near 1e308, a node linked to itself, nodes the model has no pattern of).

Each case was a traceback, a NaN answer with exit 0 (a coefficient of 1e300, a position of
1e308), or a refusal that named neither the file nor the field. Each must now be exit 1 with one
line ``error: ...`` naming the file and the field, no traceback, nothing written.

The commands run in this process (:func:`cli_helpers.run_here`); one refusal
(:data:`IN_A_PROCESS`) runs as a process of its own, so that the process boundary stays covered.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from cli_helpers import D, M, P, S, answer, assert_one_line_error, invoke_in, listing, smoke_flight

from rplearn.io.modelfile import read_model_file, write_model_file


def _edited(d: Path, source: str, name: str, edit: Callable[[dict[str, Any]], None]) -> None:
    """``source`` with ``edit`` applied to its payload, written with a matching checksum as ``name``."""
    kind, payload = read_model_file(d / source)
    edit(payload)
    write_model_file(d / name, kind, payload)


def _set(path: tuple[str, ...], value: Any) -> Callable[[dict[str, Any]], None]:
    def edit(payload: dict[str, Any]) -> None:
        for key in path[:-1]:
            payload = payload[key]
        payload[path[-1]] = value
    return edit


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("hostile_files")
    smoke_flight(d, extra=(["fit", D, "--model", "mean", "-o", "mean.json"],))
    edits = {
        "gauge_null.json": _set(("gauge",), None),
        "provenance_str.json": _set(("provenance",), "zz"),
        "basis_xx.json": _set(("basis", "kind"), "xx"),
        "order_neg.json": _set(("basis", "order"), -1),
        "coef_1e300.json": lambda p: p["coefficients"]["A"].__setitem__(3, 1e300),
        "rmse_neg.json": _set(("training", "rmse_db"), -1.0),
        "rmse_null.json": _set(("training", "rmse_db"), None),
        "coverage_short.json": lambda p: p["training"]["coverage_deg"]["A"].pop(),
        "coverage_null.json": lambda p: p["training"]["coverage_deg"]["B"].__setitem__(7, None),
    }
    for name, edit in edits.items():
        _edited(d, M, name, edit)
    _edited(d, "mean.json", "mean_provenance_null.json", _set(("provenance",), None))
    (d / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    data = pd.read_parquet(d / D)
    data.assign(tx_x=np.where(np.arange(len(data)) == 4, 1e308, data["tx_x"])).to_parquet(d / "far.parquet")
    data.assign(rx=data["tx"]).to_parquet(d / "self.parquet")
    data.assign(tx=data["tx"].replace("A", "C"), rx=data["rx"].replace("A", "C")).to_parquet(d / "node_c.parquet")
    data.iloc[:0].to_csv(d / "header.csv", index=False)
    data.iloc[:1].to_parquet(d / "one_row.parquet")
    data.assign(tx_x=data["rx_x"], tx_y=data["rx_y"], tx_z=data["rx_z"]).to_parquet(d / "samepos.parquet")
    pose = pd.read_parquet(d / P)
    pose.assign(qw=np.where(np.arange(len(pose)) == 9, 1e200, pose["qw"])).to_parquet(d / "q1e200.parquet")
    signal = pd.read_parquet(d / S)
    pose.to_csv(d / "pose.csv", index=False)
    signal.to_csv(d / "signal.csv", index=False)
    az, el = np.meshgrid(np.arange(-180.0, 180.0, 15.0), np.arange(-90.0, 91.0, 15.0))
    pd.DataFrame({"az_deg": az.ravel(), "el_deg": el.ravel(), "gain_dbi": 2.0 * np.cos(np.radians(el.ravel()))}
                 ).to_csv(d / "ref.csv", index=False)
    signal.assign(t=np.where(np.arange(len(signal)) == 3, np.nan, signal["t"])).to_parquet(d / "nan_t.parquet")
    signal.iloc[:0].to_parquet(d / "no_signals.parquet")
    signal.assign(rx=signal["tx"]).to_parquet(d / "self_signals.parquet")
    return d


PREDICT = ["predict", "{model}", D, "-o", "p.csv"]
ORIENT = ["orient", M, "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "30,0,20"]
#: (command line, text the one error line must hold); ``{model}`` is the model file of the case.
REFUSED = {
    # tracebacks (TypeError, ValueError, RecursionError)
    "gauge null": (["orient", "gauge_null.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "30,0,20"],
                   "gauge_null.json: field 'gauge' must be a list, got NoneType"),
    "provenance a string": (["export", "provenance_str.json", "-o", "g.csv"],
                            "provenance_str.json: field 'provenance' must be an object, got str"),
    "mean model, provenance null": (["evaluate", "mean_provenance_null.json", D],
                                    "mean_provenance_null.json: field 'provenance' must be an object"),
    "JSON nested 100,000 deep": (PREDICT, "deep.json: not a valid JSON model file (nested too deeply"),
    # refusals that did not name the file
    "basis kind xx": (PREDICT, "basis_xx.json: basis: unknown basis 'xx'"),
    "basis order -1": (["plot", "order_neg.json", "-o", "p.png"], "order_neg.json: basis: SH order must be a positive"),
    "dataset node C, model of A and B": (["evaluate", M, "node_c.parquet"],
                                         "node_c.parquet: node(s) C in columns tx/rx, but sh3.json has patterns of A, B only"),
    "predict node C": (["predict", M, "node_c.parquet", "-o", "p.csv"], "node_c.parquet: node(s) C in columns tx/rx"),
    "fit on a node linked to itself": (["fit", "self.parquet", "--order", "3", "-o", "m.json"],
                                       "self.parquet: tx equals rx (B) at row 0"),
    # exit 0 with NaN answers, or with a wrong or no answer
    "coefficient 1e300": (PREDICT, "coef_1e300.json: a coefficient of magnitude 1e+300 dB"),
    "evaluate, coefficient 1e300": (["evaluate", "coef_1e300.json", D], "coef_1e300.json: a coefficient of magnitude"),
    "training RMSE -1": (PREDICT, "rmse_neg.json: training.rmse_db: expected a finite number >= 0, got -1.0"),
    "coverage grid one short": (PREDICT, "coverage_short.json: training.coverage_deg.A: expected 16384 angles, got 16383"),
    "coverage grid with a null": (PREDICT, "coverage_null.json: training.coverage_deg.B: entry 7 is None"),
    "position 1e308, predict": (["predict", M, "far.parquet", "-o", "p.csv"], "far.parquet: tx_x 1e+308 at row 4 is outside"),
    "position 1e308, evaluate": (["evaluate", M, "far.parquet"], "far.parquet: tx_x 1e+308 at row 4"),
    "position 1e308, k-NN fit": (["fit", "far.parquet", "--model", "knn", "-o", "k.json"], "far.parquet: tx_x 1e+308"),
    "evaluate on a node linked to itself": (["evaluate", M, "self.parquet"], "self.parquet: tx equals rx (B) at row 0"),
    "predict a node linked to itself": (["predict", M, "self.parquet", "-o", "p.csv"], "self.parquet: tx equals rx"),
    "predict both ends at one place": (["predict", M, "samepos.parquet", "-o", "p.csv"],
                                      "samepos.parquet: tx/rx positions: 2672 of 2672 sample(s) are not in the far field"),
    "trajectory --rate 0.5": (["trajectory", "--rate", "0.5", "-o", "plan"], "--rate: expected at least 1 Hz, got 0.5 Hz"),
    "a pose whose qw is 1e200": (["sync", "--poses", "q1e200.parquet", "--signals", S, "--link", "all", "-o", "s.parquet"],
                                 "q1e200.parquet: quaternion (qw, qx, qy, qz) has a norm beyond any float (a corrupt value) "
                                 "at row 9"),
    # outputs named for another kind of file than the one written (a model as a .parquet, a PNG as a
    # .csv: read back as what its name says), an empty name (a fit that saved nothing, exit 0), a
    # --record a CSV session ignored
    "fit -o a .parquet name": (["fit", D, "--order", "3", "-o", "model.parquet"],
                               "model.parquet: a model file (JSON) is written here, but the name says otherwise; name it .json"),
    "fit -o ''": (["fit", D, "--order", "3", "-o", ""], "--out: an empty file name"),
    "export a grid to .json": (["export", M, "-o", "grid.json"], "grid.json: a grid CSV is written here"),
    "plot to .csv": (["plot", M, "-o", "p.csv"], "p.csv: a PNG image is written here"),
    "sweep --plot .pdf": (["sweep", D, "--orders", "1..2", "--plot", "s.pdf"], "s.pdf: a PNG image is written here"),
    "reference to .parquet": (["reference", "A=ref.csv", "-o", "r.parquet"], "r.parquet: a model file (JSON)"),
    "live --html h.json": (["live", "pose.csv,signal.csv", "-o", "l.json", "--html", "h.json", "--quiet", "--no-advice"],
                           "h.json: an HTML page is written here"),
    "live --record of a CSV session": (["live", "pose.csv,signal.csv", "-o", "l.json", "--record", "x.tlog", "--quiet",
                                        "--no-advice"], "--record: x.tlog: a CSV source is recorded already"),
    "fit on one row": (["fit", "one_row.parquet", "--order", "3", "-o", "m.json"],
                       "more than the 1 samples of the learning data can identify; no sh order fits (SH-1 alone needs 2)"),
    "report --test-units nosuch": (["report", D, "--test-units", "nosuch", "-o", "rep"],
                                   f"{D}: unknown unit(s) nosuch; the dataset has learn_0, test_90 (set it with --test-units)"),
    "predict a dataset of no rows": (["predict", M, "header.csv", "-o", "p.csv"], "header.csv: the dataset has no rows"),
    "plot the directions of no rows": (["plot", M, "--dataset", "header.csv", "-o", "p.png"], "header.csv: the dataset has no rows"),
    # options: a traceback, sizes that hung or ran out of memory, flags named wrong or not at all
    "BG kernels of 1e-9 rad^2": (["fit", D, "--model", "bg", "--order", "3", "--sigma", "1e-9", "-o", "m.json"],
                                 "the samples do not identify BG-3 for 2 nodes: design rank 0"),
    "sweep --orders 1..100000000": (["sweep", D, "--orders", "1..100000000"],
                                    "--orders: order 100000000: SH-100000000 for 2 antennas has 20,000,000,000,000,000 "
                                    "coefficients, more than the 1,345 samples of the learning data can identify; "
                                    "the largest sh order that fits is 25"),
    "links --draws 100000000": (["links", M, P, "--tx-power", "20", "--sensitivity", "-90", "--draws", "100000000",
                                 "-o", "l.csv"], "--draws: 100,000,000 draws would take"),
    "orient --caution inf": (ORIENT + ["--caution", "inf"], "--caution: expected a finite number >= 0, got inf"),
    "orient --tx-pos nan": (["orient", M, "--tx", "A", "--rx", "B", "--tx-pos", "nan,0,20", "--rx-pos", "30,0,20"],
                            "--tx-pos: expected three finite numbers x,y,z in metres, got 'nan,0,20'"),
    "links --at before the logs": (["links", M, P, "--tx-power", "20", "--at", "0", "-o", "l.csv"],
                                   f"--at: no time asked has two drones with a pose (1 time(s), 0 .. 0 s); the pose logs of {P}"),
    "trajectory --distance 1e-9": (["trajectory", "--distance", "1e-9", "-o", "plan"],
                                   "--distance: expected at least 5 m between the drones, got 1e-09 m"),
    "replay a dataset": (["replay", D], f"{D}: no MAVLink message in it to send"),
    "trajectory --speed 1e-9": (["trajectory", "--speed", "1e-9", "-o", "plan"],
                                "--speed: at 1e-09 m/s even one loop per unit would take"),
}

#: The refusals that run as processes of their own (a size refusal: were the check to fail, the
#: work would run in the test process).
IN_A_PROCESS = {"coefficient 1e300", "links --draws 100000000", "sweep --orders 1..100000000"}
assert IN_A_PROCESS <= REFUSED.keys()

_MODELS = {"JSON nested 100,000 deep": "deep.json", "basis kind xx": "basis_xx.json", "coefficient 1e300": "coef_1e300.json",
           "training RMSE -1": "rmse_neg.json", "coverage grid one short": "coverage_short.json",
           "coverage grid with a null": "coverage_null.json"}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_refused_in_one_line_naming_the_file_and_nothing_written(workdir, case):
    args, needle = REFUSED[case]
    args = [a.replace("{model}", _MODELS.get(case, M)) for a in args]
    before = listing(workdir)
    assert_one_line_error(answer(args, workdir, case in IN_A_PROCESS), needle, case)
    assert listing(workdir) == before


def test_the_files_edited_back_still_read(workdir):
    """The checks refuse what no fit writes, not the model files fits write: the smoke model
    written again through the same path predicts (its coverage grids, spreads and provenance
    are as a fit writes them)."""
    _edited(workdir, M, "same.json", lambda p: None)
    invoke_in(workdir, ["predict", "same.json", D, "-o", "same.csv"])
    table = pd.read_csv(workdir / "same.csv")
    assert np.isfinite(table[["gain_pred_db", "rssi_pred_std_db", "tx_coverage_deg"]].to_numpy()).all()
    assert json.loads((workdir / "same.json").read_text())["model"]["training"]["coverage_deg"]["A"]


#: Signal tables ``inspect`` said nothing wrong of ("problems: none found"; times "nan .. nan s").
INSPECTED = {
    "nan_t.parquet": "nan_t.parquet: column t: 1 row(s) with a non-numeric, NaN or infinite value (first at row 3); "
                     "sync drops them (invalid_value)",
    "no_signals.parquet": "no_signals.parquet: no signal rows (a header without samples)",
    "self_signals.parquet": "self_signals.parquet: columns tx, rx: 2,672 row(s) from a node to itself (first at row 0); "
                            "sync drops them (tx_equals_rx)",
}


@pytest.mark.parametrize("name", sorted(INSPECTED))
def test_inspect_says_what_sync_will_drop(workdir, name):
    proc = answer(["inspect", name], workdir)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    problems = proc.stdout.split("problems:", 1)[1]
    assert f"  - {INSPECTED[name]}" in problems.splitlines(), problems
    clean = answer(["inspect", S], workdir)
    assert clean.stdout.rstrip().endswith("problems: none found")


def test_a_model_without_its_residual_says_the_packet_spread_is_nan(workdir):
    """A model file that states no training residual (a hand-made one) gives NaN in
    rssi_pred_std_db: said, not left for the user to find in the table (it was silent)."""
    proc = answer(["predict", "rmse_null.json", D, "-o", "nan_std.csv"], workdir)
    assert proc.returncode == 0, proc.stderr
    assert "note: rssi_pred_std_db is NaN in every row: the model file states no training residual" in proc.stderr
    table = pd.read_csv(workdir / "nan_std.csv")
    assert table["rssi_pred_std_db"].isna().all() and np.isfinite(table["gain_pred_std_db"]).all()
    assert "rssi_pred_std_db is NaN" not in answer(["predict", M, D, "-o", "std.csv"], workdir).stderr


def test_report_repeats_beyond_the_budget_write_no_folder(workdir):
    """``report --repeats 100000000`` learned SH-2 until killed (past 120 s), its folder half
    written; now the first run's time prices the rest, refused before the folder is made."""
    before = listing(workdir)
    proc = answer(["report", D, "--paper-models", "SH-2", "--repeats", "100000000", "-o", "rep"], workdir, process=True)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert lines[-1].startswith("error: --repeats: 100,000,000 runs of sh-2 would take about"), lines
    assert all(line.startswith("... ") for line in lines[:-1]), lines  # the progress lines of a non-terminal
    assert listing(workdir) == before


def test_an_output_name_without_a_suffix_says_no_kind_and_is_written(workdir):
    """Only a suffix of another kind is refused (``model.parquet``): ``-o model`` writes the model there."""
    proc = answer(["fit", D, "--order", "3", "-o", "plain_model"], workdir)
    assert proc.returncode == 0, proc.stderr
    assert read_model_file(workdir / "plain_model")[0]
    assert answer(["predict", "plain_model", D, "-o", "plain.csv"], workdir).returncode == 0


@pytest.mark.parametrize("name", ["models/", "model.json/"])
def test_an_output_name_ending_with_a_separator_names_a_folder_and_is_refused_before_the_work(workdir, name):
    """``-o models/`` names a folder: refused at once (before the fit, which then failed to write it)."""
    before = listing(workdir)
    proc = answer(["fit", D, "--order", "3", "-o", name], workdir)
    assert proc.returncode != 0
    assert_one_line_error(proc, f"{name}: names a folder")
    assert listing(workdir) == before
