"""Feed-forward torques computed from the model alone (thesis §4.2 and §5.3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.control.dither import Dither, DitherParameters
from leadthrough.errors import ParameterError
from leadthrough.friction.compensation import CoulombCompensation, CoulombCompensationParameters
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics
from leadthrough.model.snapshot import ModelSnapshot


def measurement_delay(value: object, name: str = "measurement_delay") -> int:
    """``value`` as a measurement delay [periods]: an integer ≥ 1, else ParameterError.

    A torque measured at period k was applied over the period before, so it holds at
    the latest the command sent at period k − 1: a delay of 0 would be a measurement of
    a command not yet computed.
    """
    is_integer = isinstance(value, int | np.integer) and not isinstance(value, bool)
    if not is_integer or int(value) < 1:  # type: ignore[call-overload]
        raise ParameterError(name, f"must be a whole number of periods ≥ 1 (a command is "
                             f"measured one period after it is sent at the earliest), got "
                             f"{value!r}")  # fmt: skip
    return int(value)  # type: ignore[call-overload]


class DelayLine:
    """What was sent, as the torque measured now contains it: ``delay`` periods ago.

    One entry per period, pushed with :meth:`push`; :attr:`measured` is the entry pushed
    ``delay`` periods before the current one (zeros at the start). A ring buffer
    preallocated once: a period copies its entry in and the measured one out.

    Args:
        shape: Shape of one entry, e.g. (2, n) for a command and its dither [Nm].
        delay: Periods from sending to measuring (≥ 1, see :func:`measurement_delay`).
    """

    def __init__(self, shape: tuple[int, ...], delay: int) -> None:
        self.delay = measurement_delay(delay)
        self._ring = np.zeros((self.delay, *shape))
        self.reset()

    def reset(self) -> None:
        """Nothing sent yet: zeros."""
        self._ring[...] = 0.0
        self._oldest = 0  # the slot pushed ``delay`` periods ago, overwritten next

    @property
    def measured(self) -> FloatArray:
        """The entry sent ``delay`` periods ago (a fresh copy)."""
        return self._ring[self._oldest].copy()

    def push(self, entry: ArrayLike) -> None:
        """Record what is sent this period."""
        self._ring[self._oldest] = entry
        self._oldest = (self._oldest + 1) % self.delay


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
            (commanded ``measurement_delay`` periods ago): subtract it from the observer
            input. None when the caller keeps the delay line (``measurement_delay=None``,
            as :class:`~leadthrough.control.lead_through.LeadThrough` does: one line for
            the command and its dither).
    """

    gravity: FloatArray
    friction: FloatArray
    dither: FloatArray
    dither_in_measurement: FloatArray | None

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
            measured motor torque (an integer ≥ 1): with a robot that applies commands one
            period late (the thesis' interface, the twin's default), a command sent at step
            k is applied over the next period and measured at step k + 2. None: the caller
            keeps the delay line (``dither_in_measurement`` is then None).
    """

    def __init__(
        self,
        dynamics: Dynamics,
        friction: FrictionModel | None = None,
        dt: float = 0.004,
        compensation: CoulombCompensationParameters | None = None,
        dither: DitherParameters | None = None,
        measurement_delay: int | None = 2,
    ) -> None:
        self.dynamics = dynamics
        self.friction = friction or FrictionModel.from_robot(dynamics.robot)
        self.compensation = CoulombCompensation(self.friction, compensation, dt)
        self.dither = None if dither is None else Dither(self.friction, dt, dither)
        n = dynamics.n
        self._sent = None if measurement_delay is None else DelayLine((n,), measurement_delay)

    def reset(self) -> None:
        """Forget filter, dither and delay-line states."""
        self.compensation.reset()
        if self.dither is not None:
            self.dither.reset()
        if self._sent is not None:
            self._sent.reset()

    def step(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        model: ModelSnapshot | None = None,
        t: float | None = None,
    ) -> FeedForwardTorques:
        """The feed-forward for joint readings q [rad] and velocities q̇ [rad/s].

        Args:
            q: Joint readings [rad].
            qd: Joint velocities [rad/s].
            model: The model at (q, q̇) computed this period, if the caller has it.
            t: Time of the sample [s] (the dither's clock); default: the dither counts
                its own periods.
        """
        q = np.asarray(q, dtype=float)
        if self.dither is None:
            dither, dead_band = np.zeros(self.dynamics.n), None
        else:
            dither = self.dither.step(qd, q, t)
            base = self.compensation.parameters.dead_band
            dead_band = np.where(self.dither.active, self.dither.parameters.moving_velocity, base)
        in_measurement = None
        if self._sent is not None:
            in_measurement = self._sent.measured
            self._sent.push(dither)
        gravity = self.dynamics.gravity(q) if model is None else model.gravity
        # (gravity, friction, dither, dither_in_measurement), positional: the cheaper call
        return FeedForwardTorques(gravity, self.compensation.step(qd, q, dead_band), dither,
                                  in_measurement)  # fmt: skip
