"""Pose-signal matching (rplearn.data.sync): interpolation, drops by reason, streaming."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rplearn.core.geometry import quat_wxyz_from_yaw, slerp_wxyz
from rplearn.data.streaming import synchronise_stream, synchronise_to_parquet
from rplearn.data.sync import DROP_REASONS, SyncOptions, SyncSummary, synchronise
from rplearn.data.tables import MATCHED_COLUMNS
from rplearn.errors import InputError


def pose_log(node: str, t, xyz, yaw_rad) -> pd.DataFrame:
    q = quat_wxyz_from_yaw(np.asarray(yaw_rad, float))
    xyz = np.asarray(xyz, float)
    return pd.DataFrame({"t": np.asarray(t, float), "node": node, "x": xyz[:, 0], "y": xyz[:, 1],
                         "z": xyz[:, 2], "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3]})


def signal_log(t, tx, rx, rssi=-50.0) -> pd.DataFrame:
    n = len(t)
    return pd.DataFrame({"t": np.asarray(t, float), "tx": tx if isinstance(tx, list) else [tx] * n,
                         "rx": rx if isinstance(rx, list) else [rx] * n,
                         "rssi_dbm": np.broadcast_to(np.asarray(rssi, float), (n,)).copy(),
                         "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})


@pytest.fixture
def two_nodes() -> pd.DataFrame:
    a = pose_log("A", [0.0, 0.1, 0.2, 1.0, 1.1], [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0]],
                 [0.0, np.pi / 2, np.pi, np.pi, np.pi])
    b = pose_log("B", [0.0], [[10, 10, 5]], [np.pi / 3])  # static ground station
    return pd.concat([a, b], ignore_index=True)


def test_hand_computed_interpolation(two_nodes):
    res = synchronise(two_nodes, signal_log([0.05, 0.125], "A", "B"))
    d = res.dataset
    assert list(d.columns[: len(MATCHED_COLUMNS)]) == list(MATCHED_COLUMNS)
    np.testing.assert_allclose(d[["tx_x", "tx_y", "tx_z"]].to_numpy(), [[0.5, 0, 0], [1.25, 0, 0]])
    # halfway between yaw 0 and 90 deg is 45 deg; a quarter of the way from 90 to 180 is 112.5
    np.testing.assert_allclose(d[["tx_qw", "tx_qx", "tx_qy", "tx_qz"]].to_numpy(),
                               quat_wxyz_from_yaw(np.radians([45.0, 112.5])), atol=1e-12)
    # the static node holds its pose at every time
    np.testing.assert_allclose(d[["rx_x", "rx_y", "rx_z"]].to_numpy(), [[10, 10, 5]] * 2)
    np.testing.assert_allclose(d[["rx_qw", "rx_qz"]].to_numpy(),
                               [[np.cos(np.pi / 6), np.sin(np.pi / 6)]] * 2, atol=1e-12)


def test_drops_are_counted_by_reason(two_nodes):
    sig = pd.concat([
        signal_log([0.05], "A", "B"),                       # kept
        signal_log([0.06, 0.07, 0.08, 0.09, 0.11, 0.12], "A", "B",
                   [0.0, -127.0, -128.0, 127.0, np.nan, np.inf]),  # sentinels, then two missing
        signal_log([0.13, 0.14], "A", "B", [274.0, -300.0]),  # no radio reports these
        signal_log([0.5], "A", "B"),                        # inside the 0.2 -> 1.0 gap
        signal_log([-0.1, 1.5], "A", "B"),                  # outside A's span
        signal_log([0.05], "A", "C"),                       # C has no pose log
        signal_log([0.05], "A", "A"),                       # tx equals rx
        signal_log([np.nan], "A", "B"),                     # no time
        signal_log([0.15], "B", "A"),                       # kept (other direction)
        signal_log([0.05], "A", "N"),                       # N sits 0.1 m from A: near field at 2.4 GHz
    ], ignore_index=True)
    near = pose_log("N", [0.0], [[0.5, 0.0, 0.1]], [0.0])
    two_nodes = pd.concat([two_nodes, near], ignore_index=True)
    res = synchronise(two_nodes, sig)
    s = res.summary
    assert s.n_in == len(sig) and s.n_out == 2 == len(res.dataset)
    assert s.dropped == {"late": 0, "duplicate": 0, "invalid_value": 1, "outside_window": 0, "nan_rssi": 2,
                         "unparsable_rssi": 0, "sentinel_rssi": 4, "implausible_rssi": 2, "tx_equals_rx": 1, "other_link": 0, "duplicate_reading": 0,
                         "unknown_node": 1, "out_of_span": 2, "pose_gap": 1, "near_field": 1, "disarmed": 0,
                         "on_ground": 0}
    assert s.n_in == s.n_out + s.n_dropped
    assert s.unknown_nodes == ["C"]
    text = s.to_text()
    assert "sentinel_rssi): 4" in text and "(nan_rssi): 2" in text and "nodes without a pose log: C" in text
    # one direction only, as the paper does for non-reciprocal links
    one = synchronise(two_nodes, sig, SyncOptions(link=("B", "A")))
    assert one.summary.n_out == 1 and one.summary.dropped["other_link"] == 6  # A->B (4), A->C, A->N
    assert set(one.dataset["tx"]) == {"B"}
    # a larger gap threshold bridges the gap
    assert synchronise(two_nodes, sig, SyncOptions(max_gap_s=1.0)).summary.dropped["pose_gap"] == 0


def test_unknown_nodes_are_said_once_in_the_summary_not_also_as_a_log_warning(two_nodes, caplog):
    with caplog.at_level("WARNING"):
        res = synchronise(two_nodes, pd.concat([signal_log([0.05], "A", "B"), signal_log([0.05], "A", "C")]))
    assert res.summary.unknown_nodes == ["C"] and "nodes without a pose log: C" in res.summary.to_text()
    assert not caplog.records  # a refusal's one error line (min_samples) would follow a warning line


def test_unknown_node_can_be_an_error(two_nodes):
    with pytest.raises(InputError, match=r"signal log: field tx/rx: unknown node id\(s\) C at row 0"):
        synchronise(two_nodes, signal_log([0.05], "A", "C"), SyncOptions(on_unknown_node="error"))


def test_too_few_samples_and_bad_options(two_nodes):
    with pytest.raises(InputError, match="only 0 signal sample"):
        synchronise(two_nodes, signal_log([5.0], "A", "B"))
    with pytest.raises(InputError, match="missing column"):
        synchronise(two_nodes, signal_log([0.05], "A", "B").drop(columns="rssi_dbm"))
    with pytest.raises(InputError, match="max_gap_s") as e:
        SyncOptions(max_gap_s=-1)
    assert e.value.param == "max_gap_s"
    with pytest.raises(InputError, match=r"clock offsets \(clock_offsets_s\) name node") as e:
        synchronise(two_nodes, signal_log([0.05], "A", "B"), SyncOptions(clock_offsets_s={"Z": 1.0}))
    assert e.value.param == "clock_offsets_s"


@pytest.mark.parametrize("field, value", [
    ("link", ("A", "A")), ("link", ("A",)), ("max_gap_s", 0.0), ("max_gap_s", np.nan),
    ("clock_offsets_s", {"A": "x"}), ("signal_clock_offset_s", np.inf), ("sentinel_rssi_dbm", ["a"]),
    ("on_unknown_node", "skip"), ("min_samples", -1),
])
def test_sync_options_name_the_field_at_fault(field, value):
    with pytest.raises(InputError, match=f"^{field}: expected") as e:
        SyncOptions(**{field: value})
    assert e.value.param == field and "--" not in str(e.value)


def test_sync_options_defaults_and_type(two_nodes):
    opts = SyncOptions(link=["A", "B"], clock_offsets_s={"A": 0})
    assert opts.link == ("A", "B") and opts.clock_offsets_s == {"A": 0.0}
    assert (SyncOptions().max_gap_s, SyncOptions().on_unknown_node, SyncOptions().min_samples) == (0.2, "drop", 1)
    with pytest.raises(InputError, match="expected a SyncOptions") as e:
        synchronise(two_nodes, signal_log([0.05], "A", "B"), {"max_gap_s": 1.0})
    assert e.value.param == "options"


def test_clock_offsets_shift_the_logs(two_nodes):
    want = synchronise(two_nodes, signal_log([0.05, 0.15], "A", "B")).dataset
    shifted = two_nodes.copy()
    shifted.loc[shifted["node"] == "A", "t"] += 100.0  # A's clock runs 100 s ahead
    got = synchronise(shifted, signal_log([1000.05, 1000.15], "A", "B"),
                      SyncOptions(clock_offsets_s={"A": -100.0}, signal_clock_offset_s=-1000.0)).dataset
    np.testing.assert_allclose(got[list(MATCHED_COLUMNS[3:])].to_numpy(),
                               want[list(MATCHED_COLUMNS[3:])].to_numpy(), atol=1e-9)
    np.testing.assert_allclose(got["t"], want["t"], atol=1e-9)


def test_duplicate_pose_times_are_an_error(two_nodes):
    dup = pd.concat([two_nodes, two_nodes.iloc[[1]]], ignore_index=True)
    with pytest.raises(InputError, match="field t: 1 duplicate timestamp"):
        synchronise(dup, signal_log([0.05], "A", "B"))


def test_nan_pose_is_an_error(two_nodes):
    bad = two_nodes.copy()
    bad.loc[2, "y"] = np.nan
    with pytest.raises(InputError, match="column y has 1 .*NaN"):
        synchronise(bad, signal_log([0.05], "A", "B"))


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_slerp_equals_scipy(seed):
    from scipy.spatial.transform import Rotation, Slerp

    rng = np.random.default_rng(seed)
    r = Rotation.random(2, random_state=seed)
    f = rng.uniform(0, 1, 16)
    want = Slerp([0.0, 1.0], r)(f).as_quat()  # x, y, z, w
    want = np.concatenate([want[:, 3:], want[:, :3]], axis=1)
    q = np.concatenate([r.as_quat()[:, 3:], r.as_quat()[:, :3]], axis=1)
    got = slerp_wxyz(np.repeat(q[:1], 16, 0), np.repeat(q[1:], 16, 0), f)
    # same rotation: q or -q
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", got, want)), 1.0, atol=1e-9)


def _flight(n_signal=5000, seed=1):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 60.0, 0.01)
    a = pose_log("A", t, np.c_[np.cos(t), np.sin(t), 0 * t + 2], t)
    b = pose_log("B", t + 0.003, np.c_[5 + np.cos(t), np.sin(2 * t), 0 * t + 3], -t)
    ts = np.sort(rng.uniform(-1, 61, n_signal))
    tx = rng.choice(["A", "B"], n_signal).tolist()
    rx = ["B" if x == "A" else "A" for x in tx]
    rssi = np.round(rng.uniform(-90, -20, n_signal))
    rssi[::97] = -127.0
    return pd.concat([a, b], ignore_index=True), signal_log(ts, tx, rx, rssi).assign(unit="u1")


def test_stream_equals_one_shot(tmp_path):
    pose, sig = _flight()
    one = synchronise(pose, sig)
    chunks = [sig.iloc[i:i + 777] for i in range(0, len(sig), 777)]
    parts = list(synchronise_stream(pose, chunks))
    total = SyncSummary()
    for p in parts:
        total.merge(p.summary)
    got = pd.concat([p.dataset for p in parts], ignore_index=True)
    pd.testing.assert_frame_equal(got, one.dataset)
    assert total.n_in == one.summary.n_in and total.dropped == one.summary.dropped
    assert "unit" in got.columns  # extra columns are kept
    summary = synchronise_to_parquet(pose, iter(chunks), str(tmp_path / "m.parquet"))
    back = pd.read_parquet(tmp_path / "m.parquet")
    pd.testing.assert_frame_equal(back, one.dataset, check_dtype=False)
    assert summary.n_out == len(back) and set(summary.dropped) == set(DROP_REASONS)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-5, 65) | st.sampled_from([np.nan, np.inf, -np.inf, 20.2, 20.0]),
                min_size=1, max_size=40),
       st.floats(0.001, 2.0))
def test_every_sample_is_kept_or_counted(times, max_gap):
    pose, _ = _flight(10)
    pose = pose[(pose["t"] < 20) | (pose["t"] > 20.5)]  # a 0.5 s gap
    sig = signal_log(times, "A", "B")
    res = synchronise(pose, sig, SyncOptions(max_gap_s=max_gap, min_samples=0))
    s = res.summary
    assert s.n_in == s.n_out + s.n_dropped == len(times)
    d = res.dataset
    assert np.all(np.isfinite(d[list(MATCHED_COLUMNS[3:])].to_numpy()))


def test_exact_duplicate_rows_are_dropped_and_counted(two_nodes):
    sig = signal_log([0.05, 0.06, 0.07], "A", "B", [-50.0, -51.0, -52.0])
    doubled = pd.concat([sig, sig.iloc[[1]], sig.iloc[[1]]], ignore_index=True)
    near = sig.iloc[[2]].assign(rssi_dbm=-53.0)  # same time, other value: not a duplicate
    res = synchronise(two_nodes, pd.concat([doubled, near], ignore_index=True))
    assert res.summary.dropped["duplicate"] == 2
    assert res.summary.n_out == 4
    assert "dropped (duplicate): 2" in res.summary.to_text()


def test_non_unit_quaternions_are_counted_and_normalised(two_nodes):
    pose = two_nodes.copy()
    pose.loc[1, ["qw", "qx", "qy", "qz"]] = [5.0, 0.0, 0.0, 0.0]
    pose.loc[2, "qw"] = pose.loc[2, "qw"] * (1 + 5e-4)  # within the tolerance
    res = synchronise(pose, signal_log([0.05, 0.125], "A", "B"))
    assert res.summary.non_unit_quaternions == 1
    assert "non-unit quaternion (|norm - 1| > 0.001, normalised): 1" in res.summary.to_text()
    np.testing.assert_allclose(np.linalg.norm(res.dataset[["tx_qw", "tx_qx", "tx_qy", "tx_qz"]], axis=1), 1.0)
    chunks = list(synchronise_stream(pose, [signal_log([0.05], "A", "B")] * 2))
    assert [c.summary.non_unit_quaternions for c in chunks] == [1, 0, 0]  # the last: the notes on the whole log
    assert chunks[-1].summary.n_in == 0 and chunks[-1].summary.fixed_nodes == ["B"]


def test_the_nodes_taken_as_fixed_are_named_with_what_was_taken(two_nodes):
    # a node logged with one row, or only identical rows, holds still over its log's span: was done without a word
    still = pose_log("C", [0.0, 0.5, 1.0], [[5, 5, 0]] * 3, [0.0] * 3)  # a station logged at 2 Hz
    pose = pd.concat([two_nodes, still], ignore_index=True)
    signal = pd.concat([signal_log([0.05, 0.125], "A", "B"), signal_log([0.1], "C", "A")], ignore_index=True)
    summary = synchronise(pose, signal).summary
    assert summary.fixed_nodes == ["B", "C"]
    [note] = [n for n in summary.notes if n.startswith("fixed node(s)")]
    assert note.endswith(": B at every time (one pose row); C from t = 0.000 to 1.000 s (identical pose rows, "
                         "no pose gap between them)")
    assert note in summary.to_text()
    streamed = SyncSummary()
    for res in synchronise_stream(pose, [signal]):
        streamed.merge(res.summary)
    assert streamed.fixed_nodes == ["B", "C"] and note in streamed.notes
    moving = synchronise(two_nodes[two_nodes["node"] == "A"], signal_log([0.05], "A", "A2"), SyncOptions(min_samples=0))
    assert moving.summary.fixed_nodes == [] and not [n for n in moving.summary.notes if "fixed node" in n]


def test_link_naming_a_node_in_no_signal_log(two_nodes):
    sig = signal_log([0.05], "A", "B")
    with pytest.raises(InputError, match=r"link A:Q: node Q is in no signal log; the signal logs name A, B$") as e:
        synchronise(two_nodes, sig, SyncOptions(link=("A", "Q")))
    assert e.value.param == "link"
    with pytest.raises(InputError, match=r"no signal from B to A; directions present: A:B$"):
        synchronise(two_nodes, sig, SyncOptions(link=("B", "A")))


def test_duplicate_rows_equals_pandas_duplicated_on_unsorted_logs():
    from rplearn.data.sync import duplicate_rows

    rng = np.random.default_rng(4)
    n = 3000
    df = pd.DataFrame(
        {
            "t": rng.integers(0, 400, n).astype(float),  # many shared times, unsorted
            "tx": rng.choice(["A", "B"], n),
            "rx": "C",
            "rssi_dbm": rng.integers(-62, -58, n).astype(float),
            "tx_power_dbm": 20.0,
            "frequency_hz": 2.4e9,
        }
    )
    expected = df.duplicated(keep="first").to_numpy()
    assert 0 < expected.sum() < n
    np.testing.assert_array_equal(duplicate_rows(df), expected)
    np.testing.assert_array_equal(duplicate_rows(df.drop_duplicates()), np.zeros(n - expected.sum(), bool))


def _station_flight(station_rows: int, seed: int = 3):
    """A drone at 10 Hz for 60 s and a ground station logged ``station_rows`` times (identical)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 60.0, 0.1)
    drone = pose_log("D", t, np.c_[20 * np.cos(t / 10), 20 * np.sin(t / 10), 10 + t / 10], t / 7)
    times = np.linspace(0.0, 60.0, station_rows) if station_rows > 1 else [0.0]
    station = pose_log("G", times, [[1.0, 2.0, 1.5]] * len(times), [0.3] * len(times))
    sig = signal_log(np.sort(rng.uniform(0.0, 59.9, 2000)), "D", "G", rng.normal(-60.0, 3.0, 2000))
    return pd.concat([drone, station], ignore_index=True), sig


