"""The ``hexapod`` command (layer 7)."""

from hexapod.cli.entry import main

__all__ = ["main"]
