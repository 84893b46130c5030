"""Every example of issue 10 ("Nothing lost, nothing invented"), run as the user ran it.

Each case is a command line on a small simulated flight, or on a file made bad on purpose, with
what must come out: either a refusal (exit 1, one line ``error: ...`` naming the file, row, flag
or value; no traceback, no file written) or a result that counts what it dropped or fixed.
Examples shown elsewhere are named at the bottom, with the test that shows them.

The commands run in this process (:func:`cli_helpers.run_here`: the exit code, stdout and stderr a
user's process shows), except one refusal (:data:`IN_A_PROCESS`), so that the process boundary
stays covered.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_helpers import D, M, P, S, answer, assert_one_line_error, listing, run_here, smoke_flight

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
SYNC = ["sync", "--poses", P, "--link", "all", "-o", "out.parquet", "--signals"]
ORIENT = ["orient", M, "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "30,0,20"]


def _bad_files(d: Path) -> None:
    """Inputs a hostile (or unlucky) user gives, each with one thing wrong."""
    sig = pd.read_parquet(d / S)
    edits = {
        "empty_tx.csv": lambda s: s.assign(tx=s["tx"].astype(object).where(s.index != 3, None)),
        "mhz.csv": lambda s: s.assign(frequency_hz=2412.0),
        "f1e30.csv": lambda s: s.assign(frequency_hz=np.where(s.index == 2, 1e30, s["frequency_hz"])),
        "p1e6.csv": lambda s: s.assign(tx_power_dbm=np.where(s.index == 2, 1e6, s["tx_power_dbm"])),
        "above_tx.csv": lambda s: s.assign(rssi_dbm=np.where(s.index == 2, s["tx_power_dbm"] + 5, s["rssi_dbm"])),
    }
    for name, edit in edits.items():
        edit(sig.copy()).to_csv(d / name, index=False)
    pose = pd.read_parquet(d / P)
    mixed = pose[["t", "node", "x", "y", "z"]].assign(roll_deg=5.0, pitch_deg=-3.0, yaw_ned_deg=90.0)
    mixed.to_csv(d / "mixed_euler.csv", index=False)
    data = pd.read_parquet(d / D)
    data.loc[3, "tx_qw"] *= 2.0  # a non-unit quaternion: normalised and counted
    data.to_parquet(d / "scaled_q.parquet")
    data.loc[4, ["rx_qw", "rx_qx", "rx_qy", "rx_qz"]] = 0.0  # no attitude at all
    data.to_parquet(d / "zero_q.parquet")
    pd.concat([data, data], ignore_index=True).to_parquet(d / "twice.parquet")  # a dataset in the file twice
    pose.assign(node=pose["node"].replace({"A": "C", "B": "E"})).to_csv(d / "other_nodes.csv", index=False)
    above = pd.read_parquet(d / D)
    above.loc[5, "rssi_dbm"] = above.loc[5, "tx_power_dbm"] + 3.0
    above.to_parquet(d / "above_tx.parquet")
    ulog = (FIXTURES / "px4-ulog" / "sample_log_small.ulg").read_bytes()
    (d / "cut.ulg").write_bytes(ulog[: len(ulog) // 2])
    pcap = (FIXTURES / "radiotap-pcap" / "ieee802.11_htc.pcap").read_bytes()
    (d / "cut.pcap").write_bytes(pcap[:-5])
    model = json.loads((d / M).read_text())
    (d / "nan_model.json").write_text(json.dumps(model).replace('"rmse_db": ', '"rmse_db": NaN, "x": ', 1))


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("hostile")
    smoke_flight(d)
    _bad_files(d)
    from rplearn.models import load_model

    no_rmse = load_model(d / M)
    no_rmse.training = no_rmse.training.replace(rmse_db=None)
    no_rmse.save(str(d / "no_rmse.json"))
    (d / "folder").mkdir()
    return d


#: Refusals: (command line, text the one error line must hold).
REFUSED = {
    # class 4, unbounded work: sizes checked before any work, with the largest possible value
    "fit --degree 1000": (["fit", D, "--degree", "1000", "-o", "x.json"], "the largest sh order that fits is"),
    "fit bg degree 1000": (["fit", D, "--model", "bg", "--degree", "1000", "-o", "x.json"], "the largest bg order that fits is"),
    "fit poly degree 1000": (["fit", D, "--model", "poly", "--degree", "1000", "-o", "x.json"], "the largest poly order that fits is"),
    "export --step-deg 0.001": (["export", M, "--format", "grid", "--step-deg", "0.001", "-o", "g.csv"], "expected a step in [0.1, 180] deg"),
    "links --step 1e-9": (["links", M, P, "--tx-power", "20", "--step", "1e-9", "-o", "l.csv"], "use a step of at least"),
    "headings --step 0.000001": (["headings", M, "--pos", "A=0,0,20", "--pos", "B=30,0,20", "--tx-power", "20",
                                  "--step", "0.000001", "-o", "h.json"], "expected a yaw step in [0.01, 90] deg"),
    # class 5, silent wrong answers
    "frequency 2412 (MHz)": (SYNC + ["mhz.csv"], "mhz.csv: frequency_hz 2412 at row 0 is not a radio carrier in Hz"),
    "frequency 1e30": (SYNC + ["f1e30.csv"], "f1e30.csv: frequency_hz 1e+30 at row 2"),
    "tx power 1e6 dBm": (SYNC + ["p1e6.csv"], "p1e6.csv: tx_power_dbm 1e+06 at row 2 is outside"),
    "--gauge-dbi nan": (["fit", D, "--degree", "3", "--gauge-node", "A", "--gauge-dbi", "nan", "-o", "x.json"], "--gauge-dbi"),
    "roll/pitch ENU with yaw NED": (["sync", "--poses", "mixed_euler.csv", "--signals", S, "-o", "x.parquet"], "attitude columns mix frames"),
    "orient --frequency 0": (ORIENT + ["--frequency", "0"], "--frequency: expected a positive frequency in Hz, got 0"),
    "orient --frequency 2412": (ORIENT + ["--frequency", "2412"], "looks like MHz"),
    "orient --tx-power 1e6": (ORIENT + ["--tx-power", "1e6"], "tx_power_dbm 1e+06 is outside -40 to 60 dBm"),
    "links --tx-power 1e6": (["links", M, P, "--tx-power", "1e6", "-o", "l.csv"], "is outside -40 to 60 dBm"),
    "RSSI above tx power in a dataset": (["fit", "above_tx.parquet", "--degree", "3", "-o", "x.json"], "above_tx.parquet"),
    # class 6, tracebacks and messages naming neither file nor row
    "literal NaN in a model file": (["predict", "nan_model.json", D, "-o", "p.csv"], "nan_model.json"),
    "simulate --seed -1": (["simulate", "--seed", "-1", "-o", "s"], "--seed: expected a non-negative integer, got -1"),
    "zero-norm quaternion": (["fit", "zero_q.parquet", "--degree", "3", "-o", "x.json"],
                             "zero_q.parquet: quaternion (rx_qw, rx_qx, rx_qy, rx_qz) has zero norm at row 4"),
    "-o /proc/x": (["fit", D, "--degree", "3", "-o", "/proc/x.json"], "/proc/x.json: cannot create a file in /proc"),
    "-o into a missing folder": (["fit", D, "--degree", "3", "-o", "nowhere/x.json"], "nowhere/x.json: cannot write into a non-existent directory"),
    "-o /dev/full": (["fit", D, "--degree", "3", "-o", "/dev/full"], "/dev/full: is not a regular file"),
    "-o an existing folder": (["fit", D, "--degree", "3", "-o", "folder"], "folder: is a directory"),
    "markup in a missing input's name": (["fit", "[b]no[/]:fire:.parquet", "-o", "x.json"], "[b]no[/]:fire:.parquet: no such file"),
    "markup in an output name": (["plot", M, "-o", "[/]x.png"], "[/]x.png: cannot write into a non-existent directory"),
    # issue 38, hostile logs: a dataset learned twice; a warning line before the refusal
    "fit on a dataset in the file twice": (["fit", "twice.parquet", "--degree", "3", "-o", "x.json"],
                                           "twice.parquet: 2,672 row(s) repeat an earlier row in every column"),
    "evaluate on a dataset in the file twice": (["evaluate", M, "twice.parquet"], "twice.parquet: 2,672 row(s) repeat"),
    "signals naming only nodes without a pose log": (["sync", "--poses", "other_nodes.csv", "--signals", S, "-o", "x.parquet"],
                                                     "nodes without a pose log: A, B"),
}


#: The refusal that runs as a process of its own.
IN_A_PROCESS = "-o /dev/full"
assert IN_A_PROCESS in REFUSED


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_refused_in_one_line_and_nothing_written(workdir, case):
    args, needle = REFUSED[case]
    before = listing(workdir)
    assert_one_line_error(answer(args, workdir, case == IN_A_PROCESS), needle, case)
    assert listing(workdir) == before  # nothing written, no temporary file left


#: Results that count what they dropped or fixed: (command line, text the output must hold).
COUNTED = {
    "empty tx cell": (SYNC + ["empty_tx.csv"], "dropped (invalid_value): 1"),
    "RSSI above tx power in a signal log": (SYNC + ["above_tx.csv"], "dropped (implausible_rssi): 1"),
    "quaternion normalised in fit": (["fit", "scaled_q.parquet", "--degree", "3", "-o", "q.json"],
                                     "samples with a non-unit quaternion (|norm - 1| > 0.001, normalised): 1"),
    "cut-off ULog": (["inspect", "cut.ulg", "--node", "cut.ulg=A"], "cut.ulg: the file is cut off inside the message at byte"),
    "cut-off pcap": (["inspect", "cut.pcap", "--receiver", "cut.pcap=B"], "cut.pcap: the file is cut off inside the message at byte"),
    "model without a training RMSE": (["predict", "no_rmse.json", D, "-o", "p_no_rmse.csv"], "wrote 2,672 predictions"),
    "markup in an output name": (["predict", M, D, "-o", "[b]x:fire:.csv"], "to [b]x:fire:.csv (RMSE"),
}


@pytest.mark.parametrize("case", sorted(COUNTED))
def test_counted_or_said_not_hidden(workdir, case):
    args, needle = COUNTED[case]
    proc = run_here(args, workdir, ok=False)
    out = proc.stdout + proc.stderr
    assert "Traceback" not in out and needle in out, (case, out)
    assert "problems: none found" not in out
    if case == "empty tx cell":
        written = pd.read_parquet(workdir / "out.parquet")
        assert not set(written["tx"]) - {"A", "B"}  # no node named 'nan' or ''


def test_sync_streams_a_csv_signal_log(workdir):
    """Class 4: big CSV signal logs are read in chunks (memory in benchmarks/sync_csv_memory.py)."""
    shutil.copy(workdir / "above_tx.csv", workdir / "big.csv")
    proc = run_here(SYNC + ["big.csv"], workdir, ok=False)
    assert proc.returncode == 0, proc.stderr


# Shown elsewhere:
# - class 1 (outputs destroying inputs) and class 2 (atomic writes, 8 concurrent fits, full disk,
#   SIGTERM): tests/cli/test_outputs_not_inputs.py, tests/test_atomic.py
# - class 3 and random text as ids and paths: tests/io/test_hostile_names.py
# - the API examples (PatternSet.evaluate with degrees, ModelSpec('sh', 3.7), a NaN gauge, MHz in
#   ReaderOptions): tests/data/test_validation.py; wrong argument types: tests/test_argtypes.py
# - streamed sync equal to the whole-log sync: tests/workflows/test_sync_logs.py
# - model files byte-identical under SOURCE_DATE_EPOCH: tests/models/test_model_files.py
