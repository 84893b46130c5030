"""``trajectory --optimize --from-model``: the plan is made for the earlier flight's layout (a
ground station and a drone, their names) and its radio's packet rate, where the flags say
nothing. Before, a SiK telemetry flight of a station ``gcs`` and a drone ``sys1`` at 1 packet/s
was planned for two drones ``A``, ``B`` turning together at 80 packets/s."""

from __future__ import annotations

import pytest
from simulated_flights import synced

from rplearn.errors import InputError
from rplearn.io.modelfile import read_model_file, write_model_file
from rplearn.models import ModelSpec
from rplearn.models.options import FitOptions
from rplearn.workflows.calibration_plan import OptimizeOptions, optimize_plan
from rplearn.workflows.learning import fit_dataset
from rplearn.workflows.plan_layout import DEFAULT_PACKET_RATE_HZ, plan_layout

PLAN = dict(model="sh-5", target_spread_db=2.5, budget_s=40.0)


@pytest.fixture(scope="module")
def station_flight(tmp_path_factory):
    """``fit --order auto`` of the ``ground`` preset (a static station G and a drone D), its
    model file, and the station's id."""
    d = tmp_path_factory.mktemp("ground")
    flight = synced("ground", 0)
    path = str(d / "auto.json")
    outcome = fit_dataset(str(flight.folder / "m.parquet"), ModelSpec.parse("sh"), options=FitOptions(auto=True), output=path)
    return path, outcome.fitted.model


def test_the_fit_records_the_station_held_still_and_the_radios_rate(station_flight):
    _, model = station_flight
    assert model.training.fixed_nodes == ("G",)
    # the preset's radio sends 80 packets/s each way; the median interval between readings is its period
    assert model.training.packet_rate_hz == pytest.approx(80.0, rel=0.02)


def test_a_plan_from_it_is_for_its_station_and_drone_at_its_rate(station_flight, tmp_path):
    path, model = station_flight
    plan = optimize_plan(str(tmp_path / "plan"), OptimizeOptions(**PLAN, from_model=path))
    assert tuple(plan.start_spread_db) == ("D", "G")
    assert plan.steps and all(set(s.manoeuvre.candidate.unit.nodes) == {"D", "G"} for s in plan.steps)
    assert not any(" of G" in s.manoeuvre.name or "G turning" in s.manoeuvre.name for s in plan.steps)  # the station stays
    assert "a ground station G, held still in the earlier flight, and a drone D" in plan.prior
    assert f"{model.training.packet_rate_hz:.3g} packets/s in each link direction, the earlier flight's" in plan.prior
    stated = optimize_plan(str(tmp_path / "stated"), OptimizeOptions(**PLAN, from_model=path,
                                                                     packet_rate_hz=model.training.packet_rate_hz, station=True))
    assert [s.spread_db for s in stated.steps] == [s.spread_db for s in plan.steps]  # the same plan, said by flags
    assert "packets/s" not in stated.prior and "held still" not in stated.prior


def test_flags_override_the_earlier_layout_and_rate(station_flight, tmp_path):
    path, _ = station_flight
    drones = optimize_plan(str(tmp_path / "drones"), OptimizeOptions(**PLAN, from_model=path, station=False))
    assert set(drones.start_spread_db) == {"D", "G"} and "held still" not in drones.prior
    slow = optimize_plan(str(tmp_path / "slow"), OptimizeOptions(**PLAN, from_model=path, packet_rate_hz=1.0))
    fast = optimize_plan(str(tmp_path / "fast"), OptimizeOptions(**PLAN, from_model=path))
    assert max(slow.steps[-1].spread_db.values()) > max(fast.steps[-1].spread_db.values())


