"""Every example of issue 29's classes 1, 2 and 7, run as the user ran it: outputs that destroyed
inputs, saves that deleted files they did not write, the same data counted twice, and messages
that named neither the file nor the flag.

Each refusal is exit 1 with one line ``error: ...`` naming the file and the flag, no traceback,
and no file written or removed; the saves that must succeed leave every file they did not
write byte-identical. The library side (random path specs, concurrent saves of swarm models) is
in tests/io/test_resolve.py and tests/io/test_modelfile.py.

The commands run in this process (:func:`cli_helpers.run_here`: the exit code, stdout and stderr a
user's process shows), except one refusal (:data:`IN_A_PROCESS`), so that the process boundary
stays covered, and the two synchronised fits, whose being two processes is the point.
"""

from __future__ import annotations

import os
import shutil
import subprocess

import pandas as pd
import pytest
from cli_helpers import RPLEARN, D, M, P, S, answer, digests, run_here, smoke_flight

FIT = ["--order", "3", "-o", "m.json"]
SIGNALS = ["sync", "--poses", P, "--link", "all", "--tx-power", "20", "--frequency", "2.4e9", "-o", "o.parquet",
           "--signals"]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("hostile_paths")
    smoke_flight(d, extra=(["fit", D, "--model", "mean", "-o", "mean.json"],
                           ["fit", D, "--model", "knn", "--order", "20", "-o", "knn.json"]))
    data = pd.read_parquet(d / D)
    for name in ("a.parquet", "b.parquet"):
        shutil.copy(d / D, d / name)
    (d / "parts").mkdir()
    half = len(data) // 2
    data.iloc[:half].to_parquet(d / "parts" / "p1.parquet")
    data.iloc[half:].to_parquet(d / "parts" / "p2.parquet")
    (d / "ln").mkdir()
    shutil.copy(d / D, d / "ln" / "a.parquet")
    os.symlink("a.parquet", d / "ln" / "b.parquet")  # a file and a link to it in one folder
    (d / "hive" / "rssi_dbm=-50").mkdir(parents=True)
    shutil.copy(d / D, d / "hive" / "rssi_dbm=-50" / "x.parquet")
    (d / "empty.bin").write_bytes(b"")
    (d / "two.bin").write_bytes(b"\xa3\x95")
    shutil.copy(d / D, d / "pq.bin")  # a Parquet table named .bin
    import numpy as np

    az, el = np.meshgrid(np.arange(-180.0, 180.0, 15.0), np.arange(-90.0, 91.0, 15.0))
    pd.DataFrame({"az_deg": az.ravel(), "el_deg": el.ravel(), "gain_dbi": 2.0 * np.cos(np.radians(el.ravel()))}
                 ).to_csv(d / "ref.csv", index=False)
    return d


# (command line, words the one line must hold); "{abs}" is the working directory
REFUSED = {
    # class 1: outputs that destroyed inputs given as a list or a glob
    "fit list -o one of it": (["fit", "a.parquet,b.parquet", "--order", "3", "-o", "b.parquet"],
                              ["b.parquet", "is also an input", "--out"]),
    "fit glob -o one of it": (["fit", "parts/*.parquet", "--order", "3", "-o", "parts/p1.parquet"],
                              ["parts/p1.parquet", "is also an input", "--out"]),
    "fit glob -o a file it would match": (["fit", "parts/*.parquet", "--order", "3", "-o", "parts/p3.parquet"],
                                          ["parts/p3.parquet", "--out", "would join"]),
    "evaluate glob --markdown in it": (["evaluate", M, "parts/*.parquet", "--markdown", "parts/x.parquet"],
                                       ["--markdown", "parts/x.parquet"]),
    "evaluate folder --json in it": (["evaluate", M, "parts", "--json", "parts/x.json"], ["--json", "parts/x.json"]),
    "predict list -o one of it": (["predict", M, "a.parquet,b.parquet", "-o", "a.parquet"], ["a.parquet", "--out"]),
    "sweep list -o one of it": (["sweep", "a.parquet,b.parquet", "--orders", "1..2", "-o", "b.parquet"],
                                ["b.parquet", "--out"]),
    # class 2: one file counted twice; a Hive folder over a measurement
    "a,./a": (["fit", "a.parquet,./a.parquet", *FIT], ["a.parquet and ./a.parquet are one file"]),
    "relative and absolute": (["fit", "a.parquet,{abs}/a.parquet", *FIT], ["a.parquet and {abs}/a.parquet are one file"]),
    "a file and its link in one folder": (["fit", "ln", *FIT], ["ln/a.parquet and ln/b.parquet are one file"]),
    "a glob over a file and its link": (["evaluate", M, "ln/*.parquet"], ["ln/a.parquet and ln/b.parquet are one file"]),
    "sync --poses twice": (["sync", "--poses", P, "--poses", "./" + P, "--signals", S, "--link", "all", "-o", "o.parquet"],
                           [P, "./" + P, "are one file"]),
    "hive rssi_dbm=-50": (["fit", "hive", *FIT], ["hive/rssi_dbm=-50", "rssi_dbm", "x.parquet"]),
    # class 7: messages that named neither the file nor the flag
    "inspect empty .bin": (["inspect", "empty.bin"], ["empty.bin", "empty file"]),
    "inspect 2-byte .bin": (["inspect", "two.bin"], ["two.bin", "too short"]),
    "inspect Parquet named .bin": (["inspect", "pq.bin"], ["pq.bin", "Parquet", "rename it .parquet"]),
    "sync empty .bin": ([*SIGNALS, "empty.bin"], ["empty.bin", "empty file"]),
    "sync 2-byte .bin": ([*SIGNALS, "two.bin"], ["two.bin", "too short"]),
    "sync Parquet named .bin": ([*SIGNALS, "pq.bin"], ["pq.bin", "Parquet"]),
    "--prior-std without --prior": (["fit", D, "--order", "auto", "--prior-std", "3", "-o", "m.json"],
                                    ["--prior-std", "--prior "]),
    "--prior-std for nodes without a prior": (["fit", D, "--order", "auto", "--prior", f"A={M}", "--prior-std", "3",
                                               "-o", "m.json"], ["--prior-std", "B"]),
    "--mount of a node without a pattern": (["reference", "A=ref.csv", "--mount", "B=0,0,0", "-o", "r.json"],
                                            ["--mount", "B"]),
    "--mount without a node": (["reference", "A=ref.csv", "--mount", "=1,2,3", "-o", "r.json"], ["--mount", "=1,2,3"]),
    "links --plot = -o": (["links", M, P, "--tx-power", "20", "-o", "l.csv", "--plot", "l.csv"],
                          ["--plot", "l.csv", "--out"]),
    "links --connectivity = -o": (["links", M, P, "--tx-power", "20", "-o", "l.csv", "--connectivity", "./l.csv"],
                                  ["--connectivity", "l.csv", "--out"]),
    "sweep --plot = -o": (["sweep", D, "--orders", "1..2", "-o", "s.csv", "--plot", "s.csv"], ["--plot", "s.csv", "--out"]),
    "evaluate --json = --markdown": (["evaluate", M, D, "--json", "t.md", "--markdown", "t.md"],
                                     ["--markdown", "t.md", "--json"]),
    "plot --spread = -o": (["plot", M, "-o", "p.png", "--spread", "p.png"], ["--spread", "p.png", "--out"]),
    "--prior A= (no file)": (["fit", D, "--order", "auto", "--prior", "A=", "-o", "m.json"], ["--prior", "A="]),
    "a mean model as prior": (["fit", D, "--order", "auto", "--prior", "A=mean.json", "-o", "m.json"],
                              ["--prior", "mean.json", "mean"]),
    "a k-NN model as prior": (["fit", D, "--order", "auto", "--prior", "A=knn.json", "-o", "m.json"],
                              ["--prior", "knn.json", "knn"]),
    # issue 38: a folder output that is a file (report failed with "File exists" after learning)
    "report -o its dataset": (["report", D, "-o", D], [D, "is a file, not a folder", "--out"]),
    "simulate -o a file": (["simulate", "--preset", "smoke", "-o", M], [M, "is a file, not a folder", "--out"]),
    "demo -o a file": (["demo", "-o", D], [D, "is a file, not a folder", "--out"]),
    "trajectory -o a file": (["trajectory", "-o", M], [M, "is a file, not a folder", "--out"]),
    "report -o inside a file": (["report", D, "-o", f"{M}/r"], [f"{M}/r", "which is a file", "--out"]),
}


