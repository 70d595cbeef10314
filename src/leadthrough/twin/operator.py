"""The simulated operator: the person who grabs the arm in the digital twin.

An :class:`Operator` acts on the robot in two ways, both zero by default (nobody touches
the arm): a wrench at the flange and a torque directly on the joints. The simulator asks
for both at every physics step and logs what it applies; the operators record nothing.

- :class:`Hand` pulls the flange along a Cartesian :class:`~leadthrough.twin.paths.Path`
  through a spring–damper, force-limited like a person.
- :class:`JointHand` turns one joint along a :class:`~leadthrough.twin.paths.JointMinimumJerk`
  reference, as in the single-joint tests of the thesis.
- :class:`TorqueProfile` applies a scripted torque (steps, ramps, pulses) on one joint, for
  observer tests with a known ground truth.

Sign convention (SPEC §1): a torque in a joint's positive direction is positive.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from leadthrough.twin import _checks as check
from leadthrough.twin.errors import OperatorError
from leadthrough.twin.paths import JointMinimumJerk, Path

FloatArray = NDArray[np.float64]


class Operator:
    """Base operator: nobody touches the arm (zero wrench, zero joint torque)."""

    def wrench(self, t: float, flange_pose: ArrayLike, flange_velocity: ArrayLike) -> FloatArray:
        """Wrench the operator applies at the flange origin, in world axes.

        Args:
            t: Time [s].
            flange_pose: Pose of the flange in the world, 4×4 homogeneous matrix [m].
            flange_velocity: Flange twist ``(v, ω)`` in world axes, shape (6,) [m/s, rad/s].

        Returns:
            ``(f, m)``, shape (6,): force [N] and moment [Nm] at the flange origin, world axes.
        """
        return np.zeros(6)

    def joint_torque(self, t: float, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Torque the operator applies directly on the joints.

        Args:
            t: Time [s].
            q: Joint positions, shape (n,) [rad].
            qd: Joint velocities, shape (n,) [rad/s].

        Returns:
            Joint torque, shape (n,) [Nm], arm side, positive in each joint's positive direction.
        """
        return np.zeros(np.asarray(q).shape[0])

    def holds(self, t: float) -> bool:
        """Whether the operator holds the arm, and with it its enabling device, at ``t`` [s].

        A person who touches the arm holds it throughout; :class:`During` only inside its
        window. (The twin asks only an operator who touches the arm.)
        """
        return True


NoOperator = Operator
"""Nobody touches the arm."""


@dataclass(frozen=True)
class HandParameters:
    """Impedance of a relaxed human hand holding the flange; isotropic.

    The defaults are those of a relaxed arm: endpoint stiffness is a few hundred N/m
    (Mussa-Ivaldi, Hogan & Bizzi 1985, J. Neurosci. 5(10)), endpoint viscosity is of the
    order of 10–20 N s/m (Tsuji et al. 1995, Biol. Cybern. 72), and 60 N is a pull a
    person sustains comfortably. The rotational impedance is off by default (force only);
    a weak wrist is a few Nm/rad. A hand that holds a posture trembles: physiological tremor
    is 8–12 Hz, a few tenths of a millimetre at the hand (Elble & Koller 1990, *Tremor*);
    off by default.

    Attributes:
        stiffness: Translational stiffness [N/m], >= 0.
        damping: Translational damping [N s/m], >= 0.
        max_force: Largest force norm the hand applies [N], > 0.
        rotational_stiffness: Rotational stiffness [Nm/rad], >= 0.
        rotational_damping: Rotational damping [Nm s/rad], >= 0.
        max_moment: Largest moment norm the hand applies [Nm], > 0.
        tremor: Amplitude of the tremor of the hand's reference, per world axis [m], >= 0:
            ``a sin(2π f t + φ_k)`` with phases 0, 120° and 240° on x, y and z.
        tremor_frequency: Its frequency ``f`` [Hz], > 0.
    """

    stiffness: float = 300.0
    damping: float = 20.0
    max_force: float = 60.0
    rotational_stiffness: float = 0.0
    rotational_damping: float = 0.0
    max_moment: float = 5.0
    tremor: float = 0.0
    tremor_frequency: float = 9.0

    def __post_init__(self) -> None:
        names = ("stiffness", "damping", "rotational_stiffness", "rotational_damping", "tremor")
        for name in names:
            object.__setattr__(self, name, check.real(name, getattr(self, name), minimum=0.0))
        for name in ("max_force", "max_moment", "tremor_frequency"):
            value = check.real(name, getattr(self, name), minimum=0.0, strict=True)
            object.__setattr__(self, name, value)


