"""No command overwrites its own input: an output that is an input is refused before any work,
with one line and exit code 1, and every input stays byte for byte as it was (issue 10).

The commands run in this process (:func:`cli_helpers.run_here`: the exit code, stdout and stderr a
user's process shows), except: one case of each refusal test (``sync -o poses``, ``export
--step-deg``), so that the process boundary stays covered; the 8 concurrent fits (processes at
once are the point); one of the two SOURCE_DATE_EPOCH fits (two interpreters, two hash seeds).
"""

from __future__ import annotations

import subprocess
import time

import pytest
from cli_helpers import RPLEARN, answer, digests, smoke_flight

P, S, D, M, T = "flight/pose_log.parquet", "flight/signal_log.parquet", "data.parquet", "sh3.json", "flight/ground_truth.json"

#: Every command that writes files, with each of its outputs set to each of its inputs.
CASES = {
    "sync -o poses": ["sync", "--poses", P, "--signals", S, "-o", P],
    "sync -o signals": ["sync", "--poses", P, "--signals", S, "-o", S],
    "fit -o dataset": ["fit", D, "-o", D],
    "evaluate --json model": ["evaluate", M, D, "--json", M],
    "evaluate --json dataset": ["evaluate", M, D, "--json", D],
    "evaluate --markdown model": ["evaluate", M, D, "--markdown", M],
    "evaluate --markdown dataset": ["evaluate", M, D, "--markdown", D],
    "predict -o dataset": ["predict", M, D, "-o", D],
    "links -o poses": ["links", M, P, "--tx-power", "20", "-o", P],
    "links --connectivity poses": ["links", M, P, "--tx-power", "20", "-o", "l.csv", "--connectivity", P],
    "links --plot poses": ["links", M, P, "--tx-power", "20", "-o", "l.csv", "--plot", P],
    "links --connectivity = -o": ["links", M, P, "--tx-power", "20", "-o", "l.csv", "--connectivity", "l.csv"],
    "headings -o model": ["headings", M, "--pos", "A=0,0,20", "--pos", "B=30,0,20", "--tx-power", "20", "-o", M],
    "sweep -o dataset": ["sweep", D, "--orders", "2..3", "-o", D],
    "sweep --plot dataset": ["sweep", D, "--orders", "2..3", "--plot", D],
    "export -o model": ["export", M, "--format", "grid", "-o", M],
    "plot -o model": ["plot", M, "-o", M],
    "plot -o truth": ["plot", M, "--truth", T, "-o", T],
    "plot -o dataset": ["plot", M, "--dataset", D, "-o", D],
}


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("outputs")
    return smoke_flight(d)


@pytest.mark.parametrize("case", sorted(CASES))
def test_an_output_that_is_an_input_is_refused_and_nothing_changes(workdir, case):
    before = digests(workdir)
    started = time.perf_counter()
    proc = answer(CASES[case], workdir, process=case == "sync -o poses")
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 1 and len(lines) == 1 and lines[0].startswith("error:"), proc.stderr
    assert any(s in lines[0] for s in ("is also an input", "unknown table format", "is also given as --")), lines[0]
    assert "Traceback" not in proc.stderr
    assert digests(workdir) == before  # inputs byte-identical, no file added
    assert time.perf_counter() - started < 60


def test_concurrent_fits_to_one_file_leave_one_whole_model(workdir):
    """8 `fit -o same.json` at once: every run succeeds and the file is one run's whole model."""
    import numpy as np

    from rplearn.models import load_model

    procs = [subprocess.Popen(RPLEARN + ["fit", D, "--degree", "3", "-o", "same.json"], cwd=workdir,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(8)]
    codes = [p.wait(timeout=300) for p in procs]
    for p in procs:
        p.stdout.close()
        p.stderr.close()
    assert codes == [0] * 8
    final, reference = load_model(workdir / "same.json"), load_model(workdir / M)  # checksum verified
    np.testing.assert_array_equal(final.coef, reference.coef)
    assert [n for n in (p.name for p in workdir.iterdir()) if n.startswith(".rplearn-")] == []


@pytest.mark.parametrize(
    "args, flag",
    [
        (["fit", D, "--degree", "1000", "-o", "big.json"], "--order"),
        (["fit", D, "--model", "bg", "--degree", "1000", "-o", "big.json"], "--order"),
        (["fit", D, "--model", "poly", "--degree", "1000", "-o", "big.json"], "--order"),
        (["export", M, "--step-deg", "0.001", "-o", "g.csv"], "--step-deg"),
        (["links", M, P, "--tx-power", "20", "--step", "1e-9", "-o", "l.csv"], "--step"),
        (["headings", M, "--pos", "A=0,0,20", "--pos", "B=30,0,20", "--tx-power", "20", "--step", "0.000001"], "--step"),
    ],
)
def test_work_too_large_for_the_data_or_memory_is_refused_at_once(workdir, args, flag):
    started = time.perf_counter()
    proc = answer(args, workdir, process=flag == "--step-deg")
    assert proc.returncode == 1 and proc.stderr.startswith("error:") and flag in proc.stderr, proc.stderr
    assert time.perf_counter() - started < 30  # interpreter start-up included (in a process); no work is done
    assert not (workdir / "big.json").exists()


def test_model_files_are_reproducible_with_source_date_epoch(workdir):
    """Same inputs and options, SOURCE_DATE_EPOCH set: byte-identical model files (no wall time).
    One fit runs in a process of its own, one in this process: two interpreters, two hash seeds."""
    import json

    env = {"SOURCE_DATE_EPOCH": "1700000000"}
    runs = []
    for process in (True, False):
        proc = answer(["fit", D, "--degree", "3", "-o", "r.json"], workdir, process, env)
        assert proc.returncode == 0, proc.stderr
        runs.append((workdir / "r.json").read_bytes())
    assert runs[0] == runs[1]
    doc = json.loads(runs[0])
    assert "ltd_s" not in doc["model"]["training"]
    assert doc["model"]["provenance"]["created_utc"] == "2023-11-14T22:13:20Z"
