"""rplearn.workflows.live_ranking: the manoeuvre ranking runs beside the live loop, one at a
time, and the refits go on meanwhile; a stop or Ctrl-C does not wait for it."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import rplearn.workflows.live as live_module
from rplearn.data.sync import synchronise
from rplearn.data.tables import link_samples
from rplearn.models.load import load_model
from rplearn.models.options import FitOptions
from rplearn.models.spec import ModelSpec
from rplearn.sim import simulate
from rplearn.workflows.live import LiveOptions, replay_session, run_live
from rplearn.workflows.live_ranking import RankingWorker

ROWS = [("orbit", 30.0, 1.5), ("yaw turn", 10.0, 1.2), ("climb", 20.0, 1.9), ("descent", 20.0, 2.5)]


@pytest.fixture(scope="module")
def smoke() -> tuple[pd.DataFrame, pd.DataFrame]:
    r = simulate("smoke", seed=0)
    return r.pose_log, r.signal_log.drop(columns=["unit"])


class _Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_one_ranking_at_a_time_its_snapshot_taken_only_when_it_starts():
    gate, snapshots = threading.Event(), []

    def ranker(stats, fitted, latest):
        gate.wait(30.0)
        return ROWS

    def snapshot():
        snapshots.append(1)
        return None, None, pd.DataFrame()

    worker = RankingWorker(ranker, beside=True)
    assert worker.submit(snapshot, refit=1) and worker.running
    assert not worker.submit(snapshot, refit=2) and snapshots == [1]  # never two at once
    assert worker.collect() is None
    gate.set()
    assert worker.wait(30.0)
    done = worker.collect()
    assert done is not None and done.refit == 1 and list(done.rows) == ROWS and done.took_s >= 0
    assert worker.collect() is None  # collected once
    assert worker.submit(snapshot, refit=3) and worker.wait(30.0) and worker.collect().refit == 3


def test_the_period_between_starts_and_a_failure_kept_as_a_note():
    clock = _Clock()
    calls = []

    def ranker(stats, fitted, latest):
        calls.append(1)
        if len(calls) == 2:
            raise ValueError("singular")
        return ROWS

    worker = RankingWorker(ranker, beside=False, every_s=15.0, clock=clock)
    snap = lambda: (None, None, pd.DataFrame())  # noqa: E731
    assert worker.submit(snap, 1) and worker.collect().rows[0][0] == "orbit"
    clock.now += 14.0
    assert not worker.submit(snap, 2)
    clock.now += 1.0
    assert worker.submit(snap, 3)
    failed = worker.collect()
    assert failed.rows == () and failed.error == "ValueError: singular"


def test_a_closed_worker_drops_the_running_ranking_and_starts_none():
    gate = threading.Event()
    worker = RankingWorker(lambda *a: gate.wait(30.0) and ROWS, beside=True)
    worker.submit(lambda: (None, None, pd.DataFrame()), 1)
    worker.close()
    gate.set()
    worker.wait(30.0)
    assert worker.collect() is None and worker.started == 1 and worker.finished == 0
    assert not worker.submit(lambda: (None, None, pd.DataFrame()), 2)


def test_refits_go_on_while_a_slow_ranking_runs(smoke, tmp_path):
    """A ranking that returns only after three more refits: in the loop it could never end
    (it would wait 60 s for refits that cannot come); beside the loop they come. Only the first
    ranking waits so: the last ones, started near the end of the logs, would each wait the 60 s
    for refits that never come (the replay waits for them at its end)."""
    pose, sig = smoke
    refits: list[int] = []
    seen: dict[str, int] = {}

    def on_update(status) -> None:
        refits.append(status.refits)

    def slow(stats, fitted, latest):
        if "start" in seen:
            return ROWS
        start = refits[-1] if refits else 0
        deadline = time.monotonic() + 60.0
        while (refits[-1] if refits else 0) < start + 3 and time.monotonic() < deadline:
            time.sleep(0.01)
        seen.setdefault("start", start)
        seen.setdefault("end", refits[-1])
        return ROWS

    options = LiveOptions(spec=ModelSpec.parse("sh", order=4), fit=FitOptions(), refit_s=5.0, manoeuvres=slow)
    outcome = replay_session(pose, sig, str(tmp_path / "m.json"), options, on_update=on_update)
    assert seen["end"] >= seen["start"] + 3  # three refits while the first ranking ran
    assert outcome.status.refits > seen["end"]
    assert outcome.status.manoeuvres == ROWS[:3] and outcome.status.manoeuvres_refit >= 1
    assert "ranked at refit" in outcome.status.summary()


def _without_times(doc):
    """A model file's content without its wall times (learning time) and hash."""
    if isinstance(doc, dict):
        return {k: _without_times(v) for k, v in doc.items() if not (k.endswith("_s") and "ltd" in k) and k != "sha256"}
    if isinstance(doc, list):
        return [_without_times(v) for v in doc]
    return doc


