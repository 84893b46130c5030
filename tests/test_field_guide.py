"""The README's field guide runs as written, on the real ArduPilot log it names, and prints
what the guide says it prints."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

from test_docs import _run_plain, plain_lines

ROOT = Path(__file__).resolve().parents[1]


def _guide_commands() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"<!-- field-guide -->\s*```\n(.*?)```\s*<!-- /field-guide -->", text, re.S)
    assert block, "README.md has no field-guide block"
    return block.group(1)


def test_the_field_guide_runs_on_the_real_log_and_prints_what_it_says(tmp_path):
    commands = _guide_commands()
    assert "tests/fixtures/ardupilot/" in commands and "rplearn sync" in commands
    (tmp_path / "tests").symlink_to(ROOT / "tests")  # the guide runs from a clone's top folder
    env = dict(os.environ, PATH=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""))
    lines = plain_lines(commands)  # LOG=...; rplearn commands in this process (tests/test_docs.py)
    assert lines and lines[0][0] == "set" and all(kind == "rplearn" for kind, _ in lines[1:]), lines
    out = {line.split()[1]: _run_plain([lines[0], (kind, line)], tmp_path, env, ROOT / "README.md")
           for kind, line in lines[1:]}
    # the guide's first command as a user's shell runs it: the rplearn script on the PATH
    proc = subprocess.run(["bash", "-c", f"{lines[0][1]}\n{lines[1][1]}"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300, check=False)
    assert proc.returncode == 0 and "gcs: 1 rows, static" in proc.stdout + proc.stderr, (proc.stdout, proc.stderr)
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    # inspect: the station's placement and heading, the link-lost reports
    assert "station placed at the vehicle's first position fix (no HOME_POSITION in the log)" in out["inspect"]
    assert "assumed level and facing east" in out["inspect"]
    assert ("57 radio message(s) with a zero RSSI while the vehicle was silent (link lost): kept as outage events"
            in out["inspect"])
    assert "gcs: 1 rows, static" in out["inspect"] and "2735 rows" in out["inspect"]
    # sync: the counts the guide quotes
    assert "signal samples in: 1026, matched: 974" in out["sync"] and "dropped (near_field)" in out["sync"]
    assert "974 of 1,026" in readme
    # fit: the chosen order and validation RMSE, the gauge, the spread where the flight never looked
    chosen = re.search(r"order (\d+), smoothing \S+, validation RMSE ([\d.]+) dB", out["fit"])
    assert chosen, out["fit"]
    assert f"SH-{chosen.group(1)}, validation RMSE {float(chosen.group(2)):.1f} dB" in readme
    assert "gauge:" in out["fit"] and "where the flight never looked" in out["fit"]
    spread = re.search(r"never looked each pattern may be off by \(1 sigma\): gcs ([\d.]+) dB", out["fit"])
    assert spread and f"±{float(spread.group(1)):.1f} dB" in readme
    # plot, report, orient
    assert (tmp_path / "patterns.png").stat().st_size > 10_000
    html = (tmp_path / "report" / "report.html").read_text(encoding="utf-8")
    assert "no &#x27;unit&#x27; column" in html or "no 'unit' column" in html
    # report: the cross-validated model fit learns, scored on the held-out fifth; its figures
    held_out = re.search(r"\| (SH-\d+) \| ([\d.]+) \|", out["report"])
    assert held_out and "scored on the held-out test[5/5]" in out["report"], out["report"]
    assert f"{held_out.group(1)}, {float(held_out.group(2)):.1f} dB RMSE on the held-out fifth" in readme
    training = re.search(r"training RMSE ([\d.]+) dB", html)
    assert training and f"against the {float(training.group(1)):.1f} dB it fits where it learned" in readme
    assert "Measured and predicted" in html and "The patterns in 3-D" in html
    assert (tmp_path / "report" / "model.json").stat().st_size > 1_000
    gain = re.search(r"\(([+-][\d.]+) dB\), \+- ([\d.]+) dB", out["orient"])
    assert gain, out["orient"]
    assert f"{gain.group(1)} dB" in readme and f"±{gain.group(2)} dB" in readme, out["orient"]
