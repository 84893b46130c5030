"""rplearn.viz."""
