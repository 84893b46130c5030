"""The version of rplearn (one place; read by model files, figures and reports)."""

__version__ = "0.1.0"
