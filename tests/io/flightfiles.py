"""Helpers of tests/io: one simulated flight, writers putting it in every format, and ``rplearn``
run in this process."""

from __future__ import annotations

import functools
import subprocess
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

DATA = Path(__file__).resolve().parents[1] / "fixtures"
EPOCH_S = 1_700_000_000.0  # put the flight on a realistic UNIX time, as real logs are
MAC = {"A": "02:00:00:00:00:0a", "B": "02:00:00:00:00:0b"}
RSSI_MSG = "rplearn_msgs/msg/LinkQuality"
RSSI_MSGDEF = "std_msgs/Header header\nfloat32 rssi_dbm\nstring peer\n"
POSE_TYPES = {"A": "nav_msgs/msg/Odometry", "B": "geometry_msgs/msg/PoseWithCovarianceStamped"}
POSE_TOPICS = {"/A/odom": "A", "/B/pose": "B"}
RSSI_TOPICS = {"/A/rssi": ("B", "A"), "/B/rssi": ("A", "B")}
TX_POWER_DBM = 20.0
FREQUENCY_HZ = 2.412e9


@functools.lru_cache(maxsize=1)
def _ground_logs() -> tuple[pd.DataFrame, pd.DataFrame]:
    from rplearn.sim.flight import simulate

    sim = simulate("ground", seed=1)
    return sim.pose_log, sim.signal_log


def ground_simulation() -> tuple[pd.DataFrame, pd.DataFrame]:
    """The ``ground`` preset's pose and signal log (seed 1), simulated once per process (per
    xdist worker; the same seed gives the same flight): each caller gets its own copies, so
    that no test reads what another one changed."""
    pose, signal = _ground_logs()
    return pose.copy(), signal.copy()


def ground_flight(station_yaw_enu_deg: float) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The ``ground`` preset's flight (seed 1), its station one static row as a tlog holds it (a
    tlog cannot log the station's pose): its median position at its first time, facing
    ``station_yaw_enu_deg`` (ENU, its true heading). Returns the pose and the signal log."""
    from rplearn.core.geometry import quat_wxyz_from_yaw

    pose, signal = ground_simulation()
    g = pose[pose["node"] == "G"]
    q = quat_wxyz_from_yaw(np.radians(station_yaw_enu_deg))
    station = pd.DataFrame({"t": [g["t"].min()], "node": ["G"], "x": [g["x"].median()], "y": [g["y"].median()],
                            "z": [g["z"].median()], "qw": [q[0]], "qx": [q[1]], "qy": [q[2]], "qz": [q[3]]})
    return pd.concat([pose[pose["node"] == "D"], station], ignore_index=True), signal


def simulated_dataflash(path: Path, seed: int = 3, station_xyz: tuple[float, float, float] | None = None) -> Path:
    """The ``smoke`` preset's flight (``seed``) as a DataFlash log written by :mod:`rplearn.io.dataflash_writer`
    (thousands of ATT, POS and RAD; vehicle A, station B): B one static row at its first pose, or at ``station_xyz``
    (ENU [m]: two flights' logs from one home). Returns ``path``."""
    from rplearn.io._common import Logs
    from rplearn.io.dataflash_writer import write_dataflash
    from rplearn.sim.flight import simulate

    sim = simulate("smoke", seed=seed)
    pose, signal = sim.pose_log, sim.signal_log
    station = pose[pose["node"] == "B"].iloc[[0]]
    if station_xyz is not None:
        station = station.assign(x=station_xyz[0], y=station_xyz[1], z=station_xyz[2])
    logs = Logs(pd.concat([pose[pose["node"] == "A"], station], ignore_index=True),
                signal[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]])
    write_dataflash(logs, path, vehicle="A", station="B", origin_geodetic=(47.3977, 8.5456, 90.0))
    return path


