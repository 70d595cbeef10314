"""Dithering against stiction (thesis §5.3, SPEC §5).

A square wave of 15 Hz and 0.3·τ_C is added to the feed-forward of each joint that is
at rest: too small to move the joint, it keeps the gearbox vibrating, which lowers the
torque the operator needs to start a motion, and so the torque the momentum observer
cannot see. It is switched off on a joint as soon as that joint moves, and back on
after the joint has rested for a while. Its torque must be removed from the observer's
input, and the friction compensation's dead-band is widened while it is on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.errors import ParameterError
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.validation import real


@dataclass(frozen=True)
class DitherParameters:
    """Dither settings (defaults: thesis §5.3).

    Attributes:
        frequency: Square-wave frequency [Hz] (15: below the resonances of Fig. 5.3).
        amplitude: Amplitude as a fraction of each joint's Coulomb level [–] (0.3).
        moving_velocity: A joint moves above this speed [rad/s]: dither off at once, and the
            friction compensation dead-band while dithering. Under a
            :class:`~leadthrough.control.lead_through.LeadThrough` this is its
            ``rest_velocity``, the one definition of "at rest".
        rest_time: Time below ``moving_velocity`` before the dither comes back [s].
        park_time: Once *every* joint has rested this long, nobody is guiding the arm: the
            dither stops until a joint moves again [s]; None dithers at rest for ever (the
            thesis). A joint counts as resting here when its velocity or its velocity
            low-passed over one dither period (:attr:`Dither.slow_velocity`) is below
            ``moving_velocity``: a joint being guided moves by both, while the slips the
            dither causes, its twitch and the tail of a stop move by one only. A dithered
            joint under a static load the model does not know (a mass error, a drive gain)
            creeps, so an arm left alone would not stay where it was put: 0.6–0.8 mrad/s
            on the guiding benchmark's LuGre plants without a start-up calibration, up to
            2 mrad/s where the active law reads the friction credited to the creep as a
            push, against a released arm's budget of 1 mrad. 0.5 s (2 s before) ends such
            creeps within it; the price is a start after a longer pause, whose first joint
            breaks away without the dither.
    """

    frequency: float = 15.0
    amplitude: float = 0.3
    moving_velocity: float = 0.01
    rest_time: float = 0.2
    park_time: float | None = 0.5

    def __post_init__(self) -> None:
        real("frequency", self.frequency, minimum=0.0, strict=True, error=ParameterError)
        real("amplitude", self.amplitude, minimum=0.0, error=ParameterError)
        if self.amplitude >= 1.0:
            raise ParameterError("amplitude", "must stay below 1 (it must not move the joint)")
        real("moving_velocity", self.moving_velocity, minimum=0, strict=True, error=ParameterError)
        real("rest_time", self.rest_time, minimum=0.0, error=ParameterError)
        if self.park_time is not None:
            real("park_time", self.park_time, minimum=0.0, strict=True, error=ParameterError)


class Dither:
    """Square-wave dither on the joints at rest.

    Time comes from the samples (``step(qd, q, t)``): the wave's phase counts from the
    first sample, the rest and park times from when each joint came to rest. Without
    ``t`` it counts its own periods of ``dt``.

    Args:
        friction: Model whose Coulomb levels set the amplitudes.
        dt: Control period [s].
        parameters: Dither settings.
    """

    def __init__(
        self, friction: FrictionModel, dt: float, parameters: DitherParameters | None = None
    ) -> None:
        self.parameters = parameters or DitherParameters()
        self.friction = friction
        self.dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
        self.reset()

    def reset(self) -> None:
        """Start a new wave; every joint counts as having rested long enough."""
        n = self.friction.n_joints
        self._start: float | None = None  # time of the first sample [s]
        self._periods = 0  # periods counted when no time is given
        self._rest_since = np.full(n, -np.inf)  # when each joint came to rest [s], NaN: moving
        self.active = np.ones(n, dtype=bool)
        self._quiet_since: float | None = None  # when every joint was at rest [s]
        self._slow = np.zeros(n)  # the velocity low-passed over a dither period [rad/s]
        self._now = 0.0

    @property
    def parked(self) -> bool:
        """Whether every joint has rested for ``park_time``: the dither is off."""
        park_time = self.parameters.park_time
        if park_time is None or self._quiet_since is None:
            return False
        return bool(self._lasted(self._now - self._quiet_since, park_time))

    def _lasted(self, elapsed: FloatArray | float, duration: float) -> NDArray[np.bool_]:
        """Whether samples spanning ``elapsed`` [s] (each one period) cover ``duration`` [s].

        Half a period of tolerance: a robot's clock (e.g. Unix time, 0.2 µs resolution
        at 1.7e9 s) or its jitter does not move a decision by a period.
        """
        return np.asarray(elapsed + self.dt >= duration - 0.5 * self.dt, dtype=bool)

    def clock(self, t: float | None) -> tuple[float, float]:
        """Advance the clock to the sample at ``t`` [s]: (time since the first sample [s], wave).

        The wave is ±1, the square wave's sign; without ``t`` the dither counts its own
        periods of ``dt``.
        """
        if t is None:
            t = self._periods * self.dt
            self._periods += 1
        if self._start is None:
            self._start = float(t)
        now = self._now = float(t) - self._start  # small numbers: a Unix clock loses nothing
        # a sample on an edge (within 1e-4 half-period: clock rounding) starts the new half
        frequency = self.parameters.frequency
        return now, (1.0 if math.floor(2.0 * frequency * now + 1e-4) % 2 == 0 else -1.0)

    @property
    def rest_since(self) -> FloatArray:
        """When each joint came to rest [s since the first sample]; NaN: moving.

        The array itself: a compiled step updates it in place.
        """
        return self._rest_since

    @property
    def slow_pole(self) -> float:
        """Pole of the low-pass whose time constant is one dither period [–]."""
        return math.exp(-self.dt * self.parameters.frequency)

    @property
    def slow_velocity(self) -> FloatArray:
        """Each joint's velocity low-passed over one dither period [rad/s].

        The array itself: a compiled step updates it in place.
        """
        return self._slow

    @property
    def quiet_since(self) -> float:
        """When every joint came to rest [s since the first sample]; NaN: a joint moves."""
        return math.nan if self._quiet_since is None else self._quiet_since

    @quiet_since.setter
    def quiet_since(self, value: float) -> None:
        self._quiet_since = None if math.isnan(value) else value

    def step(self, qd: ArrayLike, q: ArrayLike | None = None, t: float | None = None) -> FloatArray:
        """Dither torque [Nm] for this period, zero on moving joints.

        The readable form; :class:`~leadthrough.control.feedforward.PassiveFeedForward`
        runs the same decisions compiled, with the friction compensation.

        Args:
            qd: Joint velocities [rad/s].
            q: Joint readings [rad] (for position-dependent Coulomb levels).
            t: Time of the sample [s], any origin (a robot's Unix clock included).
        """
        return self.decide(qd, q, *self.clock(t))

    def decide(self, qd: ArrayLike, q: ArrayLike | None, now: float, wave: float) -> FloatArray:
        """:meth:`step` after the clock (:meth:`clock`): which joints dither, and how much [Nm]."""
        p = self.parameters
        qd = np.asarray(qd, dtype=float)
        still = np.abs(qd) < p.moving_velocity
        # at rest since then (−inf: long enough already); NaN while moving
        self._rest_since = np.where(still, np.fmin(self._rest_since, now), np.nan)
        pole, finite = self.slow_pole, np.isfinite(qd)  # a NaN sample moves, filters nothing
        self._slow = np.where(finite, pole * self._slow + (1.0 - pole) * qd, self._slow)
        # a joint guided moves now *and* over the last dither period (slips, twitches, the
        # tail of a stop are not guiding)
        quiet = still | (finite & (np.abs(self._slow) < p.moving_velocity))
        if np.count_nonzero(quiet) != quiet.size:  # a joint moves (count: 4× np.all's speed)
            self._quiet_since = None
        elif self._quiet_since is None:
            self._quiet_since = now
        rested = self._lasted(now - self._rest_since, p.rest_time)
        self.active = rested if not self.parked else np.zeros_like(rested)
        return np.where(self.active, wave * p.amplitude * self.friction.coulomb_level(q), 0.0)
