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
        from rplearn.core.blas import blas_threads_for
        import rplearn.models.auto  # order selection
        assert "scipy.linalg" in sys.modules
        libs = [p for p in threadpool_info() if p["user_api"] == "blas"]
        with blas_threads_for(1_333, 242):
            assert [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"] == [1] * len(libs)
        print("ok", len(libs))
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0 and proc.stdout.startswith("ok"), proc.stdout + proc.stderr
