"""A written plan flown by a preset whose node names are not the plan's (``simulate --plan``):
its station as the preset's station, its drone as the preset's drone, the logs under the plan's
names; a layout the preset cannot fly refused in one line naming the presets that can. It was
refused for any plan under other names: "node(s) gcs, sys1 have no antenna in preset ground (D, G)"."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.errors import InputError
from rplearn.plan.campaign import Campaign, still_nodes, write_references
from rplearn.plan.ground import GroundPassUnit
from rplearn.plan.references import read_plan
from rplearn.plan.trajectory import TrajectoryUnit
from rplearn.sim.flight import simulate
from rplearn.sim.presets import make_preset
from rplearn.workflows.plan_flight import plan_flight

_FAST = dict(distance_m=20.0, height_m=15.0, n_loops=1, speed_m_s=3.0, accel_m_s2=3.0, yaw_rate_deg_s=90.0)


@pytest.fixture(scope="module")
def station_plan(tmp_path_factory) -> str:
    """A station ``gcs`` and a drone ``sys1`` (one short pass), as a real log's plan names them."""
    folder = tmp_path_factory.mktemp("station_plan")
    unit = GroundPassUnit(nodes=("gcs", "sys1"), n_passes=1, speed_m_s=8.0, label="01_pass")
    write_references(Campaign((unit,)), str(folder))  # type: ignore[arg-type]
    return str(folder)


@pytest.fixture(scope="module")
def drones_plan(tmp_path_factory) -> str:
    folder = tmp_path_factory.mktemp("drones_plan")
    write_references(Campaign((TrajectoryUnit(nodes=("uav2", "uav1"), label="01_loop", **_FAST),)), str(folder))  # type: ignore[arg-type]
    return str(folder)


def test_the_station_and_the_drone_of_a_plan_are_told_apart_by_the_fit_rule(station_plan, drones_plan):
    assert still_nodes(read_plan(station_plan)) == ("gcs",)
    assert still_nodes(read_plan(drones_plan)) == ()
    assert still_nodes(make_preset("ground").campaign) == ("G",)
    assert still_nodes(make_preset("paper").campaign) == ()


def test_a_station_plan_flies_on_the_ground_preset_under_its_own_names(station_plan):
    flight = plan_flight("ground", station_plan)
    ground = make_preset("ground")
    assert flight.names == {"G": "gcs", "D": "sys1"}
    assert flight.text == "flying plan nodes gcs, sys1 as the ground preset's G (station), D"
    assert flight.config.node_antennas == {"gcs": ground.node_antennas["G"], "sys1": ground.node_antennas["D"]}
    result = simulate(flight.config, seed=3)
    assert set(result.pose_log["node"]) == {"gcs", "sys1"}
    assert set(result.signal_log["tx"]) | set(result.signal_log["rx"]) == {"gcs", "sys1"}
    assert result.ground_truth.nodes == ("gcs", "sys1")
    station = result.pose_log[result.pose_log["node"] == "gcs"][["x", "y", "z"]].to_numpy()
    assert np.linalg.norm(station - np.median(station, axis=0), axis=1).max() <= 5.0
    drone = result.pose_log[result.pose_log["node"] == "sys1"][["x", "y", "z"]].to_numpy()
    assert np.ptp(drone, axis=0).max() > 5.0


def test_two_drones_fly_as_a_two_drone_presets_in_sorted_order_with_their_offsets(drones_plan):
    flight = plan_flight("paper", drones_plan)
    assert flight.names == {"A": "uav1", "B": "uav2"}
    assert flight.text == "flying plan nodes uav1, uav2 as the paper preset's A, B"
    assert flight.config.radio.link_offsets_db == ((("uav1", "uav2"), 1.0), (("uav2", "uav1"), -2.5))
    assert flight.config.ground_truth().link_offsets_db == {"uav1->uav2": 1.0, "uav2->uav1": -2.5}


def test_a_plan_under_the_presets_names_is_flown_as_before(tmp_path):
    write_references(Campaign((TrajectoryUnit(nodes=("A", "B"), label="01_loop", **_FAST),)), str(tmp_path))  # type: ignore[arg-type]
    flight = plan_flight("trio", str(tmp_path))
    assert flight.names == {} and flight.text == "" and set(flight.config.node_antennas) == {"A", "B", "C"}


@pytest.mark.parametrize(("plan", "preset", "said"), [
    ("station", "paper", "the plan flies a station gcs and a drone sys1; preset paper flies two drones A, B: fly it with "
                         "--preset ground (or tworay, campaign), or map its nodes with --node-map PLAN=PRESET,..."),
    ("drones", "ground", "the plan flies two drones uav1, uav2; preset ground flies a station G and a drone D: fly it with "
                         "--preset paper (or trio, smoke, pathloss), or map its nodes with --node-map PLAN=PRESET,..."),
])
def test_a_layout_the_preset_cannot_fly_is_refused_naming_the_presets_that_can(station_plan, drones_plan, plan, preset, said):
    folder = station_plan if plan == "station" else drones_plan
    with pytest.raises(InputError) as err:
        plan_flight(preset, folder)
    assert str(err.value) == f"{folder}: {said}" and err.value.param == "preset"


def test_a_stated_node_map_overrides_the_roles(station_plan):
    ground = make_preset("ground")
    flight = plan_flight("ground", station_plan, {"gcs": "D", "sys1": "G"})
    assert flight.config.node_antennas == {"gcs": ground.node_antennas["D"], "sys1": ground.node_antennas["G"]}
    assert flight.text == "flying plan nodes gcs, sys1 as the ground preset's D, G (station) (--node-map)"
    # a station plan on two drones, as the user says
    assert plan_flight("paper", station_plan, {"gcs": "B", "sys1": "A"}).names == {"B": "gcs", "A": "sys1"}


@pytest.mark.parametrize(("node_map", "said"), [
    ({"gcs": "G", "sys": "D"}, "sys is no node of the plan in"),
    ({"gcs": "G"}, "the plan's sys1 is not mapped"),
    ({"gcs": "G", "sys1": "X"}, "X is no node of preset ground (D, G)"),
    ({"gcs": "G", "sys1": "G"}, "two plan nodes mapped to one preset node (expected one to one)"),
])
def test_a_node_map_that_does_not_fit_is_refused_in_one_line(station_plan, node_map, said):
    with pytest.raises(InputError) as err:
        plan_flight("ground", station_plan, node_map)
    assert said in str(err.value) and "\n" not in str(err.value) and err.value.param == "node_map"