def _synthetic_flight() -> tuple[pd.DataFrame, pd.DataFrame]:
    """Two drones circling, poses at 100 Hz, packets at 80 Hz each way, integer RSSI."""
    t = np.arange(0.0, 6.0, 0.01)
    rows = []
    for node, radius, phase, z in (("A", 5.0, 0.0, 3.0), ("B", 8.0, np.pi, 4.0)):
        ang = 0.4 * t + phase
        yaw = ang + np.pi / 2
        roll = 0.1 * np.sin(2 * t)
        from rplearn.core.geometry import quat_wxyz_from_euler

        q = quat_wxyz_from_euler(roll, 0.05 * np.cos(t), yaw)
        rows.append(pd.DataFrame({"t": t, "node": node, "x": radius * np.cos(ang),
                                  "y": radius * np.sin(ang), "z": z + 0.2 * np.sin(t),
                                  "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3]}))
    pose = pd.concat(rows, ignore_index=True)
    ts = np.arange(0.005, 5.99, 0.0125)
    rng = np.random.default_rng(0)
    sig = pd.DataFrame({
        "t": np.concatenate([ts, ts + 0.004]),
        "tx": ["A"] * len(ts) + ["B"] * len(ts),
        "rx": ["B"] * len(ts) + ["A"] * len(ts),
        "rssi_dbm": np.round(rng.uniform(-80, -30, 2 * len(ts))),
        "tx_power_dbm": TX_POWER_DBM,
        "frequency_hz": FREQUENCY_HZ,
    }).sort_values("t", kind="stable").reset_index(drop=True)
    return pose, sig


@pytest.fixture(scope="session")
def flight() -> tuple[pd.DataFrame, pd.DataFrame]:
    """Canonical (pose, signal) logs of one flight on UNIX time.

    The colleague's simulator (``rplearn.sim.flight``, preset "smoke") when it is available,
    else a small synthetic flight of two drones circling.
    """
    try:
        from rplearn.sim.flight import simulate

        res = simulate("smoke", seed=0)
        pose, sig = res.pose_log.copy(), res.signal_log.copy()
        assert set(pose["node"]) == {"A", "B"}
    except ImportError:
        pose, sig = _synthetic_flight()
    pose["t"] = pose["t"] + EPOCH_S
    sig["t"] = sig["t"] + EPOCH_S
    sig["rssi_dbm"] = np.round(sig["rssi_dbm"])  # pcap stores an integer dBm
    sig = sig[["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]]
    return pose.reset_index(drop=True), sig.reset_index(drop=True)


# ------------------------------------------------------------------------------------------
# writers


def _time(types, t_s: float, ros1: bool):
    sec = int(np.floor(t_s))
    nsec = int(round((t_s - sec) * 1e9))
    if nsec >= 1_000_000_000:
        sec, nsec = sec + 1, nsec - 1_000_000_000
    return types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec), sec * 1_000_000_000 + nsec


def _header(types, stamp, ros1: bool, seq: int, frame: str):
    H = types["std_msgs/msg/Header"]
    return H(seq=seq, stamp=stamp, frame_id=frame) if ros1 else H(stamp=stamp, frame_id=frame)


def _pose_msg(types, row, header, msgtype: str):
    P = types["geometry_msgs/msg/Point"](x=float(row.x), y=float(row.y), z=float(row.z))
    Q = types["geometry_msgs/msg/Quaternion"](x=float(row.qx), y=float(row.qy), z=float(row.qz), w=float(row.qw))
    pose = types["geometry_msgs/msg/Pose"](position=P, orientation=Q)
    if msgtype == "geometry_msgs/msg/PoseStamped":
        return types[msgtype](header=header, pose=pose)
    pwc = types["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36))
    if msgtype == "geometry_msgs/msg/PoseWithCovarianceStamped":
        return types[msgtype](header=header, pose=pwc)
    V = types["geometry_msgs/msg/Vector3"]
    twist = types["geometry_msgs/msg/Twist"](linear=V(x=0.0, y=0.0, z=0.0), angular=V(x=0.0, y=0.0, z=0.0))
    twc = types["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36))
    return types[msgtype](header=header, child_frame_id="base_link", pose=pwc, twist=twc)


def write_bag(path: Path, pose: pd.DataFrame, sig: pd.DataFrame, kind: str,
              pose_types: dict[str, str] = POSE_TYPES, copies: int = 1) -> Path:
    """Write the flight as a bag with the rosbags writer: kind "sqlite3", "mcap" or "ros1";
    every message ``copies`` times (a recorder writing each twice, say)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ros1 = kind == "ros1"
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_JAZZY)
    store.register(get_types_from_msg(RSSI_MSGDEF, RSSI_MSG))
    types = store.types
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    if ros1:
        from rosbags.rosbag1 import Writer

        writer = Writer(path)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        writer = Writer(path, version=9, storage_plugin=plugin)
    msgs = []
    with writer:
        conns = {}
        for topic, node in POSE_TOPICS.items():
            conns[topic] = writer.add_connection(topic, pose_types[node], typestore=store)
        for topic in RSSI_TOPICS:
            conns[topic] = writer.add_connection(topic, RSSI_MSG, typestore=store)
        for topic, node in POSE_TOPICS.items():
            for i, row in enumerate(pose[pose["node"] == node].itertuples()):
                stamp, ns = _time(types, row.t, ros1)
                msg = _pose_msg(types, row, _header(types, stamp, ros1, i, "map"), pose_types[node])
                msgs.append((ns, topic, msg))
        for topic, (tx, rx) in RSSI_TOPICS.items():
            sel = sig[(sig["tx"] == tx) & (sig["rx"] == rx)]
            for i, row in enumerate(sel.itertuples()):
                stamp, ns = _time(types, row.t, ros1)
                msg = types[RSSI_MSG](header=_header(types, stamp, ros1, i, rx),
                                      rssi_dbm=float(row.rssi_dbm), peer=tx)
                msgs.append((ns, topic, msg))
        msgs.sort(key=lambda m: m[0])
        for ns, topic, msg in msgs:
            for _ in range(copies):
                writer.write(conns[topic], ns, serialize(msg, msg.__msgtype__))
    return path


def write_pcaps(directory: Path, sig: pd.DataFrame) -> dict[str, Path]:
    """One radiotap capture per receiver, frames sent from the transmitter's MAC address."""
    from rplearn.io.pcap import RadiotapFields, write_radiotap_pcap

    out = {}
    for rx in sorted(set(sig["rx"])):
        sel = sig[sig["rx"] == rx]
        p = directory / f"capture_{rx}.pcap"
        write_radiotap_pcap(str(p), sel["t"].to_numpy(), sel["rssi_dbm"].to_numpy(),
                            [MAC[tx] for tx in sel["tx"]], FREQUENCY_HZ, RadiotapFields(noise_dbm=-95, antenna=1))
        out[rx] = p
    return out


def rplearn_here(args: Sequence[object]) -> subprocess.CompletedProcess[str]:
    """``rplearn ARGS`` in this process (typer's ``CliRunner``), answered as ``subprocess.run``
    answers (exit code, stdout and stderr apart), for a command that succeeds and whose output
    a test reads: a process of its own would only add its second of start-up. Refusals, whose
    exit code and one stderr line are the point, stay processes."""
    from typer.testing import CliRunner

    from rplearn.cli import app

    res = CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
    stderr = res.stderr + ("" if res.exception is None or isinstance(res.exception, SystemExit)
                           else f"{type(res.exception).__name__}: {res.exception}")
    return subprocess.CompletedProcess([str(a) for a in args], res.exit_code, res.stdout, stderr)
