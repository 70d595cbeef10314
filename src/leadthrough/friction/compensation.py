"""Coulomb friction compensation of passive lead-through (thesis §4.2.2, SPEC §4).

Only a fraction ε of the modelled Coulomb friction is compensated, and only once the
joint moves faster than the velocity noise, so that the arm still stops when released::

    τ_fc(q̇) = 0                                        |q̇| < q̇₀
            = (|q̇| − q̇₀) / (q̇₁ − q̇₀) · ε τ_C sign(q̇)    q̇₀ ≤ |q̇| < q̇₁
            = ε τ_C sign(q̇)                             |q̇| ≥ q̇₁

then smoothed by the filter H(z) of eq. (4.6) so that the operator feels no jolt when
a joint starts moving. While dithering, the dead-band q̇₀ is widened (thesis §5.3).

Active lead-through knows more than the velocity: how surely, and which way, the
operator pushes each joint (the law's signed weight ``p`` in [−1, 1]). Below the ramp
the compensation follows that push instead of falling to zero::

    τ_fc = (r(q̇) sign(q̇) + (1 − r(q̇)) p) ε τ_C,     r(q̇) the ramp above, in [0, 1]

so a joint the operator pushes keeps its compensation when it slows or sticks in the
middle of the push (no ε τ_C that flickers on and off with a velocity near q̇₀), and a
joint at rest under a push it believes starts with it. ``p = 0`` (passive mode, nobody
pushing) is the thesis' law. A resting joint whose push the law misreads then slides, and
the law misreads most where the model's error was never measured: by default
(``CoulombCompensationParameters.follow_push = "calibrated"``) the compensation follows the
push only once a start-up calibration has been accepted, and keeps the thesis' law
otherwise.

Near a joint limit the compensation must not carry the joint on: a joint the hand pushes
with little more than the friction the compensation leaves (a wrist whose axis passes
near the hand's grip, where turning does not take the push away) slides as far as its
limit, and the admittance, whose references stop ``limit_zone`` short of it, then brakes
it at full speed, in stick-slip against a compensation that flips with every bounce.
Moving towards the nearer limit, the compensation fades from whole at two zone widths
from it to none at one (:class:`LimitZone`): there the joint's own friction stops it,
where the references stop.

ε < 1 keeps the released arm stopping only if nothing else pushes it. A gravity model
that is off by ΔG pushes too, so the compensated level may also be capped per joint by
a **ceiling** [Nm] (:func:`compensation_ceiling`): the friction that is surely there,
``(1 − e_f) τ_C``, minus the gravity error that may be, so that compensation plus model
error never exceed the friction and a released joint still comes to rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import ParameterError
from leadthrough.filters import low_pass, pole
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.validation import real

#: When active mode's compensation follows the push (:class:`CoulombCompensationParameters`).
FOLLOW_PUSH = ("never", "calibrated", "always")


@dataclass(frozen=True)
class CoulombCompensationParameters:
    """Parameters of the compensation law.

    Attributes:
        fraction: ε, the compensated fraction of τ_C [–], in [0, 1] (thesis: 0.7).
        dead_band: q̇₀, no compensation below it [rad/s] (thesis: 0.003, above the noise).
        full_velocity: q̇₁, full compensation above it [rad/s] (not given in the thesis;
            0.01 rad/s, a few times q̇₀, ramps in over a fraction of a degree per second).
        follow_push: Active lead-through only: when, below the ramp, the compensation
            follows how surely and which way the admittance reads a push on the joint
            (module docstring): ``"calibrated"`` once a start-up calibration has been
            accepted (the default), ``"always"`` (``true`` in TOML), or ``"never"``
            (``false``: the thesis' law in both modes). Calibrated, it lightens guiding a
            little and shakes less in the worst cases; without a calibration a resting
            joint the law misreads slides (dry #1's relaxed circle: 1.5× passive's
            vibration against 0.96× with the thesis' law; README).
        held_fraction: Active lead-through only: ε while a hand holds the enabling device
            on a model a start-up calibration measured (``JointState.enabling``; when the
            law lets go of its friction margin). The thesis' 0.7 leaves 30 % of the
            friction so that a released arm stops; the device says when the hand lets go,
            and the controller then sends gravity alone, so while it is held the
            compensation may be the friction surely there (1: the ceiling, ``(1 − e) τ_C``
            less the gravity error that may be, caps it). None (the default) keeps
            ``fraction``: 1 is lighter on the YuMi's plants whose friction was identified
            first (0.35 of passive's effort against 0.47) but shakes more in other cases
            (the nominal model's tail case 1.40 → 1.96× passive; the UR10e's relaxed
            circles 1.71 → 2.16; README, *An enabling device*).
    """

    fraction: float = 0.7
    dead_band: float = 0.003
    full_velocity: float = 0.01
    follow_push: str = "calibrated"
    held_fraction: float | None = None

    def __post_init__(self) -> None:
        if isinstance(self.follow_push, bool):  # TOML's true / false
            object.__setattr__(self, "follow_push", "always" if self.follow_push else "never")
        if self.follow_push not in FOLLOW_PUSH:
            raise ParameterError("follow_push", f"must be one of {', '.join(FOLLOW_PUSH)} (or "
                                 f"true / false), got {self.follow_push!r}")  # fmt: skip
        _fraction("fraction", self.fraction)
        if self.held_fraction is not None:
            _fraction("held_fraction", self.held_fraction)
        real("dead_band", self.dead_band, minimum=0.0, error=ParameterError)
        if real("full_velocity", self.full_velocity, error=ParameterError) <= self.dead_band:
            raise ParameterError("full_velocity", "must be above dead_band")


def _fraction(name: str, value: float) -> None:
    """A fraction of τ_C [–]: a finite number in [0, 1], or a one-line error naming it."""
    if real(name, value, minimum=0.0, error=ParameterError) > 1.0:
        raise ParameterError(name, f"must be ≤ 1, got {value:g}")


def coulomb_compensation(
    qd: ArrayLike,
    coulomb: ArrayLike,
    fraction: float,
    dead_band: ArrayLike,
    full_velocity: ArrayLike,
    ceiling: ArrayLike | None = None,
    push: ArrayLike | None = None,
) -> FloatArray:
    """The law above, unfiltered [Nm]; arrays broadcast over joints (and samples).

    ``ceiling`` [Nm], if given, caps the compensated level ``ε τ_C`` per joint. ``push``
    [–], if given, is how surely and which way someone pushes each joint, in [−1, 1]:
    below the ramp the compensation follows it (module docstring); None is zero.
    """
    qd = np.asarray(qd, dtype=float)
    dead_band = np.asarray(dead_band, dtype=float)
    ramp = (np.abs(qd) - dead_band) / (np.asarray(full_velocity) - dead_band)
    ramp = np.minimum(np.maximum(ramp, 0.0), 1.0)  # np.clip's result, at half its cost
    level = fraction * np.asarray(coulomb, dtype=float)
    if ceiling is not None:
        level = np.minimum(level, ceiling)
    if push is None:
        return ramp * np.sign(qd) * level
    return (ramp * np.sign(qd) + (1.0 - ramp) * np.asarray(push, dtype=float)) * level


@dataclass(frozen=True, eq=False)
class LimitZone:
    """Where the compensation fades before the joint limits.

    Attributes:
        low: Lower joint limits [rad], (n,) (−inf: none).
        high: Upper joint limits [rad], (n,) (inf: none).
        width: The zone's width [rad] (``LeadThroughParameters.limit_zone``), > 0: the
            compensation towards a limit is whole ``2 · width`` from it and none within
            ``width`` of it.
    """

    low: FloatArray
    high: FloatArray
    width: float

    def __post_init__(self) -> None:
        if real("width", self.width, error=ParameterError) <= 0.0:
            raise ParameterError("width", f"must be > 0, got {self.width:g}")

    def share(self, q: ArrayLike, torque: ArrayLike) -> FloatArray:
        """What is left of a compensation ``torque`` [Nm] at ``q`` [rad], per joint [–].

        ``clip(d / width − 1, 0, 1)``, with d the room [rad] between the joint and the
        limit the torque pushes it towards (a NaN reading gives NaN).
        """
        q, torque = np.asarray(q, dtype=float), np.asarray(torque, dtype=float)
        room = np.where(torque < 0.0, q - self.low, self.high - q)
        return np.clip(room / self.width - 1.0, 0.0, 1.0)


def compensation_ceiling(
    coulomb: ArrayLike, friction_error: ArrayLike, gravity_error: ArrayLike
) -> FloatArray:
    """The most Coulomb compensation a released joint stops with [Nm], ≥ 0.

    Args:
        coulomb: The model's Coulomb levels τ_C(q) [Nm].
        friction_error: Relative error of those levels [–]: the plant has at least
            ``(1 − friction_error) τ_C``.
        gravity_error: How far the gravity model may be off here [Nm].
    """
    surely = (1.0 - np.asarray(friction_error, dtype=float)) * np.asarray(coulomb, dtype=float)
    return np.maximum(surely - np.asarray(gravity_error, dtype=float), 0.0)


class CoulombCompensation:
    """The filtered compensation torque, one control period at a time.

    The torque is low-passed with the thesis' filter, defined by its time constant
    (:data:`~leadthrough.filters.TIME_CONSTANT`, 7.8 ms): its pole follows ``dt``.

    Args:
        friction: Friction model whose τ_C(q) is compensated.
        parameters: ε, q̇₀, q̇₁.
        dt: Control period [s].
        limits: Where the compensation fades before the joint limits; None: nowhere
            (the thesis' law).
    """

    def __init__(
        self,
        friction: FrictionModel,
        parameters: CoulombCompensationParameters | None = None,
        dt: float = 0.004,
        limits: LimitZone | None = None,
    ) -> None:
        self.friction = friction
        self.parameters = parameters or CoulombCompensationParameters()
        #: ε in use [–]: the parameters' ``fraction`` unless a controller sets another
        #: (``PassiveFeedForward.use_fraction``).
        self.fraction = self.parameters.fraction
        self.limits = limits
        self._pole = pole(dt)
        self._torque = np.zeros(friction.n_joints)

    def reset(self) -> None:
        """Forget the filter state."""
        self._torque[:] = 0.0

    @property
    def pole(self) -> float:
        """Pole of the filter H(z) at this ``dt`` [–]."""
        return self._pole

    @property
    def filtered(self) -> FloatArray:
        """The filter's state, the latest torque [Nm].

        The array itself: a compiled step updates it in place.
        """
        return self._torque

    def step(
        self,
        qd: ArrayLike,
        q: ArrayLike | None = None,
        dead_band: ArrayLike | None = None,
        ceiling: ArrayLike | None = None,
        push: ArrayLike | None = None,
    ) -> FloatArray:
        """Filtered compensation torque [Nm], (n,), for velocities q̇ [rad/s].

        Args:
            qd: Joint velocities [rad/s].
            q: Joint positions [rad], for a position-dependent Coulomb level and the
                fade before the limits (:attr:`limits`; none without ``q``).
            dead_band: Per-joint q̇₀ overriding the parameter (widened while dithering);
                the ramp then ends at ``max(q̇₁, 2 q̇₀)``.
            ceiling: Per-joint cap on the compensated level [Nm]
                (:func:`compensation_ceiling`); None: no cap.
            push: How surely and which way someone pushes each joint [–], in [−1, 1]:
                below the ramp the compensation follows it; None: zero (the thesis).
        """
        p = self.parameters
        band: float | FloatArray
        full: float | FloatArray
        if dead_band is None:
            band, full = p.dead_band, max(p.full_velocity, 2.0 * p.dead_band)
        else:
            band = np.asarray(dead_band, dtype=float)
            full = np.maximum(p.full_velocity, 2.0 * band)
        level = self.friction.coulomb_level(q)
        raw = coulomb_compensation(qd, level, self.fraction, band, full, ceiling, push)
        if self.limits is not None and q is not None:
            raw = raw * self.limits.share(q, raw)
        self._torque = low_pass(self._torque, raw, self._pole)
        return self._torque.copy()
