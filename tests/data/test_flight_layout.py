"""The flight's layout a matched dataset shows: the nodes that held still and the radio's packet
rate (``training.fixed_nodes``, ``training.packet_rate_hz``), which the next flight's plan is made for."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.data.flight_layout import fixed_nodes, packet_rate_hz

POSE = ("x", "y", "z", "qw", "qx", "qy", "qz")


def _rows(t: np.ndarray, tx: list[str], rx: list[str], poses: dict[str, np.ndarray]) -> pd.DataFrame:
    """Matched rows at times ``t``, each end at its node's pose of that row."""
    out = {"t": t, "tx": tx, "rx": rx, "rssi_dbm": np.full(t.size, -60.0)}
    for end, names in (("tx", tx), ("rx", rx)):
        block = np.stack([poses[n][i] for i, n in enumerate(names)])
        for j, c in enumerate(POSE):
            out[f"{end}_{c}"] = block[:, j]
    return pd.DataFrame(out)


def _station_and_drone(n: int = 200, rate_hz: float = 10.0, jitter_m: float = 0.0, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    t = np.repeat(np.arange(n // 2) / rate_hz, 2)
    station = np.tile([5.0, -2.0, 1.5, 1.0, 0.0, 0.0, 0.0], (n, 1))
    station[:, :3] += rng.normal(0.0, jitter_m, (n, 3)) if jitter_m else 0.0
    drone = np.column_stack([rng.uniform(-50, 50, (n, 3)), np.ones(n), np.zeros((n, 3))])
    tx = ["D", "G"] * (n // 2)
    rx = ["G", "D"] * (n // 2)
    return _rows(t, tx, rx, {"G": station, "D": drone})


def test_a_station_held_still_is_fixed_and_the_drone_is_not():
    assert fixed_nodes(_station_and_drone()) == ("G",)


def test_a_station_whose_logged_pose_wanders_still_holds_still():
    # a station logged with its own GPS and attitude estimate wanders by a metre or two
    assert fixed_nodes(_station_and_drone(jitter_m=1.0)) == ("G",)


def test_a_drone_turning_in_place_does_not_hold_still():
    rows = _station_and_drone()
    drone = (rows["tx"] == "D").to_numpy()
    yaw = np.linspace(0.0, 2.0 * np.pi, int(drone.sum()))
    for end, mine in (("tx", drone), ("rx", ~drone)):
        rows.loc[mine, [f"{end}_x", f"{end}_y", f"{end}_z"]] = 0.0
        rows.loc[mine, f"{end}_qw"] = np.cos(yaw / 2.0)
        rows.loc[mine, f"{end}_qz"] = np.sin(yaw / 2.0)
    assert fixed_nodes(rows) == ("G",)


def test_a_node_fixed_as_transmitter_but_elsewhere_as_receiver_is_not_fixed():
    rows = _station_and_drone()
    rows.loc[rows["rx"] == "G", "rx_x"] += 30.0  # its rows as receiver put it 30 m away
    assert fixed_nodes(rows) == ()


def test_a_glitch_in_a_few_rows_does_not_move_a_station():
    rows = _station_and_drone(n=1000)
    glitch = rows.index[(rows["tx"] == "G").to_numpy()][:3]
    rows.loc[glitch, "tx_x"] += 500.0
    assert fixed_nodes(rows) == ("G",)


def test_nan_poses_are_not_a_node_held_still():
    rows = _station_and_drone()
    rows.loc[5, "tx_x" if rows.loc[5, "tx"] == "G" else "rx_x"] = np.nan
    assert fixed_nodes(rows) == ()


def test_rows_without_poses_say_nothing():
    rows = _station_and_drone().drop(columns=["rx_qz"])
    assert fixed_nodes(rows) is None and fixed_nodes(rows.iloc[:0]) is None


@pytest.mark.parametrize("rate_hz", [1.0, 4.0, 80.0])
def test_the_packet_rate_is_each_directions_reporting_rate_despite_gaps(rate_hz):
    rows = _station_and_drone(n=400, rate_hz=rate_hz)
    # a gap of 60 s (an outage, a battery swap between flights) and a dropped stretch
    later = rows["t"] > rows["t"].median()
    rows.loc[later, "t"] += 60.0
    rows = rows.drop(index=rows.index[50:70])
    assert packet_rate_hz(rows) == pytest.approx(rate_hz, rel=1e-9)


def test_repeated_times_and_too_few_rows_give_no_rate():
    rows = _station_and_drone(n=4)
    rows["t"] = 1.0
    assert packet_rate_hz(rows) is None and packet_rate_hz(rows.iloc[:1]) is None


def test_a_rate_no_radio_has_is_not_recorded():
    rows = _station_and_drone(n=40)
    rows["t"] = rows["t"] * 1e-9  # readings a nanosecond apart: a clock in the wrong unit
    assert packet_rate_hz(rows) is None


def test_a_large_dataset_is_read_in_an_even_sample(monkeypatch):
    import rplearn.data.flight_layout as layout
    monkeypatch.setattr(layout, "LAYOUT_ROWS", 50)
    rows = _station_and_drone(n=1000, jitter_m=1.0)
    assert layout.fixed_nodes(rows) == ("G",)


# -- the bounded summary of rows read a chunk at a time (streamed, Dask, live fits) ----------------

def _sketch(rows: pd.DataFrame, cuts: list[int]):
    """:class:`LayoutSketch` of ``rows`` cut into chunks at ``cuts``, merged in order."""
    from rplearn.data.flight_layout import LayoutSketch
    out = LayoutSketch()
    for a, b in zip([0, *cuts], [*cuts, len(rows)]):
        out.merge(LayoutSketch.of_rows(rows.iloc[a:b]))
    return out


@pytest.mark.parametrize("cuts", [[], [1], [97, 98, 250], list(range(7, 400, 7))], ids=["whole", "1 row", "uneven", "7 rows"])
def test_a_sketch_of_chunks_reads_the_layout_of_the_rows_in_memory(cuts):
    rows = _station_and_drone(n=400, rate_hz=4.0, jitter_m=1.0)
    later = rows["t"] > rows["t"].median()
    rows.loc[later, "t"] += 60.0  # a gap between flights: not the rate
    sketch = _sketch(rows, cuts)
    assert sketch.fixed_nodes() == fixed_nodes(rows) == ("G",)
    assert sketch.packet_rate_hz() == packet_rate_hz(rows) == pytest.approx(4.0, rel=1e-9)  # few intervals: exact
    assert sketch.recorded() == {"fixed_nodes": ("G",), "packet_rate_hz": sketch.packet_rate_hz()}


def test_a_sketch_says_nothing_where_the_rows_say_nothing():
    from rplearn.data.flight_layout import LayoutSketch
    assert LayoutSketch().recorded() == {"fixed_nodes": None, "packet_rate_hz": None}
    rows = _station_and_drone(n=40)
    assert _sketch(rows.drop(columns=["rx_qz"]), [20]).fixed_nodes() is None  # no poses of both ends
    rows["t"] = rows["t"] * 1e-9  # a clock in the wrong unit: no radio's rate
    assert _sketch(rows, [20]).packet_rate_hz() is None and _sketch(rows, [20]).fixed_nodes() == ("G",)


def _jittered(n: int, rate_hz: float = 80.0, seed: int = 1) -> pd.DataFrame:
    """Two directions reporting at ``rate_hz`` with a jittered clock (every interval distinct)."""
    rows = _station_and_drone(n=n, rate_hz=rate_hz, jitter_m=1.0, seed=seed)
    rng = np.random.default_rng(seed)
    rows["t"] = rows["t"] + np.repeat(rng.uniform(0.0, 0.3 / rate_hz, n // 2), 2)
    return rows


def test_a_long_flight_is_summed_up_in_bounded_memory_whatever_its_chunks(monkeypatch):
    import rplearn.data.flight_layout as layout
    monkeypatch.setattr(layout, "LAYOUT_ROWS", 500)
    monkeypatch.setattr(layout, "INTERVAL_VALUES", 64)
    rows = _jittered(20_000)
    expected = packet_rate_hz(rows)
    one, many = _sketch(rows, []), _sketch(rows, list(range(997, 20_000, 997)))
    for sketch in (one, many):
        assert 250 <= len(sketch.keys) <= 500 and sketch.poses.shape == (len(sketch.keys), 14)  # half to all of the bound
        assert all(v.values.size <= 64 and v.width > 0 for v in sketch.links.values())  # counted in bins
        assert sketch.fixed_nodes() == ("G",)
        assert sketch.packet_rate_hz() == pytest.approx(expected, rel=0.01)
    # the rows kept are those of the smallest keys whatever the chunks: the same sample
    assert np.array_equal(np.sort(one.keys), np.sort(many.keys))


def test_the_sketches_of_parts_merge_in_their_order_as_one_pass():
    rows = _jittered(6_000)
    a, b = _sketch(rows.iloc[:2500], [1000]), _sketch(rows.iloc[2500:], [1700])
    whole = _sketch(rows, [1000, 2500, 4200])
    merged = a.merge(b)
    assert merged.rows == whole.rows == len(rows)
    assert merged.fixed_nodes() == whole.fixed_nodes() == ("G",)
    assert merged.packet_rate_hz() == pytest.approx(whole.packet_rate_hz(), rel=1e-12)
    assert merged.packet_rate_hz() == pytest.approx(packet_rate_hz(rows), rel=0.005)


@pytest.mark.parametrize("cuts", [[], list(range(997, 40_000, 997)), list(range(97, 40_000, 97))], ids=["whole", "997 rows", "97 rows"])
def test_jittered_intervals_beyond_the_exact_count_give_the_rate_within_half_a_bin(cuts):
    from rplearn.data.flight_layout import FINEST_BIN, INTERVAL_VALUES
    rows = _jittered(40_000)  # 20,000 distinct intervals each way, above INTERVAL_VALUES
    sketch = _sketch(rows, cuts)
    widths = {v.width for v in sketch.links.values()}
    assert all(v.values.size <= INTERVAL_VALUES for v in sketch.links.values()) and min(widths) >= FINEST_BIN
    assert sketch.packet_rate_hz() == pytest.approx(packet_rate_hz(rows), rel=max(widths) / 2.0)
