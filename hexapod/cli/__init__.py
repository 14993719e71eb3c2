"""The ``hexapod`` command (layer 7)."""

from hexapod.cli.main import main

__all__ = ["main"]
