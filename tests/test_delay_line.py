"""The delay line of sent commands (a ring buffer) equals a plain queue of copies."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest

from leadthrough.control.feedforward import DelayLine


@pytest.mark.parametrize("delay", [1, 2, 3, 5])
def test_the_ring_buffer_returns_what_was_pushed_delay_periods_ago(delay):
    """1000 random pushes and resets: the entry pushed ``delay`` periods ago, zeros at start."""
    rng = np.random.default_rng(delay)
    line = DelayLine((2, 7), delay)
    queue = deque([np.zeros((2, 7))] * delay, maxlen=delay)
    for k in range(1000):
        if k % 300 == 299:
            line.reset()
            queue = deque([np.zeros((2, 7))] * delay, maxlen=delay)
        measured = line.measured
        np.testing.assert_array_equal(measured, queue[0])
        measured[:] = np.nan  # a fresh copy: the caller may write to it
        entry = (rng.normal(size=7), rng.normal(size=7))
        queue.append(np.array(entry))
        line.push(entry)
        entry[0][:] = np.inf  # the line keeps its own copy
