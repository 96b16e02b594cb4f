"""Command-line interface ``cct``."""

from ._main import main

__all__ = ["main"]
