"""rplearn.analysis.budget: an implausible link budget names the input most likely wrong and by how much."""

from __future__ import annotations

import re

import numpy as np
import pytest

from rplearn.analysis.budget import EXPONENT_RANGE, JOINT_LEVEL_RANGE_DB, JOINT_LEVEL_TYPICAL_DB, LINK_OFFSET_LIMIT_DB, LinkSummary, budget_findings
from rplearn.models.load import load_model
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.workflows.learning import fit_dataset

TX_ERROR_DB = 25.0


@pytest.fixture(scope="module")
def flight():
    from rplearn.sim.flight import simulate

    return simulate("smoke", seed=1).matched_truth


def _fit(df, tmp_path, name, auto=False):
    path = tmp_path / f"{name}.parquet"
    df.to_parquet(path)
    spec = ModelSpec.parse("sh") if auto else ModelSpec.parse("sh", order=4)
    out = fit_dataset(str(path), spec, options=FitOptions(auto=auto), output=str(tmp_path / f"{name}.json"))
    return out, load_model(str(tmp_path / f"{name}.json")).training["budget"]


@pytest.mark.parametrize("auto", [False, True])
def test_a_transmit_power_given_25_db_too_high_is_named_with_about_25_db(flight, tmp_path, auto):
    clean, none = _fit(flight, tmp_path, "clean", auto)
    assert none == [] and not any("link budget" in w for w in clean.warnings)
    wrong, found = _fit(flight.assign(tx_power_dbm=flight["tx_power_dbm"] + TX_ERROR_DB), tmp_path, "wrong", auto)
    [level] = [f for f in found if f["check"] == "level"]
    assert level["inputs"][0] == "--tx-power" and level["subject"] == "A<->B"
    assert level["off_by_db"] == pytest.approx(TX_ERROR_DB, abs=3.0)  # measured: 25 + (typical - true level)
    assert level["value"] < JOINT_LEVEL_RANGE_DB[0]
    [text] = [w for w in wrong.warnings if w.startswith("link budget")]
    said = re.search(r"\(--tx-power\) is probably too high by about (\d+) dB", text)
    assert said and abs(int(said.group(1)) - TX_ERROR_DB) <= 3


def test_relative_scale_says_nothing_of_the_level_but_still_checks_the_offsets(flight, tmp_path):
    shifted = flight.assign(tx_power_dbm=flight["tx_power_dbm"] + TX_ERROR_DB, rssi_scale="relative")
    fit, found = _fit(shifted, tmp_path, "relative")
    assert found == []
    clean_diff = 2 * abs(fit.fitted.model.training["link_offsets_db"][0]["offset_db"])  # the simulated radios' own
    assert clean_diff < LINK_OFFSET_LIMIT_DB
    # one radio transmitting 10 dB more than the other: the two directions differ by 10 dB
    louder = (shifted["tx"] == "A").to_numpy()
    rssi = shifted["rssi_dbm"].to_numpy() + np.where(louder, 10.0, 0.0)
    for scale, name in (("relative", "rel-offset"), ("dbm", "dbm-offset")):
        df = shifted.assign(rssi_dbm=rssi, rssi_scale=scale, tx_power_dbm=flight["tx_power_dbm"])
        _, found = _fit(df, tmp_path, name)
        assert [f["check"] for f in found] == ["offset"]
        assert found[0]["value"] - clean_diff == pytest.approx(10.0, abs=0.5) and found[0]["subject"] == "A<->B"
        assert found[0]["inputs"] == ["--tx-power", "--rssi-scale"]


def _link(level=JOINT_LEVEL_TYPICAL_DB, exponent=2.0, distance=(5.0, 50.0), f=2.44e9):
    return LinkSummary("gcs", "uav", 500, level, distance, exponent, f)


