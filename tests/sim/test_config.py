"""Renaming a simulation's nodes (``simulate --plan`` flying a plan under its own names): every
per-node field follows."""

from __future__ import annotations

import pytest

from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign
from rplearn.plan.trajectory import TrajectoryUnit
from rplearn.sim.config import renamed_nodes
from rplearn.sim.presets import make_preset


def _campaign(*nodes: str) -> Campaign:
    return Campaign((TrajectoryUnit(nodes=nodes, n_loops=1, label="01_loop"),))  # type: ignore[arg-type]


def test_renaming_renames_the_antennas_and_the_link_offsets_and_drops_the_others():
    paper = make_preset("paper")
    renamed = renamed_nodes(paper, {"A": "uav1", "B": "uav2"}, _campaign("uav1", "uav2"))
    assert renamed.node_antennas == {"uav1": paper.node_antennas["A"], "uav2": paper.node_antennas["B"]}
    assert renamed.radio.offsets_dict() == {"uav1->uav2": 1.0, "uav2->uav1": -2.5}
    assert renamed.campaign.nodes == ("uav1", "uav2") and renamed.flight == paper.flight
    trio = renamed_nodes(make_preset("trio"), {"A": "C", "B": "A"}, _campaign("C", "A"))  # no old name meets a new one
    assert trio.node_antennas == {"C": make_preset("trio").node_antennas["A"], "A": make_preset("trio").node_antennas["B"]}


def test_a_renaming_that_is_not_one_to_one_or_leaves_a_flown_node_out_is_refused():
    paper = make_preset("paper")
    with pytest.raises(InputError, match="distinct new names"):
        renamed_nodes(paper, {"A": "uav1", "B": "uav1"}, _campaign("uav1", "uav2"))
    with pytest.raises(InputError, match="distinct new names"):
        renamed_nodes(paper, {"X": "uav1"}, _campaign("uav1", "uav2"))
    with pytest.raises(InputError, match="no antenna given for node"):
        renamed_nodes(paper, {"A": "uav1"}, _campaign("uav1", "uav2"))
