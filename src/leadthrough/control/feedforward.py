"""Feed-forward torques computed from the model alone (thesis §4.2 and §5.3)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.control.dither import Dither, DitherParameters
from leadthrough.friction.compensation import CoulombCompensation, CoulombCompensationParameters
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics


class GravityCompensation:
    """The controller of thesis §4.2.1: command the gravity torque, ``τ = G(q)``.

    With it alone the arm floats and joint friction holds it where it is left.

    Args:
        dynamics: Model of the arm.
    """

    def __init__(self, dynamics: Dynamics) -> None:
        self.dynamics = dynamics

    def step(
        self, q: ArrayLike, qd: ArrayLike, tau_measured: ArrayLike | None = None
    ) -> FloatArray:
        """Gravity torque [Nm] at the joint readings ``q`` [rad]."""
        return self.dynamics.gravity(q)


@dataclass(frozen=True, eq=False)
class FeedForwardTorques:
    """The parts of a feed-forward command [Nm], each (n,).

    Attributes:
        gravity: G(q).
        friction: Coulomb compensation τ_fc(q̇) (filtered).
        dither: Dither torque (zero on moving joints or when dithering is off).
        dither_in_measurement: The dither torque the latest measured motor torque contains
            (commanded ``measurement_delay`` periods ago): subtract it from the observer input.
    """

    gravity: FloatArray
    friction: FloatArray
    dither: FloatArray
    dither_in_measurement: FloatArray

    @property
    def total(self) -> FloatArray:
        """Sum of the parts: gravity + friction + dither."""
        return self.gravity + self.friction + self.dither


class PassiveFeedForward:
    """Passive lead-through feed-forward: ``τ_ff = G(q) + τ_fc(q̇) + dither`` (§4.2, §5.3).

    Args:
        dynamics: Model of the arm.
        friction: Friction model for the compensation and the dither amplitudes.
        dt: Control period [s].
        compensation: Parameters of the Coulomb compensation law.
        dither: Dither settings, or None for no dithering.
        measurement_delay: Control steps between sending a command and reading it back in the
            measured motor torque: with a robot that applies commands one period late (the
            thesis' interface, the twin's default), a command sent at step k is applied over
            the next period and measured at step k + 2.
    """

    def __init__(
        self,
        dynamics: Dynamics,
        friction: FrictionModel | None = None,
        dt: float = 0.004,
        compensation: CoulombCompensationParameters | None = None,
        dither: DitherParameters | None = None,
        measurement_delay: int = 2,
    ) -> None:
        self.dynamics = dynamics
        self.friction = friction or FrictionModel.from_robot(dynamics.robot)
        self.compensation = CoulombCompensation(self.friction, compensation)
        self.dither = None if dither is None else Dither(self.friction, dt, dither)
        self._sent = deque([np.zeros(dynamics.n)] * max(measurement_delay, 1),
                           maxlen=max(measurement_delay, 1))  # fmt: skip
        self._delay = measurement_delay

    def reset(self) -> None:
        """Forget filter, dither and delay-line states."""
        self.compensation.reset()
        if self.dither is not None:
            self.dither.reset()
        zeros = [np.zeros(self.dynamics.n) for _ in self._sent]
        self._sent.clear()
        self._sent.extend(zeros)  # new arrays: torques already handed out stay as they were

    def step(self, q: ArrayLike, qd: ArrayLike) -> FeedForwardTorques:
        """The feed-forward for joint readings q [rad] and velocities q̇ [rad/s]."""
        q = np.asarray(q, dtype=float)
        n = self.dynamics.n
        dither, dead_band = np.zeros(n), None
        if self.dither is not None:
            dither = self.dither.step(qd, q)
            base = self.compensation.parameters.dead_band
            dead_band = np.where(self.dither.active, self.dither.parameters.moving_velocity, base)
        in_measurement = self._sent[0] if self._delay else dither
        self._sent.append(dither)
        return FeedForwardTorques(
            gravity=self.dynamics.gravity(q),
            friction=self.compensation.step(qd, q, dead_band),
            dither=dither,
            dither_in_measurement=in_measurement,
        )