@pytest.mark.parametrize("rows", [2, 600])
def test_a_station_logged_many_times_is_static(rows):
    """Issue 12, acceptance 3: 2 (start and end of the flight) or 600 identical rows give the
    dataset of one row; before, all but the samples next to a logged pose were pose gaps."""
    one = synchronise(*_station_flight(1)).dataset
    many = synchronise(*_station_flight(rows)).dataset
    assert len(one) == 2000
    pd.testing.assert_frame_equal(one, many)


def test_a_station_moved_between_flights_is_refused_with_both_positions():
    poses, sig = _station_flight(1)
    moved = pose_log("G", [0.0, 1.0, 59.0, 60.0], [[1, 2, 1.5], [1, 2, 1.5], [31, 2, 1.5], [31, 2, 1.5]], [0.3] * 4)
    poses = pd.concat([poses[poses["node"] == "D"], moved], ignore_index=True)
    with pytest.raises(InputError, match=r"node G holds still at \(1.00, 2.00, 1.50\) m until t=1.000 s and at "
                                         r"\(31.00, 2.00, 1.50\) m from t=59.000 s"):
        synchronise(poses, sig)
    # a drone with a logging gap, moving before and after it, is a track, not a moved station
    gap = poses[poses["node"] == "D"]
    gap = gap[(gap["t"] < 20) | (gap["t"] > 25)]
    res = synchronise(pd.concat([gap, pose_log("G", [0.0], [[1, 2, 1.5]], [0.3])], ignore_index=True), sig)
    assert res.summary.dropped["pose_gap"] > 0 and len(res.dataset) > 1500