def test_the_ranges_and_which_input_each_finding_names():
    assert budget_findings([_link()]) == []
    # a level too high: the transmit power given is too low
    [high] = budget_findings([_link(level=JOINT_LEVEL_RANGE_DB[1] + 10)])
    assert high.off_by_db == pytest.approx(-(JOINT_LEVEL_RANGE_DB[1] + 10 - JOINT_LEVEL_TYPICAL_DB))
    assert "too low by about" in high.text and "--frequency" not in high.inputs
    # a frequency that is no common band, off by what a common band gives: named
    off = 20 * np.log10(5.8e9 / 0.6e9)
    [freq] = budget_findings([_link(level=JOINT_LEVEL_TYPICAL_DB - off, f=0.6e9)])
    assert freq.inputs[-1] == "--frequency" and "5800 MHz, not 600 MHz" in freq.text
    [band] = budget_findings([_link(level=JOINT_LEVEL_TYPICAL_DB - off, f=0.915e9)])  # a common band: believed
    assert "--frequency" not in band.inputs
    # the gain falls with distance faster than any environment: the station's place
    [far] = budget_findings([_link(exponent=EXPONENT_RANGE[1] + 1.5)])
    assert far.check == "distance" and far.inputs[0] == "the station's place" and "faster" in far.text
    assert budget_findings([_link(exponent=6.0, distance=(40.0, 50.0))]) == []  # too little spread to judge
    # relative scale: no level, but the distance trend and the offsets still
    offsets = [{"tx": "gcs", "rx": "uav", "offset_db": 4.0, "se_db": 0.2},
               {"tx": "uav", "rx": "gcs", "offset_db": -4.0, "se_db": 0.2}]
    found = budget_findings([_link(level=-60.0, exponent=6.0)], offsets=offsets, relative=True)
    assert [f.check for f in found] == ["distance", "offset"]
    assert found[1].value == pytest.approx(8.0) and found[1].value > LINK_OFFSET_LIMIT_DB
    assert "gcs->uav reads 8.0 dB above uav->gcs" in found[1].text
    # an offset within its standard error is no finding; a sphere mean outside the range is
    assert budget_findings([_link()], offsets=[{**offsets[0], "se_db": 3.0}]) == []
    [mean] = budget_findings([_link()], sphere_means={"uav": -25.0})
    assert mean.check == "pattern-mean" and mean.subject == "uav" and mean.inputs[0] == "--tx-power"


def test_a_swarm_judges_each_node_by_its_power_mean(tmp_path):
    """Odd cycles identify each node's mean: a patch with deep nulls (dB-mean -11 dBi, power mean
    -2 dBi) is no finding; every transmit power 25 dB too high puts about half of it on each end."""
    from rplearn.sim.flight import simulate

    trio = simulate("trio", seed=0).matched_truth
    _, clean = _fit(trio, tmp_path, "trio")
    assert clean == []
    _, found = _fit(trio.assign(tx_power_dbm=trio["tx_power_dbm"] + TX_ERROR_DB), tmp_path, "trio-wrong")
    means = {f["subject"]: f for f in found if f["check"] == "pattern-mean"}
    assert sorted(means) == ["A", "B", "C"]
    for f in means.values():
        assert f["inputs"][0] == "--tx-power" and f["off_by_db"] == pytest.approx(TX_ERROR_DB, abs=6.0)


def test_a_node_placed_5_m_off_shows_as_a_distance_trend_naming_the_stations_place(flight, tmp_path):
    """The smoke flight hovers at one distance: placed 5 m off, a node's computed distances vary
    while the received power does not (apparent exponent near 0), which free space cannot do."""
    moved = flight.copy()
    for end in ("tx", "rx"):
        moved.loc[moved[end] == "B", f"{end}_x"] += 5.0
    _, found = _fit(moved, tmp_path, "moved")
    [far] = [f for f in found if f["check"] == "distance"]
    assert far["inputs"][0] == "the station's place" and far["value"] < EXPONENT_RANGE[0]
    _, clean = _fit(flight, tmp_path, "still")
    assert not [f for f in clean if f["check"] == "distance"]
