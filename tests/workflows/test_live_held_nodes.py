"""A live session without ``--nodes`` fixes its node list from the first rows it learns. A node whose
first poses the CSV source holds back (a ground station at the ENU origin logging its attitude) has the
rows of its links waiting in the matcher meanwhile, so the session must not fix its nodes from the other
links before those rows are placed: the held node's rows were refused later ("appeared after the session
fixed its nodes"), ending the session (found by hostile46)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.data.live_sync import HOLD_S
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.errors import InputError
from rplearn.io import read_logs
from rplearn.io.live_sources import CsvTail
from rplearn.io.options import ReaderOptions
from rplearn.workflows.live import LiveOptions, _Session

READER = ReaderOptions(nan_policy="drop")


def _tail_and_session(folder, options: LiveOptions | None = None):
    """Empty pose and signal CSVs with their headers, a tail of them and a session reading it."""
    pose, signal = folder / "pose.csv", folder / "signal.csv"
    pose.write_text("t,node,x,y,z,qw,qx,qy,qz\n")
    signal.write_text("t,tx,rx,rssi_dbm,tx_power_dbm,frequency_hz\n")
    return pose, signal, CsvTail(str(pose), str(signal), READER), _Session(options or LiveOptions(reader=READER), str(folder / "m.json"),
                                                                          str(folder))


def _append(pose, signal, s: int, rng, g_links_from: float = 0.0, g_poses_from: float = 0.0) -> None:
    """One second at 10 Hz: G still at the origin with attitude noise, A and B flying, every link both ways
    (G's from ``g_links_from`` [s]; G's poses from ``g_poses_from``)."""
    with pose.open("a") as fp, signal.open("a") as fs:
        for k in range(10):
            t = s + 0.1 * k
            yaw = 0.02 * rng.standard_normal()
            fp.write((f"{t:.2f},G,0,0,0,{np.cos(yaw / 2):.9f},0,0,{np.sin(yaw / 2):.9f}\n" if t >= g_poses_from else "")
                     + f"{t + 0.03:.2f},A,{10 + 2 * t:g},5,20,1,0,0,0\n"
                     f"{t + 0.05:.2f},B,{-10 - t:g},-5,25,1,0,0,0\n")
            for j, (a, b) in enumerate((("A", "B"), ("B", "A"), ("A", "G"), ("G", "A"), ("B", "G"), ("G", "B"))):
                if "G" in (a, b) and t < g_links_from:
                    continue
                fs.write(f"{t + 0.06 + 0.005 * j:.3f},{a},{b},{-60 - 0.1 * j - 0.01 * k:.2f},20,433000000\n")


#: Seconds of log appended between two polls: two (a poll a second made 80 polls a test; the hold is in the
#: table's time, :data:`HOLD_S`, so what runs out when is the same).
POLL_S = 2


def _flight(pose, signal, tail, session, seconds: int, rng, **kw) -> None:
    """``seconds`` of :func:`_append`, polled, fed and learned every :data:`POLL_S` seconds; the last poll final."""
    for s in range(0, seconds, POLL_S):
        for k in range(s, min(s + POLL_S, seconds)):
            _append(pose, signal, k, rng, **kw)
        final = s + POLL_S >= seconds
        polled = tail.poll(final=final)
        session.feed(polled.poses, polled.signals, polled.held_nodes)
        session.learn(final=final)


@pytest.mark.parametrize("g_links_from", [0.0, 3.0])
def test_a_held_node_is_in_the_sessions_node_list_and_its_rows_are_learned(tmp_path, g_links_from):
    """Also when the held node's links start later than the others' (a station's radio heard from t = 3 s: the
    rows of A and B learned first fixed the nodes as A, B, and G's rows ended the session when its hold ran out)."""
    rng = np.random.default_rng(7)
    pose, signal, tail, session = _tail_and_session(tmp_path)
    _flight(pose, signal, tail, session, int(HOLD_S) + 20, rng, g_links_from=g_links_from)
    assert session.stats is not None and session.stats.nodes == ("A", "B", "G")
    logs, _ = read_logs([str(pose), str(signal)], READER)
    whole = synchronise(logs.pose, logs.signal)
    assert session.stats.n_samples == len(whole.dataset)
    assert session.status.dropped.get("unknown_node", 0) == 0
    assert not any(n.startswith("nodes: ") for n in session.status.notes)


def test_while_the_node_list_waits_the_view_says_why(tmp_path):
    rng = np.random.default_rng(8)
    pose, signal, tail, session = _tail_and_session(tmp_path)
    for s in range(5):
        _append(pose, signal, s, rng)
        polled = tail.poll()
        session.feed(polled.poses, polled.signals, polled.held_nodes)
        session.learn()
    assert session.stats is None and session.status.matched > 0  # matched, not yet learned
    assert any(n.startswith("nodes: learning waits for the first poses of G") for n in session.status.notes)


def test_a_radio_heard_that_logs_no_poses_does_not_hold_the_learning_back(tmp_path):
    """Rows naming a node that no source holds (a radio of another team, heard all along) wait in the matcher and
    are dropped as unknown_node; the session learns from the first poll as before."""
    pose, signal, tail, session = _tail_and_session(tmp_path)
    for s in range(5):
        with pose.open("a") as fp, signal.open("a") as fs:
            for k in range(10):
                t = s + 0.1 * k
                fp.write(f"{t:.2f},A,{10 + 2 * t:g},5,20,1,0,0,0\n{t + 0.05:.2f},B,{-10 - t:g},-5,25,1,0,0,0\n")
                fs.write(f"{t + 0.06:.3f},A,B,-60,20,433000000\n{t + 0.07:.3f},Z,A,-80,20,433000000\n")
        polled = tail.poll()
        assert polled.held_nodes == frozenset()
        session.feed(polled.poses, polled.signals, polled.held_nodes)
        session.learn()
    assert session.stats is not None and session.stats.nodes == ("A", "B")
    assert session.matcher.waiting_nodes == frozenset({"Z"})
    assert not any(n.startswith("nodes: ") for n in session.status.notes)


def test_clock_offsets_naming_a_held_node_lose_no_rows_while_it_is_held(tmp_path):
    """``clock_offsets_s`` naming G, whose poses the source holds back: every poll's match raised 'clock offsets name
    node(s) G without a pose log' and the rows taken for it were lost (20 of 198 learned, a note per poll)."""
    rng = np.random.default_rng(9)
    sync = SyncOptions(clock_offsets_s={"G": 0.0})
    pose, signal, tail, session = _tail_and_session(tmp_path, LiveOptions(reader=READER, sync=sync))
    _flight(pose, signal, tail, session, int(HOLD_S) + 20, rng)
    logs, _ = read_logs([str(pose), str(signal)], READER)
    assert session.stats is not None and session.stats.n_samples == len(synchronise(logs.pose, logs.signal, sync).dataset)
    assert not any("clock offsets" in n for n in session.status.notes)


def test_a_match_refused_in_flight_ends_the_session_and_learns_no_rows_twice(tmp_path):
    """A station moved between flights (G still at one place, no poses for 20 s, still at another): ``sync`` refuses
    it. The session caught the error at every poll and learned the previous poll's matched rows again each time
    (learned grew by 20 a poll while matched stayed)."""
    pose, signal, tail, session = _tail_and_session(tmp_path, LiveOptions(reader=READER, nodes=("A", "B", "G")))
    learned = []
    with pytest.raises(InputError, match="node G holds still"):
        for s in range(40):
            with pose.open("a") as fp, signal.open("a") as fs:
                for k in range(10):
                    t = s + 0.1 * k
                    if t < 5 or t >= 25:
                        fp.write(f"{t:.2f},G,{5 if t < 5 else 80},2,1,1,0,0,0\n")
                    fp.write(f"{t + 0.03:.2f},A,{10 + 2 * t:g},5,20,1,0,0,0\n{t + 0.05:.2f},B,{-10 - t:g},-5,25,1,0,0,0\n")
                    fs.write(f"{t + 0.06:.3f},A,B,-60,20,433000000\n{t + 0.07:.3f},B,A,-60,20,433000000\n")
            polled = tail.poll()
            session.feed(polled.poses, polled.signals, polled.held_nodes)
            session.learn()
            learned.append(session.stats.n_samples if session.stats is not None else 0)
    assert session.stats is not None and session.stats.n_samples == session.matcher.summary.n_out == learned[-1]


def test_a_node_first_logged_after_the_node_list_is_fixed_is_a_counted_drop_not_the_sessions_end(tmp_path):
    """G's pose log starts 2 s after its links: at the first poll no source holds it, the session fixes A, B, and
    G's rows, matched once its poses come, were refused by the statistics, ending the session (review46b). Now they
    are dropped (late_node, counted, with a note naming G and --nodes) and the session goes on learning A-B."""
    rng = np.random.default_rng(9)
    pose, signal, tail, session = _tail_and_session(tmp_path)
    seconds = int(HOLD_S) + 10
    _flight(pose, signal, tail, session, seconds, rng, g_poses_from=2.0)
    assert session.stats is not None and session.stats.nodes == ("A", "B")
    assert session.status.dropped["late_node"] > 0
    assert any(n.startswith("late: node(s) G appeared after the session fixed its nodes (A, B)") and "--nodes" in n
               for n in session.status.notes)
    assert session.stats.n_samples == 2 * 10 * seconds - 2  # every A-B row but the last, after the last pose
    assert session.status.dropped["late_node"] > 4 * 10 * (seconds - 3)  # G's four links once its poses come
