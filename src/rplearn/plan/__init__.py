"""rplearn.plan."""
