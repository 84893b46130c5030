"""Fixtures of tests/io (the helpers live in flightfiles.py)."""

from flightfiles import flight  # noqa: F401  (session fixture)
