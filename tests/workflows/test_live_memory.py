"""What a live session keeps does not grow with the number of batches (issue 27, acceptance 2:
memory flat over a long flight). Counted in lengths of the session's structures, not in RSS,
so that the test is not noisy: every list, dict, deque, array and table reachable from the
session is measured at three times of a replay, and none may keep growing once the bounded
ones are full."""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterator
from types import FunctionType, MethodType, ModuleType

import numpy as np
import pandas as pd
import pytest

import rplearn.data.flight_layout as flight_layout
import rplearn.models.live_drift as live_drift
import rplearn.workflows.live as live_module
from rplearn.core.geometry import quat_wxyz_from_euler_ned_frd_deg
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.workflows.live import LiveOptions, replay_session
from rplearn.workflows.live_status import Prequential

# 30 batches (of 1 s) and 6 refits (every 5 s) between marks: a structure that grows per batch grows by 30, one per refit by 6
MINUTES, RATE_HZ = 1.5, 10.0
MARKS_S = (30.0, 60.0, 90.0)


def _flight(minutes: float, rate_hz: float) -> tuple[pd.DataFrame, pd.DataFrame]:
    """A drone ``D`` orbiting station ``G`` and yawing, packets both ways (as benchmarks/live.py)."""
    rng = np.random.default_rng(0)
    t = np.arange(0.0, minutes * 60.0, 1.0 / rate_hz)
    ang = 2 * np.pi * t / 40.0
    q = quat_wxyz_from_euler_ned_frd_deg(np.zeros_like(t), 10.0 * np.sin(2 * np.pi * t / 23.0),
                                         np.degrees(2 * np.pi * t / 17.0) % 360.0)
    drone = pd.DataFrame({"t": t, "node": "D", "x": 50 * np.cos(ang), "y": 50 * np.sin(ang), "z": 20.0 + 5 * np.sin(ang / 3),
                          "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3]})
    station = pd.DataFrame({"t": [0.0], "node": ["G"], "x": [0.0], "y": [0.0], "z": [1.5], "qw": [1.0], "qx": [0.0],
                            "qy": [0.0], "qz": [0.0]})
    ts = t[1:-1] + 0.5 / rate_hz
    tx = np.where(np.arange(ts.size) % 2 == 0, "D", "G")
    rssi = -60.0 + 2.0 * np.cos(np.interp(ts, t, ang) * 3) + rng.normal(0.0, 2.0, ts.size)
    signal = pd.DataFrame({"t": ts, "tx": tx, "rx": np.where(tx == "D", "G", "D"), "rssi_dbm": rssi,
                           "tx_power_dbm": 20.0, "frequency_hz": 433e6})
    return pd.concat([station, drone], ignore_index=True), signal


def _sizes(obj: object, path: str, seen: set[int], depth: int = 0) -> Iterator[tuple[str, int]]:
    """(path, length) of every container, array and table reachable from ``obj`` through
    attributes and container items (items of one container share a path)."""
    if id(obj) in seen or depth > 8 or isinstance(obj, (type, ModuleType, FunctionType, MethodType, str, bytes)):
        return
    seen.add(id(obj))
    if isinstance(obj, np.ndarray):
        yield path, int(obj.size)
        return
    if isinstance(obj, (pd.DataFrame, pd.Series, pd.Index)):
        yield path, len(obj)
        return
    if isinstance(obj, dict):
        yield path, len(obj)
        for v in obj.values():
            yield from _sizes(v, path + "{}", seen, depth + 1)
        return
    if isinstance(obj, (list, tuple, deque, set, frozenset)):
        yield path, len(obj)
        for v in obj:
            yield from _sizes(v, path + "[]", seen, depth + 1)
        return
    fields = getattr(obj, "__dict__", None)
    if isinstance(fields, dict) and type(obj).__module__.startswith("rplearn"):
        for name, v in fields.items():
            yield from _sizes(v, f"{path}.{name}", seen, depth + 1)


def footprint(session: object) -> dict[str, int]:
    """The largest length at every path reachable from a live session, but its current model's
    (sized by the model's order, which an automatic choice raises as data come, up to
    ``MAX_AUTO_ORDER``: bounded, not per batch)."""
    out: dict[str, int] = {}
    for path, n in _sizes(session, "session", {id(getattr(session, "fitted", None))}):
        out[path] = max(out.get(path, 0), n)
    return out


def _growing(marks: list[dict[str, int]]) -> dict[str, tuple[int, ...]]:
    """Paths whose length grew over both later intervals by more than a row or two and 5 %."""
    first, middle, last = marks
    out = {}
    for path in last:
        a, b, c = first.get(path, 0), middle.get(path, 0), last[path]
        if c - b > max(2, 0.05 * b) and b - a > max(2, 0.05 * a):
            out[path] = (a, b, c)
    return out


def _replay(monkeypatch, tmp_path, options: LiveOptions) -> list[dict[str, int]]:
    """Footprints of a replayed session at :data:`MARKS_S`, its bounded structures made small so
    that they are full before the first mark."""
    sessions = []
    original = live_module._Session.__init__

    def init(self, *args, **kwargs) -> None:
        original(self, *args, **kwargs)
        self.preq = Prequential(max_bins=16)
        sessions.append(self)

    monkeypatch.setattr(live_module._Session, "__init__", init)
    monkeypatch.setattr(live_module, "BUDGET_WINDOW_ROWS", 100)
    monkeypatch.setattr(live_drift, "MAX_OPEN_BLOCKS", 4)  # the drift's open blocks (64, 320 s) full by the first mark too
    monkeypatch.setattr(flight_layout, "LAYOUT_ROWS", 64)  # the layout's sample of rows (100,000) at its bound by the first mark
    monkeypatch.setattr(flight_layout, "INTERVAL_VALUES", 8)  # and its intervals per link direction (4,096)
    marks: list[dict[str, int]] = []
    left = list(MARKS_S)

    def on_update(status) -> None:
        if left and status.elapsed_s >= left[0]:
            left.pop(0)
            marks.append(footprint(sessions[0]))

    pose, signal = _flight(MINUTES, RATE_HZ)
    replay_session(pose, signal, str(tmp_path / "m.json"), options, batch_s=1.0, on_update=on_update)
    assert len(marks) == len(MARKS_S)
    return marks


def _ranker(stats, fitted, latest):
    return [("yaw turn", 10.0, 1.0)]


def _planting_history(monkeypatch) -> None:
    """Plant a per-batch record in the session (``session.history``, one entry per batch): the
    footprint must find it growing, so that a run finding nothing else proves the check can fail."""
    original = live_module._Session.learn

    def learn(self, final: bool = False) -> None:
        original(self, final)
        self.__dict__.setdefault("history", []).append(math.nan)

    monkeypatch.setattr(live_module._Session, "learn", learn)


@pytest.mark.parametrize("auto", [False, True], ids=["fixed order, with a ranking", "automatic order"])
def test_what_a_session_keeps_does_not_grow_with_its_batches(monkeypatch, tmp_path, auto):
    """Only the per-batch record planted in the session grows (:func:`_planting_history`: the
    check finds a structure that grows with the batches, in the same replay; it was a replay of
    its own)."""
    _planting_history(monkeypatch)
    options = LiveOptions(spec=ModelSpec.parse("sh") if auto else ModelSpec.parse("sh", order=4),
                          fit=FitOptions(auto=auto), refit_s=5.0, manoeuvres=None if auto else _ranker)
    marks = _replay(monkeypatch, tmp_path, options)
    assert len(marks[-1]) > 20  # the walk reached the session's parts
    assert "session.preq._n" in marks[-1] and "session.matcher._seen.sorted" in marks[-1]
    # the layout's sample of rows is between half and all of its bound, filling again after each halving (it may
    # grow from mark to mark by chance): its bound is checked instead
    layout = "session.stats.layout."
    assert 0 < marks[-1][layout + "keys"] <= 64 and marks[-1][layout + "poses"] == 14 * marks[-1][layout + "keys"]
    assert max(m[layout + "links{}.values"] for m in marks) <= 8
    assert {p for p in _growing(marks) if not p.startswith(layout)} == {"session.history"}