def test_relative_power_keeps_strong_samples_and_says_so(tmp_path):
    """Issue 12, item 3: an uncalibrated radio's dB above +30 are kept with --rssi-scale relative
    (dropped as implausible in dBm); the dataset says its scale, and fits from it."""
    from typer.testing import CliRunner

    from rplearn.cli import app
    from rplearn.io.files import read_dataset
    from rplearn.sim import simulate

    def rplearn(*args: str):  # in this process: the exit codes and messages are checked, not the process boundary
        return CliRunner().invoke(app, list(args), env={"COLUMNS": "400"})

    simulate("smoke", seed=2, out_dir=str(tmp_path / "f"))
    sig = pd.read_parquet(tmp_path / "f" / "signal_log.parquet")
    sig["rssi_dbm"] = sig["rssi_dbm"] + 110.0  # dB above some noise floor, not dBm
    sig.to_csv(tmp_path / "rel.csv", index=False)
    base = ["sync", "--poses", str(tmp_path / "f" / "pose_log.parquet"), "--signals", str(tmp_path / "rel.csv")]
    as_dbm = rplearn(*base, "-o", str(tmp_path / "dbm.parquet"))
    assert as_dbm.exit_code == 1 and "implausible_rssi" in as_dbm.output, as_dbm.output
    rel = rplearn(*base, "--rssi-scale", "relative", "-o", str(tmp_path / "rel.parquet"))
    assert rel.exit_code == 0, rel.output
    d = read_dataset(str(tmp_path / "rel.parquet"))
    assert len(d) > 0.9 * len(sig) and set(d["rssi_scale"]) == {"relative"} and d["rssi_dbm"].max() > 30
    fit = rplearn("fit", str(tmp_path / "rel.parquet"), "--degree", "3", "-o", str(tmp_path / "m.json"))
    assert fit.exit_code == 0, fit.output
    with pytest.raises(InputError, match="rssi_scale"):
        SyncOptions(rssi_scale="linear")


