"""LiveStatistics: bounded segments, refits from statistics, the exact last refit."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rplearn.core.bases import make_basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq.block_sums import time_block_labels
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.data.sync import synchronise
from rplearn.data.tables import link_samples
from rplearn.data.units import Stretches
from rplearn.io.files import write_table
from rplearn.models.auto_spread import block_drift_std_db
from rplearn.models.live_drift import DriftBlocks
from rplearn.models.live_stats import LiveStatistics
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.sim import simulate
from rplearn.workflows.learning import fit_dataset

ALL_STRETCHES = ["flight[1/5]", "flight[2/5]", "flight[3/5]", "flight[4/5]", "test[5/5]"]


@pytest.fixture(scope="module")
def matched() -> pd.DataFrame:
    r = simulate("smoke", seed=1)
    return synchronise(r.pose_log, r.signal_log.drop(columns=["unit"])).dataset.sort_values("t", kind="stable")


def _learn(matched: pd.DataFrame, spec: ModelSpec, options: FitOptions, spool: str | None, batch_s: float = 1.0,
           max_open: int | None = None, swap: bool = False):
    """The rows learned in batches of ``batch_s``; ``max_open``: the drift's blocks kept open at
    most; ``swap``: each pair of neighbouring batches given in the other order (rows 1 s late)."""
    st = LiveStatistics(spec, ["A", "B"], options, spool_dir=spool, max_segments=5)
    if max_open is not None:
        st.drift = DriftBlocks(st.basis, 2, max_open)
    t = matched["t"].to_numpy()
    starts = list(np.arange(t.min(), t.max() + batch_s, batch_s))
    if swap:
        for i in range(0, len(starts) - 1, 2):
            starts[i], starts[i + 1] = starts[i + 1], starts[i]
    for a in starts:
        rows = matched[(t >= a) & (t < a + batch_s)]
        if len(rows):
            st.add(rows, st.samples(rows))
            assert max_open is None or len(st.drift.open) <= max_open
    return st


@pytest.fixture(scope="module")
def offline(matched, tmp_path_factory):
    """``fit --order auto`` of the matched rows, every stretch learned (what a live session fits)."""
    path = str(tmp_path_factory.mktemp("offline") / "data.parquet")
    write_table(matched, path)
    return fit_dataset(path, ModelSpec.parse("sh"), ALL_STRETCHES, options=FitOptions(auto=True)).fitted.model


def _max_difference_db(a, b, rows: pd.DataFrame) -> float:
    s = link_samples(rows, "rows", nodes=("A", "B"))
    return float(np.abs(a.predict_gain(s) - b.predict_gain(s)).max())


def test_the_last_automatic_refit_is_fit_on_every_stretch(matched, tmp_path):
    st = _learn(matched, ModelSpec.parse("sh"), FitOptions(auto=True), str(tmp_path))
    assert len(st.segments) == 5 and st.n_samples == len(matched)
    write_table(matched, str(tmp_path / "data.parquet"))
    offline = fit_dataset(str(tmp_path / "data.parquet"), ModelSpec.parse("sh"), ALL_STRETCHES,
                          options=FitOptions(auto=True)).fitted.model
    live = st.refit(final=True).model
    assert live.label == offline.label
    assert _max_difference_db(live, offline, matched) < 1e-6
    # a refit during the flight cuts at segment boundaries: close, not the same folds
    assert st.refit(final=False).model.label.startswith("SH-")


def test_the_last_automatic_refit_states_the_offline_drift_and_planning_weight(matched, offline, tmp_path):
    """The live model file has what ``trajectory --optimize --from-model`` plans with: the drift
    (it had none: a live session kept no time blocks for it) and the planning weight, those of
    ``fit --order auto`` of the same rows, a block the stretches' cuts fall in counted per stretch."""
    st = _learn(matched, ModelSpec.parse("sh"), FitOptions(auto=True), str(tmp_path))
    stretches = Stretches.of_times(matched["t"].to_numpy())
    t, cut = matched["t"].to_numpy(), time_block_labels(np.array(stretches.starts_s))
    assert any(((time_block_labels(t) == b) & (stretches.index(t) != stretches.index(np.array([s])))).any()
               for b, s in zip(cut, stretches.starts_s))  # a cut inside a block with rows on both sides
    expected, got = offline.training, st.refit(final=True).model.training
    assert expected.drift_std_db is not None and expected.drift_std_db > 0
    assert got.drift_std_db == pytest.approx(expected.drift_std_db, rel=1e-9)
    assert got.planning_penalty_weight == pytest.approx(expected.planning_penalty_weight, rel=1e-9)
    # in flight the blocks are read whole (the cuts move as samples come): a drift all the same
    assert st.refit().model.training.drift_std_db is not None


