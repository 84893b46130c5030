"""rplearn.sim."""
