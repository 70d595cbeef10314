"""The calibration's clock: jittered stamps read as the robot's ticks."""

import numpy as np
import pytest

from leadthrough.control.ticks import TickClock

DT = 0.001  # [s]


def _ticks(stamps: np.ndarray) -> np.ndarray:
    clock = TickClock(DT)
    return np.array([clock(t) for t in stamps]) / DT


@pytest.mark.parametrize("jitter", [0.3, 0.4])
def test_stamps_within_half_a_period_of_their_tick_are_read_exactly(jitter):
    """Each stamp off its tick by up to ±40 % of a period: every tick read from the 20th on.

    The first stamp's own jitter is not every later one's: the stamps' mean lead is learned
    (without it, a first stamp 0.4 periods late misreads every later one 0.1 periods early).
    """
    k = np.arange(5000)
    stamps = 17.0 + DT * (k + np.random.default_rng(4).uniform(-jitter, jitter, k.size))
    np.testing.assert_array_equal(np.rint(_ticks(stamps))[20:], k[20:])


def test_a_gap_counts_every_period_lost():
    """60 samples lost: the next tick is 61 periods after the last one read."""
    k = np.r_[np.arange(300), np.arange(360, 1000)]
    jitter = np.random.default_rng(5).uniform(-0.3, 0.3, k.size)
    np.testing.assert_array_equal(np.rint(_ticks(DT * (k + jitter)))[20:], k[20:])


def test_a_clock_a_little_fast_or_slow_is_followed():
    """A driver's clock 1000 ppm off the robot's over 20 000 periods: the robot's ticks.

    A quartz clock is 20–100 ppm off; the mean lead follows it 100 samples behind (0.1
    periods here).
    """
    k = np.arange(20_000)
    for rate in (0.999, 1.001):
        jitter = np.random.default_rng(6).uniform(-0.3, 0.3, k.size)
        np.testing.assert_array_equal(np.rint(_ticks(DT * (rate * k + jitter)))[20:], k[20:])
