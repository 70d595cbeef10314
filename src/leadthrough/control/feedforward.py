"""Feed-forward torques computed from the model alone (thesis §4.2 and §5.3)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.compiled import kernel
from leadthrough.control.dither import Dither, DitherParameters
from leadthrough.errors import ParameterError
from leadthrough.friction.compensation import (
    CoulombCompensation,
    CoulombCompensationParameters,
    LimitZone,
    compensation_ceiling,
)
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
    preallocated once: a period copies its entry in and the measured one out. It keeps
    ``capacity`` entries, so that ``delay`` may be changed later up to that
    (:class:`~leadthrough.control.interface_delay.InterfaceDelay` reads it from the data).

    Args:
        shape: Shape of one entry, e.g. (2, n) for a command and its dither [Nm].
        delay: Periods from sending to measuring (≥ 1, see :func:`measurement_delay`).
        capacity: Entries kept (default ``delay``; at least ``delay``).
    """

    def __init__(self, shape: tuple[int, ...], delay: int, capacity: int | None = None) -> None:
        self.delay = measurement_delay(delay)
        self.capacity = max(self.delay, capacity or self.delay)
        self._ring = np.zeros((self.capacity, *shape))
        self.reset()

    def reset(self) -> None:
        """Nothing sent yet: zeros."""
        self._ring[...] = 0.0
        self._next = 0  # the slot written next: the one pushed ``capacity`` periods ago

    @property
    def measured(self) -> FloatArray:
        """The entry sent ``delay`` periods ago (a fresh copy)."""
        return self._ring[(self._next - self.delay) % self.capacity].copy()

    def push(self, entry: ArrayLike) -> None:
        """Record what is sent this period."""
        self._ring[self._next] = entry
        self._next = (self._next + 1) % self.capacity


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

    @cached_property
    def total(self) -> FloatArray:
        """Sum of the parts: gravity + friction + dither (a compiled step fills it in)."""
        return self.gravity + self.friction + self.dither


