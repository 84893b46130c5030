"""One BLAS thread for small fits (issue 13, item 4)."""

from __future__ import annotations

import numpy  # noqa: F401  (loads the BLAS libraries whose threads are counted)
import scipy.linalg  # noqa: F401
from threadpoolctl import threadpool_info

from rplearn.core.blas import SMALL_FIT_FLOPS, blas_threads_for, is_small_fit


def blas_threads() -> list[int]:
    return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]


def test_small_fits_run_on_one_blas_thread_and_big_ones_keep_theirs():
    before = blas_threads()
    assert before, "numpy's BLAS is visible to threadpoolctl"
    with blas_threads_for(1_333, 242):  # the paper's SH-10, two nodes
        assert blas_threads() == [1] * len(before)
    assert blas_threads() == before
    with blas_threads_for(2_000_000, 1_250):  # SH-24, two nodes, a long campaign
        assert blas_threads() == before


def test_the_rule():
    assert is_small_fit(1_333, 242) and is_small_fit(20_000, 242)
    assert not is_small_fit(2_000_000, 242) and not is_small_fit(10, 3_000)
    assert SMALL_FIT_FLOPS > 1_333 * 242**2