def test_the_final_model_is_that_of_the_ranking_in_the_loop(smoke, tmp_path):
    pose, sig = smoke

    def ranker(stats, fitted, latest):
        time.sleep(0.2)  # slower than a batch: rankings overlap the refits
        return ROWS

    outcomes = {}
    for beside in (True, False):  # a refit every 15 s of the 75 s flight: five automatic-order refits and the last
        options = LiveOptions(refit_s=15.0, manoeuvres=ranker, rank_beside=beside)
        out = tmp_path / f"{beside}.json"
        # 3-s batches: a refit every fifth batch (every fifteenth at 1 s), a third of the batches
        outcomes[beside] = (replay_session(pose, sig, str(out), options, batch_s=3.0), out)
    (a, path_a), (b, path_b) = outcomes[True], outcomes[False]
    assert a.status.refits == b.status.refits and a.fitted.model.label == b.fitted.model.label
    # a ranking beside the loop holds the process-wide BLAS limit at one thread while it runs, so the
    # batches predicted meanwhile may be summed by another thread count: the running score agrees
    # to rounding, the final model (refitted after the ranking ends) bit for bit
    assert a.prequential.n_samples == b.prequential.n_samples
    assert a.prequential.sse == pytest.approx(b.prequential.sse, rel=1e-12, abs=0.0)
    s = link_samples(synchronise(pose, sig).dataset, "smoke", nodes=a.fitted.model.nodes)
    np.testing.assert_array_equal(a.fitted.model.predict_gain(s), b.fitted.model.predict_gain(s))
    np.testing.assert_array_equal(a.fitted.model.predict_gain_std(s), b.fitted.model.predict_gain_std(s))
    assert a.status.manoeuvres == b.status.manoeuvres == ROWS[:3]
    assert _without_times(json.loads(path_a.read_text())) == _without_times(json.loads(path_b.read_text()))


def _csv_source(pose: pd.DataFrame, sig: pd.DataFrame, folder: Path) -> str:
    pose.to_csv(folder / "pose.csv", index=False)
    sig.to_csv(folder / "signal.csv", index=False)
    return f"{folder / 'pose.csv'},{folder / 'signal.csv'}"


class _Workers(list):
    """Records the session's ranking worker."""

    def make(self, *args, **kwargs) -> RankingWorker:
        worker = RankingWorker(*args, **kwargs)
        self.append(worker)
        return worker


def test_a_stop_does_not_wait_for_a_running_ranking(smoke, tmp_path, monkeypatch):
    pose, sig = smoke
    gate = threading.Event()
    workers = _Workers()
    monkeypatch.setattr(live_module, "RankingWorker", workers.make)
    # the stop's wait for the ranking, 5 s, shortened: the ranking waits 120 s, so a stop that
    # waited for it would still take longer than the 100 s checked below
    monkeypatch.setattr(live_module, "STOP_RANKING_WAIT_S", 0.5)
    options = LiveOptions(spec=ModelSpec.parse("sh", order=4), fit=FitOptions(), refit_s=0.2, idle_s=1.0,
                          manoeuvres=lambda *a: gate.wait(120.0) and ROWS)
    try:
        t0 = time.monotonic()
        outcome = run_live(_csv_source(pose, sig, tmp_path), str(tmp_path / "m.json"), options)
        took = time.monotonic() - t0
        worker = workers[0]
        assert worker.started >= 1 and worker.running and worker.closed  # left running, its result to be dropped
        assert took < 100.0  # it returned long before the ranking could
        assert outcome.status.stopped.startswith("end of stream") and not outcome.status.ranking_running
        assert any(n.startswith("stop: ") and "BLAS limit" in n for n in outcome.status.notes)  # waited, then said
    finally:
        gate.set()
    assert worker.wait(30.0) and worker.collect() is None and worker.finished == 0
    assert load_model(str(tmp_path / "m.json")).label == outcome.fitted.model.label