class PassiveFeedForward:
    """Passive lead-through feed-forward: ``τ_ff = G(q) + τ_fc(q̇) + dither`` (§4.2, §5.3).

    A period is one compiled pass (:func:`_feed_forward_step`: the dither's decisions and
    torque, the widened dead-band, the filtered compensation and the sum); with
    ``compiled = False`` it is the readable NumPy code of :class:`Dither` and
    :class:`CoulombCompensation`, which the tests hold it to.

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
        friction_error: Relative error of the Coulomb levels [–] (scalar or per joint) for
            the compensation's ceiling; default the friction model's ``relative_error``.
        gravity_uncertainty: Relative error of G(q) [–] (masses, drive gains): with it the
            Coulomb compensation stays below its ceiling (the friction surely there minus
            ``gravity_uncertainty · |G(q) − G_ref|``, see :meth:`step`), so that a released
            joint still stops, and the dither within ± the same ceiling
            (:func:`dither_within`), so that alone it moves no joint. None: no ceiling (the
            thesis' law).
        limit_zone: Width of the zone before each joint limit [rad] in which the Coulomb
            compensation no longer pushes the joint towards the limit (whole two widths
            from it, none within one: :class:`~leadthrough.friction.compensation.LimitZone`).
            None: it pushes up to the limit (the thesis' law).
    """

    #: Run :meth:`step` compiled (:func:`_feed_forward_step`); False runs the NumPy reference.
    compiled = True

    def __init__(
        self,
        dynamics: Dynamics,
        friction: FrictionModel | None = None,
        dt: float = 0.004,
        compensation: CoulombCompensationParameters | None = None,
        dither: DitherParameters | None = None,
        measurement_delay: int | None = 2,
        friction_error: ArrayLike | None = None,
        gravity_uncertainty: float | None = None,
        limit_zone: float | None = None,
    ) -> None:
        self.dynamics = dynamics
        self.friction = friction or FrictionModel.from_robot(dynamics.robot)
        relative = self.friction.relative_error if friction_error is None else friction_error
        self.friction_error = np.broadcast_to(np.asarray(relative, dtype=float),
                                              (dynamics.n,)).copy()  # fmt: skip
        self.gravity_uncertainty = gravity_uncertainty
        # the joint limits, for the compiled step and the NumPy one
        robot = dynamics.robot
        self._low, self._high = robot.q_min.astype(float), robot.q_max.astype(float)
        limits = None if limit_zone is None else LimitZone(self._low, self._high, limit_zone)
        self.compensation = CoulombCompensation(self.friction, compensation, dt, limits)
        self.dither = None if dither is None else Dither(self.friction, dt, dither)
        n = dynamics.n
        self._sent = None if measurement_delay is None else DelayLine((n,), measurement_delay)
        law, dither_settings = self.compensation.parameters, self.dither and self.dither.parameters
        park_time = dither_settings and dither_settings.park_time
        self._scalars = np.array([  # FEED_FORWARD_SCALARS
            dither_settings.moving_velocity if dither_settings else law.dead_band,
            dither_settings.rest_time if dither_settings else 0.0,
            math.inf if park_time is None else park_time, dt, law.dead_band, law.fraction,
            law.full_velocity, self.compensation.pole,
            math.nan if gravity_uncertainty is None else gravity_uncertainty,
            self.dither.slow_pole if self.dither else 0.0,
            math.inf if not dither_settings or dither_settings.creep is None
            else dither_settings.creep, math.nan if limits is None else limits.width])  # fmt: skip
        self._no_rest = np.full(n, np.nan)  # the dither's state when there is no dither
        self._no_slow = np.zeros(n)
        self._no_position = np.full(n, np.nan)
        self._no_reference = np.zeros(n)
        self._no_push = np.zeros(n)
        self._no_active = np.zeros(n, dtype=bool)

    def use_fraction(self, fraction: float) -> None:
        """Compensate ``fraction`` of τ_C from the next period on (ε [–], under the ceiling)."""
        self.compensation.fraction = fraction
        self._scalars[_FRACTION] = fraction

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
        gravity_reference: FloatArray | None = None,
        push: FloatArray | None = None,
    ) -> FeedForwardTorques:
        """The feed-forward for joint readings q [rad] and velocities q̇ [rad/s].

        Args:
            q: Joint readings [rad].
            qd: Joint velocities [rad/s].
            model: The model at (q, q̇) computed this period, if the caller has it.
            t: Time of the sample [s] (the dither's clock); default: the dither counts
                its own periods.
            gravity_reference: G where the gravity model's error was last measured (the
                start-up calibration's pose) [Nm]: the model may be off by
                ``gravity_uncertainty`` times the change since. None: zero (all of G).
            push: How surely and which way the operator pushes each joint [–], in
                [−1, 1] (active mode: the law's signed weight); below the velocity ramp the
                Coulomb compensation follows it (:mod:`~leadthrough.friction.compensation`).
                None: zero, the thesis' law.
        """
        q, velocity = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        gravity = self.dynamics.gravity(q) if model is None else model.gravity
        dither = self.dither
        now, wave = (0.0, 0.0) if dither is None else dither.clock(t)
        reference = self._no_reference if gravity_reference is None else gravity_reference
        if not (self.compiled and math.isfinite(now) and velocity.shape == gravity.shape
                and q.shape == gravity.shape):  # fmt: skip
            return self._numpy_step(q, velocity, gravity, now, wave, reference, push)
        parts = np.empty((3, gravity.shape[0]))  # friction, dither, total
        pushed = self._no_push if push is None else push
        compensation = self.compensation
        errors = (self.friction_error, reference, pushed, self._low, self._high)
        level = compensation.friction.coulomb_level(q)
        if dither is None:
            _feed_forward_step(q, velocity, level, gravity, *errors, self._no_rest,
                               self._no_slow, self._no_position, self._no_position,
                               self._no_active, compensation.filtered, parts, False, 0.0,
                               math.nan, 0.0, self._scalars)  # fmt: skip
        else:
            amplitude = wave * dither.amplitude
            dither.quiet_since = _feed_forward_step(q, velocity, level, gravity, *errors,
                dither.rest_since, dither.slow_velocity, dither.slow_position, dither.anchor,
                dither.active, compensation.filtered, parts, True, now, dither.quiet_since,
                amplitude, self._scalars)  # fmt: skip
        torques = FeedForwardTorques(gravity, parts[0], parts[1], self._measured(parts[1]))
        torques.__dict__["total"] = parts[2]  # the cached sum, computed by the kernel
        return torques

    def _numpy_step(
        self,
        q: FloatArray,
        qd: FloatArray,
        gravity: FloatArray,
        now: float,
        wave: float,
        reference: FloatArray,
        push: FloatArray | None,
    ) -> FeedForwardTorques:
        """:meth:`step` with the NumPy code of :class:`Dither` and :class:`CoulombCompensation`."""
        ceiling = None
        if self.gravity_uncertainty is not None:
            gravity_error = self.gravity_uncertainty * np.abs(gravity - reference)
            level = self.compensation.friction.coulomb_level(q)
            ceiling = compensation_ceiling(level, self.friction_error, gravity_error)
        if self.dither is None:
            dither, dead_band = np.zeros(self.dynamics.n), None
        else:
            dither = self.dither.decide(qd, q, now, wave)
            if ceiling is not None:
                dither = dither_within(dither, ceiling)
            base = self.compensation.parameters.dead_band
            dead_band = np.where(self.dither.active, self.dither.parameters.moving_velocity, base)
        # (gravity, friction, dither, dither_in_measurement), positional: the cheaper call
        friction = self.compensation.step(qd, q, dead_band, ceiling, push)
        return FeedForwardTorques(gravity, friction, dither, self._measured(dither))

    def _measured(self, dither: FloatArray) -> FloatArray | None:
        """The dither the measured torque holds now, after recording this period's."""
        if self._sent is None:
            return None
        in_measurement = self._sent.measured
        self._sent.push(dither)
        return in_measurement


