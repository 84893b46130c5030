"""``rplearn live`` and ``rplearn replay`` on hostile and messy input (audit48): a pose log that
ends before the signal log, a ``--fixed`` node that never appears, a CSV logger that restarted
appending to its file, outputs that would overwrite each other, bad ``replay`` flags, a silent
MAVLink stream and a corrupt ``.tlog``. Each refusal is one line naming the flag or the file;
each drop is counted by name; live's rows and counts are those of ``sync``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_helpers import invoke


def _tables(n: int = 300, drone_rows: slice = slice(None)) -> tuple[pd.DataFrame, pd.DataFrame]:
    """A drone D circling a station G at 40 m, yawing; 10 Hz poses (``drone_rows`` of them), a packet per 0.1 s."""
    t = np.arange(n) * 0.1
    a = 2 * np.pi * t / 20.0
    yaw = a * 3.0
    drone = pd.DataFrame({"t": t, "node": "D", "x": 40 * np.cos(a), "y": 40 * np.sin(a), "z": 20.0 + 5 * np.sin(a * 2),
                          "qw": np.cos(yaw / 2), "qx": 0.0, "qy": 0.0, "qz": np.sin(yaw / 2)}).iloc[drone_rows]
    station = pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [1.5], "qw": [1.0],
                            "qx": [0.0], "qy": [0.0], "qz": [0.0]})
    rng = np.random.default_rng(3)
    sig = pd.DataFrame({"t": t + 0.05, "tx": "D", "rx": "G", "rssi_dbm": -60.0 + rng.normal(0, 2, n),
                        "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})
    return pd.concat([drone, station], ignore_index=True), sig


def _write(d: Path, pose: pd.DataFrame, sig: pd.DataFrame) -> str:
    pose.to_csv(d / "pose.csv", index=False)
    sig.to_csv(d / "signal.csv", index=False)
    return f"{d / 'pose.csv'},{d / 'signal.csv'}"


def _live(d: Path, source: str, *flags: str):
    return invoke(["live", source, "-o", d / "m.json", "--quiet", "--no-advice", "--idle", "0.2", "--order", "2", *flags],
                  ok=False)


def _error(res) -> str:
    lines = [line for line in res.output.splitlines() if line.strip()]
    assert res.exit_code == 1 and len(lines) == 1 and lines[0].startswith("error:"), res.output
    return lines[0]


def _counts(text: str) -> dict[str, int]:
    """``dropped (reason): n`` lines of a summary."""
    out = {}
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("dropped ("):
            reason, n = line[len("dropped ("):].split("): ")
            out[reason] = int(n.split()[0])  # where some were may follow: 1 (pose.csv line 101)
    return out


def test_a_pose_log_that_ends_before_the_signal_log_is_out_of_span_as_sync_counts_it(tmp_path):
    """The drone's poses end at 15 s, its packets go on to 30 s: the live matcher kept one pose row of
    it, a static track, and learned the 151 rows after it at that stale pose (300 learned, sync 149)."""
    source = _write(tmp_path, *_tables(drone_rows=slice(0, 150)))
    res = _live(tmp_path, source)
    assert res.exit_code == 0, res.output
    synced = invoke(["sync", "--poses", tmp_path / "pose.csv", "--signals", tmp_path / "signal.csv", "-o", tmp_path / "s.csv"])
    assert "matched: 149" in synced.output and _counts(synced.output.replace("  dropped", "dropped")) == {"out_of_span": 151}
    assert ", 149 matched, 149 learned" in res.output and _counts(res.output) == {"out_of_span": 151}


def test_a_fixed_node_that_no_row_names_gets_a_note_and_one_outside_nodes_is_refused(tmp_path):
    source = _write(tmp_path, *_tables())
    line = _error(_live(tmp_path, source, "--fixed", "X", "--nodes", "D,G"))
    assert line.startswith("error: --fixed: X") and "--nodes" in line
    res = invoke(["live", source, "-o", tmp_path / "m.json", "--quiet", "--idle", "0.2", "--order", "2", "--fixed", "X"], ok=False)
    assert res.exit_code == 0, res.output
    assert "--fixed X: no matched row names it (the session's nodes: D, G)" in res.output
    res = invoke(["live", source, "-o", tmp_path / "m.json", "--quiet", "--idle", "0.2", "--order", "2", "--fixed", "G"], ok=False)
    assert res.exit_code == 0 and "--fixed" not in res.output, res.output


@pytest.mark.parametrize("flag", ["--html", "--record"])
def test_an_output_given_twice_is_refused_before_any_work_naming_both_flags(tmp_path, flag):
    """--html or --record equal to -o: the page or the recording overwrote the model (or was refused as 'an input')."""
    source = _write(tmp_path, *_tables())
    model = tmp_path / "m.json"
    model.write_text("{}")
    res = invoke(["live", source if flag == "--html" else "udpin:127.0.0.1:9", "-o", model, "--quiet", "--no-advice",
                  "--tx-power", "20", "--frequency", "433e6", flag, model], ok=False)
    line = _error(res)
    assert f"{flag}: {model} is also given as --out" in line
    assert model.read_text() == "{}"
    res = invoke(["live", "udpin:127.0.0.1:9", "-o", model, "--quiet", "--tx-power", "20", "--frequency", "433e6",
                  "--html", tmp_path / "p.html", "--record", tmp_path / "p.html"], ok=False)
    assert "--record" in _error(res) and "--html" in _error(res)


def _port() -> int:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_a_silent_mavlink_stream_says_nothing_came_and_records_no_empty_tlog(tmp_path):
    res = invoke(["live", f"udpin:127.0.0.1:{_port()}", "-o", tmp_path / "m.json", "--quiet", "--tx-power", "20",
                  "--frequency", "433e6", "--duration", "1", "--record", tmp_path / "r.tlog"], ok=False)
    line = _error(res)
    assert "no MAVLink message received from it in 1 s" in line and "rplearn-live-" not in line
    assert not (tmp_path / "r.tlog").exists() and not (tmp_path / "m.json").exists()


def test_a_session_that_ends_without_a_model_says_why(tmp_path):
    source = _write(tmp_path, *_tables(n=30))
    line = _error(invoke(["live", source, "-o", tmp_path / "m.json", "--quiet", "--no-advice", "--idle", "0.2"], ok=False))
    assert "30 signal rows received, 29 matched, 29 learned" in line and "too few" in line and "--order" in line


def _with_line(path: Path, at: int, line: str) -> None:
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[:at] + [line] + lines[at:]))


@pytest.mark.parametrize("table", ["pose", "signal"])
def test_a_header_repeated_mid_file_is_a_counted_drop_and_another_header_is_refused(tmp_path, table):
    """A logger restarted appending to its file writes its header again: the pose table was refused as a NaN time,
    the signal table's line dropped as invalid_value; another header (other columns) must not be read as rows."""
    source = _write(tmp_path, *_tables())
    path = tmp_path / f"{table}.csv"
    header = path.read_text().splitlines(keepends=True)[0]
    _with_line(path, 100, header)
    res = _live(tmp_path, source)
    assert res.exit_code == 0, res.output
    assert _counts(res.output) == {"repeated_header": 1, "out_of_span": 1}
    assert f"dropped (repeated_header): 1 ({path} line 101)" in res.output  # review 51: where it was (was not said)
    _with_line(path, 150, ",".join(reversed(header.strip().split(","))) + "\n")
    line = _error(_live(tmp_path, source))
    assert f"{path}: line 151: another header in the file" in line


