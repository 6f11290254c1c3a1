"""The version of op2motion (written into pose files' provenance)."""

__version__ = "0.2.0"