def dither_within(dither: FloatArray, ceiling: FloatArray) -> FloatArray:
    """The dither [Nm] within ± the compensation's ceiling [Nm]: alone it moves no joint.

    The ceiling is the friction surely there less the gravity error that may remain
    (:func:`~leadthrough.friction.compensation.compensation_ceiling`): a released joint
    stops under a compensation below it, and a resting one stays under a dither below it.
    """
    return np.clip(dither, -ceiling, ceiling)


#: Scalars of :func:`_feed_forward_step`, in order (``park_time`` inf: never parks).
FEED_FORWARD_SCALARS = ("moving_velocity", "rest_time", "park_time", "dt", "dead_band",
                        "fraction", "full_velocity", "pole", "gravity_uncertainty",
                        "slow_pole", "creep", "limit_zone")  # fmt: skip
_FRACTION = FEED_FORWARD_SCALARS.index("fraction")


@kernel
def _feed_forward_step(q, qd, level, gravity, friction_error, reference, push, low, high,
                       rest_since, slow, position, anchor, active, filtered, parts,
                       dithering, now, quiet_since, amplitude, scalars):  # fmt: skip
    """One period of :class:`PassiveFeedForward`, in place; returns the new ``quiet_since``.

    The same decisions and arithmetic, in the same order, as the NumPy reference
    (:meth:`Dither.decide`, the dead-band widened on the dithered joints, then
    :meth:`CoulombCompensation.step`): rest times (``np.fmin``, NaN while moving), the
    velocity low-passed over a dither period (``slow``, a NaN or infinite sample leaves it
    and moves) and the position so (``position``, NaN: none yet; a NaN reading leaves it;
    restarted from the reading where a joint comes to rest),
    the park (a joint rests if either velocity is below ``moving_velocity``;
    ``quiet_since`` NaN: not every joint rests; ``park_time`` inf: never), the creep
    (``anchor`` each rested joint's position while every joint rests, kept until a joint
    moves, NaN otherwise; an anchored joint farther than ``creep`` from it gets −inf: that
    joint parked; ``creep`` inf: never), the rested joints and their dither
    ``amplitude · τ_C(q)`` [Nm]
    (``amplitude`` signed by the wave, within ± the ceiling below), each "lasted" test
    ``elapsed + dt >= duration − dt / 2``; the compensation ramp ends at
    ``max(q̇₁, 2 q̇₀)``, the level ``ε τ_C`` capped by
    :func:`~leadthrough.friction.compensation.compensation_ceiling` (its ``max(·, 0)`` as
    written there; ``gravity_uncertainty`` NaN: no cap), below the ramp the ``push``
    (zeros: the thesis' law), its share left towards a limit in [``low``, ``high``]
    (:meth:`~leadthrough.friction.compensation.LimitZone.share`; ``limit_zone`` NaN: whole),
    then the low-pass filter.
    ``parts`` gets the rows
    friction, dither and gravity + friction + dither [Nm]. Without ``dithering`` the
    dither state is not touched and the dead-band is q̇₀ on every joint.
    """
    moving_velocity, rest_time, park_time, dt = scalars[0], scalars[1], scalars[2], scalars[3]
    dead_band, fraction, full_velocity, pole = scalars[4], scalars[5], scalars[6], scalars[7]
    gravity_uncertainty, slow_pole, creep = scalars[8], scalars[9], scalars[10]
    limit_zone = scalars[11]
    capped = gravity_uncertainty == gravity_uncertainty  # not NaN
    zoned = limit_zone == limit_zone
    n = qd.shape[0]
    if dithering:
        every_joint_rests = True
        for i in range(n):
            still = abs(qd[i]) < moving_velocity
            since = rest_since[i]
            stopped = still and since != since  # came to rest in this sample
            if still:
                rest_since[i] = now if since != since or now < since else since  # np.fmin
            else:
                rest_since[i] = math.nan
            finite = abs(qd[i]) < math.inf  # NaN compares False
            if finite:
                slow[i] = slow_pole * slow[i] + (1.0 - slow_pole) * qd[i]
            if abs(q[i]) < math.inf:
                old = position[i]
                restart = stopped or old != old
                position[i] = q[i] if restart else slow_pole * old + (1.0 - slow_pole) * q[i]
            if not (still or (finite and abs(slow[i]) < moving_velocity)):
                every_joint_rests = False
        if not every_joint_rests:
            quiet_since = math.nan
        elif quiet_since != quiet_since:
            quiet_since = now
        for i in range(n):
            rested = (now - rest_since[i]) + dt >= rest_time - 0.5 * dt
            if quiet_since != quiet_since:  # a joint moves: no anchors, nothing parked
                anchor[i] = math.nan
            elif anchor[i] != -math.inf:  # −inf: crept, parked
                if abs(position[i] - anchor[i]) > creep:  # False for a NaN anchor
                    anchor[i] = -math.inf
                elif rested and anchor[i] != anchor[i]:  # kept through a twitch
                    anchor[i] = position[i]
            active[i] = rested and anchor[i] != -math.inf
        # False for a NaN quiet_since; park_time inf: never
        parked = (now - quiet_since) + dt >= park_time - 0.5 * dt
        for i in range(n):
            active[i] = active[i] and not parked
    for i in range(n):
        on = dithering and active[i]
        compensated = fraction * level[i]
        dither = amplitude * level[i] if on else 0.0
        if capped:
            surely = (1.0 - friction_error[i]) * level[i]
            cap = surely - gravity_uncertainty * abs(gravity[i] - reference[i])
            cap = cap if cap > 0.0 or cap != cap else 0.0  # np.maximum(·, 0)
            compensated = compensated if compensated < cap or compensated != compensated else cap
            if dithering and (abs(dither) > cap or cap != cap):  # nor the dither (np.clip)
                dither = cap if dither > 0.0 else -cap
        band = moving_velocity if on else dead_band
        full = 2.0 * band
        full = full if full > full_velocity or full != full else full_velocity
        ramp = (abs(qd[i]) - band) / (full - band)
        ramp = ramp if ramp > 0.0 or ramp != ramp else 0.0
        ramp = ramp if ramp < 1.0 or ramp != ramp else 1.0
        sign = 1.0 if qd[i] > 0.0 else (-1.0 if qd[i] < 0.0 else qd[i])  # np.sign (NaN, ±0)
        raw = (ramp * sign + (1.0 - ramp) * push[i]) * compensated
        if zoned:  # LimitZone.share (np.clip keeps a NaN)
            room = q[i] - low[i] if raw < 0.0 else high[i] - q[i]
            share = room / limit_zone - 1.0
            share = share if share < 1.0 or share != share else 1.0
            share = share if share > 0.0 or share != share else 0.0
            raw = raw * share
        filtered[i] = pole * filtered[i] + (1.0 - pole) * raw
        parts[0, i], parts[1, i] = filtered[i], dither
        parts[2, i] = gravity[i] + filtered[i] + dither
    return quiet_since
