"""A sample's time as the robot's controller ticks it, read through jittered stamps.

A robot samples at its controller's ticks, every ``dt``. A driver that stamps a sample on
receipt (a host's clock, a ROS message's header) adds its own jitter; a lost sample leaves a
tick without one. The start-up calibration's motion and momentum balance, and the observer's
prediction over the periods since the sample before, are integrals over time: they need the
ticks, not the stamps (``LeadThrough`` keeps one clock for both).

:class:`TickClock` takes each stamp to the nearest tick, after removing the stamps' mean lead
over their ticks (their phase, learned as they come, so that the first stamp's own jitter
is not every later one's): a stamp within half a period of its tick is read exactly, a gap
of several periods counts them all, a clock that runs slightly fast or slow is followed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: Samples over which the stamps' mean lead is averaged once that many have come [–]
PHASE_SAMPLES = 100


@dataclass
class TickClock:
    """Time since the first stamp, in whole periods of the robot's controller.

    Attributes:
        dt: The controller's period [s].
        start: The first stamp [s] (None until one came).
        lead: The stamps' mean lead over their ticks, from ``start`` [s].
        samples: Stamps taken so far.
        tick: The latest sample's tick [s] (NaN: none yet).
    """

    dt: float
    start: float | None = None
    lead: float = 0.0
    samples: int = 0
    tick: float = math.nan  # the latest sample's tick [s] (none yet)

    def __call__(self, t: float) -> float:
        """The tick of the sample stamped ``t`` [s], as time since the first stamp's tick [s]."""
        self.advance(t)
        return self.tick

    def advance(self, t: float) -> int:
        """Take the sample stamped ``t`` [s]: the periods since the one before (1 the first).

        More than one where samples were lost; at least one (a stamp repeated or a period
        early is one more sample).
        """
        if self.start is None:
            self.start = t
        since = t - self.start
        tick = self.dt * round((since - self.lead) / self.dt)
        self.samples += 1
        self.lead += (since - tick - self.lead) / min(self.samples, PHASE_SAMPLES)
        periods = 1 if math.isnan(self.tick) else max(1, round((tick - self.tick) / self.dt))
        self.tick = tick
        return periods
