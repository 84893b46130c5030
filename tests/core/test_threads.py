"""One BLAS thread for small fits (issue 13, item 4); threads from the size and the free cores (issue 30)."""

from __future__ import annotations

import numpy  # noqa: F401  (loads the BLAS libraries whose threads are counted)
import pytest
import scipy.linalg  # noqa: F401
from threadpoolctl import threadpool_info

from rplearn.core import threads
from rplearn.core.threads import (
    SMALL_FIT_FLOPS,
    THREADS_ENV,
    blas_thread_count,
    blas_threads_for,
    free_cores,
    free_cores_of,
    is_small_fit,
    prediction_flops,
    thread_override,
    usable_cores,
)
from rplearn.errors import InputError


def blas_threads() -> list[int]:
    return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]


def test_small_fits_run_on_one_blas_thread_and_big_ones_keep_theirs(monkeypatch):
    before = blas_threads()
    assert before, "numpy's BLAS is visible to threadpoolctl"
    monkeypatch.delenv(THREADS_ENV, raising=False)
    monkeypatch.setattr(threads, "free_cores", lambda: max(before))  # an idle machine
    with blas_threads_for(1_333, 242):  # the paper's SH-10, two nodes
        assert blas_threads() == [1] * len(before)
    assert blas_threads() == before
    with blas_threads_for(2_000_000, 1_250):  # SH-24, two nodes, a long campaign
        assert blas_threads() == before


def test_the_rule():
    assert is_small_fit(1_333, 242) and is_small_fit(20_000, 242)
    assert not is_small_fit(2_000_000, 242) and not is_small_fit(10, 3_000)
    assert SMALL_FIT_FLOPS > 1_333 * 242**2


