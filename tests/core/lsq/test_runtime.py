"""The process-wide resources of the statistics (rplearn.core.lsq.runtime): one object owns the
worker pool, its lock, the per-thread block buffers and the fork hook."""

from __future__ import annotations

import os
import sys
import threading

import numpy as np
import pytest

from rplearn.core.lsq.runtime import DEFAULT_RUNTIME, StatisticsRuntime


def test_blocks_come_back_in_order_and_errors_reach_the_caller():
    def work(s: int) -> int:
        if s == 7:
            raise ValueError("block 7")
        return s * s

    assert list(DEFAULT_RUNTIME.in_order(work, range(6))) == [s * s for s in range(6)]
    assert list(DEFAULT_RUNTIME.in_order(work, [3])) == [9]
    with pytest.raises(ValueError, match="block 7"):
        list(DEFAULT_RUNTIME.in_order(work, range(10)))
    assert list(DEFAULT_RUNTIME.in_order(work, range(3))) == [0, 1, 4]  # the pool is free again


def test_a_busy_pool_leaves_the_caller_to_compute_its_blocks_itself():
    runtime = StatisticsRuntime()
    seen: list[str] = []

    def work(s: int) -> int:
        seen.append(threading.current_thread().name)
        return s

    outer = runtime.in_order(work, range(4))
    assert next(outer) == 0  # the pool is now held by this generator
    assert list(runtime.in_order(work, range(4))) == [0, 1, 2, 3]
    assert list(outer) == [1, 2, 3]
    assert threading.current_thread().name in seen and any(n.startswith("rplearn-stats") for n in seen)


def test_each_runtime_owns_its_buffers_per_thread():
    runtime = StatisticsRuntime()
    assert runtime.buffer_size() == 0
    buf = runtime.block_buffer(1000)
    assert buf.size == 1000 and runtime.buffer_size() == 1000 and np.all(buf == 0.0)
    assert runtime.block_buffer(10).base is buf.base  # reused, not grown
    sizes: list[int] = []
    other = threading.Thread(target=lambda: sizes.append(runtime.buffer_size()))
    other.start()
    other.join()
    assert sizes == [0]  # another thread has a buffer of its own
    runtime.release_buffer()
    assert runtime.buffer_size() == 0


