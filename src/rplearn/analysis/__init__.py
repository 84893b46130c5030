"""rplearn.analysis."""