def test_ctrl_c_while_a_ranking_runs_leaves_the_last_model(smoke, tmp_path, monkeypatch):
    pose, sig = smoke
    gate = threading.Event()
    workers = _Workers()
    monkeypatch.setattr(live_module, "RankingWorker", workers.make)

    def on_update(status) -> None:
        if status.ranking_running:
            raise KeyboardInterrupt

    options = LiveOptions(spec=ModelSpec.parse("sh", order=4), fit=FitOptions(), refit_s=0.2, idle_s=30.0,
                          manoeuvres=lambda *a: gate.wait(120.0) and ROWS)
    try:
        with pytest.raises(KeyboardInterrupt):
            run_live(_csv_source(pose, sig, tmp_path), str(tmp_path / "m.json"), options, on_update=on_update)
        assert workers[0].closed and workers[0].running
    finally:
        gate.set()
    assert workers[0].wait(30.0) and workers[0].collect() is None
    model = load_model(str(tmp_path / "m.json"))
    s = link_samples(synchronise(pose, sig).dataset, "smoke", nodes=model.nodes)
    assert np.isfinite(model.predict_gain(s)).all()


def _blas_threads() -> list[int]:
    from threadpoolctl import threadpool_info

    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


def test_a_ranking_started_while_a_refit_holds_a_limit_still_ranks_on_one_blas_thread():
    """A refit of the loop holds a 2-thread BLAS limit when the ranking starts: the ranking
    waits for it to end, then ranks on one thread (not the whole ranking on the refit's two)."""
    from rplearn.core.threads import _controller, _exclusive_limit

    held, release = threading.Event(), threading.Event()
    seen: list[list[int]] = []

    def refit() -> None:
        with _exclusive_limit(_controller().select(user_api="blas"), 2):
            held.set()
            release.wait(30.0)

    def ranker(stats, fitted, latest):
        seen.append(_blas_threads())
        return ROWS

    loop = threading.Thread(target=refit)
    loop.start()
    assert held.wait(30.0) and max(_blas_threads()) == 2
    worker = RankingWorker(ranker, beside=True)
    worker.submit(lambda: (None, None, pd.DataFrame()), 1)
    time.sleep(0.2)
    release.set()
    loop.join(30.0)
    assert worker.wait(30.0) and worker.collect().rows
    assert seen == [[1] * len(seen[0])]


def test_a_ranking_finished_between_refits_is_on_the_page_at_once(smoke, tmp_path):
    """The ``--html`` page is rewritten when a ranking arrives, not only at the next refit."""
    pose, sig = smoke
    page = tmp_path / "live.html"
    seen: list[bool] = []

    def on_update(status) -> None:
        if status.manoeuvres and not seen:
            seen.append("next manoeuvre 1" in page.read_text() and ROWS[0][0] in page.read_text())

    def ranker(*args):
        time.sleep(0.5)  # finishes after the refit that started it has written the page
        return ROWS

    # the CSVs are whole at the first read: after the first refit (1 s in) no new sample comes, so
    # no refit writes the page again; the ranking 0.5 s later is on it all the same (the silence
    # that ends the stream leaves it 2.5 s, as 8 s did after a first refit at 5 s)
    options = LiveOptions(spec=ModelSpec.parse("sh", order=4), fit=FitOptions(), refit_s=1.0, idle_s=4.0,
                          manoeuvres=ranker)
    run_live(_csv_source(pose, sig, tmp_path), str(tmp_path / "m.json"), options, on_update=on_update, html=str(page))
    assert seen == [True]


def test_the_last_refit_after_a_stop_does_not_run_under_a_rankings_blas_limit(smoke, tmp_path, monkeypatch):
    """A ranking still running at the end of the stream holds the BLAS limit: the stop waits for
    it (up to STOP_RANKING_WAIT_S) so the last refit finds the limit free."""
    from rplearn.core import threads

    pose, sig = smoke
    free_at_last_refit: list[bool] = []
    refit = live_module._Session.refit

    def recording_refit(self, final=False):
        if final:
            got = threads._LIMIT_LOCK.acquire(blocking=False)
            if got:
                threads._LIMIT_LOCK.release()
            free_at_last_refit.append(got)
        return refit(self, final)

    monkeypatch.setattr(live_module._Session, "refit", recording_refit)
    workers = _Workers()
    monkeypatch.setattr(live_module, "RankingWorker", workers.make)

    def ranker(*args):
        time.sleep(2.0)  # still running when the stream ends (idle_s after the only read)
        return ROWS

    options = LiveOptions(spec=ModelSpec.parse("sh", order=4), fit=FitOptions(), refit_s=0.2, idle_s=1.0,
                          manoeuvres=ranker)
    outcome = run_live(_csv_source(pose, sig, tmp_path), str(tmp_path / "m.json"), options)
    assert workers[0].started == 1 and not workers[0].running and workers[0].closed
    assert free_at_last_refit == [True]
    assert not any(n.startswith("stop: ") for n in outcome.status.notes)
    assert live_module.STOP_RANKING_WAIT_S > 2.0