def test_the_drift_blocks_stay_bounded_whatever_the_batches_order(matched, offline, tmp_path):
    """Two blocks kept open at most (the rest folded into fixed-size sums) and the batches given
    out of order: the same drift as the offline fit, no row late."""
    st = _learn(matched, ModelSpec.parse("sh"), FitOptions(auto=True), str(tmp_path), max_open=2, swap=True)
    assert st.drift.folded.n_blocks > 10 and st.drift.late_rows == 0
    got = st.refit(final=True).model.training.drift_std_db
    assert got == pytest.approx(offline.training.drift_std_db, rel=1e-9)
    assert st.drift.folded.cross.shape == (2 * 100,) * 2  # SH-10's coefficients, whatever the length


def test_a_row_for_a_block_already_folded_is_counted_late(matched):
    """One block kept open: rows of block 0 after block 2 came are counted late (the offline fit
    would add them to block 0's first rows)."""
    st = LiveStatistics(ModelSpec.parse("sh"), ["A", "B"], FitOptions(auto=True))
    st.drift = DriftBlocks(st.basis, 2, max_open=1)
    label = time_block_labels(matched["t"].to_numpy())
    first, third = matched[label == label.min()], matched[label == label.min() + 2]
    for rows in (first, third, first):
        st.add(rows, st.samples(rows))
    # the late rows are a block of their own, folded at once (the oldest of two open): block 0 counted twice
    assert st.drift.late_rows == len(first) and list(st.drift.open) == [label.min() + 2]
    assert st.drift.folded.n_blocks == 2 and st.drift.folded.sum_n == 2 * len(first)
    assert st.drift.folded.link_blocks == 1  # one block label: one distinct block of the link


@pytest.mark.parametrize("max_open", [None, 1])
def test_the_drift_blocks_count_each_links_distinct_blocks(max_open):
    """Three nodes seen for 10 s: 6 block vectors (3 links x 2 blocks) but 2 distinct blocks
    per link, in the sums kept open or folded and at a smaller order (the fields copied): no
    drift read from them (it was: 6 vectors passed for 6 blocks)."""
    rng = np.random.default_rng(2)
    n = 500
    t = np.sort(rng.uniform(0.0, 10.0, n))
    tx = rng.integers(0, 3, n)
    rx = (tx + rng.integers(1, 3, n)) % 3
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), np.arcsin(rng.uniform(-1.0, 1.0, (2, n)))
    drift = DriftBlocks(make_basis("sh", 4), 3, max_open)
    drift.add(t, tx, rx, Directions(az[0], el[0], az[1], el[1]), rng.normal(0.0, 1.0, n))
    sums = drift.closed()
    small = drift.at(sums, make_basis("sh", 2))
    assert sums.n_blocks == small.n_blocks == 6 and sums.link_blocks == small.link_blocks == drift.link_block_count() == 2
    total = NormalEquations(make_basis("sh", 2), 3).add(Directions(az[0], el[0], az[1], el[1]), tx, rx, rng.normal(0.0, 1.0, n))
    assert block_drift_std_db(small, total, 1.0, 1e-6, 2.0, 1.0) is None


def test_a_few_seconds_session_states_no_drift_as_the_offline_fit(matched, tmp_path):
    """A session of 7 s (one link in 2 blocks, many block vectors once cut into stretches and
    both directions): no drift, as ``fit --order auto`` of the same rows states none (the
    offline fit stored 11.7 dB for such a flight before it counted distinct blocks per link)."""
    t = matched["t"].to_numpy()
    short = matched[t < t.min() + 7.0]
    st = _learn(short, ModelSpec.parse("sh"), FitOptions(auto=True), str(tmp_path))
    assert st.drift.link_block_count() < 4
    assert st.refit(final=True).model.training.drift_std_db is None
    write_table(short, str(tmp_path / "short.parquet"))
    offline = fit_dataset(str(tmp_path / "short.parquet"), ModelSpec.parse("sh"), ALL_STRETCHES, options=FitOptions(auto=True))
    assert offline.fitted.model.training.drift_std_db is None


def test_a_fixed_order_session_states_no_drift(matched):
    st = _learn(matched, ModelSpec.parse("sh", order=4), FitOptions(), None)
    assert st.drift is None and st.refit().model.training.drift_std_db is None


def test_a_fixed_order_refit_is_fit_of_every_sample(matched, tmp_path):
    spec = ModelSpec.parse("sh", order=6)
    st = _learn(matched, spec, FitOptions(), None)
    assert len(st.segments) == 1
    write_table(matched, str(tmp_path / "data.parquet"))
    offline = fit_dataset(str(tmp_path / "data.parquet"), spec, ALL_STRETCHES, options=FitOptions()).fitted.model
    assert _max_difference_db(st.refit().model, offline, matched) < 1e-6


