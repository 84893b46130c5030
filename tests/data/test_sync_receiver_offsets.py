"""Signal clock offsets per receiver (``SyncOptions.signal_clock_offset_s``) naming a node no signal row names as its
receiver (review 51): the offset was ignored without a word by ``sync`` (whole or streamed) and ``live``. ``sync``
refuses it naming the option, the node and the receivers; live, where a receiver may start late, checks it at the
end of the stream and says it in a note (as it says a pose clock offset naming a node without poses)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from rplearn.data.live_sync import LiveMatcher
from rplearn.data.streaming import synchronise_stream, synchronise_to_parquet
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.errors import InputError

REFUSAL = r"signal clock offsets \(signal_clock_offset_s\) name receiver\(s\) Z that no signal row names as rx; receivers: A, B$"


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> tuple[Path, Path, pd.DataFrame, pd.DataFrame]:
    """The smoke flight (nodes A and B, both links) as CSV files and as canonical logs."""
    from rplearn.io import read_logs
    from rplearn.sim import simulate

    out = tmp_path_factory.mktemp("smoke")
    paths = simulate("smoke", seed=0, out_dir=str(out), log_format="csv").paths
    logs, _ = read_logs([paths["pose_log"], paths["signal_log"]])
    return Path(paths["pose_log"]), Path(paths["signal_log"]), logs.pose, logs.signal


@pytest.mark.parametrize("offsets", [{"Z": 1.0}, {"A": 0.5, "Z": 1.0}])
def test_sync_refuses_an_offset_for_a_receiver_no_row_names(flight, tmp_path, offsets):
    _, _, pose, signal = flight
    options = SyncOptions(signal_clock_offset_s=offsets)
    with pytest.raises(InputError, match="^signal log: " + REFUSAL) as got:
        synchronise(pose, signal, options)
    assert got.value.param == "signal_clock_offset_s"
    chunks = [signal.iloc[:500], signal.iloc[500:]]
    with pytest.raises(InputError, match=REFUSAL):
        list(synchronise_stream(pose, chunks, options))
    with pytest.raises(InputError, match=REFUSAL):
        synchronise_to_parquet(pose, chunks, str(tmp_path / "d.parquet"), options)
    assert list(tmp_path.iterdir()) == []


def test_an_offset_for_a_node_that_only_transmits_is_refused(flight):
    """An offset per receiver shifts the rows that node receives: a node named only as tx has none to shift."""
    _, _, pose, signal = flight
    one_way = signal[signal["rx"] == "B"]
    with pytest.raises(InputError, match=r"name receiver\(s\) A that no signal row names as rx; receivers: B$"):
        synchronise(pose, one_way, SyncOptions(signal_clock_offset_s={"A": 0.5}))


def test_offsets_for_the_receivers_the_rows_name_are_taken(flight):
    _, _, pose, signal = flight
    plain = synchronise(pose, signal)
    shifted = synchronise(pose, signal, SyncOptions(signal_clock_offset_s={"A": 0.0, "B": 0.0}))
    assert shifted.summary.n_out == plain.summary.n_out > 2000


def test_sync_logs_refuses_it_and_writes_nothing(flight, tmp_path):
    from rplearn.workflows.logs import sync_logs

    pose, signal, _, _ = flight
    with pytest.raises(InputError, match=f"^{signal}: " + REFUSAL):
        sync_logs([str(pose)], [str(signal)], str(tmp_path / "d.parquet"), sync_options=SyncOptions(signal_clock_offset_s={"Z": 1.0}))
    assert list(tmp_path.iterdir()) == []


def test_live_matching_checks_it_at_the_end_of_the_stream(flight):
    """A receiver may start late in a stream: no refusal while rows come, the check at the end."""
    _, _, pose, signal = flight
    matcher = LiveMatcher(SyncOptions(signal_clock_offset_s={"A": 0.0, "Z": 1.0}))
    matcher.add_poses(pose)
    matcher.add_signals(signal.iloc[:1000])
    assert len(matcher.match().dataset) > 0
    matcher.add_signals(signal.iloc[1000:])
    with pytest.raises(InputError, match="^signal stream: " + REFUSAL):
        matcher.match(final=True)
    assert len(matcher.last_matched) > 1000  # the rows of the last match are kept (rplearn live learns them)


def test_rplearn_live_says_it_in_a_note(flight, tmp_path):
    from rplearn.workflows.live import LiveOptions, run_live

    pose, signal, _, _ = flight
    options = LiveOptions(refit_s=5.0, idle_s=0.3, sync=SyncOptions(signal_clock_offset_s={"Z": 1.0}))
    outcome = run_live(f"{pose},{signal}", str(tmp_path / "m.json"), options)
    assert outcome.status.matched > 2000 and (tmp_path / "m.json").exists()
    assert any(n.startswith("signal stream: signal clock offsets (signal_clock_offset_s) name receiver(s) Z") for n in outcome.status.notes)
