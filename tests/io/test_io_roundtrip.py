"""Acceptance 1: one flight written in every format gives back the same matched dataset."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from flightfiles import FREQUENCY_HZ, MAC, POSE_TOPICS, RSSI_MSG, RSSI_MSGDEF, RSSI_TOPICS, TX_POWER_DBM, write_bag, write_pcaps

from rplearn.data.sync import synchronise
from rplearn.data.tables import MATCHED_COLUMNS
from rplearn.io import ReaderOptions, detect_format, read_logs
from rplearn.io.files import write_table
from rplearn.io.pcap import read_pcap
from rplearn.io.rosbag import RosbagOptions, read_rosbag
from rplearn.io.tables import read_pose_table, read_signal_table


def _canon(df: pd.DataFrame) -> pd.DataFrame:
    return df.loc[:, list(MATCHED_COLUMNS)].sort_values(["t", "tx"], kind="stable").reset_index(drop=True)


def assert_same_matched(got: pd.DataFrame, want: pd.DataFrame) -> None:
    got, want = _canon(got), _canon(want)
    assert len(got) == len(want) > 100
    assert (got["tx"].to_numpy() == want["tx"].to_numpy()).all()
    assert (got["rx"].to_numpy() == want["rx"].to_numpy()).all()
    np.testing.assert_allclose(got["t"], want["t"], rtol=0, atol=2e-6)
    num = [c for c in MATCHED_COLUMNS if c not in ("t", "tx", "rx")]
    np.testing.assert_allclose(got[num].to_numpy(), want[num].to_numpy(), rtol=1e-9, atol=1e-5)


@pytest.fixture(scope="module")
def reference(flight):
    pose, sig = flight
    return synchronise(pose, sig).dataset


@pytest.mark.parametrize("ext", ["csv", "parquet"])
def test_tables_round_trip(tmp_path, flight, reference, ext):
    pose, sig = flight
    write_table(pose, str(tmp_path / f"pose.{ext}"))
    write_table(sig, str(tmp_path / f"signal.{ext}"))
    p, pmeta = read_pose_table(str(tmp_path / f"pose.{ext}"))
    s, _ = read_signal_table(str(tmp_path / f"signal.{ext}"))
    assert pmeta["format"] == ext and pmeta["position"] == "enu"
    assert_same_matched(synchronise(p, s).dataset, reference)
    logs, meta = read_logs([tmp_path / f"pose.{ext}", tmp_path / f"signal.{ext}"])
    assert [f["kind"] for f in meta["files"]] == ["pose", "signal"]
    assert_same_matched(synchronise(logs.pose, logs.signal).dataset, reference)


@pytest.mark.parametrize("kind", ["sqlite3", "mcap", "ros1"])
def test_rosbag_round_trip(tmp_path, flight, reference, kind):
    pose, sig = flight
    path = tmp_path / ("flight.bag" if kind == "ros1" else "flight_bag")
    write_bag(path, pose, sig, kind)
    assert detect_format(path) == ("ros1" if kind == "ros1" else "ros2")
    logs, meta = read_rosbag(
        path, POSE_TOPICS, RSSI_TOPICS, rssi_field="rssi_dbm", tx_power_dbm=TX_POWER_DBM,
        frequency_hz=FREQUENCY_HZ, options=RosbagOptions(msg_definitions={RSSI_MSG: RSSI_MSGDEF}),
    )
    assert meta["format"] == ("ros1" if kind == "ros1" else "ros2")
    assert meta["topics"]["/A/odom"] == int((pose["node"] == "A").sum())
    assert len(logs.signal) == len(sig)
    assert_same_matched(synchronise(logs.pose, logs.signal).dataset, reference)


def test_rosbag_custom_type_from_definition_file(tmp_path, flight):
    """The RSSI type is registered from a .msg file; a field path that is wrong says so."""
    pose, sig = flight
    path = write_bag(tmp_path / "b", pose.iloc[::10], sig.iloc[::10], "mcap")
    msg_file = tmp_path / "LinkQuality.msg"
    msg_file.write_text(RSSI_MSGDEF)
    logs, _ = read_rosbag(path, POSE_TOPICS, RSSI_TOPICS, rssi_field="rssi_dbm",
                          tx_power_dbm=20.0, frequency_hz=2.4e9,
                          options=RosbagOptions(msg_definitions={RSSI_MSG: str(msg_file)}))
    np.testing.assert_array_equal(np.sort(logs.signal["rssi_dbm"]), np.sort(sig.iloc[::10]["rssi_dbm"]))
    from rplearn.errors import InputError

    with pytest.raises(InputError, match=r"/A/rssi: field 'link.rssi' not found"):
        read_rosbag(path, POSE_TOPICS, RSSI_TOPICS, rssi_field="link.rssi", tx_power_dbm=20.0,
                    frequency_hz=2.4e9)
    with pytest.raises(InputError, match=r"/A/rssi: field 'peer' is str, expected a number"):
        read_rosbag(path, POSE_TOPICS, RSSI_TOPICS, rssi_field="peer", tx_power_dbm=20.0,
                    frequency_hz=2.4e9)


def test_pcap_round_trip(tmp_path, flight, reference):
    pose, sig = flight
    caps = write_pcaps(tmp_path, sig)
    amap = {mac: node for node, mac in MAC.items()}
    parts = []
    for rx, p in caps.items():
        assert detect_format(p) == "pcap"
        s, meta = read_pcap(str(p), rx, TX_POWER_DBM, address_map=amap)
        assert sum(meta["dropped"].values()) == 0
        assert set(s["noise_dbm"]) == {-95.0} and set(s["antenna"]) == {1.0}
        parts.append(s)
    s = pd.concat(parts, ignore_index=True)
    got = synchronise(pose, s).dataset
    assert_same_matched(got, reference)
    # and through the dispatcher, with the pose log as CSV
    write_table(pose, str(tmp_path / "pose.csv"))
    logs, _ = read_logs([tmp_path / "pose.csv", *caps.values()],
                        ReaderOptions(receivers={str(p): rx for rx, p in caps.items()},
                                      address_map=amap, tx_power_dbm=TX_POWER_DBM))
    assert_same_matched(synchronise(logs.pose, logs.signal).dataset, reference)


def test_pcapng_round_trip(tmp_path, flight, reference):
    from rplearn.io.pcap import write_radiotap_pcap

    pose, sig = flight
    amap = {mac: node for node, mac in MAC.items()}
    parts = []
    for rx in ("A", "B"):
        sel = sig[sig["rx"] == rx]
        p = tmp_path / f"cap_{rx}.pcapng"
        write_radiotap_pcap(str(p), sel["t"].to_numpy(), sel["rssi_dbm"].to_numpy(),
                            [MAC[tx] for tx in sel["tx"]], FREQUENCY_HZ, pcapng=True)
        assert p.read_bytes()[:4] == b"\x0a\x0d\x0d\x0a" and detect_format(p) == "pcap"
        s, meta = read_pcap(str(p), rx, TX_POWER_DBM, address_map=amap)
        assert len(s) == len(sel) and meta["frames"] == len(sel)
        parts.append(s)
    assert_same_matched(synchronise(pose, pd.concat(parts, ignore_index=True)).dataset, reference)


def test_ros2_bag_without_embedded_definitions(tmp_path, flight):
    """Like a ROS 2 Humble bag: no definitions inside; the custom type comes from the user."""
    import sqlite3

    from rplearn.errors import InputError, LogFormatError

    pose, sig = flight
    path = write_bag(tmp_path / "old", pose.iloc[::20], sig.iloc[::20], "sqlite3")
    db = next(path.glob("*.db3"))
    con = sqlite3.connect(db)
    con.execute("DELETE FROM message_definitions")
    con.commit()
    con.close()
    with pytest.raises(LogFormatError) as e:
        read_rosbag(path, POSE_TOPICS, RSSI_TOPICS, rssi_field="rssi_dbm", tx_power_dbm=20.0,
                    frequency_hz=2.4e9)
    assert "register its definition (msg_definitions=" in str(e.value) and e.value.param == "msg_definitions"
    assert "msg_definitions=" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(InputError, match="missing.msg: no such file"):
        read_rosbag(path, POSE_TOPICS, RSSI_TOPICS, rssi_field="rssi_dbm", tx_power_dbm=20.0,
                    frequency_hz=2.4e9, options=RosbagOptions(msg_definitions={RSSI_MSG: "missing.msg"}))
    logs, _ = read_rosbag(path, POSE_TOPICS, RSSI_TOPICS, rssi_field="rssi_dbm", tx_power_dbm=20.0,
                          frequency_hz=2.4e9, options=RosbagOptions(msg_definitions={RSSI_MSG: RSSI_MSGDEF}))
    assert len(logs.signal) == len(sig.iloc[::20])
    assert len(logs.pose) == len(pose.iloc[::20])


def test_synthetic_fallback_flight_round_trips(tmp_path):
    """The fixture's own flight (used when rplearn.sim.flight is absent) is valid and round-trips."""
    from flightfiles import _synthetic_flight

    pose, sig = _synthetic_flight()
    want = synchronise(pose, sig).dataset
    caps = write_pcaps(tmp_path, sig)
    amap = {mac: node for node, mac in MAC.items()}
    got = pd.concat([read_pcap(str(p), rx, TX_POWER_DBM, address_map=amap)[0] for rx, p in caps.items()])
    assert_same_matched(synchronise(pose, got).dataset, want)


@pytest.mark.parametrize("bad, field", [({"tx_power_field": ""}, "tx_power_field"), ({"frequency_field": 5}, "frequency_field"),
                                        ({"msg_definitions": "Type.msg"}, "msg_definitions"),
                                        ({"time_source": "wall"}, "time_source")])
def test_rosbag_options_refuse_a_bad_value_naming_it(bad, field):
    from rplearn.errors import InputError

    with pytest.raises(InputError) as err:
        RosbagOptions(**bad)
    assert err.value.param == field and "\n" not in str(err.value)
