"""Hostile node ids and paths (issue 10, item 3): random text, markup, emoji, '/', '..' as node
ids go through sync, fit, export and inspect; the result is an RplearnError or a correct result,
and no file is ever written outside the output folder."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rplearn.data.sync import synchronise
from rplearn.data.tables import link_samples
from rplearn.errors import RplearnError
from rplearn.io.files import write_table
from rplearn.io.inspect import inspect_logs
from rplearn.io.msi import export_msi_files
from rplearn.models import ModelSpec, fit_model

HOSTILE = st.one_of(
    st.sampled_from(["[b]A[/b]", "[/]", ":fire:", "../../evil", "/etc/passwd", "..", ".", "a/b", "🚁", "nan", " ", ""]),
    st.text(min_size=0, max_size=12),
)


def flight(a: str, b: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Two drones circling each other for 20 s, packets both ways."""
    t = np.arange(0.0, 20.0, 0.05)
    ang = 2 * np.pi * t / 20.0
    rows = []
    for node, sign in ((a, 1.0), (b, -1.0)):
        yaw = ang * sign
        rows.append(pd.DataFrame({"t": t, "node": node, "x": 5 * sign * np.cos(ang), "y": 5 * sign * np.sin(ang), "z": 20.0,
                                  "qw": np.cos(yaw / 2), "qx": 0.0, "qy": 0.0, "qz": np.sin(yaw / 2)}))
    poses = pd.concat(rows, ignore_index=True)
    rng = np.random.default_rng(0)
    ts = np.sort(rng.uniform(0.5, 19.5, 600))
    tx = np.where(np.arange(ts.size) % 2 == 0, a, b)
    rx = np.where(tx == a, b, a)
    signal = pd.DataFrame({"t": ts, "tx": tx, "rx": rx, "rssi_dbm": -50.0 + rng.normal(0, 2, ts.size),
                           "tx_power_dbm": 20.0, "frequency_hz": 2.4e9})
    return poses, signal


def files_under(root: Path) -> set[str]:
    return {str(p) for p in root.rglob("*")}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=HOSTILE, b=HOSTILE)
def test_hostile_node_ids_give_an_error_or_a_correct_result_inside_the_output_folder(tmp_path_factory, a, b):
    root = tmp_path_factory.mktemp("hostile")
    out = root / "out"
    out.mkdir()
    outside_before = files_under(root) - files_under(out)
    try:
        poses, signal = flight(a, b)
        write_table(poses, str(root / "poses.csv"))
        write_table(signal, str(root / "signal.csv"))
        report = inspect_logs([str(root / "poses.csv"), str(root / "signal.csv")])
        assert report.to_text()
        matched = synchronise(poses, signal).dataset
        fitted = fit_model(link_samples(matched, "hostile"), ModelSpec.parse("sh-2"))
        assert set(fitted.model.nodes) == {str(a), str(b)}
        paths = export_msi_files(fitted.model, out, 2.4e9)
        assert len(paths) == 2
        for p in paths:
            assert os.path.dirname(os.path.abspath(p)) == str(out)
    except RplearnError:
        pass
    written_outside = files_under(root) - files_under(out) - outside_before - {str(root / "poses.csv"), str(root / "signal.csv")}
    assert written_outside == set()
