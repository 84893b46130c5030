"""The next flight planned from a real telemetry log's fit (ArduPilot SiK radio, a ground
station ``gcs`` and a drone ``sys1``, one reading a second each way): the plan is for that
station and drone at that rate, as the user would fly it, not for the planner's two drones at
80 packets/s; and ``trajectory``'s options of ``--optimize`` given without it are refused, not
ignored."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_helpers import answer, assert_one_line_error, listing, real_log_fit, run_here


@pytest.fixture(scope="module")
def fitted(tmp_path_factory) -> Path:
    return real_log_fit(tmp_path_factory.mktemp("real_plan"))


def test_the_plan_is_for_the_logs_station_and_drone_at_its_radios_rate(fitted):
    proc = run_here(["trajectory", "--optimize", "--from-model", "earlier.json", "--budget-s", "40", "-o", "next"], fitted)
    assert "planned for a ground station gcs, held still in the earlier flight, and a drone sys1" in proc.stdout, proc.stdout
    rate = proc.stdout.split(" packets/s in each link direction, the earlier flight's")[0].rsplit(" ", 1)[-1]
    assert 0.8 <= float(rate) <= 1.2, proc.stdout  # the SiK radio's one report a second each way
    assert " of gcs" not in proc.stdout and "A 0" not in proc.stdout  # the station stays; no drones A, B
    files = listing(fitted / "next")
    assert files and all(name.endswith(("_sys1.csv", "_gcs.csv")) for name in files)


def test_flags_state_another_layout_and_rate(fitted):
    proc = run_here(["trajectory", "--optimize", "--from-model", "earlier.json", "--budget-s", "30", "--two-drones",
                     "--packet-rate", "20", "-o", "drones"], fitted)
    assert "held still" not in proc.stdout and "packets/s" not in proc.stdout.split("\n")[0]
    assert "turning" in proc.stdout or "orbit" in proc.stdout


@pytest.mark.parametrize("flag", [["--noise", "3"], ["--packet-rate", "2"], ["--prior-std", "6"], ["--drift", "1"],
                                  ["--station"], ["--target-spread", "3"], ["--budget-s", "60"]])
def test_an_option_of_optimize_without_it_is_refused_not_ignored(tmp_path, flag):
    proc = answer(["trajectory", *flag, "-o", "plan"], tmp_path)
    assert_one_line_error(proc, f"{flag[0]}: it is an option of --optimize's plan, not of the paper's campaign; add --optimize")
    assert listing(tmp_path) == []