def test_a_drone_resting_on_its_pad_before_a_sparse_log_is_not_a_moved_station():
    """Review: identical rows on the pad, then a 1 Hz flight (all changes across 'gaps' longer
    than max_gap): a track whose samples are pose gaps, not a refused station."""
    t = np.arange(0.0, 60.0, 1.0)
    xyz = np.c_[np.where(t < 10, 0.0, t), np.zeros_like(t), np.where(t < 10, 0.0, 10.0)]
    drone = pose_log("A", t, xyz, np.zeros_like(t))
    res = synchronise(pd.concat([drone, pose_log("B", [0.0], [[5, 5, 1]], [0.0])], ignore_index=True),
                      signal_log(np.arange(0.5, 59.0, 0.5), "A", "B"), SyncOptions(min_samples=0))
    assert res.summary.dropped["pose_gap"] > 0
    turned = pose_log("G", [0.0, 1.0, 50.0, 51.0], [[0, 0, 1]] * 4, [0.0, 0.0, 1.0, 1.0])
    with pytest.raises(InputError, match="turned: the same position, another attitude"):
        synchronise(pd.concat([drone, turned], ignore_index=True), signal_log([20.0], "A", "G"))


def test_missing_and_text_rssi_are_counted_under_what_they_are(two_nodes):
    """A NaN or empty RSSI is ``nan_rssi``, text that is no number ``unparsable_rssi``, never ``sentinel_rssi``."""
    sig = signal_log([0.05, 0.06, 0.07, 0.08, 0.09, 0.11], "A", "B")
    sig["rssi_dbm"] = pd.Series([-50.0, "n/a?", "", None, "NaN", "-127"], dtype=object)
    s = synchronise(two_nodes, sig).summary
    assert (s.dropped["nan_rssi"], s.dropped["unparsable_rssi"], s.dropped["sentinel_rssi"]) == (3, 1, 1)
    assert s.n_out == 1 and "(unparsable_rssi): 1" in s.to_text()


def test_an_empty_unit_cell_is_refused_at_sync_naming_file_column_and_row(two_nodes):
    """A sample of no trajectory unit passed sync and was refused by fit later: refused here."""
    sig = signal_log([0.05, 0.06, 0.07], "A", "B").assign(unit=["u1", " ", "u1"])
    with pytest.raises(InputError, match=r"^sig.csv: column unit is empty at row 1 \(1 row\(s\)\)"):
        synchronise(two_nodes, sig, source="sig.csv")
    assert len(synchronise(two_nodes, sig.assign(unit="u1")).dataset) == 3
