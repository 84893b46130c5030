"""rplearn.data."""