class Hand(Operator):
    """A hand that pulls the flange along ``path`` through a saturated spring–damper.

    Force ``f = K (p_ref − p) + D (v_ref − v)``, limited in norm to ``max_force``. Moment
    ``m = −K_r e − D_r ω``, limited in norm to ``max_moment``, where ``e`` is the rotation
    vector [rad, world] from the orientation held since the first call to the current one.
    The keyword arguments are the fields of :class:`HandParameters`, stored in
    ``parameters``.

    Attributes:
        path: Reference the flange origin is pulled along [m, world].
        parameters: Impedance of the hand.
    """

    def __init__(
        self,
        path: Path,
        *,
        stiffness: float = HandParameters.stiffness,
        damping: float = HandParameters.damping,
        max_force: float = HandParameters.max_force,
        rotational_stiffness: float = HandParameters.rotational_stiffness,
        rotational_damping: float = HandParameters.rotational_damping,
        max_moment: float = HandParameters.max_moment,
        tremor: float = HandParameters.tremor,
        tremor_frequency: float = HandParameters.tremor_frequency,
    ) -> None:
        check.path_like("path", path)
        self.path = path
        self.parameters = HandParameters(stiffness, damping, max_force, rotational_stiffness,
                                         rotational_damping, max_moment, tremor,
                                         tremor_frequency)  # fmt: skip
        self._held_orientation: FloatArray | None = None

    @classmethod
    def from_parameters(cls, path: Path, parameters: HandParameters) -> Hand:
        """A hand with the impedance ``parameters``."""
        return cls(path, **dataclasses.asdict(parameters))

    @property
    def held_orientation(self) -> FloatArray | None:
        """Flange orientation [world] held since the first call, ``None`` before it."""
        return self._held_orientation

    def reset(self) -> None:
        """Forget the held orientation: the next call holds the flange orientation anew."""
        self._held_orientation = None

    def wrench(self, t: float, flange_pose: ArrayLike, flange_velocity: ArrayLike) -> FloatArray:
        """Wrench ``(f [N], m [Nm])`` at the flange origin in world axes; see the class."""
        pose = check.array("flange_pose", flange_pose, (4, 4))
        twist = check.array("flange_velocity", flange_velocity, (6,))
        if self._held_orientation is None:
            self._held_orientation = pose[:3, :3].copy()
        p = self.parameters
        position, velocity = (self.path.reference(t) if isinstance(self.path, Path)
                              else (self.path.position(t), self.path.velocity(t)))  # fmt: skip
        if p.tremor > 0.0:
            position, velocity = _trembling(position, velocity, t, p)
        force = _impedance(
            error=position - pose[:3, 3],
            rate_error=velocity - twist[:3],
            gains=(p.stiffness, p.damping),
            limit=p.max_force,
        )
        if p.rotational_stiffness == 0.0 and p.rotational_damping == 0.0:
            return np.concatenate([force, np.zeros(3)])
        rotation_error = Rotation.from_matrix(pose[:3, :3] @ self._held_orientation.T).as_rotvec()
        moment = _impedance(
            error=-rotation_error,
            rate_error=-twist[3:],
            gains=(p.rotational_stiffness, p.rotational_damping),
            limit=p.max_moment,
        )
        return np.concatenate([force, moment])


