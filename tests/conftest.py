"""Test-session setup shared by every test module."""

import os

# scikit-learn's array-API conformance checks (run by tests/test_estimators.py) only run when
# scipy's array-API support is on, and scipy reads this once, at import: set it before any test
# module imports scipy, so that those checks run instead of being skipped.
os.environ.setdefault("SCIPY_ARRAY_API", "1")

# The simulator's coloured noise (rplearn.sim.noise.ar1_filter) runs scipy's lfilter, the same
# bits as its plain loop, whenever scipy.signal is imported already (a process that only
# simulates a smoke flight is spared the import): imported here once per test process, the
# suite's many simulated flights skip the loop (about 60 s of the suite's CPU, py-spy).
import scipy.signal  # noqa: E402,F401

#: The order the suite's files run in (``make test``: ``pytest -n 2``, xdist's ``load`` scheduling,
#: which hands the tests out in this order: large runs of consecutive tests at the start, a few
#: at a time at the end). The longest tests first, so that none starts last while the other
#: worker has nothing left to do, and the many short unit tests last, where a module split
#: between the two workers costs the least (each worker builds the module's fixtures). A path
#: named by none of these runs in the middle, in collection order; the order within a file is
#: never changed.
FIRST = ("tests/test_benchmarks.py", "tests/test_readme_examples.py", "tests/test_typing.py", "tests/test_docs.py",
         "tests/test_field_guide.py", "tests/analysis/", "tests/cli/", "tests/io/", "tests/workflows/", "tests/models/",
         "tests/viz/", "tests/integrations/", "tests/sim/", "tests/test_signatures.py")
LAST = ("tests/test_architecture.py", "tests/data/", "tests/plan/", "tests/core/", "tests/test_atomic.py", "tests/test_repository.py",
        "tests/test_work_budget.py", "tests/test_public_api.py", "tests/test_argtypes.py")


def run_rank(nodeid: str) -> int:
    """Where a test's file runs: its place in :data:`FIRST`, after them an unnamed path, then its
    place in :data:`LAST`."""
    path = "tests/" + nodeid.split("::", 1)[0].split("tests/", 1)[-1]
    for rank, prefix in enumerate(FIRST):
        if path.startswith(prefix):
            return rank
    for rank, prefix in enumerate(LAST):
        if path.startswith(prefix):
            return len(FIRST) + 1 + rank
    return len(FIRST)


def pytest_collection_modifyitems(config, items):
    """Run the files in :func:`run_rank`'s order (a stable sort: every worker collects the same order)."""
    items.sort(key=lambda item: run_rank(item.nodeid))