@pytest.mark.skipif(not hasattr(os, "fork") or sys.platform == "darwin", reason="needs fork")
def test_a_forked_child_starts_with_a_fresh_pool():
    """Forked while the parent holds the pool: the child has neither its threads nor its lock."""
    runtime = StatisticsRuntime()
    held = runtime.in_order(lambda s: s, range(3))
    assert next(held) == 0 and runtime._pool is not None
    pid = os.fork()
    if pid == 0:  # the child: no pool, and a free lock of its own
        os._exit(0 if runtime._pool is None and runtime._lock.acquire(blocking=False) else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert runtime._pool is not None and list(held) == [1, 2]  # the parent keeps its own


def test_riding_jobs_are_queued_behind_the_last_block_and_run_on_the_workers():
    """Jobs given to ``overlapping`` are submitted to the pool after every block of the pass (the
    pool starts its queue in order) and run on the workers; results come in the jobs' order."""
    from concurrent.futures import ThreadPoolExecutor

    submitted: list[str] = []

    class Recording(ThreadPoolExecutor):
        def submit(self, fn, /, *args, **kwargs):  # type: ignore[override]
            submitted.append("block" if args else "job")
            return super().submit(fn, *args, **kwargs)

    runtime = StatisticsRuntime()
    runtime._pool = Recording(max_workers=2, thread_name_prefix="rplearn-stats")

    def job(i: int):
        return lambda: (i, threading.current_thread().name)

    with runtime.overlapping([job(0), job(1), job(2)]) as riding:
        assert not riding.started
        assert list(runtime.in_order(lambda s: s, range(5))) == [0, 1, 2, 3, 4]
        assert riding.started
        assert list(runtime.in_order(lambda s: s, range(2))) == [0, 1]  # a later pass queues them no more
        results = riding.results()
    assert submitted == ["block"] * 5 + ["job"] * 3 + ["block"] * 2
    assert [i for i, _ in results] == [0, 1, 2]
    assert all(name.startswith("rplearn-stats") for _, name in results)


def test_riding_jobs_no_pass_queued_are_computed_when_asked_and_once():
    runtime = StatisticsRuntime()
    calls: list[int] = []

    def job(i: int):
        return lambda: calls.append(i) or i * 10

    with runtime.overlapping([job(0), job(1)]) as riding:
        assert list(runtime.in_order(lambda s: s, [5])) == [5]  # one block: the caller's, no workers
        assert not riding.started
        assert riding.results() == [0, 10]  # computed now (two jobs: on the workers)
    assert sorted(calls) == [0, 1]
    with runtime.overlapping([]) as riding:
        pass
    assert riding.results() == []


def test_an_error_inside_the_block_settles_the_riding_jobs_and_a_jobs_error_reaches_the_caller():
    runtime = StatisticsRuntime()
    gate = threading.Event()
    ran: list[int] = []

    def slow() -> int:
        gate.wait(5)
        ran.append(1)
        return 1

    with pytest.raises(ValueError, match="in the block"):
        with runtime.overlapping([slow, slow, slow, slow]) as riding:
            list(runtime.in_order(lambda s: s, range(2)))
            gate.set()
            raise ValueError("in the block")
    assert all(f.done() for f in riding._futures or [])  # none left running behind the caller

    def bad() -> int:
        raise KeyError("job")

    with runtime.overlapping([bad]) as riding:
        list(runtime.in_order(lambda s: s, range(2)))
    with pytest.raises(KeyError, match="job"):
        riding.results()


def test_jobs_beside_the_caller_run_on_the_workers_and_come_back_in_order():
    """``beside``: the jobs run on the workers while the caller works; their results in the
    jobs' order; an error of a job reaches the caller; the pool is free again afterwards."""
    runtime = StatisticsRuntime()
    where: list[str] = []

    def job(k: int):
        def run() -> int:
            where.append(threading.current_thread().name)
            return k * k
        return run

    with runtime.beside([job(k) for k in range(5)]) as results:
        mine = sum(range(100))  # the caller's own work meanwhile
        assert results() == [0, 1, 4, 9, 16]
        assert results() == [0, 1, 4, 9, 16]  # asked again: the same, not run again
    assert mine == 4950 and len(where) == 5
    assert all(name.startswith("rplearn-stats") for name in where)

    def fails() -> int:
        raise ValueError("job 1")

    with pytest.raises(ValueError, match="job 1"), runtime.beside([job(0), fails]) as results:
        results()
    assert list(runtime.in_order(lambda s: s + 1, range(3))) == [1, 2, 3]  # the pool is free again


def test_jobs_beside_a_busy_pool_run_in_the_caller_when_asked_and_once():
    runtime = StatisticsRuntime()
    runs: list[str] = []

    def job() -> int:
        runs.append(threading.current_thread().name)
        return 7

    outer = runtime.in_order(lambda s: s, range(4))
    assert next(outer) == 0  # the pool is held by this generator
    with runtime.beside([job, job]) as results:
        assert runs == []  # nothing runs before it is asked for
        assert results() == [7, 7] and results() == [7, 7]
    assert runs == [threading.current_thread().name] * 2
    assert list(outer) == [1, 2, 3]
    with runtime.beside([]) as results:  # no job: nothing to hold the pool for
        assert results() == []


@pytest.mark.parametrize("ahead", [None, 6])
def test_a_caller_that_keeps_every_result_queues_every_job_behind_a_long_one(ahead):
    """``in_order(ahead=n)``: all ``n`` jobs queued at once, so that the other worker goes on past
    a long first job (the order selection's final solve beside the inflations' folds); by
    default only :attr:`StatisticsRuntime.ahead` are (the accumulation's bounded memory)."""
    runtime = StatisticsRuntime(workers=2, ahead=3)
    last_started = threading.Event()

    def work(i: int) -> bool:
        if i == 0:  # the long job: done when the last job has started, or after a while
            return last_started.wait(timeout=1.0)
        if i == 5:
            last_started.set()
        return True

    try:
        results = list(runtime.in_order(work, range(6), ahead=ahead))
    finally:
        runtime.forget_pool()
    assert results[1:] == [True] * 5
    assert results[0] is (ahead is not None)
