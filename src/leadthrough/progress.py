"""A minimal text progress bar for long runs (stderr, only when it is a terminal or forced)."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class Progress:
    """Report progress of ``total`` units of work, at most a few times per second.

    Args:
        total: Amount of work (e.g. simulated seconds).
        label: Text in front of the bar.
        enabled: Show the bar; default only when stderr is a terminal.
        stream: Where to write (default stderr).
    """

    def __init__(
        self,
        total: float,
        label: str = "",
        enabled: bool | None = None,
        stream: TextIO | None = None,
    ) -> None:
        self.stream = stream or sys.stderr
        self.total = max(total, 1e-12)
        self.label = label
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self._start = time.perf_counter()
        self._last = -1.0
        self.done = 0.0

    def advance(self, amount: float) -> None:
        """Add ``amount`` units of finished work and redraw (throttled)."""
        self.done += amount
        self.update(self.done)

    def update(self, done: float) -> None:
        """Redraw the bar for ``done`` units finished (throttled to 5 Hz)."""
        now = time.perf_counter()
        if not self.enabled or (now - self._last < 0.2 and done < self.total):
            return
        self._last = now
        fraction = min(done / self.total, 1.0)
        bar = "█" * int(30 * fraction) + "·" * (30 - int(30 * fraction))
        elapsed = now - self._start
        self.stream.write(f"\r{self.label} {bar} {100 * fraction:5.1f}% {elapsed:6.1f} s")
        self.stream.flush()

    def close(self) -> None:
        """Finish the line."""
        if self.enabled:
            self.update(self.total)
            self.stream.write("\n")
            self.stream.flush()
