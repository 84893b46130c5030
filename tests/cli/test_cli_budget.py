"""``fit`` warns of an implausible link budget, naming the input and by how much."""

from __future__ import annotations

import re


def test_fit_warns_of_a_transmit_power_given_too_high(tmp_path):
    from typer.testing import CliRunner

    from rplearn.cli import app
    from rplearn.sim.flight import simulate

    df = simulate("smoke", seed=4).matched_truth
    df.assign(tx_power_dbm=df["tx_power_dbm"] + 25.0).to_parquet(tmp_path / "wrong.parquet")
    df.to_parquet(tmp_path / "right.parquet")
    runner = CliRunner()
    wrong = runner.invoke(app, ["fit", str(tmp_path / "wrong.parquet"), "-o", str(tmp_path / "w.json")], env={"COLUMNS": "400"})
    assert wrong.exit_code == 0, wrong.output
    said = re.search(r"warning: link budget of A<->B: .*\(--tx-power\) is probably too high by about (\d+) dB", wrong.output)
    assert said and 22 <= int(said.group(1)) <= 28, wrong.output
    right = runner.invoke(app, ["fit", str(tmp_path / "right.parquet"), "-o", str(tmp_path / "r.json")], env={"COLUMNS": "400"})
    assert right.exit_code == 0 and "link budget" not in right.output
