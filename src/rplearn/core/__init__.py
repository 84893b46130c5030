"""rplearn.core."""
