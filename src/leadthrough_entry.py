"""The ``leadthrough`` command's entry point, outside the package on purpose.

Importing :mod:`leadthrough` takes a moment (Pinocchio, NumPy): a Ctrl-C then must still
be one line, not Python's traceback, and the package cannot catch what happens while it
is itself being imported. This module imports nothing heavy before its handler is in
place.
"""

from __future__ import annotations

import sys


def main() -> int:
    """Start the command line; Ctrl-C while it starts prints one line and returns 130."""
    try:
        from leadthrough.cli.main import main as command_line
    except KeyboardInterrupt:
        print("leadthrough: interrupted while starting: nothing was done", file=sys.stderr)
        return 130
    return command_line()


if __name__ == "__main__":
    sys.exit(main())
