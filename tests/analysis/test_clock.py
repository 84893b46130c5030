"""rplearn.analysis.clock and ``sync --estimate-offset`` (issue 12, item 5): a node's clock
offset found from the signal."""

from __future__ import annotations

import pandas as pd
import pytest
from simulated_flights import simulated

from rplearn.analysis.clock import estimate_clock_offset
from rplearn.errors import InputError

INJECTED_S = 0.35


def late_logs(preset, seed, late_s=INJECTED_S):
    """A campaign whose node B logs its poses ``late_s`` early on the common clock (its clock
    runs behind): the offset to add to B's pose times is ``+late_s``. The simulator's logs as
    written (simulated once per process: tests/simulated_flights.py), read into new tables."""
    files, _ = simulated(preset, seed)
    pose = pd.read_parquet(files / "pose_log.parquet")
    sig = pd.read_parquet(files / "signal_log.parquet")
    pose.loc[pose["node"] == "B", "t"] -= late_s
    return pose, sig


@pytest.mark.slow
def test_an_injected_offset_is_recovered_within_20_ms():
    """Acceptance 5 on the paper's campaign (both directions of A-B, 40,000 packets used)."""
    pose, sig = late_logs("paper", 2)
    est = estimate_clock_offset(pose, sig, "B")
    assert abs(est.offset_s - INJECTED_S) < 0.02 and abs(est.offset_s - INJECTED_S) < 3 * est.std_s, est.summary()
    assert not est.at_edge and est.rmse_db.min() < est.rmse_db[0]


def test_a_short_flight_says_how_unsure_it_is_and_an_edge_is_flagged():
    pose, sig = late_logs("smoke", 2)
    est = estimate_clock_offset(pose, sig, "B")
    assert abs(est.offset_s - INJECTED_S) < 3 * est.std_s and est.std_s < 0.1, est.summary()
    narrow = estimate_clock_offset(pose, sig, "B", window_s=0.2)
    assert narrow.at_edge and "widen it" in narrow.summary()
    with pytest.raises(InputError, match="node Z has no pose log"):
        estimate_clock_offset(pose, sig, "Z")
    with pytest.raises(InputError, match="offset window"):
        estimate_clock_offset(pose, sig, "B", window_s=-1.0)


def _sync(*args: str):
    """``rplearn sync ARGS`` in this process (typer's ``CliRunner``, stdout and stderr apart): the
    process boundary is not what these checks are about."""
    from typer.testing import CliRunner

    from rplearn.cli import app

    return CliRunner().invoke(app, ["sync", *args], env={"COLUMNS": "400"})


def test_sync_reports_the_offset_and_applies_it_only_when_asked(tmp_path, monkeypatch):
    pose, sig = late_logs("smoke", 1)
    pose.to_parquet(tmp_path / "poses.parquet")
    sig.to_parquet(tmp_path / "signals.parquet")
    monkeypatch.chdir(tmp_path)
    base = ["--poses", "poses.parquet", "--signals", "signals.parquet", "--estimate-offset", "B"]
    kept = _sync(*base, "-o", "kept.parquet")
    assert kept.exit_code == 0 and "clock offset of B: +0.3" in kept.stdout and "not applied" in kept.stderr, kept.output
    used = _sync(*base, "--apply-offset", "-o", "used.parquet")
    assert used.exit_code == 0, used.output
    plain = _sync(*base[:-2], "--offset", "B=0.35", "-o", "plain.parquet")
    assert plain.exit_code == 0, plain.output
    kept, used, plain = (pd.read_parquet(tmp_path / f) for f in ("kept.parquet", "used.parquet", "plain.parquet"))
    key = ["t", "tx", "rx"]
    vs_plain = used.merge(plain, on=key, suffixes=("", "_plain"))
    vs_kept = used.merge(kept, on=key, suffixes=("", "_kept"))
    b_rx = vs_plain["rx"] == "B"
    # applied: B's poses are (nearly) those of the true offset, and not those of no offset
    assert (vs_plain.loc[b_rx, "rx_x"] - vs_plain.loc[b_rx, "rx_x_plain"]).abs().max() < 0.3
    assert (vs_kept["rx_qz"] != vs_kept["rx_qz_kept"]).mean() > 0.3
    no = _sync(*base[:-2], "--apply-offset", "-o", "x.parquet")
    assert no.exit_code == 1 and "give --estimate-offset" in no.stderr


def test_a_still_node_or_a_wide_window_is_handled():
    pose, sig = late_logs("smoke", 1)
    still = pose.copy()
    b = still["node"] == "B"
    still.loc[b, ["x", "y", "z", "qw", "qx", "qy", "qz"]] = still.loc[b, ["x", "y", "z", "qw", "qx", "qy", "qz"]].iloc[0].to_numpy()
    with pytest.raises(InputError, match="holds still"):
        estimate_clock_offset(still, sig, "B")
    # shifts of +-5 s bring the drones within 2 wavelengths for some packets: those are left out
    # (it used to stop with a far-field error); the smoke flight circles, so +-5 s is ambiguous
    wide = estimate_clock_offset(pose, sig, "B", window_s=5.0)
    assert wide.offsets_s.min() == pytest.approx(-5.0) and 0 < wide.n_samples < estimate_clock_offset(pose, sig, "B").n_samples


def test_the_usable_packet_pass_keeps_the_rows_of_full_interpolation():
    """:func:`usable_at_every_shift` (positions only) keeps exactly the rows the full pose
    interpolation (:func:`track_at`) keeps, shift by shift: packets falling into a pose gap, off the
    span or within the far-field limit at some shift are dropped, on either end of the link."""
    import numpy as np

    from rplearn.analysis.clock import track_at, usable_at_every_shift
    from rplearn.data.poses import PoseTrack

    rng = np.random.default_rng(5)
    t_pose = np.concatenate([np.arange(0.0, 20.0, 0.1), np.arange(22.0, 40.0, 0.1)])  # a 2-s gap
    xyz = np.column_stack([10 * np.cos(t_pose / 5), 10 * np.sin(t_pose / 5), 5 + 0.1 * t_pose])
    quat = np.tile([1.0, 0.0, 0.0, 0.0], (t_pose.size, 1))
    track = PoseTrack("B", t_pose, xyz, quat)
    t_sig = np.sort(rng.uniform(-1.0, 41.0, 3000))
    far_end = rng.normal(0.0, 8.0, (t_sig.size, 3))
    near_m = np.full(t_sig.size, 4.0)
    node_is_tx = rng.random(t_sig.size) < 0.5
    shifts = np.linspace(-0.5, 0.5, 21)
    expected = np.ones(t_sig.size, bool)
    for shift in shifts:
        pos, _, status = track_at(track, t_sig, shift, 0.5)
        tx = np.where(node_is_tx[:, None], pos, far_end)
        rx = np.where(node_is_tx[:, None], far_end, pos)
        expected &= (status == 0) & (np.linalg.norm(tx - rx, axis=1) > near_m)
    kept = usable_at_every_shift(track, t_sig, shifts, far_end, near_m, 0.5)
    assert np.array_equal(kept, expected)
    assert 0.5 < expected.mean() < 0.95  # the gap, the span and the near field each drop some
