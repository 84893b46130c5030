"""rplearn.models."""
