"""A real telemetry log's next flight flown in the simulator before the real one: the plan of
``trajectory --optimize --from-model`` names the log's station ``gcs`` and drone ``sys1``, and
``simulate --preset ground --plan`` flies them as the preset's station ``G`` and drone ``D``
under their own names, so that ``sync`` and ``fit`` of the simulated flight give a model of
``gcs`` and ``sys1`` that plans the flight after. It was refused: "node(s) gcs, sys1 have no
antenna in preset ground (D, G)"."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_helpers import answer, assert_one_line_error, listing, real_log_fit, run_here


@pytest.fixture(scope="module")
def planned(tmp_path_factory) -> Path:
    """The plan ``next/`` made from the real log's fit (a station gcs, a drone sys1)."""
    d = real_log_fit(tmp_path_factory.mktemp("sim_plan"))
    run_here(["trajectory", "--optimize", "--from-model", "earlier.json", "--budget-s", "30", "-o", "next"], d)
    return d


def test_the_real_logs_plan_flies_on_the_ground_preset_and_learns_a_model_of_its_nodes(planned):
    d = planned
    sim = run_here(["simulate", "--preset", "ground", "--plan", "next", "--seed", "1", "-o", "sim"], d)
    assert sim.stdout.splitlines()[0] == "flying plan nodes gcs, sys1 as the ground preset's G (station), D"
    poses = pd.read_parquet(d / "sim" / "pose_log.parquet")
    signals = pd.read_parquet(d / "sim" / "signal_log.parquet")
    assert set(poses["node"]) == {"gcs", "sys1"} and set(signals["tx"]) | set(signals["rx"]) == {"gcs", "sys1"}
    assert set(json.loads((d / "sim" / "ground_truth.json").read_text())["nodes"]) == {"gcs", "sys1"}
    assert sorted(listing(d / "sim" / "references")) == sorted(listing(d / "next"))
    station = poses.loc[poses["node"] == "gcs", ["x", "y", "z"]].to_numpy()
    assert np.linalg.norm(station - np.median(station, axis=0), axis=1).max() <= 5.0
    run_here(["sync", "--poses", "sim/pose_log.parquet", "--signals", "sim/signal_log.parquet", "--link", "all",
              "-o", "s.parquet"], d)
    run_here(["fit", "s.parquet", "--order", "auto", "-o", "sim.json"], d)
    model = json.loads((d / "sim.json").read_text())["model"]
    assert model["nodes"] == ["gcs", "sys1"] and model["training"]["fixed_nodes"] == ["gcs"]
    after = run_here(["trajectory", "--optimize", "--from-model", "sim.json", "--budget-s", "30", "-o", "after"], d)
    assert "planned for a ground station gcs, held still in the earlier flight, and a drone sys1" in after.stdout
    assert listing(d / "after") and all(n.endswith(("_gcs.csv", "_sys1.csv")) for n in listing(d / "after"))


def test_a_stated_node_map_flies_the_plan_as_it_says(planned):
    sim = run_here(["simulate", "--preset", "ground", "--plan", "next", "--node-map", "gcs=G, sys1=D", "-o", "mapped"], planned)
    assert sim.stdout.splitlines()[0] == "flying plan nodes gcs, sys1 as the ground preset's G (station), D (--node-map)"
    run_here(["simulate", "--preset", "paper", "--plan", "next", "--node-map", "gcs=B,sys1=A", "-o", "on_paper"], planned)
    assert set(pd.read_parquet(planned / "on_paper" / "pose_log.parquet")["node"]) == {"gcs", "sys1"}


def test_a_station_plan_on_two_drones_is_refused_naming_the_preset_that_flies_it(planned):
    proc = answer(["simulate", "--preset", "paper", "--plan", "next", "-o", "refused"], planned, process=True)
    assert_one_line_error(proc, "next: the plan flies a station gcs and a drone sys1; preset paper flies two drones A, B: "
                                "fly it with --preset ground (or tworay, campaign), or map its nodes with --node-map")
    assert not (planned / "refused").exists()


@pytest.mark.parametrize(("value", "said"), [
    ("gcs=G,sys1", "--node-map: expected PLAN=PRESET,... (e.g. gcs=G,sys1=D), got 'gcs=G,sys1'"),
    ("gcs=G,gcs=D", "--node-map: gcs is mapped twice in 'gcs=G,gcs=D'"),
    ("gcs=G,sys1=G", "--node-map: two plan nodes are flown as G in 'gcs=G,sys1=G' (expected one to one)"),
])
def test_a_node_map_of_bad_syntax_is_a_usage_error(planned, value, said):
    proc = answer(["simulate", "--preset", "ground", "--plan", "next", "--node-map", value, "-o", "bad"], planned)
    assert proc.returncode == 2 and proc.stderr.strip() == f"error: {said}" and not (planned / "bad").exists()


@pytest.mark.parametrize(("value", "said"), [
    ("gcs=G,sys=D", "--node-map: gcs=G, sys=D: sys is no node of the plan in next (gcs, sys1)"),
    ("gcs=G,sys1=X", "--node-map: gcs=G, sys1=X: X is no node of preset ground (D, G)"),
    ("gcs=G", "--node-map: gcs=G: the plan's sys1 is not mapped (the plan in next flies gcs, sys1)"),
])
def test_a_node_map_naming_other_nodes_is_refused_in_one_line(planned, value, said):
    proc = answer(["simulate", "--preset", "ground", "--plan", "next", "--node-map", value, "-o", "bad"], planned)
    assert_one_line_error(proc, said)
    assert proc.stderr.strip() == f"error: {said}" and not (planned / "bad").exists()


def test_a_node_map_without_a_plan_and_a_plan_for_the_fleet_are_refused(tmp_path):
    proc = answer(["simulate", "--preset", "smoke", "--node-map", "gcs=G,sys1=D", "-o", "f"], tmp_path)
    assert proc.returncode == 2 and proc.stderr.strip() == "error: --node-map: needs --plan, the folder of reference files to fly"
    proc = answer(["simulate", "--preset", "fleet", "--plan", "next", "-o", "f"], tmp_path)
    assert_one_line_error(proc, "--plan: the fleet preset flies its own flights, not a plan")
    assert listing(tmp_path) == []
