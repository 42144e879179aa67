"""The package version, at the bottom of the layers (run.json, --version and the API read it)."""

__version__ = "0.1.0"
