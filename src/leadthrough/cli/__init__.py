"""The command-line tool ``leadthrough``."""

from leadthrough.cli.main import main

__all__ = ["main"]