def _trembling(
    position: FloatArray, velocity: FloatArray, t: float, p: HandParameters
) -> tuple[FloatArray, FloatArray]:
    """The reference ``position`` [m] and ``velocity`` [m/s] with the hand's tremor added."""
    omega = 2.0 * np.pi * p.tremor_frequency
    phase = omega * t + _TREMOR_PHASES
    return position + p.tremor * np.sin(phase), velocity + p.tremor * omega * np.cos(phase)


#: Phases of the tremor on the world's x, y and z axes [rad].
_TREMOR_PHASES = np.array([0.0, 2.0 * np.pi / 3.0, 4.0 * np.pi / 3.0])


@dataclass(frozen=True, eq=False)
class JointHand(Operator):
    """A hand that turns one joint along a minimum-jerk reference, torque-limited.

    ``τ = K (q_ref − q) + D (q̇_ref − q̇)`` on joint ``joint`` only, clipped to
    ``±max_torque``. The defaults match the scale of the thesis' single-joint hand tests
    (external torques from 0.1 Nm on the wrist to a few Nm, Figs. 5.6 and 6.7).

    Attributes:
        joint: 0-based index of the joint turned.
        path: Reference of that joint.
        stiffness: Stiffness [Nm/rad], >= 0.
        damping: Damping [Nm s/rad], >= 0.
        max_torque: Largest torque magnitude [Nm], > 0.
    """

    joint: int
    path: JointMinimumJerk
    stiffness: float = 20.0
    damping: float = 2.0
    max_torque: float = 5.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "joint", check.index("joint", self.joint))
        check.path_like("path", self.path)
        for name in ("stiffness", "damping"):
            object.__setattr__(self, name, check.real(name, getattr(self, name), minimum=0.0))
        max_torque = check.real("max_torque", self.max_torque, minimum=0.0, strict=True)
        object.__setattr__(self, "max_torque", max_torque)

    def joint_torque(self, t: float, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Torque [Nm] on joint ``joint`` only, shape (n,); see the class."""
        q, qd = check.joint_state(q, qd, self.joint)
        torque = self.stiffness * (self.path.position(t) - q[self.joint]) + self.damping * (
            self.path.velocity(t) - qd[self.joint]
        )
        tau = np.zeros(q.shape[0])
        tau[self.joint] = np.clip(torque, -self.max_torque, self.max_torque)
        return tau


@dataclass(frozen=True)
class TorqueSegment:
    """A scripted torque: a linear rise, a hold, then zero.

    The torque rises from 0 at ``start`` to ``amplitude`` in ``rise_time``, is held until
    ``stop`` (exclusive) and is zero outside. A zero ``rise_time`` is a step.

    Attributes:
        start: Time the torque starts [s].
        amplitude: Torque held [Nm].
        rise_time: Duration of the linear rise [s], >= 0.
        stop: Time the torque stops [s], > start + rise_time; ``inf`` holds it forever.
    """

    start: float
    amplitude: float
    rise_time: float = 0.0
    stop: float = math.inf

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", check.real("start", self.start))
        object.__setattr__(self, "amplitude", check.real("amplitude", self.amplitude))
        object.__setattr__(self, "rise_time", check.real("rise_time", self.rise_time, minimum=0.0))
        stop = self.stop if self.stop == math.inf else check.real("stop", self.stop)
        if stop <= self.start + self.rise_time:
            raise OperatorError("stop", f"must be > start + rise_time, got {stop:g}")
        object.__setattr__(self, "stop", float(stop))

    def value(self, t: ArrayLike) -> FloatArray:
        """Torque [Nm] at time(s) ``t`` [s], of the shape of ``t``."""
        t = np.asarray(t, dtype=float)
        if self.rise_time > 0.0:
            level = np.clip((t - self.start) / self.rise_time, 0.0, 1.0)
        else:
            level = (t >= self.start).astype(float)
        return self.amplitude * np.where(t < self.stop, level, 0.0)


def step(t0: float, amplitude: float) -> TorqueSegment:
    """A step of ``amplitude`` [Nm] at ``t0`` [s], held forever."""
    return TorqueSegment(start=t0, amplitude=amplitude)


def ramp(t0: float, t1: float, amplitude: float) -> TorqueSegment:
    """A linear rise from 0 at ``t0`` [s] to ``amplitude`` [Nm] at ``t1`` [s], then held."""
    check.after(t0, t1)
    return TorqueSegment(start=t0, amplitude=amplitude, rise_time=t1 - t0)


def pulse(t0: float, t1: float, amplitude: float) -> TorqueSegment:
    """A rectangular pulse of ``amplitude`` [Nm] from ``t0`` to ``t1`` (exclusive) [s]."""
    check.after(t0, t1)
    return TorqueSegment(start=t0, amplitude=amplitude, stop=t1)


@dataclass(frozen=True, eq=False)
class TorqueProfile(Operator):
    """Scripted torque on one joint: the sum of ``segments`` (:func:`step`, :func:`ramp`...).

    Attributes:
        joint: 0-based index of the joint pushed.
        segments: Torque segments, summed; a single segment is accepted.
    """

    joint: int
    segments: tuple[TorqueSegment, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "joint", check.index("joint", self.joint))
        segments = self.segments
        segments = (segments,) if isinstance(segments, TorqueSegment) else segments
        if not (
            isinstance(segments, list | tuple)
            and all(isinstance(segment, TorqueSegment) for segment in segments)
        ):
            raise OperatorError("segments", "must be TorqueSegment values (from step, ramp, pulse)")
        object.__setattr__(self, "segments", tuple(segments))

    def value(self, t: ArrayLike) -> FloatArray:
        """Total scripted torque [Nm] at time(s) ``t`` [s], of the shape of ``t``."""
        return sum((s.value(t) for s in self.segments), np.zeros(np.shape(t)))

    def joint_torque(self, t: float, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Torque [Nm] on joint ``joint`` only, shape (n,)."""
        q, _ = check.joint_state(q, qd, self.joint)
        tau = np.zeros(q.shape[0])
        tau[self.joint] = self.value(t)
        return tau


class During(Operator):
    """``operator`` acting only from ``start`` until ``stop`` [s], its clock starting at ``start``.

    A person who grabs the arm once the controller is ready and lets go later.
    """

    def __init__(self, operator: Operator, start: float, stop: float = np.inf) -> None:
        self.operator, self.start, self.stop = operator, start, stop

    def wrench(self, t: float, flange_pose: FloatArray, flange_velocity: FloatArray) -> FloatArray:
        """The operator's wrench inside the window, zero outside."""
        if not self.start <= t < self.stop:
            return np.zeros(6)
        return self.operator.wrench(t - self.start, flange_pose, flange_velocity)

    def joint_torque(self, t: float, q: FloatArray, qd: FloatArray) -> FloatArray:
        """The operator's joint torque inside the window, zero outside."""
        if not self.start <= t < self.stop:
            return np.zeros(len(q))
        return self.operator.joint_torque(t - self.start, q, qd)

    def holds(self, t: float) -> bool:
        """Held inside the window only: the enabling device is let go with the arm."""
        return self.start <= t < self.stop and self.operator.holds(t - self.start)


def _impedance(
    error: FloatArray, rate_error: FloatArray, gains: tuple[float, float], limit: float
) -> FloatArray:
    """``K · error + D · rate_error`` scaled down to norm ``limit`` if it exceeds it."""
    stiffness, damping = gains
    output = stiffness * error + damping * rate_error
    norm = math.sqrt(output.dot(output))  # what np.linalg.norm computes, at a fifth of its cost
    return output * (limit / norm) if norm > limit else output
