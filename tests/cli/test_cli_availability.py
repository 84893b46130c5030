"""``--sensitivity`` on predict, links, orient and headings (issue 28, items 1-3)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_helpers import invoke

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "models_main"


def test_predict_writes_the_availability_of_a_preset_radio(tmp_path):
    out = tmp_path / "pred.csv"
    invoke(["predict", FIXTURES / "auto.json", FIXTURES / "poses.csv", "-o", out, "--sensitivity", "wifi-54mbps"])
    table = pd.read_csv(out)
    p = table["availability"].to_numpy()
    assert np.all((p >= 0) & (p <= 1)) and p.std() > 0
    # the higher the predicted RSSI (for one spread), the more available
    order = np.argsort(table["rssi_pred_dbm"].to_numpy())
    assert np.corrcoef(np.arange(order.size), p[order])[0, 1] > 0.5
    bad = invoke(["predict", FIXTURES / "auto.json", FIXTURES / "poses.csv", "-o", out, "--sensitivity", "wifi"], ok=False)
    assert bad.exit_code != 0 and "--sensitivity" in bad.output and "esp32-11b" in bad.output


@pytest.fixture(scope="module")
def swarm(tmp_path_factory):
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "analysis"))
    from test_availability import formation, posterior_model

    d = tmp_path_factory.mktemp("swarm")
    posterior_model().save(d / "m.json")
    formation(8).to_csv(d / "poses.csv", index=False)
    return d


def test_links_writes_availability_and_the_connectivity_probability(swarm):
    d = swarm
    res = invoke(["links", d / "m.json", d / "poses.csv", "--as", "C=A", "--as", "D=B", "--tx-power", "20",
                  "-o", d / "links.csv", "--connectivity", d / "conn.csv", "--sensitivity", "-68", "--draws", "300",
                  "--pair", "A-D"])
    assert "P(connected)" in res.output and "weakest link" in res.output
    links, conn = pd.read_csv(d / "links.csv"), pd.read_csv(d / "conn.csv")
    assert links["availability"].between(0, 1).all() and len(conn) == 8
    assert {"p_connected", "p_connected_se", "p_path_A-D"} <= set(conn.columns)
    assert (conn["p_path_A-D"] >= conn["p_connected"]).all()
    bad = invoke(["links", d / "m.json", d / "poses.csv", "--as", "C=A", "--as", "D=B", "--tx-power", "20",
                  "-o", d / "l2.csv", "--pair", "A-D"], ok=False)
    assert bad.exit_code != 0 and "--sensitivity" in bad.output


def test_orient_and_headings_rank_by_availability(swarm):
    d = swarm
    res = invoke(["orient", d / "m.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "150,0,25",
                  "--turn", "both", "--sensitivity", "-62", "--min-availability", "0.9"])
    assert "availability at -62 dBm" in res.output
    res = invoke(["headings", d / "m.json", "--pos", "A=0,0,20", "--pos", "B=150,0,25", "--pos", "C=70,130,22",
                  "--as", "C=A", "--tx-power", "20", "--sensitivity", "esp32-11b", "-o", d / "yaws.json"])
    assert "availability of the weakest link at -97 dBm" in res.output
    bad = invoke(["orient", d / "m.json", "--tx", "A", "--rx", "B", "--tx-pos", "0,0,20", "--rx-pos", "150,0,25",
                  "--min-availability", "0.9"], ok=False)
    assert bad.exit_code != 0 and "sensitivity" in bad.output