def test_a_fixed_order_fit_imports_no_scipy_and_order_selection_limits_scipys_blas(tmp_path):
    """scipy costs 0.1-0.3 s to import: a fixed-order fit goes without it. Order selection loads
    it with its module, before any BLAS limit, so a limit reaches scipy's OpenBLAS too."""
    import subprocess
    import sys
    import textwrap

    from rplearn.sim.flight import simulate

    simulate("smoke", seed=1).matched_truth.to_parquet(tmp_path / "m.parquet")
    code = textwrap.dedent(f"""
        import sys
        from rplearn.workflows.learning import fit_dataset
        from rplearn.models.spec import ModelSpec
        fit_dataset({str(tmp_path / "m.parquet")!r}, ModelSpec.parse("sh-6"))
        assert not [m for m in sys.modules if m == "scipy" or m.startswith("scipy.")], "scipy imported"
        from threadpoolctl import threadpool_info
        from rplearn.core.threads import blas_threads_for
        import rplearn.models.auto  # order selection
        assert "scipy.linalg" in sys.modules
        libs = [p for p in threadpool_info() if p["user_api"] == "blas"]
        assert len(libs) == 2 and min(p["num_threads"] for p in libs) > 1, libs  # numpy's and scipy's, threaded
        with blas_threads_for(1_333, 242):
            assert [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"] == [1] * len(libs)
        print("ok", len(libs))
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0 and proc.stdout.startswith("ok"), proc.stdout + proc.stderr


def test_an_openmp_limit_leaves_a_concurrent_blas_limit_alone():
    """threadpoolctl's limiter restores every library it holds: the OpenMP limit of a coverage
    query, ending while another thread holds a BLAS limit, must not undo (or keep) that one."""
    import threading

    import pykdtree.kdtree  # noqa: F401  (its OpenMP runtime)

    from rplearn.core.threads import one_blas_thread, one_openmp_thread

    before = blas_threads()
    if max(before) < 2:
        import pytest

        pytest.skip("BLAS runs one thread here: nothing to restore")
    a_in, b_in, a_out = threading.Event(), threading.Event(), threading.Event()
    seen: list[list[int]] = []

    def a() -> None:
        with one_blas_thread():
            a_in.set()
            b_in.wait(5)
        a_out.set()

    def b() -> None:
        a_in.wait(5)
        with one_openmp_thread():
            b_in.set()
            a_out.wait(5)
        seen.append(blas_threads())

    threads = [threading.Thread(target=a), threading.Thread(target=b)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(10)
    assert seen == [before] and blas_threads() == before


def test_a_log_distance_fit_loads_scipy_before_its_clock_starts():
    """The exponent's identifiability check solves through scipy: imported during the warm-up
    (not timed), not inside the first fit's LTD."""
    import subprocess
    import sys

    code = ("import sys\nfrom rplearn.models.fit import _warm_up\nfrom rplearn.models.spec import ModelSpec\n"
            "from rplearn.core.environment import PathLoss\nfrom rplearn.models.options import FitOptions\n"
            "_warm_up(ModelSpec.parse('sh-6'), 100)\nassert 'scipy.linalg' not in sys.modules\n"
            "_warm_up(ModelSpec.parse('sh-6'), 100, FitOptions(path_loss=PathLoss('log-distance')))\nassert 'scipy.linalg' in sys.modules\n"
            "print('ok')")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stdout + proc.stderr


def test_overlapping_blas_limits_from_two_threads_leave_the_threads_as_they_were():
    """A limit is process-wide and restores what it found: one thread's limit (the statistics'
    workers) and another's (a large solve's hold on numpy's BLAS) ending in either order must
    not leave numpy on one thread, or lift a limit whose work still runs (found by review)."""
    import threading

    from rplearn.core.threads import numpy_blas_one_thread, one_blas_thread

    before = blas_threads()
    assert max(before) > 1, "this machine's BLAS runs several threads"
    for first, second in ((one_blas_thread, numpy_blas_one_thread), (numpy_blas_one_thread, one_blas_thread)):
        a_in, b_in, a_out = threading.Event(), threading.Event(), threading.Event()
        inside_a: list[list[int]] = []

        def a() -> None:
            with first():
                a_in.set()
                b_in.wait(5)
                inside_a.append(blas_threads())  # b's limit has ended by now: a's must still hold
            a_out.set()

        def b() -> None:
            a_in.wait(5)
            with second():
                pass
            b_in.set()
            a_out.wait(5)

        threads = [threading.Thread(target=a), threading.Thread(target=b)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(10)
        assert min(inside_a[0]) == 1, (first.__name__, inside_a)
        assert blas_threads() == before, (first.__name__, second.__name__)


def test_free_cores_are_the_usable_ones_less_the_others_load():
    assert free_cores_of(2, 1.0) == 2  # only this process runs
    assert free_cores_of(2, 2.0) == 1  # another keeps a core busy
    assert free_cores_of(2, 9.0) == 1  # never fewer than one
    assert free_cores_of(8, 3.0) == 6 and free_cores_of(8, 0.0) == 8
    assert 1 <= free_cores() <= usable_cores()


def test_big_work_gets_the_free_cores_and_small_work_one_thread(monkeypatch):
    monkeypatch.delenv(THREADS_ENV, raising=False)
    monkeypatch.setattr(threads, "free_cores", lambda: 1)  # a core busy elsewhere
    assert blas_thread_count(1e12) == 1
    monkeypatch.setattr(threads, "free_cores", lambda: 4)
    assert blas_thread_count(1e12) == 4 and blas_thread_count(SMALL_FIT_FLOPS / 2) == 1
    # a million links with spreads is big work, ten thousand without is not
    assert prediction_flops(1_000_000, 100, spreads=True) >= SMALL_FIT_FLOPS
    assert prediction_flops(10_000, 100) < SMALL_FIT_FLOPS


def test_the_environment_overrides_the_policy_everywhere(monkeypatch):
    monkeypatch.setenv(THREADS_ENV, "1")
    assert thread_override() == 1 and blas_thread_count(1e15) == 1
    before = blas_threads()
    with blas_threads_for(2_000_000, 1_250):  # big, but the override says one thread
        assert blas_threads() == [1] * len(before)
    assert blas_threads() == before
    monkeypatch.setenv(THREADS_ENV, "3")
    assert blas_thread_count(10.0) == 3  # even small work
    for bad in ("0", "-2", "two", "1.5"):
        monkeypatch.setenv(THREADS_ENV, bad)
        with pytest.raises(InputError, match=THREADS_ENV) as err:
            thread_override()
        assert err.value.param == THREADS_ENV
    monkeypatch.setenv(THREADS_ENV, "")
    assert thread_override() is None


def test_a_prediction_runs_under_the_policy(monkeypatch):
    import numpy as np

    from rplearn.core.bases import make_basis
    from rplearn.core.geometry import Directions
    from rplearn.data.tables import LinkSamples
    from rplearn.models.patterns import PatternSet

    basis = make_basis("sh", 3)
    model = PatternSet(basis, ("A", "B"), np.ones((2, basis.n_coef)), covariance=np.eye(2 * basis.n_coef))
    z = np.zeros(4)
    samples = LinkSamples(Directions(z, z, z, z), np.zeros(4, np.intp), np.ones(4, np.intp), ("A", "B"),
                          np.full(4, np.nan), np.full(4, 10.0), np.full(4, 2.4e9))
    seen = []
    real = basis.evaluate

    def spy(*args):
        seen.append(blas_threads())
        return real(*args)

    monkeypatch.setattr(type(basis), "evaluate", lambda self, *a: spy(*a))
    monkeypatch.delenv(THREADS_ENV, raising=False)
    model.predict_gain(samples)
    assert seen and all(counts == [1] * len(counts) for counts in seen)  # small work: one thread
