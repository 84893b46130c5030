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
