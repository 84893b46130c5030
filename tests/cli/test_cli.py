"""The command line as a user drives it (issue 5): the pipeline ``simulate -> sync -> fit ->
evaluate -> export -> predict``, every user error, and the other commands.

The commands run in this process (:func:`cli_helpers.run_here`: the same command line, exit
code, stdout and stderr as a user's process, without a second of start-up each;
tests/cli/test_cli_in_process.py compares the two). Processes of their own
(:func:`cli_helpers.run`): the pipeline ``simulate -> sync -> fit -> evaluate -> export ->
predict`` (issue 5's acceptance: through the real command line; the SH-3 model file names a
process's command line), one user error (``missing file``) and ``--version``."""

from __future__ import annotations

import json
import os

import numpy as np
import pandas as pd
import pytest
from cli_helpers import answer, run_here, run_ok

from rplearn.data.tables import MATCHED_COLUMNS


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    run_ok(["simulate", "--preset", "smoke", "--seed", "3", "-o", "flight"], d)
    run_ok(
        ["sync", "--poses", "flight/pose_log.parquet", "--signals", "flight/signal_log.parquet", "--link", "A:B", "-o", "data.parquet"],
        d,
    )
    return d


def test_simulate_sync_fit_evaluate_export_predict(workdir):
    d = workdir
    for name in ("pose_log.parquet", "signal_log.parquet", "ground_truth.json"):
        assert (d / "flight" / name).stat().st_size > 0
    data = pd.read_parquet(d / "data.parquet")
    assert list(data.columns[: len(MATCHED_COLUMNS)]) == list(MATCHED_COLUMNS)
    assert set(data["tx"]) == {"A"} and set(data["rx"]) == {"B"} and len(data) > 500
    units = sorted(data["unit"].unique())
    learn = [u for u in units if not u.startswith("test")]
    test = [u for u in units if u.startswith("test")]

    run_ok(["fit", "data.parquet", "--model", "sh", "--degree", "3", "--units", ",".join(learn), "-o", "sh3.json"], d)
    run_ok(["fit", "data.parquet", "--model", "mean", "--units", ",".join(learn), "-o", "m.json"], d)
    model = json.loads((d / "sh3.json").read_text())
    assert model["schema"] == "rplearn.model" and model["type"] == "patterns"
    assert len(model["model"]["coefficients"]["A"]) == 9
    assert model["model"]["gauge"][0]["rule"] == "equal-mean"
    assert model["model"]["provenance"]["rplearn_version"] and "fit" in model["model"]["provenance"]["command"]

    ev = run_ok(["evaluate", "sh3.json", "m.json", "data.parquet", "--units", ",".join(test), "--json", "t1.json", "--markdown", "t1.md"], d)
    assert "| SH-3 |" in ev.stdout and "| M |" in ev.stdout
    rows = {r["model"]: r for r in json.loads((d / "t1.json").read_text())["rows"]}
    assert rows["SH-3"]["rmse_db"] < rows["M"]["rmse_db"]
    assert rows["M"]["n_params"] == 1 and rows["SH-3"]["n_params"] == 18
    assert (d / "t1.md").read_text().startswith("| Method")

    run_ok(["export", "sh3.json", "--format", "grid", "--step-deg", "10", "-o", "grid.csv"], d)
    grid = pd.read_csv(d / "grid.csv")
    assert list(grid.columns) == ["node", "az_deg", "el_deg", "gain_db"]
    assert set(grid["node"]) == {"A", "B"} and np.isfinite(grid["gain_db"]).all()
    run_ok(["export", "sh3.json", "--format", "msi", "-o", "msi"], d)
    assert (d / "msi" / "A.msi").read_text().count("\n") > 720

    run_ok(["predict", "sh3.json", "data.parquet", "-o", "pred.csv"], d)
    pred = pd.read_csv(d / "pred.csv")
    assert len(pred) == len(data)
    assert {"gain_pred_db", "rssi_pred_dbm", "gain_pred_std_db"} <= set(pred.columns)
    assert (pred["gain_pred_std_db"] > 0).all()
    resid = pred["rssi_pred_dbm"] - pred["rssi_dbm"]
    assert np.sqrt(np.mean(resid**2)) < 12.0

    inspect = run_here(["inspect", "flight/pose_log.parquet", "flight/signal_log.parquet"], d)
    assert "A -> B" in inspect.stdout
    orient = run_here(["orient", "sh3.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "10,0,20"], d)
    assert "best yaw" in orient.stdout and "1 sigma" in orient.stdout
    bold = run_here(["orient", "sh3.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "10,0,20",
                "--caution", "0"], d)
    assert "best yaw" in bold.stdout and "chosen by its lower bound" not in bold.stdout
    import inspect as _inspect

    from rplearn.analysis.headings import CAUTION_Z
    from rplearn.cli.swarm import orient as orient_command

    assert _inspect.signature(orient_command).parameters["caution"].default.default == CAUTION_Z


USER_ERRORS = {
    "missing file": (["fit", "nope.parquet", "-o", "x.json"], "nope.parquet"),
    "missing column": (["fit", "nocol.csv", "-o", "x.json"], "missing column"),
    "bad column value": (["fit", "nanpose.csv", "-o", "x.json"], "tx_qw"),
    "bad model file": (["predict", "bad.json", "data.parquet", "-o", "p.csv"], "bad.json"),
    "unknown node": (["orient", "sh3.json", "--tx", "Z", "--rx", "B", "--tx-pos", "0,0,0", "--rx-pos", "9,0,0"], "unknown node 'Z'"),
    "unknown model": (["fit", "data.parquet", "--model", "zernike", "-o", "x.json"], "unknown model"),
    "unknown unit": (["fit", "data.parquet", "--units", "nope", "-o", "x.json"], "unknown unit"),
    "bad link": (["sync", "--poses", "flight/pose_log.parquet", "--signals", "flight/signal_log.parquet", "--link", "AB", "-o", "x.parquet"], "--link"),
    "bad preset": (["simulate", "--preset", "mars", "-o", "x"], "mars"),
    "empty order range": (["sweep", "data.parquet", "--orders", "5..3"], "--orders"),
    "bad offset": (["sync", "--poses", "flight/pose_log.parquet", "--signals", "flight/signal_log.parquet", "--offset", "A=abc", "-o", "x.parquet"],
                   "--offset"),
    "missing output directory": (["predict", "sh3.json", "data.parquet", "-o", "no/such/dir/p.csv"], "non-existent directory"),
    "zero neighbours": (["fit", "data.parquet", "--model", "knn", "--degree", "0", "-o", "k.json"], "positive integer"),
    "sentinel rssi in a dataset": (["fit", "sentinel.csv", "-o", "x.json"], "sentinel"),
    "unreadable log": (["inspect", "trunc.parquet"], "could not be read"),
    "plan over a limit": (["trajectory", "-o", "plan", "--max-flight-time", "100", "--check-model", "none"], "above the limit 100 s"),
    "option of another model": (["fit", "data.parquet", "--model", "knn", "--ridge", "5", "-o", "k.json"], "--ridge: not used by NN-400"),
    "degree of a mean": (["fit", "data.parquet", "--model", "mean", "--degree", "7", "-o", "m7.json"], "--order"),
    "BG option on SH": (["fit", "data.parquet", "--model", "sh", "--sigma", "3", "-o", "s.json"], "used by BG models only"),
    "gauge level without node": (["fit", "data.parquet", "--gauge-dbi", "2", "-o", "g.json"], "--gauge-dbi needs --gauge-node"),
    "contradicting degree": (["fit", "data.parquet", "--model", "sh-10", "--degree", "5", "-o", "c.json"], "contradicts"),
    "bad model in a report": (["report", "data.parquet", "--paper-models", "m,foo", "-o", "rep_bad"], "unknown model"),
    "unknown table format": (["predict", "sh3.json", "data.parquet", "-o", "pred.txt"], "unknown table format"),
    "conflicting repeated option": (["headings", "sh3.json", "--pos", "A=0,0,20", "--pos", "A=5,0,20", "--tx-power", "20"], "given twice"),
}


def test_trajectory_writes_references_and_checks_the_plan(tmp_path):
    proc = run_here(["trajectory", "-o", "plan", "--psi0", "0,24,48", "--test-psi0", "36"], tmp_path)
    files = sorted(os.listdir(tmp_path / "plan"))
    assert len(files) == 8 and "learn_24_B.csv" in files and "test_36_A.csv" in files
    ref = pd.read_csv(tmp_path / "plan" / "learn_0_A.csv")
    assert list(ref.columns) == ["t", "x", "y", "z", "yaw_deg"] and ref["t"].is_monotonic_increasing
    # the paper's plan decouples SH-10 up to the one constant two drones leave free
    assert "rank 199 (null space 1, expected 1)" in proc.stdout
    # one unit alone does not: the check says so before anyone flies
    thin = run_here(["trajectory", "-o", "thin", "--psi0", "0", "--loops", "2"], tmp_path)
    assert "rank 199" not in thin.stdout and "not" in thin.stdout.lower()


@pytest.fixture(scope="module")
def user_error_inputs(workdir):
    """``workdir`` with the bad files the user errors read, written once for all cases (no
    case writes into them: a refusal writes nothing)."""
    d = workdir
    data = pd.read_parquet(d / "data.parquet")
    data.drop(columns=["rssi_dbm"]).to_csv(d / "nocol.csv", index=False)
    bad = data.copy()
    bad.loc[5, "tx_qw"] = np.nan
    bad.to_csv(d / "nanpose.csv", index=False)
    (d / "bad.json").write_text('{"schema": "rplearn.model", "schema_version": 1, "sha')
    sent = data.copy()
    sent.loc[3, "rssi_dbm"] = -127.0
    sent.to_csv(d / "sentinel.csv", index=False)
    (d / "trunc.parquet").write_bytes((d / "data.parquet").read_bytes()[:300])
    if not (d / "sh3.json").exists():
        run_here(["fit", "data.parquet", "--model", "sh", "--degree", "3", "-o", "sh3.json"], d)
    return d


#: A flag's value that is none of its words or not of its form: a usage error, exit code 2 (was 1).
FLAG_VALUES = {"bad link", "bad model in a report", "bad offset", "bad preset", "unknown model"}


@pytest.mark.parametrize("case", sorted(USER_ERRORS))
def test_user_errors_print_one_line_and_exit_1(user_error_inputs, case):
    d = user_error_inputs
    args, needle = USER_ERRORS[case]
    proc = answer(args, d, process=case == "missing file")
    assert proc.returncode == (2 if case in FLAG_VALUES else 1), proc.stderr
    lines = [l for l in proc.stderr.strip().splitlines() if l.strip()]
    assert len(lines) == 1, proc.stderr  # (inspect prints its report on stdout first)
    assert "Traceback" not in proc.stderr and lines[0].startswith("error:")
    assert needle in lines[0]


def test_node_ids_that_look_numeric_stay_text(workdir, tmp_path):
    """Node "01" in a CSV stays "01" (not 1), so links and models keep matching."""
    d = workdir
    pose = pd.read_parquet(d / "flight" / "pose_log.parquet")
    sig = pd.read_parquet(d / "flight" / "signal_log.parquet")
    ren = {"A": "01", "B": "02"}
    pose.assign(node=pose["node"].map(ren)).to_csv(tmp_path / "p.csv", index=False)
    sig.assign(tx=sig["tx"].map(ren), rx=sig["rx"].map(ren)).to_csv(tmp_path / "s.csv", index=False)
    run_here(["sync", "--poses", "p.csv", "--signals", "s.csv", "--link", "01:02", "-o", "d.csv"], tmp_path)
    data = pd.read_csv(tmp_path / "d.csv", dtype={"tx": str, "rx": str})
    assert set(data["tx"]) == {"01"} and len(data) > 500
    run_here(["fit", "d.csv", "--model", "sh", "--degree", "2", "-o", "m.json"], tmp_path)
    ev = run_here(["evaluate", "m.json", "d.csv"], tmp_path)
    assert "| SH-2 |" in ev.stdout


def test_datetime_times_are_seconds(workdir, tmp_path):
    d = workdir
    pose = pd.read_parquet(d / "flight" / "pose_log.parquet")
    sig = pd.read_parquet(d / "flight" / "signal_log.parquet")
    epoch = 1.7e9
    pose.assign(t=pd.to_datetime(pose["t"] + epoch, unit="s", utc=True)).to_parquet(tmp_path / "p.parquet")
    sig.assign(t=pd.to_datetime(sig["t"] + epoch, unit="s", utc=True)).to_parquet(tmp_path / "s.parquet")
    run_here(["sync", "--poses", "p.parquet", "--signals", "s.parquet", "--link", "A:B", "-o", "d.parquet"], tmp_path)
    ref = pd.read_parquet(d / "data.parquet")
    got = pd.read_parquet(tmp_path / "d.parquet")
    assert len(got) == len(ref)
    np.testing.assert_allclose(got["t"].to_numpy() - epoch, ref["t"].to_numpy(), atol=1e-5)
    # float64 seconds near 1.7e9 resolve 0.24 us: a few micrometres at flight speed
    np.testing.assert_allclose(got["tx_x"].to_numpy(), ref["tx_x"].to_numpy(), atol=1e-5)


def test_sweep_plot_report_and_images(workdir):
    d = workdir
    sw = run_here(["sweep", "data.parquet", "--orders", "2..4", "-o", "sweep.csv", "--plot", "sweep.png"], d)
    assert "lowest test RMSE at order" in sw.stdout
    frame = pd.read_csv(d / "sweep.csv")
    assert frame["order"].tolist() == [2, 3, 4] and np.isfinite(frame["test_rmse_db"]).all()
    run_here(["fit", "data.parquet", "--model", "sh", "--degree", "3", "-o", "sh3p.json"], d)
    run_here(["plot", "sh3p.json", "--truth", "flight/ground_truth.json", "--dataset", "data.parquet", "-o", "maps.png"], d)
    run_here(["export", "sh3p.json", "--format", "images", "-o", "img"], d)
    rep = run_here(["report", "data.parquet", "--model", "sh3p.json", "--paper-models", "m,sh-3", "--repeats", "1", "-o", "rep"], d)
    assert "model: SH-3" in rep.stdout and "| M |" in rep.stdout and "median of the runs" in rep.stdout
    page = (d / "rep" / "report.html").read_text()
    # time series, residuals, coverage, polar cuts, maps, spread (plotly.js holds the string too)
    assert page.count('<img src="data:image/png;base64,') == 6
    assert page.count("Plotly.newPlot(") == 2  # one rotatable 3-D view per node
    for png in ("sweep.png", "maps.png", "img/pattern_A.png", "img/pattern_B.png"):
        assert (d / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", png


def test_version_needs_no_command(tmp_path):
    proc = run_ok(["--version"], tmp_path)
    assert proc.stdout.startswith("rplearn ")


def test_bad_options_write_nothing(workdir):
    run_here(["report", "data.parquet", "--paper-models", "m,foo", "-o", "rep_nothing"], workdir, ok=False)
    assert not (workdir / "rep_nothing").exists()
    run_here(["trajectory", "-o", "plan_nothing", "--check-model", "foo"], workdir, ok=False)
    assert not (workdir / "plan_nothing").exists()


def test_predict_links_never_flown_and_honest_spreads(workdir):
    """Poses without RSSI can be predicted; the predictive spread includes the training residual."""
    d = workdir
    data = pd.read_parquet(d / "data.parquet")
    fit = run_here(["fit", "data.parquet", "--model", "sh", "--degree", "4", "-o", "sh4.json"], d)
    assert "note: learning from units" in fit.stderr and "left out test" in fit.stderr
    model = json.loads((d / "sh4.json").read_text())["model"]
    learn_units = [u for u in sorted(data["unit"].unique()) if not u.startswith("test")]
    assert model["training"]["n_samples"] == int(data["unit"].isin(learn_units).sum())
    data.drop(columns=["rssi_dbm"]).to_csv(d / "poses_only.csv", index=False)
    blind = run_here(["predict", "sh4.json", "poses_only.csv", "-o", "blind.csv"], d)
    assert "RMSE" not in blind.stdout
    seen = run_here(["predict", "sh4.json", "data.parquet", "-o", "seen.csv"], d)
    assert "RMSE against the" in seen.stdout
    a, b = pd.read_csv(d / "blind.csv"), pd.read_csv(d / "seen.csv")
    assert "rssi_dbm" not in a.columns
    np.testing.assert_allclose(a["rssi_pred_dbm"], b["rssi_pred_dbm"], atol=1e-9)
    rmse = model["training"]["rmse_db"]
    np.testing.assert_allclose(a["rssi_pred_std_db"] ** 2, a["gain_pred_std_db"] ** 2 + rmse**2, rtol=1e-9)
    # about 68 % of measured values fall within one predictive standard deviation
    inside = np.abs(b["rssi_dbm"] - b["rssi_pred_dbm"]) < b["rssi_pred_std_db"]
    assert 0.55 < inside.mean() < 0.8
    # sentinel RSSI in rows to predict is no obstacle either
    sent = data.copy()
    sent.loc[:10, "rssi_dbm"] = -128.0
    sent.to_csv(d / "sentinel_rows.csv", index=False)
    run_here(["predict", "sh4.json", "sentinel_rows.csv", "-o", "sent_pred.csv"], d)
    # another carrier of the band: predicted, with a warning; another band: refused (issue 29, class 4)
    data.drop(columns=["rssi_dbm"]).assign(frequency_hz=2.6e9).to_csv(d / "other_channel.csv", index=False)
    warned = run_here(["predict", "sh4.json", "other_channel.csv", "-o", "other_pred.csv"], d)
    assert "warning:" in warned.stderr and "2.600 GHz" in warned.stderr
    data.drop(columns=["rssi_dbm"]).assign(frequency_hz=5.8e9).to_csv(d / "other_band.csv", index=False)
    refused = run_here(["predict", "sh4.json", "other_band.csv", "-o", "band_pred.csv"], d, ok=False)
    assert refused.returncode == 1 and "at 5.8 GHz, but the" in refused.stderr and not (d / "band_pred.csv").exists()


def test_evaluate_scores_unseen_units_by_default(workdir):
    d = workdir
    data = pd.read_parquet(d / "data.parquet")
    units = sorted(data["unit"].unique())
    learn = [u for u in units if not u.startswith("test")]
    run_here(["fit", "data.parquet", "--model", "sh", "--degree", "3", "--units", ",".join(learn), "-o", "sh3_units.json"], d)
    ev = run_here(["evaluate", "sh3_units.json", "data.parquet", "--json", "ev_default.json"], d)
    assert "which no model learned from" in ev.stderr
    n_test = int((~data["unit"].isin(learn)).sum())
    assert json.loads((d / "ev_default.json").read_text())["rows"][0]["n_samples"] == n_test
    train = run_here(["evaluate", "sh3_units.json", "data.parquet", "--units", learn[0]], d)
    assert "training scores" in train.stderr
    (d / "sh3_copy.json").write_bytes((d / "sh3_units.json").read_bytes())
    both = run_here(["evaluate", "sh3_units.json", "sh3_copy.json", "data.parquet"], d)
    assert "| SH-3 (sh3_units.json) |" in both.stdout and "| SH-3 (sh3_copy.json) |" in both.stdout


def test_links_of_a_swarm_through_the_cli(workdir):
    d = workdir
    if not (d / "sh3.json").exists():
        run_here(["fit", "data.parquet", "--model", "sh", "--degree", "3", "-o", "sh3.json"], d)
    proc = run_here(
        ["links", "sh3.json", "flight/pose_log.parquet", "--tx-power", "20", "--step", "0.5",
         "--connectivity", "conn.csv", "--plot", "links.png", "-o", "links.parquet"],
        d,
    )
    assert "connected at" in proc.stdout and "wrote" in proc.stdout
    links = pd.read_parquet(d / "links.parquet")
    assert set(zip(links["tx"], links["rx"])) == {("A", "B"), ("B", "A")}
    assert {"rssi_pred_dbm", "rssi_pred_std_db", "up", "distance_m"} <= set(links.columns)
    conn = pd.read_csv(d / "conn.csv")
    assert (conn["n_drones"] == 2).sum() == links["t"].nunique()  # other times: a drone between units
    assert (conn["connected"] == ((conn["n_missing"] == 0) & (conn["bottleneck_rssi_dbm"] >= -85.0))).all()
    assert (d / "links.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # a third drone that carries A's antenna
    poses = pd.read_parquet(d / "flight" / "pose_log.parquet")
    third = poses[poses["node"] == "A"].assign(node="C", x=lambda f: f["x"] + 15.0)
    pd.concat([poses, third]).to_csv(d / "three.csv", index=False)
    bad = run_here(["links", "sh3.json", "three.csv", "--tx-power", "20", "-o", "l3.csv"], d, ok=False)
    assert bad.returncode == 1 and "--as C=NODE" in bad.stderr and "Traceback" not in bad.stderr
    good = run_here(["links", "sh3.json", "three.csv", "--tx-power", "20", "--as", "C=A", "-o", "l3.csv"], d)
    assert "C (A)" in good.stdout
    assert len(pd.read_csv(d / "l3.csv").groupby(["tx", "rx"])) == 6


def test_headings_through_the_cli(workdir):
    d = workdir
    if not (d / "sh3.json").exists():
        run_here(["fit", "data.parquet", "--model", "sh", "--degree", "3", "-o", "sh3.json"], d)
    proc = run_here(
        ["headings", "sh3.json", "--pos", "A=0,0,20", "--pos", "B=40,0,20", "--pos", "C=20,30,25", "--as", "C=A",
         "--tx-power", "20", "--yaw", "A=90", "-o", "yaws.csv"],
        d,
    )
    assert "bottleneck RSSI" in proc.stdout
    yaws = pd.read_csv(d / "yaws.csv")
    assert sorted(yaws["drone"]) == ["A", "B", "C"] and yaws["yaw_deg"].between(-180, 180).all()
    bad = run_here(["headings", "sh3.json", "--pos", "A=0,0", "--tx-power", "20"], d, ok=False)
    assert bad.returncode == 2 and "x,y,z" in bad.stderr  # a usage error


def test_a_plan_is_a_pose_log_for_links_and_sync_reports_reader_drops(workdir):
    d = workdir
    run_here(["trajectory", "-o", "plan", "--check-model", "none"], d)
    proc = run_here(
        ["links", "sh3.json", "plan/test_36_A.csv", "plan/test_36_B.csv", "--node", "plan/test_36_A.csv=A",
         "--node", "plan/test_36_B.csv=B", "--tx-power", "20", "-o", "plan_links.csv"],
        d,
    )
    assert "level flight (roll = pitch = 0) is assumed" in proc.stdout and "connected at" in proc.stdout
    poses = pd.read_parquet(d / "flight" / "pose_log.parquet")
    poses.loc[[3, 10, 11], "x"] = np.nan
    poses.to_csv(d / "pose_nan.csv", index=False)
    sync = run_here(["sync", "--poses", "pose_nan.csv", "--signals", "flight/signal_log.parquet", "--nan-policy", "drop", "-o", "nan_sync.parquet"], d)
    assert "dropped 3 pose row(s) (nan_pose)" in sync.stdout


def test_trajectory_optimize_prints_the_expected_spread_and_writes_the_plan(tmp_path):
    proc = run_here(["trajectory", "--optimize", "--check-model", "sh-5", "--target-spread", "2.5", "--budget-s", "120",
                "--noise", "4", "--prior-std", "4", "-o", "plan"], tmp_path)
    assert "expected per-node pattern spread over time" in proc.stdout and "(prior)" in proc.stdout
    files = sorted(os.listdir(tmp_path / "plan"))
    assert files and files[0].startswith("01_") and all(f.endswith(".csv") for f in files)
    bad = run_here(["trajectory", "--optimize", "--budget-s", "-5", "-o", "plan2"], tmp_path, ok=False)
    assert bad.returncode == 1 and "--budget-s" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1


def test_trajectory_optimize_plans_for_the_given_packet_rate(tmp_path):
    """A radio reporting 2 packets/s learns less per second than the default 80/s: the plan takes
    longer to the target (the planner had the 80/s built in, whatever the radio)."""
    args = ["trajectory", "--optimize", "--check-model", "sh-4", "--target-spread", "3", "--budget-s", "300", "--noise", "4",
            "--prior-std", "4"]

    def planned_s(*extra: str, out: str) -> float:
        last = run_here([*args, *extra, "-o", out], tmp_path).stdout.strip().splitlines()[-1]
        assert "target 3 dB reached after" in last
        return float(last.split("reached after ")[1].split(" s")[0])

    assert planned_s("--packet-rate", "2", out="slow") > 1.2 * planned_s(out="default")
    for bad in ("0", "nan", "-1"):
        proc = run_here([*args, "--packet-rate", bad, "-o", f"bad{bad}"], tmp_path, ok=False)
        assert proc.returncode == 1 and "--packet-rate" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
        assert not (tmp_path / f"bad{bad}").exists()


def test_fit_auto_says_how_to_plan_the_next_flight_and_the_plan_takes_its_prior(workdir, tmp_path):
    """``fit --order auto`` stores the next plan's prior and drift and prints the command;
    ``trajectory --optimize --from-model`` plans with them (explicit flags over them); a bad
    model file or --from-model without --optimize is one line."""
    d = workdir
    fit = run_here(["fit", "data.parquet", "--order", "auto", "-o", "auto_plan.json"], d)
    assert "plan the next flight: rplearn trajectory --optimize --from-model auto_plan.json -o next_plan" in fit.stdout
    training = json.loads((d / "auto_plan.json").read_text())["model"]["training"]
    assert training["drift_std_db"] >= 0 and training["planning_penalty_weight"] > 0
    plan = run_here(["trajectory", "--optimize", "--from-model", "auto_plan.json", "--check-model", "sh-5", "--target-spread", "2.5",
                     "--budget-s", "120", "-o", str(tmp_path / "next")], d)
    assert "prior from auto_plan.json: a fit of nodes A, B: noise" in plan.stdout and "(stated)" not in plan.stdout
    assert f"drift {training['drift_std_db']:.2f} dB per 5-s block" in plan.stdout and os.listdir(tmp_path / "next")
    stated = run_here(["trajectory", "--optimize", "--from-model", "auto_plan.json", "--check-model", "sh-5", "--target-spread", "2.5",
                       "--budget-s", "120", "--noise", "7", "--drift", "0.3", "-o", str(tmp_path / "stated")], d)
    assert "noise 7.00 dB (stated)" in stated.stdout and "drift 0.30 dB per 5-s block (stated)" in stated.stdout
    fixed = run_here(["fit", "data.parquet", "--order", "3", "-o", "sh3_plan.json"], d)
    assert "plan the next flight" not in fixed.stdout
    for args, text in ((["--optimize", "--from-model", "sh3_plan.json"], "sh3_plan.json is a fixed-order fit (SH-3)"),
                       (["--optimize", "--from-model", "nowhere.json"], "nowhere.json: no such"),
                       (["--from-model", "auto_plan.json"], "add --optimize")):
        bad = run_here(["trajectory", *args, "-o", str(tmp_path / "bad")], d, ok=False)
        assert bad.returncode == 1 and len(bad.stderr.strip().splitlines()) == 1
        assert bad.stderr.startswith("error: --from-model: ") and text in bad.stderr, bad.stderr
        assert not (tmp_path / "bad").exists() or not os.listdir(tmp_path / "bad")


def test_simulate_flies_a_written_plan(tmp_path):
    run_here(["trajectory", "--optimize", "--check-model", "sh-4", "--target-spread", "3", "--budget-s", "40", "--noise", "4",
         "--prior-std", "4", "-o", "plan"], tmp_path)
    run_here(["simulate", "--preset", "paper", "--plan", "plan", "--seed", "2", "-o", "flight"], tmp_path)
    signals = pd.read_parquet(tmp_path / "flight" / "signal_log.parquet")
    labels = {f.rsplit("_", 1)[0] for f in os.listdir(tmp_path / "plan")}
    assert set(signals["unit"]) == labels
    bad = run_here(["simulate", "--preset", "ground", "--plan", "plan", "-o", "f2"], tmp_path, ok=False)
    assert bad.returncode == 1 and "the plan flies two drones A, B; preset ground flies a station G and a drone D: fly it with --preset paper" in bad.stderr


def test_a_streamed_auto_fit_says_how_to_plan_and_the_plan_takes_its_file(workdir, tmp_path):
    """``fit FOLDER --order auto`` (a dataset in many files, streamed part by part) stores the
    drift and prints the next plan's command, and ``trajectory --optimize --from-model`` plans
    from its file (it was refused: "has no training.drift_std_db")."""
    d = workdir
    rows = pd.read_parquet(d / "data.parquet")
    folder = tmp_path / "parts"
    folder.mkdir()
    half = len(rows) // 2
    rows.iloc[:half].to_parquet(folder / "a.parquet", index=False)
    rows.iloc[half:].to_parquet(folder / "b.parquet", index=False)
    fit = run_here(["fit", str(folder), "--order", "auto", "-o", "streamed_plan.json"], tmp_path)
    assert "plan the next flight: rplearn trajectory --optimize --from-model streamed_plan.json -o next_plan" in fit.stdout
    training = json.loads((tmp_path / "streamed_plan.json").read_text())["model"]["training"]
    assert training["drift_std_db"] >= 0 and training["planning_penalty_weight"] > 0
    plan = run_here(["trajectory", "--optimize", "--from-model", "streamed_plan.json", "--check-model", "sh-5",
                     "--target-spread", "2.5", "--budget-s", "120", "-o", "next"], tmp_path)
    assert f"drift {training['drift_std_db']:.2f} dB per 5-s block" in plan.stdout and os.listdir(tmp_path / "next")
