"""Dithering against stiction (thesis §5.3, SPEC §5).

A square wave of 15 Hz and 0.3·τ_C (passive mode, the thesis'; 0.6·τ_C in active mode)
is added to the feed-forward of each joint that is
at rest: too small to move the joint, it keeps the gearbox vibrating, which lowers the
torque the operator needs to start a motion, and so the torque the momentum observer
cannot see. It is switched off on a joint as soon as that joint moves, and back on
after the joint has rested for a while. While every joint rests, a joint that creeps
under it is parked (its dither off until a joint moves): on a load the model does not
know, "too small to move the joint" is not true there, while the joints that do not
creep go on dithering and showing a push. After a longer rest every joint parks. Its
torque must be removed from the observer's input, and the friction compensation's
dead-band is widened while it is on.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.errors import ParameterError
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.validation import real

#: The thesis' amplitude (§5.3), a fraction of τ_C [–]: passive mode's.
PASSIVE_AMPLITUDE = 0.3
#: Active mode's amplitude, a fraction of τ_C [–]. A loaded joint breaks away at
#: ``τ_s − a τ_C``: the hand starts a motion with less force and stiction hides less of
#: its push. Twice the thesis' lightens active mode by 0.11–0.13 of passive's effort on
#: the guiding benchmark, and shakes it less, with the creep parked per joint and the
#: virtual damping shaped like the arm (design log, *A dither twice as strong, kept*);
#: passive mode keeps the thesis' dither, the baseline active mode is judged against.
ACTIVE_AMPLITUDE = 0.6


@dataclass(frozen=True)
class DitherParameters:
    """Dither settings (defaults: thesis §5.3).

    Attributes:
        frequency: Square-wave frequency [Hz] (15: below the resonances of Fig. 5.3).
        amplitude: Amplitude as a fraction of each joint's Coulomb level [–]; None: the
            mode's (:meth:`for_mode`), the thesis' 0.3 in passive mode and on its own,
            :data:`ACTIVE_AMPLITUDE` in active mode.
        moving_velocity: A joint moves above this speed [rad/s]: dither off at once, and the
            friction compensation dead-band while dithering. Under a
            :class:`~leadthrough.control.lead_through.LeadThrough` this is its
            ``rest_velocity``, the one definition of "at rest".
        rest_time: Time below ``moving_velocity`` before the dither comes back [s].
        park_time: Once *every* joint has rested this long, nobody is guiding the arm: the
            dither stops until a joint moves again [s]; None: only a creep parks (the
            joint that crept). A joint
            counts as resting here when its velocity or its velocity low-passed over one
            dither period (:attr:`Dither.slow_velocity`) is below ``moving_velocity``: a
            joint being guided moves by both, while the slips the dither causes, its twitch
            and the tail of a stop move by one only.
        creep: While every joint rests, a dithered joint whose position (low-passed over one
            dither period from where the joint came to rest, :attr:`Dither.slow_position`)
            moves this far from where its dither found it parks its own dither at once,
            until a joint moves [rad]; None: only ``park_time`` parks. The others dither
            on: parked on every joint, the push a hand starts on a loaded joint stayed
            hidden until it broke away (design log, *A creep park per joint*). Where the
            dither found a joint is kept through a twitch that passes
            ``moving_velocity``: reset there, a twitching joint's creep was never counted.
            A dithered joint under a static load the
            model does not know (a mass error, a drive gain) creeps, 0.6–2 mrad/s on the
            guiding benchmark's LuGre plants without a start-up calibration, against a
            released arm's budget of 1 mrad: the dither, meant to show a push without
            moving the arm, is then moving it. 0.2 mrad is a fifth of that budget and 20×
            what the twitch leaves in that position on the benchmark's dry plants. Parking
            on the creep itself, instead of after a time short enough for the fastest
            creep (0.5 s in the previous release), keeps the dither for the arms that do
            not creep, whose next start it lightens.
    """

    frequency: float = 15.0
    amplitude: float | None = None
    moving_velocity: float = 0.01
    rest_time: float = 0.2
    park_time: float | None = 2.0
    creep: float | None = 2e-4

    def __post_init__(self) -> None:
        real("frequency", self.frequency, minimum=0.0, strict=True, error=ParameterError)
        if self.amplitude is not None:
            real("amplitude", self.amplitude, minimum=0.0, error=ParameterError)
            if self.amplitude >= 1.0:
                raise ParameterError("amplitude", "must stay below 1 (it must not move the joint)")
        real("moving_velocity", self.moving_velocity, minimum=0, strict=True, error=ParameterError)
        real("rest_time", self.rest_time, minimum=0.0, error=ParameterError)
        if self.park_time is not None:
            real("park_time", self.park_time, minimum=0.0, strict=True, error=ParameterError)
        if self.creep is not None:
            real("creep", self.creep, minimum=0.0, strict=True, error=ParameterError)

    def for_mode(self, mode: str) -> DitherParameters:
        """These settings with the amplitude of ``mode`` (``"passive"`` or ``"active"``) if None."""
        if self.amplitude is not None:
            return self
        amplitude = ACTIVE_AMPLITUDE if mode == "active" else PASSIVE_AMPLITUDE
        return dataclasses.replace(self, amplitude=amplitude)

    def check_period(self, dt: float) -> None:
        """Refuse a ``frequency`` the control period ``dt`` [s] cannot carry.

        The wave takes, at each sample ``t = k dt``, the sign of the half-period it falls
        in (:meth:`Dither.clock`): half-periods are not whole control periods. With
        ``f dt = p/r`` in lowest terms the samples repeat every ``r`` periods and average
        ``1/r`` of the amplitude for an odd ``r``, 0 for an even one (irrational: 0 in the
        long run). At ``f ≥ 1/(2 dt)``, the Nyquist limit, the samples are another wave:
        at the limit every sample is on an edge (its sign a matter of clock jitter), above
        it an alias at ``|f − m/dt|``, a constant torque when ``f dt`` is whole.

        Raises:
            ParameterError: ``frequency`` at or above ``1/(2 dt)`` (within the clock's
                1e-4 half-period).
        """
        limit = 0.5 / dt
        if 2.0 * self.frequency * dt > 1.0 - 1e-4:
            raise ParameterError("dither frequency", f"{self.frequency:g} Hz at dt = {dt:g} s "
                                 f"is not below the Nyquist limit 1/(2 dt) = {limit:g} Hz: "
                                 "sampled every dt, the square wave becomes another wave, "
                                 "a constant torque where f·dt is whole")  # fmt: skip

    @classmethod
    def never_parked(cls, **changes: float) -> DitherParameters:
        """The thesis' dither (§5.3): on at rest for ever, neither a time nor a creep parks it.

        ``changes``: other fields, e.g. ``frequency=30.0``.
        """
        return cls(park_time=None, creep=None, **changes)


class Dither:
    """Square-wave dither on the joints at rest.

    Time comes from the samples (``step(qd, q, t)``): the wave's phase counts from the
    first sample, the rest and park times from when each joint came to rest. Without
    ``t`` it counts its own periods of ``dt``.

    Args:
        friction: Model whose Coulomb levels set the amplitudes.
        dt: Control period [s].
        parameters: Dither settings.

    Raises:
        ParameterError: A frequency at or above the Nyquist limit of ``dt``
            (:meth:`DitherParameters.check_period`).
    """

    def __init__(
        self, friction: FrictionModel, dt: float, parameters: DitherParameters | None = None
    ) -> None:
        self.parameters = (parameters or DitherParameters()).for_mode("passive")
        #: Amplitude in use, a fraction of τ_C [–] (the parameters' or the thesis').
        self.amplitude = float(self.parameters.amplitude or 0.0)
        self.friction = friction
        self.dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
        self.parameters.check_period(self.dt)
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
        self._position = np.full(n, np.nan)  # the position low-passed so [rad], NaN: none yet
        self._anchor = np.full(n, np.nan)  # where the dither found each joint [rad], NaN: off
        self._now = 0.0

    @property
    def parked(self) -> bool:
        """Whether every joint has rested for ``park_time``: the dither is off on every joint."""
        park_time, quiet_since = self.parameters.park_time, self._quiet_since
        if quiet_since is None:
            return False
        return park_time is not None and bool(self._lasted(self._now - quiet_since, park_time))

    @property
    def crept(self) -> NDArray[np.bool_]:
        """The joints that crept ``creep`` under the dither: parked until a joint moves."""
        return np.asarray(self._anchor == -np.inf)

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
    def slow_position(self) -> FloatArray:
        """Each joint's position low-passed over one dither period [rad]; NaN before a sample.

        Restarted from the reading when the joint comes to rest. The array itself: a
        compiled step updates it in place.
        """
        return self._position

    @property
    def anchor(self) -> FloatArray:
        """Where the dither found each joint while every joint rests [rad]; NaN: none.

        The :attr:`slow_position` when the joint's dither came on (or when every joint
        came to rest, if later), kept until a joint moves; −inf: the joint crept
        (:attr:`crept`). The array itself: a compiled step updates it in place.
        """
        return self._anchor

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
            q: Joint readings [rad] (position-dependent Coulomb levels, and the creep:
                without them no creep parks the dither).
            t: Time of the sample [s], any origin (a robot's Unix clock included).
        """
        return self.decide(qd, q, *self.clock(t))

    def decide(self, qd: ArrayLike, q: ArrayLike | None, now: float, wave: float) -> FloatArray:
        """:meth:`step` after the clock (:meth:`clock`): which joints dither, and how much [Nm]."""
        p = self.parameters
        qd = np.asarray(qd, dtype=float)
        still = np.abs(qd) < p.moving_velocity
        stopped = still & np.isnan(self._rest_since)  # came to rest in this sample
        # at rest since then (−inf: long enough already); NaN while moving
        self._rest_since = np.where(still, np.fmin(self._rest_since, now), np.nan)
        pole, finite = self.slow_pole, np.isfinite(qd)  # a NaN sample moves, filters nothing
        self._slow = np.where(finite, pole * self._slow + (1.0 - pole) * qd, self._slow)
        if q is not None:
            self._filter_position(np.asarray(q, dtype=float), stopped)
        # a joint guided moves now *and* over the last dither period (slips, twitches, the
        # tail of a stop are not guiding)
        quiet = still | (finite & (np.abs(self._slow) < p.moving_velocity))
        if np.count_nonzero(quiet) != quiet.size:  # a joint moves (count: 4× np.all's speed)
            self._quiet_since = None
        elif self._quiet_since is None:
            self._quiet_since = now
        rested = self._lasted(now - self._rest_since, p.rest_time)
        self._watch_creep(rested)
        self.active = rested & ~self.crept if not self.parked else np.zeros_like(rested)
        return np.where(self.active, wave * self.amplitude * self.friction.coulomb_level(q), 0.0)

    def _filter_position(self, q: FloatArray, stopped: NDArray[np.bool_]) -> None:
        """Low-pass the joint readings over one dither period (a NaN reading leaves it).

        A joint that has just stopped starts from its reading: the filter's lag behind
        the motion before (up to speed × 67 ms) is not a creep.
        """
        pole, position = self.slow_pole, self._position
        restart = stopped | np.isnan(position)
        filtered = np.where(restart, q, pole * position + (1.0 - pole) * q)
        self._position = np.where(np.isfinite(q), filtered, position)

    def _watch_creep(self, rested: NDArray[np.bool_]) -> None:
        """Anchor the rested joints while every joint rests; park one that moved ``creep``.

        An anchor stays until a joint moves (a twitch past ``moving_velocity`` does not
        reset it); a joint that crept from it is marked −inf (:attr:`crept`).
        """
        if self._quiet_since is None:  # a joint moves: no anchors, nothing parked
            self._anchor = np.full_like(self._anchor, np.nan)
            return
        anchor = self._anchor
        anchored = np.isfinite(anchor)
        # a joint that moved away from its anchor (checked before this sample's new ones)
        crept = anchored & (np.abs(self._position - anchor) > self._creep_limit)
        kept = np.where(rested & np.isnan(anchor), self._position, anchor)
        self._anchor = np.where(crept, -np.inf, kept)

    @property
    def _creep_limit(self) -> float:
        """``creep`` [rad], inf without one."""
        return math.inf if self.parameters.creep is None else self.parameters.creep