#: The refusal that runs as a process of its own.
IN_A_PROCESS = "trajectory -o a file"
assert IN_A_PROCESS in REFUSED


#: A flag's value not of its form (KEY=VALUE): a usage error, exit code 2 (was 1).
FLAG_FORMS = {"--mount without a node", "--prior A= (no file)"}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_refused_with_one_line_naming_the_file_and_flag_and_nothing_changes(workdir, case):
    args, words = REFUSED[case]
    args = [a.replace("{abs}", str(workdir)) for a in args]
    before = digests(workdir)
    proc = answer(args, workdir, case == IN_A_PROCESS)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == (2 if case in FLAG_FORMS else 1) and len(lines) == 1 and lines[0].startswith("error:"), proc.stderr
    for word in words:
        assert word.replace("{abs}", str(workdir)) in lines[0], lines[0]
    assert "Traceback" not in proc.stderr
    assert digests(workdir) == before  # nothing written, nothing removed


def test_saving_a_model_removes_no_file_it_did_not_write(workdir):
    """Saving ``nn.json`` removed the user's ``nn.json.npz`` and ``nn.json.0123456789ab.npz``."""
    folder = workdir / "save"
    folder.mkdir()
    theirs = {"nn.json.npz": b"the user's arrays", "nn.json.0123456789ab.npz": b"an old copy"}
    for name, data in theirs.items():
        (folder / name).write_bytes(data)
    for k in ("20", "30"):
        proc = run_here(["fit", f"../{D}", "--model", "knn", "--order", k, "-o", "nn.json"], folder, ok=False)
        assert proc.returncode == 0, proc.stderr
    for name, data in theirs.items():
        assert (folder / name).read_bytes() == data
    from rplearn.io.modelfile import named_sidecar
    from rplearn.models.load import load_model

    assert load_model(folder / "nn.json").n_neighbors == 30
    assert sorted(os.listdir(folder)) == sorted([*theirs, "nn.json", os.path.basename(named_sidecar(folder / "nn.json"))])


def test_two_processes_saving_different_knn_models_to_one_path_both_succeed(workdir):
    """One of two synchronised ``fit --model knn -o nn.json`` runs was refused with exit 1."""
    from rplearn.io.modelfile import named_sidecar
    from rplearn.models.load import load_model

    folder = workdir / "race"
    folder.mkdir()
    for _ in range(3):
        procs = [subprocess.Popen(RPLEARN + ["fit", f"../{D}", "--model", "knn", "--order", k, "-o", "nn.json"],
                                  cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for k in ("15", "25")]
        results = [(p.wait(timeout=300), p.communicate()[1]) for p in procs]
        assert [code for code, _ in results] == [0, 0], results
        model = load_model(folder / "nn.json")  # its sidecar's checksum verified
        assert model.n_neighbors in (15, 25)
        assert sorted(os.listdir(folder)) == sorted(["nn.json", os.path.basename(named_sidecar(folder / "nn.json"))])
