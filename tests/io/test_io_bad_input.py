"""Acceptance 3: bad input gives a one-line error naming file and field, or a counted drop."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rplearn.errors import InputError, LogFormatError, RplearnError
from rplearn.io import ReaderOptions, read_logs
from rplearn.io.pcap import RadiotapFields, read_pcap, write_radiotap_pcap
from rplearn.io.rosbag import read_rosbag
from rplearn.io.tables import read_pose_table, read_signal_table
from rplearn.io.ulog import read_ulog

DATA = Path(__file__).resolve().parents[1] / "fixtures"

POSE_CSV = (
    "t,node,x,y,z,qw,qx,qy,qz\n"
    "0.0,A,0,0,1,1,0,0,0\n"
    "0.1,A,1,0,1,1,0,0,0\n"
    "0.2,A,2,0,1,1,0,0,0\n"
    "0.0,B,5,5,0,1,0,0,0\n"
)


def one_line(exc: BaseException) -> str:
    msg = str(exc)
    assert "\n" not in msg
    return msg


def write(tmp_path: Path, text: str, name: str = "pose.csv") -> str:
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def test_good_pose_csv_with_static_node(tmp_path):
    pose, meta = read_pose_table(write(tmp_path, POSE_CSV))
    assert len(pose) == 4 and (pose["node"] == "B").sum() == 1
    assert meta["dropped"]["nan_pose"] == 0


def test_missing_column(tmp_path):
    p = write(tmp_path, POSE_CSV.replace(",qz", ",q_z"))
    with pytest.raises(InputError) as e:
        read_pose_table(p)
    assert p in one_line(e.value) and "attitude columns" in str(e.value)
    p = write(tmp_path, "t,tx,rx,rssi_dbm\n0,A,B,-50\n", "sig.csv")
    with pytest.raises(InputError, match=r"sig.csv: missing column\(s\) tx_power_dbm, frequency_hz"):
        read_signal_table(p)
    sig, _ = read_signal_table(p, tx_power_dbm=20.0, frequency_hz=2.4e9)
    assert sig["tx_power_dbm"].tolist() == [20.0]


def test_nan_pose_error_or_counted_drop(tmp_path):
    p = write(tmp_path, POSE_CSV.replace("0.1,A,1,0,1", "0.1,A,nan,0,1"))
    with pytest.raises(InputError) as e:
        read_pose_table(p)
    assert p in one_line(e.value) and "field x" in str(e.value) and "row 1" in str(e.value)
    pose, meta = read_pose_table(p, nan_policy="drop")
    assert len(pose) == 3 and meta["dropped"]["nan_pose"] == 1


@pytest.mark.parametrize("value", ["1e308", "-2e8"])
def test_a_coordinate_beyond_any_place_is_refused_or_a_counted_drop(tmp_path, value):
    """A sentinel (1e308) or corrupt x: no place in any frame, and the distances from it overflow to
    infinite joint gains (it was matched, and fit refused with a line naming no file)."""
    p = write(tmp_path, POSE_CSV.replace("0.1,A,1,0,1", f"0.1,A,{value},0,1"))
    with pytest.raises(InputError) as e:
        read_pose_table(p)
    assert one_line(e.value).startswith(f"{p}: field x has 1 row(s) with NaN, infinite or non-numeric values or "
                                        "coordinates beyond 1e8 m (first at row 1)")
    pose, meta = read_pose_table(p, nan_policy="drop")
    assert len(pose) == 3 and meta["dropped"] == {"nan_pose": 0, "implausible_pose": 1, "duplicate_pose": 0, "conflicting_pose": 0,
                                             "position_jump": 0, "repeated_header": 0}
    utm = POSE_CSV.replace(",A,0,0,1", ",A,4.5e5,5.2e6,1").replace(",A,1,0,1", ",A,450001,5.2e6,1")
    utm = write(tmp_path, utm.replace(",A,2,0,1", ",A,450002,5.2e6,1"))  # UTM eastings and northings
    assert len(read_pose_table(utm)[0]) == 4


def test_unsorted_and_duplicate_timestamps(tmp_path):
    lines = POSE_CSV.splitlines()
    unsorted = "\n".join([lines[0], lines[2], lines[1], lines[3], lines[4]]) + "\n"
    p = write(tmp_path, unsorted)
    with pytest.raises(LogFormatError) as e:
        read_pose_table(p)
    assert p in one_line(e.value) and "field t goes backwards at row 1" in str(e.value)
    assert len(read_pose_table(p, allow_unsorted=True)[0]) == 4
    dup = write(tmp_path, POSE_CSV + "0.2,A,2,0,1,1,0,0,0\n", "dup.csv")  # a copy of row 2: dropped, counted
    pose, meta = read_pose_table(dup)
    assert len(pose) == 4 and meta["dropped"]["duplicate_pose"] == 1
    dup = write(tmp_path, POSE_CSV + "0.2,A,3,0,1,1,0,0,0\n", "dup.csv")  # another pose of row 2's time
    with pytest.raises(InputError) as e:
        read_pose_table(dup)
    assert one_line(e.value).startswith(f"{dup}: field x: 2 pose row(s) share a node and time") and "rows 2 and 4" in str(e.value)


def test_geodetic_and_euler_variants(tmp_path):
    text = (
        "time,drone,lat,lon,alt,roll_ned_deg,pitch_ned_deg,yaw_ned_deg\n"
        "0.0,A,47.0,8.0,500,0,0,0\n"
        "1.0,A,47.0001,8.0,510,0,0,90\n"
    )
    pose, meta = read_pose_table(write(tmp_path, text))
    assert meta["position"] == "geodetic" and meta["attitude"] == "euler_ned_frd"
    assert meta["origin_geodetic"] == (47.0, 8.0, 500.0)
    np.testing.assert_allclose(pose[["x", "y", "z"]].iloc[0], [0, 0, 0], atol=1e-9)
    # 0.0001 deg of latitude north is ~11.1 m north (ENU y), 10 m up
    np.testing.assert_allclose(pose[["x", "y", "z"]].iloc[1], [0, 11.12, 10.0], atol=0.02)
    # heading north (NED yaw 0) is ENU yaw +90 deg; heading east (NED yaw 90) is ENU yaw 0
    np.testing.assert_allclose(pose[["qw", "qz"]].iloc[0], [np.sqrt(0.5), np.sqrt(0.5)], atol=1e-12)
    np.testing.assert_allclose(pose[["qw", "qz"]].iloc[1], [1.0, 0.0], atol=1e-12)
    enu = "t,node,x,y,z,roll_deg,pitch_deg,yaw_deg\n0,A,0,0,0,0,0,90\n"
    pose, meta = read_pose_table(write(tmp_path, enu, "enu.csv"))
    np.testing.assert_allclose(pose[["qw", "qz"]].iloc[0], [np.sqrt(0.5), np.sqrt(0.5)], atol=1e-12)
    bad = write(tmp_path, text.replace("47.0001", "147.0"), "bad.csv")
    with pytest.raises(InputError, match=r"bad.csv: field lat has 1 row\(s\) .* outside -90 to 90 deg .*first at row 1\)"):
        read_pose_table(bad)
    pose, meta = read_pose_table(bad, nan_policy="drop")  # no latitude: a sentinel or corrupt value, dropped
    assert len(pose) == 1 and meta["dropped"]["implausible_pose"] == 1


def test_column_mapping(tmp_path):
    text = "stamp,who,E,N,U,qw,qx,qy,qz\n0,A,1,2,3,1,0,0,0\n"
    pose, _ = read_pose_table(write(tmp_path, text),
                              columns={"stamp": "t", "who": "node", "E": "x", "N": "y", "U": "z"})
    assert pose[["x", "y", "z"]].iloc[0].tolist() == [1.0, 2.0, 3.0]


def test_empty_and_missing_files(tmp_path):
    with pytest.raises(LogFormatError, match="empty file"):
        read_pose_table(write(tmp_path, ""))
    with pytest.raises(InputError, match="no such file"):
        read_pose_table(str(tmp_path / "nope.csv"))
    with pytest.raises(InputError, match="unknown log format"):
        read_logs(write(tmp_path, "hello", "x.txt"))


@pytest.mark.parametrize("name", ["d.csv", "d.parquet"])
def test_an_empty_dataset_file_is_said_empty(tmp_path, name):
    from rplearn.io.files import read_dataset

    (tmp_path / name).write_bytes(b"")  # was "cannot read table (EmptyDataError: No columns to parse from file)"
    with pytest.raises(RplearnError, match=rf"{name}: empty file \(0 bytes\), not a table"):
        read_dataset(str(tmp_path / name))


def test_a_dataset_file_of_blank_lines_is_said_empty(tmp_path):
    from rplearn.io.files import read_dataset

    (tmp_path / "d.csv").write_bytes(b"\n  \r\n\n")  # was "cannot read table (EmptyDataError: ...)"
    with pytest.raises(RplearnError, match=r"d.csv: empty file \(6 bytes of blank lines\), not a table"):
        read_dataset(str(tmp_path / "d.csv"))


def _small_pcap(path: Path) -> Path:
    write_radiotap_pcap(str(path), np.array([1.0, 1.1, 1.2]), np.array([-40, -127, -60]),
                        ["02:00:00:00:00:0a"] * 3, 2.412e9, RadiotapFields(noise_dbm=-95))
    return path


def test_truncated_pcap(tmp_path):
    good = _small_pcap(tmp_path / "c.pcap")
    data = good.read_bytes()
    cut = tmp_path / "cut.pcap"
    cut.write_bytes(data[: len(data) - 20])
    try:
        sig, meta = read_pcap(str(cut), "rx", 20.0)
        assert len(sig) < 3  # a truncated last record is either reported or not returned
    except LogFormatError as e:
        assert "cut.pcap" in one_line(e)
    head = tmp_path / "head.pcap"
    head.write_bytes(data[:10])
    with pytest.raises(LogFormatError, match="head.pcap"):
        read_pcap(str(head), "rx", 20.0)
    eth = tmp_path / "eth.pcap"
    eth.write_bytes(data[:20] + (1).to_bytes(4, "little") + data[24:])
    with pytest.raises(LogFormatError, match=r"eth.pcap: link type 1, expected 127"):
        read_pcap(str(eth), "rx", 20.0)


@pytest.mark.parametrize("name", ["ieee802.11_exthdr.pcap", "ieee802.11_htc.pcap"])
def test_captures_concatenated_are_refused_naming_where_the_second_starts(tmp_path, name):
    data = (DATA / "radiotap-pcap" / name).read_bytes()
    twice = tmp_path / "twice.pcap"
    twice.write_bytes(data + data)  # was "truncated capture: the file ends inside frame 28"
    with pytest.raises(LogFormatError, match=rf"twice.pcap: another capture's file header at byte {len(data):,}"):
        read_pcap(str(twice), "rx", 20.0)


def test_a_capture_of_another_kind_after_the_first_is_named_too(tmp_path):
    # review 38: a nanosecond capture after a microsecond one was "truncated capture: the file
    # ends inside frame 3" (its header read as a record)
    first = (DATA / "radiotap-pcap" / "ieee802.11_htc.pcap").read_bytes()
    second = (DATA / "radiotap-pcap" / "ieee802.11_exthdr.pcap").read_bytes()
    both = tmp_path / "both.pcap"
    both.write_bytes(first + b"\x4d\x3c\xb2\xa1" + second[4:])
    with pytest.raises(LogFormatError, match=rf"both.pcap: another capture's file header at byte {len(first):,}"):
        read_pcap(str(both), "rx", 20.0)


def test_pcap_sentinel_rssi_is_counted_by_sync(tmp_path):
    from rplearn.data.sync import synchronise

    sig, _ = read_pcap(str(_small_pcap(tmp_path / "c.pcap")), "B", 20.0,
                       address_map={"02:00:00:00:00:0A": "A"})
    pose = pd.DataFrame({"t": [0.0, 0.0], "node": ["A", "B"], "x": [0, 5.0], "y": 0.0, "z": 0.0,
                         "qw": 1.0, "qx": 0.0, "qy": 0.0, "qz": 0.0})
    res = synchronise(pose, sig)
    assert res.summary.dropped["sentinel_rssi"] == 1 and res.summary.n_out == 2


def test_corrupt_ulog_and_bag(tmp_path):
    src = (DATA / "px4-ulog" / "sample_log_small.ulg").read_bytes()
    bad = tmp_path / "bad.ulg"
    bad.write_bytes(src[:200])
    with pytest.raises(RplearnError) as e:
        read_ulog(bad, "a")
    assert "bad.ulg" in one_line(e.value)
    junk = tmp_path / "junk.ulg"
    junk.write_bytes(b"ULog\x01\x12\x35" + bytes(range(256)) * 4)
    with pytest.raises(RplearnError, match="junk.ulg"):
        read_ulog(junk, "a")
    bag = tmp_path / "cut.bag"
    bag.write_bytes((DATA / "ros1-bag" / "test2.bag").read_bytes()[:5000])
    with pytest.raises(LogFormatError) as e:
        read_rosbag(bag, {"/jackal_velocity_controller/odom": "j"})
    assert "cut.bag" in one_line(e.value)
    good = tmp_path / "good.bag"
    shutil.copy(DATA / "ros1-bag" / "test2.bag", good)
    with pytest.raises(InputError, match=r"good.bag: topic\(s\) /nope not in the bag"):
        read_rosbag(good, {"/nope": "j"})
    with pytest.raises(InputError, match=r"topic /imu/data is sensor_msgs/msg/Imu; expected one of"):
        read_rosbag(good, {"/imu/data": "j"})


# ---------------------------------------------------------------------------- fuzzing

FUZZ = settings(max_examples=120, deadline=None, suppress_health_check=list(HealthCheck))


def _only_own_errors(fn, *args, **kwargs):
    try:
        fn(*args, **kwargs)
    except RplearnError as e:
        one_line(e)


@FUZZ
@given(st.binary(max_size=600))
def test_fuzz_csv_random_bytes(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("f") / "x.csv"
    p.write_bytes(data)
    _only_own_errors(read_pose_table, str(p))
    _only_own_errors(read_signal_table, str(p), tx_power_dbm=1.0, frequency_hz=1e9, rx="r")
    _only_own_errors(read_logs, str(p))


@FUZZ
@given(st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 255)), min_size=1, max_size=8),
       st.integers(0, 400))
def test_fuzz_csv_mutated(tmp_path_factory, edits, cut):
    raw = bytearray((POSE_CSV * 3).encode())
    for pos, val in edits:
        raw[pos % len(raw)] = val
    data = bytes(raw[: max(1, len(raw) - cut)])
    p = tmp_path_factory.mktemp("f") / "x.csv"
    p.write_bytes(data)
    _only_own_errors(read_pose_table, str(p))
    _only_own_errors(read_pose_table, str(p), nan_policy="drop", allow_unsorted=True)
    sig = tmp_path_factory.mktemp("s") / "s.csv"
    sig.write_bytes(bytes(raw).replace(b"node", b"tx"))
    _only_own_errors(read_signal_table, str(sig), tx_power_dbm=1.0, frequency_hz=1e9, rx="r")


@FUZZ
@given(st.binary(max_size=400))
def test_fuzz_pcap_random_bytes(tmp_path_factory, data):
    d = tmp_path_factory.mktemp("p")
    for head in (b"", b"\xd4\xc3\xb2\xa1", b"\x0a\x0d\x0d\x0a"):
        p = d / "x.pcap"
        p.write_bytes(head + data)
        _only_own_errors(read_pcap, str(p), "rx", 20.0)


_PCAP_SEEDS = [(DATA / "radiotap-pcap" / n).read_bytes()
               for n in ("ieee802.11_exthdr.pcap", "ieee802.11_meshid.pcap", "ieee802.11_rx-stbc.pcap")]


@FUZZ
@given(st.sampled_from(range(len(_PCAP_SEEDS))),
       st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 255)), min_size=1, max_size=12),
       st.integers(0, 300))
def test_fuzz_pcap_mutated(tmp_path_factory, which, edits, cut):
    raw = bytearray(_PCAP_SEEDS[which])
    for pos, val in edits:
        raw[pos % len(raw)] = val
    p = tmp_path_factory.mktemp("p") / "x.pcap"
    p.write_bytes(bytes(raw[: max(1, len(raw) - cut)]))
    _only_own_errors(read_pcap, str(p), "rx", 20.0)
    _only_own_errors(read_logs, str(p), ReaderOptions(receivers={str(p): "rx"}, tx_power_dbm=20.0))


def test_pcap_unmapped_addresses_are_counted(tmp_path):
    path = _small_pcap(tmp_path / "c.pcap")
    sig, meta = read_pcap(str(path), "B", 20.0, address_map={"02:00:00:00:00:99": "Z"})
    assert len(sig) == 0 and meta["dropped"]["unmapped_address"] == 3
    assert meta["addresses"] == {"02:00:00:00:00:0a": 3}


def test_geodetic_tables_share_the_first_origin(tmp_path):
    a = write(tmp_path, "t,lat,lon,alt,qw,qx,qy,qz\n0,47.0,8.0,500,1,0,0,0\n1,47.0,8.0,501,1,0,0,0\n", "a.csv")
    b = write(tmp_path, "t,lat,lon,alt,qw,qx,qy,qz\n0,47.0,8.001,500,1,0,0,0\n", "b.csv")
    logs, meta = read_logs([a, b], ReaderOptions(nodes={a: "A", b: "B"}))
    assert meta["origin_geodetic"] == (47.0, 8.0, 500.0)
    bx = logs.pose.loc[logs.pose["node"] == "B", ["x", "y"]].to_numpy()[0]
    # 0.001 deg of longitude at 47 deg N is ~76 m east
    assert bx[0] == pytest.approx(76.0, abs=0.5) and abs(bx[1]) < 0.01


@pytest.mark.parametrize("field, value", [
    ("nan_policy", "skip"), ("allow_unsorted", "yes"), ("require_valid", None), ("rssi_field", ""),
    ("origin_geodetic", (47.0, 8.0)), ("origin_geodetic", (95.0, 8.0, 0.0)), ("tx_power_dbm", float("nan")),
    ("tx_power_dbm", {"A": "x"}), ("frequency_hz", -1.0), ("nodes", ["a.ulg"]), ("rssi_topics", {"/r": "A"}),
])
def test_reader_options_name_the_field_at_fault(field, value):
    with pytest.raises(InputError, match=f"^{field}: ") as e:
        ReaderOptions(**{field: value})
    assert e.value.param == field and "--" not in one_line(e.value)


def test_reader_options_defaults_and_normalisation(tmp_path):
    opts = ReaderOptions(nodes={tmp_path / "a.ulg": "A"}, origin_geodetic=[47, 8, 500], rssi_topics={"/r": ["A", "B"]})
    assert opts.nodes == {str(tmp_path / "a.ulg"): "A"} and opts.origin_geodetic == (47.0, 8.0, 500.0)
    assert opts.rssi_topics == {"/r": ("A", "B")}
    d = ReaderOptions()
    assert (d.rssi_field, d.nan_policy, d.allow_unsorted, d.require_valid, d.tx_power_dbm) == ("rssi", "error", False, False, None)
    with pytest.raises(InputError, match="expected a ReaderOptions") as e:
        read_logs(write(tmp_path, POSE_CSV), {"nan_policy": "drop"})
    assert e.value.param == "options"


def test_reader_errors_carry_the_field_to_set(tmp_path):
    nan = write(tmp_path, POSE_CSV.replace("0.1,A,1,0,1", "0.1,A,nan,0,1"), "nan.csv")
    with pytest.raises(InputError) as e:
        read_logs(nan)
    assert e.value.param == "nan_policy" and "nan_policy='drop'" in one_line(e.value)
    assert len(read_logs(nan, ReaderOptions(nan_policy="drop"))[0].pose) == 3
    lines = POSE_CSV.splitlines()
    unsorted = write(tmp_path, "\n".join([lines[0], lines[2], lines[1], lines[3]]) + "\n", "unsorted.csv")
    with pytest.raises(LogFormatError) as e:
        read_logs(unsorted)
    assert e.value.param == "allow_unsorted"
    one_node = write(tmp_path, "t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n", "one.csv")
    with pytest.raises(InputError) as e:
        read_logs(one_node)
    assert e.value.param == "nodes" and "ReaderOptions.nodes" in str(e.value)
    assert set(read_logs(one_node, ReaderOptions(nodes={one_node: "A"}))[0].pose["node"]) == {"A"}
    cap = str(_small_pcap(tmp_path / "c.pcap"))
    with pytest.raises(InputError) as e:
        read_logs(cap)
    assert e.value.param == "receivers"
    with pytest.raises(InputError) as e:
        read_logs(cap, ReaderOptions(receivers={cap: "B"}))
    assert e.value.param == "tx_power_dbm"


def test_library_messages_name_no_cli_flags():
    """Messages raised in rplearn.io and rplearn.data name parameters, never command-line flags."""
    import ast
    import re

    flag = re.compile(r"(?<![\w-])--[a-z]")
    root = Path(__file__).resolve().parents[2] / "src" / "rplearn"
    found = []
    for path in sorted([*(root / "io").glob("*.py"), *(root / "data").glob("*.py")]):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Raise) and node.exc is not None:
                texts = [c.value for c in ast.walk(node.exc) if isinstance(c, ast.Constant) and isinstance(c.value, str)]
                found += [f"{path.name}:{node.lineno}" for t in texts if flag.search(t)]
    assert not found, found


def test_a_capture_cut_off_mid_frame_reads_its_complete_frames_and_says_the_cut(tmp_path):
    """dpkt hands on the partial last frame as if whole; the reader stops before it and says
    where the file is cut and how many frames were read (was: the whole capture refused)."""
    from rplearn.io.inspect import inspect_logs

    whole = DATA / "radiotap-pcap" / "ieee802.11_exthdr.pcap"
    cut = tmp_path / "cut.pcap"
    cut.write_bytes(whole.read_bytes()[:300])
    options = ReaderOptions(receivers={str(cut): "B"}, tx_power_dbm=20.0)
    logs, meta = read_logs([str(cut)], options)
    f = meta["files"][0]
    assert f["cut_off_record"] == "frame 2" and f["records_read"] == 1 and f["frames"] == 1
    assert 24 < f["cut_off_at_byte"] < 300
    full, _ = read_logs([str(whole)], ReaderOptions(receivers={str(whole): "B"}, tx_power_dbm=20.0))
    assert len(full.signal) > 0
    pd.testing.assert_frame_equal(logs.signal, full.signal[full.signal["frame"] == 1].reset_index(drop=True))
    text = inspect_logs([str(cut)], options).to_text()
    assert (f"cut.pcap: the file is cut off inside the message at byte {f['cut_off_at_byte']:,} (frame 2)" in text
            and "the 1 complete record(s) before it were read" in text and "none found" not in text)


def test_a_signal_log_whose_clock_restarts_is_refused_within_its_link(tmp_path):
    """A signal table whose times go back within a link (a logger that rebooted) is refused
    naming the file, the row and the link, read whole and read in chunks (the step across a
    chunk boundary); links interleaved out of order are not a step back; ``allow_unsorted``
    takes the rows (sync sorts them); ``inspect`` reports the step instead of refusing."""
    from rplearn.io.inspect import inspect_logs
    from rplearn.io.tables import iter_signal_table

    t = np.arange(0.0, 10.0, 0.5)
    rows = pd.DataFrame({"t": np.concatenate([t, t + 0.25]), "tx": ["A"] * len(t) + ["B"] * len(t),
                         "rx": ["B"] * len(t) + ["A"] * len(t), "rssi_dbm": -60.0, "tx_power_dbm": 20.0,
                         "frequency_hz": 2.4e9})  # B -> A after A -> B: time goes back across links only
    ok = tmp_path / "ok.csv"
    rows.to_csv(ok, index=False)
    assert len(read_signal_table(str(ok))[0]) == 2 * len(t)
    rebooted = rows.copy()
    rebooted.loc[30:, "t"] -= 8.0  # B -> A's logger restarts its clock at file row 30
    bad = tmp_path / "rebooted.csv"
    rebooted.to_csv(bad, index=False)
    for read in (lambda **kw: read_signal_table(str(bad), **kw)[0],
                 lambda **kw: pd.concat(list(iter_signal_table(str(bad), 7, **kw)))):  # row 30 starts no chunk
        with pytest.raises(LogFormatError) as e:
            read()
        assert str(bad) in one_line(e.value) and "field t goes backwards at row 30 (link B -> A: 4.75 -> -2.75" in str(e.value)
        assert len(read(allow_unsorted=True)) == 2 * len(t)
    with pytest.raises(LogFormatError, match="row 30 .*allow_unsorted"):
        read_logs([str(bad)])
    assert len(read_logs([str(bad)], ReaderOptions(allow_unsorted=True))[0].signal) == 2 * len(t)
    report = inspect_logs([str(bad)])
    assert any("link B -> A: time goes backwards 1 time(s)" in p for p in report.problems)
    # doubled records, a block or the whole log written again, are copies (sync drops and counts
    # them), not a clock that restarted: read whole and in chunks
    doubled = tmp_path / "doubled.csv"
    pd.concat([rows.iloc[:30], rows.iloc[25:33], rows.iloc[30:], rows], ignore_index=True).to_csv(doubled, index=False)
    assert len(read_signal_table(str(doubled))[0]) == 4 * len(t) + 8
    assert len(pd.concat(list(iter_signal_table(str(doubled), 7)))) == 4 * len(t) + 8
