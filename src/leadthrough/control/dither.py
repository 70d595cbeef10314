"""Dithering against stiction (thesis §5.3, SPEC §5).

A square wave of 15 Hz and 0.3·τ_C is added to the feed-forward of each joint that is
at rest: too small to move the joint, it keeps the gearbox vibrating, which lowers the
torque the operator needs to start a motion, and so the torque the momentum observer
cannot see. It is switched off on a joint as soon as that joint moves, and back on
after the joint has rested for a while. Its torque must be removed from the observer's
input, and the friction compensation's dead-band is widened while it is on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

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
            friction compensation dead-band while dithering.
        rest_time: Time below ``moving_velocity`` before the dither comes back [s].
        park_time: Once *every* joint has rested this long, nobody is guiding the arm: the
            dither stops until a joint moves again [s]; None dithers at rest for ever (the
            thesis). A dithered joint under a static load the model does not know (a mass
            error) creeps, so an arm left alone would not stay where it was put.
    """

    frequency: float = 15.0
    amplitude: float = 0.3
    moving_velocity: float = 0.01
    rest_time: float = 0.2
    park_time: float | None = 2.0

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
        self._rest_needed = round(self.parameters.rest_time / self.dt)  # whole periods
        park_time = self.parameters.park_time
        self._quiet_needed = None if park_time is None else round(park_time / self.dt)
        self.reset()

    def reset(self) -> None:
        """Start a new wave; every joint counts as having rested long enough."""
        self._time = 0.0
        self._rest = np.full(self.friction.n_joints, self._rest_needed)  # periods at rest
        self.active = np.ones(self.friction.n_joints, dtype=bool)
        self._quiet = 0  # periods with every joint at rest

    @property
    def parked(self) -> bool:
        """Whether every joint has rested for ``park_time``: the dither is off."""
        return self._quiet_needed is not None and self._quiet >= self._quiet_needed

    def step(self, qd: ArrayLike, q: ArrayLike | None = None) -> FloatArray:
        """Dither torque [Nm] for this period, zero on moving joints."""
        p = self.parameters
        still = np.abs(np.asarray(qd, dtype=float)) < p.moving_velocity
        self._rest = np.where(still, self._rest + 1, 0)
        self._quiet = self._quiet + 1 if np.all(still) else 0
        self.active = (self._rest >= self._rest_needed) & ~self.parked
        wave = 1.0 if np.sin(2.0 * np.pi * p.frequency * self._time) >= 0.0 else -1.0
        self._time += self.dt
        return np.where(self.active, wave * p.amplitude * self.friction.coulomb_level(q), 0.0)