def test_too_few_samples_for_an_automatic_choice_is_a_clear_error(matched):
    st = LiveStatistics(ModelSpec.parse("sh"), ["A", "B"], FitOptions(auto=True))
    rows = matched.iloc[:20]
    st.add(rows, st.samples(rows))
    with pytest.raises(Exception, match="too few"):
        st.refit()


def test_a_node_appearing_later_is_named(matched):
    st = LiveStatistics(ModelSpec.parse("sh", order=4), ["A"], FitOptions())
    with pytest.raises(Exception, match="node.*B"):
        st.samples(matched.iloc[:10])


def test_the_session_keeps_time_block_sums_and_a_whole_log_is_split_into_them(matched):
    """Batches of 1 s and the whole log in one batch give the same block sums (memory flat:
    two matrices, whatever the length); the total hands them on to the manoeuvre ranking."""
    spec = ModelSpec.parse("sh", order=4)
    batched = _learn(matched, spec, FitOptions(), None)
    whole = LiveStatistics(spec, ["A", "B"], FitOptions())
    whole.add(matched, whole.samples(matched))
    a, b = batched.total().blocks.closed(), whole.total().blocks.closed()
    assert a.n_blocks == b.n_blocks > 3 and a.sum_n == b.sum_n == len(matched)
    assert np.allclose(a.cross, b.cross, rtol=1e-9, atol=1e-6) and a.sum_yy == pytest.approx(b.sum_yy, rel=1e-9)
    assert batched.blocks is not None and batched.blocks.cross.shape == (2 * spec.basis().n_coef,) * 2


def test_outage_rows_in_a_batch_over_several_blocks_are_left_out_of_the_blocks(matched):
    """Outage rows have no sample: a batch spanning several time blocks (a whole log matched at
    the end) with lost-link rows is split by the kept samples' times (it raised IndexError)."""
    spec = ModelSpec.parse("sh", order=4)
    rows = matched.copy()
    rows["outage"] = False
    down = rows.index[[5, len(rows) // 2, len(rows) - 3]]
    rows.loc[down, "outage"] = True
    rows.loc[down, "rssi_dbm"] = np.nan
    st = LiveStatistics(spec, ["A", "B"], FitOptions())
    samples = st.samples(rows)
    assert len(samples) == len(rows) - 3 and samples.outages == 3
    st.add(rows, samples)
    assert st.blocks is not None and st.blocks.closed().sum_n == len(rows) - 3


def test_a_session_without_a_ranking_keeps_no_block_sums(matched):
    spec = ModelSpec.parse("sh", order=4)
    st = LiveStatistics(spec, ["A", "B"], FitOptions(), keep_blocks=False)
    st.add(matched, st.samples(matched))
    assert st.blocks is None and st.total().blocks is None and st.n_samples == len(matched)


@pytest.mark.parametrize("auto", [False, True], ids=["sh-4", "auto"])
def test_every_refit_records_the_flights_layout_of_the_rows_so_far(matched, offline, tmp_path, auto):
    """``training.fixed_nodes`` and ``packet_rate_hz`` of a refit, in flight and the last, are
    those of the rows learned read in memory (:mod:`rplearn.data.flight_layout`; two drones: none
    held still) and of ``fit`` of them; before, a live refit recorded neither."""
    from rplearn.data.flight_layout import fixed_nodes, packet_rate_hz
    spec = ModelSpec.parse("sh") if auto else ModelSpec.parse("sh", order=4)
    st = _learn(matched, spec, FitOptions(auto=auto), str(tmp_path) if auto else None)
    for final in (False, True):
        got = st.refit(final=final).model.training
        assert got.fixed_nodes == fixed_nodes(matched) == offline.training.fixed_nodes == ()
        assert got.packet_rate_hz == pytest.approx(packet_rate_hz(matched), rel=1e-12)
        assert got.packet_rate_hz == pytest.approx(offline.training.packet_rate_hz, rel=1e-12)


def test_the_coverage_grids_made_at_a_refit_are_those_combined_batch_by_batch(matched):
    """The grids come from the cells seen so far, made when a refit reads them: bit for bit the
    grids of each batch combined by the minimum (as ``fit`` of chunked data combines them)."""
    from rplearn.models.node_coverage import node_coverage_grids

    st = _learn(matched, ModelSpec.parse("sh-4"), FitOptions(), None, batch_s=3.0)
    t = matched["t"].to_numpy()
    expected = None
    for a in np.arange(t.min(), t.max() + 3.0, 3.0):
        rows = matched[(t >= a) & (t < a + 3.0)]
        if len(rows):
            expected = node_coverage_grids(st.samples(rows), expected)
    assert st.grids == expected and st.refit().model.training.coverage_deg == expected