TLOG = Path(__file__).resolve().parents[1] / "fixtures" / "ardupilot" / "mavlink-log_2013-10-13_16-58-51.tlog"


@pytest.mark.parametrize(("flags", "expected"), [
    (["--to", "127.0.0.1:99999"], "--to: port 99999"),
    (["--to", "no-such-host.invalid:14550"], "--to: cannot resolve the host"),
    (["--speed", "inf"], "--speed: expected a positive, finite factor, got inf"),
    (["--speed", "nan"], "--speed: expected a positive, finite factor"),
    (["--speed", "0"], "--speed: expected a positive, finite factor"),
    (["--speed", "-2"], "--speed: expected a positive, finite factor"),
])
def test_replay_refuses_a_bad_target_or_speed_in_one_line_naming_the_flag(flags, expected):
    """--speed inf was a traceback (ValueError: cannot convert float NaN to integer); an unknown host or a port out
    of range a bare '[Errno -2] Name or service not known'."""
    assert expected in _error(invoke(["replay", str(TLOG), *flags], ok=False))


def test_replay_of_a_tlog_with_a_corrupt_receive_time_does_not_wait_for_it(tmp_path):
    """One record's receive time 30,000 years after the others: replay slept until then (a hang)."""
    import struct
    import subprocess
    import sys

    data = TLOG.read_bytes()[:60000]
    bad = tmp_path / "bad.tlog"
    far = struct.unpack(">Q", data[:8])[0] + 10**18  # [us]
    bad.write_bytes(data[:25] + struct.pack(">Q", far) + data[8:25] + data[25:])
    env = {"PYTHONPATH": str(Path(__file__).resolve().parents[2] / "src")}
    done = subprocess.run([sys.executable, "-m", "rplearn", "replay", str(bad), "--to", "127.0.0.1:9", "--speed", "1e6"],
                          capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0 and "sent " in done.stdout, done.stdout + done.stderr


def test_live_on_a_tlog_cut_inside_its_first_record_says_so_naming_the_file(tmp_path):
    """pymavlink's connection indexed the file whole and raised AttributeError ('NoneType' object has no attribute
    '_instance_field'); a file with no whole message then waited for a first message forever."""
    cut = tmp_path / "cut.tlog"
    cut.write_bytes(TLOG.read_bytes()[3:40])
    line = _error(invoke(["live", str(cut), "-o", tmp_path / "m.json", "--quiet", "--no-advice", "--tx-power", "20",
                          "--frequency", "433e6", "--idle", "1"], ok=False))
    assert line == f"error: {cut}: no MAVLink message in it (a .tlog, as MAVProxy or QGroundControl record it?)"


def test_refusals_name_what_lives_command_line_can_do_never_a_library_option(tmp_path):
    """Rows out of order suggested 'allow_unsorted=True', a pose table without a node column 'ReaderOptions.nodes'
    (and, with --nodes mapped, live's --nodes, another thing), a signal table without tx 'rx=, tx_power_dbm='."""
    pose, sig = _tables()
    source = _write(tmp_path, pose, sig.iloc[[*range(50), 51, 50, *range(52, 300)]])
    line = _error(_live(tmp_path, source))
    assert "allow_unsorted" not in line and "sync the finished file with --allow-unsorted" in line
    source = _write(tmp_path, pose[pose["node"] == "D"].drop(columns="node"), sig)
    line = _error(_live(tmp_path, source))
    assert "ReaderOptions" not in line and "--nodes" not in line and "write a node column" in line
    source = _write(tmp_path, pose, sig.drop(columns="tx"))
    line = _error(_live(tmp_path, source))
    assert "rx=" not in line and "--receiver NODE" in line


def test_a_csv_source_that_is_not_two_distinct_files_is_refused(tmp_path):
    """Three files: a traceback (ValueError: too many values to unpack); one CSV: read as a MAVLink connection
    ('a MAVLink stream carries neither'); a file twice: read as its own signal table; a file that never appears:
    '0 matched' without naming it."""
    source = _write(tmp_path, *_tables())
    pose, signal = source.split(",")
    assert "a CSV source is two files" in _error(_live(tmp_path, f"{source},{tmp_path / 'x.csv'}"))
    assert "a CSV source is two files" in _error(_live(tmp_path, pose))
    assert "one file (named twice)" in _error(_live(tmp_path, f"{pose},{pose}"))
    line = _error(_live(tmp_path, f"{tmp_path / 'later.csv'},{signal}"))
    assert line.startswith(f"error: {tmp_path / 'later.csv'}: no such file")


def test_a_refused_mavlink_connection_is_one_line(tmp_path):
    """pymavlink printed its retries ('[Errno 111] Connection refused sleeping') above the error."""
    import socket

    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    line = _error(invoke(["live", f"tcp:127.0.0.1:{port}", "-o", tmp_path / "m.json", "--quiet", "--no-advice",
                          "--tx-power", "20", "--frequency", "433e6"], ok=False))
    assert "cannot open the MAVLink connection" in line
