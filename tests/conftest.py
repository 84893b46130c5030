"""Test-session setup shared by every test module."""

import os

# scikit-learn's array-API conformance checks (run by tests/test_estimators.py) only run when
# scipy's array-API support is on, and scipy reads this once, at import: set it before any test
# module imports scipy, so that those checks run instead of being skipped.
os.environ.setdefault("SCIPY_ARRAY_API", "1")