@pytest.mark.parametrize("rate", [0.0, 1e-300, 1e300])
def test_a_damaged_packet_rate_is_refused_naming_file_and_field(station_flight, tmp_path, rate):
    path, _ = station_flight
    kind, payload = read_model_file(path)
    payload["training"]["packet_rate_hz"] = rate
    bad = tmp_path / "bad.json"
    write_model_file(bad, kind, payload)
    with pytest.raises(InputError) as err:
        optimize_plan(str(tmp_path / "plan"), OptimizeOptions(**PLAN, from_model=str(bad)))
    assert f"{bad}: training.packet_rate_hz is {rate:g}" in str(err.value) and "--packet-rate" in str(err.value)
    assert "\n" not in str(err.value) and not (tmp_path / "plan").exists()


def test_without_a_model_or_its_layout_the_flags_defaults_stand():
    plain = plan_layout(None, None, 10.0, 20.0)
    assert plain.nodes == ("A", "B") and plain.fixed == () and plain.packet_rate_hz == DEFAULT_PACKET_RATE_HZ
    assert plain.text == ""
    station = plan_layout(True, None, 10.0, 20.0)
    assert station.nodes == ("D", "G") and station.fixed == ("G",)


class _Training:
    def __init__(self, fixed, rate):
        self.fixed_nodes, self.packet_rate_hz = fixed, rate


@pytest.mark.parametrize("names", [("x", "x"), ("a", "b", "c")])
def test_two_nodes_of_one_name_or_more_than_two_nodes_keep_the_plans_names(names):
    layout = plan_layout(None, None, 10.0, 20.0, _Training(("gcs",), 2.0), names)
    assert layout.nodes == ("A", "B") and layout.packet_rate_hz == 2.0


@pytest.mark.parametrize("names", [("uav/1", "gcs"), ("uav_1", "gcs"), ("drone 1", "gcs")])
def test_a_station_flight_whose_names_cannot_name_a_reference_file_is_planned_as_station_g_and_drone_d(names):
    # read_plan parses <unit>_<node>.csv: a node named with '_' wrote files it could not read back
    layout = plan_layout(None, None, 10.0, 20.0, _Training(("gcs",), 2.0), names)
    assert layout.nodes == ("D", "G") and layout.fixed == ("G",)
    assert "ground station G and a drone D, as the earlier flight's station gcs held still" in layout.text


def test_a_model_that_does_not_record_its_layout_is_not_said_to_be_two_drones():
    # a model file written before fits recorded the layout: nothing recorded is not "nobody held still"
    layout = plan_layout(None, None, 10.0, 20.0, _Training(None, None), ("gcs", "sys1"))
    assert layout.nodes == ("A", "B") and layout.fixed == ()
    assert "the earlier flight's layout is not recorded" in layout.text and "as in the earlier flight" not in layout.text
    assert "80 packets/s, the default: the earlier flight's rate is not recorded" in layout.text


def test_a_model_with_both_nodes_still_is_planned_for_two_drones():
    layout = plan_layout(None, None, 10.0, 20.0, _Training(("a", "b"), None), ("a", "b"))
    assert layout.nodes == ("a", "b") and layout.fixed == () and layout.packet_rate_hz == DEFAULT_PACKET_RATE_HZ


def test_a_packet_rate_flag_below_one_reading_in_17_minutes_is_refused():
    with pytest.raises(InputError, match=r"packet_rate_hz: 1e-300 Hz is not packets a radio reports per second: expected 0.001"):
        OptimizeOptions(packet_rate_hz=1e-300)


def test_fixed_nodes_of_another_type_are_refused_naming_the_field(station_flight, tmp_path):
    from rplearn.models import load_model
    path, _ = station_flight
    for value in ("G", {"G": 1}, [1]):
        kind, payload = read_model_file(path)
        payload["training"]["fixed_nodes"] = value
        bad = tmp_path / "bad_fixed.json"
        write_model_file(bad, kind, payload)
        with pytest.raises(Exception, match=r"training\.fixed_nodes: expected a list of node ids"):
            load_model(str(bad))
