"""Robot descriptions as data: frozen, validated dataclasses for a serial arm.

Conventions (SPEC §1): SI units, joint order from the base, torques arm side.
A joint reading ``q`` is what the robot's encoder reports; DH offsets are applied
inside the model. Every array is read-only, so a description can be shared freely.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from leadthrough import validation as check
from leadthrough.validation import FloatArray


def rpy_to_rotation(rpy: ArrayLike) -> FloatArray:
    """Rotation matrix of URDF roll-pitch-yaw angles [rad]: ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    roll, pitch, yaw = np.asarray(rpy, dtype=float)
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch),
                              np.sin(pitch), np.cos(yaw), np.sin(yaw))  # fmt: skip
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


@dataclass(frozen=True, eq=False)
class Placement:
    """A rigid transform: ``translation`` [m] and ``rotation`` of a child frame in its parent."""

    translation: FloatArray = field(default_factory=lambda: np.zeros(3))
    rotation: FloatArray = field(default_factory=lambda: np.eye(3))

    def __post_init__(self) -> None:
        object.__setattr__(self, "translation", check.real_array("xyz", self.translation, (3,)))
        object.__setattr__(self, "rotation", check.rotation_matrix("rotation", self.rotation))

    @property
    def homogeneous(self) -> FloatArray:
        """The 4×4 homogeneous matrix of this placement."""
        matrix = np.eye(4)
        matrix[:3, :3] = self.rotation
        matrix[:3, 3] = self.translation
        return matrix


@dataclass(frozen=True, eq=False)
class DHParameters:
    """One row of a standard Denavit–Hartenberg table (thesis eq. 3.1).

    ``A = Rz(q + offset) · Tz(d) · Tx(a) · Rx(alpha)`` maps link frame i into link frame i−1.

    Attributes:
        d: Link offset along z_{i−1} [m].
        a: Link length along x_i [m].
        alpha: Link twist about x_i [rad].
        offset: Added to the joint reading q to give the DH angle θ [rad].
    """

    d: float
    a: float
    alpha: float
    offset: float = 0.0

    def __post_init__(self) -> None:
        for name in ("d", "a", "alpha", "offset"):
            object.__setattr__(self, name, check.real(name, getattr(self, name)))


@dataclass(frozen=True, eq=False)
class JointOrigin:
    """A revolute joint placed like a URDF ``<origin>``, in the previous joint's frame.

    Attributes:
        placement: Joint frame in the previous joint frame (the world for joint 1, after
            the base) at q = 0.
        axis: Unit rotation axis in the joint frame.
    """

    placement: Placement
    axis: FloatArray

    def __post_init__(self) -> None:
        axis = check.real_array("axis", self.axis, (3,))
        norm = float(np.linalg.norm(axis))
        if abs(norm - 1.0) > 1e-6:
            raise check.fail("axis", f"must be a unit vector, got norm {norm:g}")
        object.__setattr__(self, "axis", axis)


@dataclass(frozen=True, eq=False)
class LinkInertial:
    """Mass properties of the link that a joint moves, in that link's frame.

    Attributes:
        mass: Link mass [kg], > 0.
        com: Centre of mass in the link frame [m].
        inertia: Inertia tensor about the centre of mass, link-frame axes [kg m²].
    """

    mass: float
    com: FloatArray
    inertia: FloatArray

    def __post_init__(self) -> None:
        object.__setattr__(self, "mass", check.real("mass", self.mass, minimum=0.0, strict=True))
        object.__setattr__(self, "com", check.real_array("com", self.com, (3,)))
        inertia = check.real_array("inertia", self.inertia, (3, 3))
        check.symmetric_positive_definite("inertia", inertia)
        object.__setattr__(self, "inertia", inertia)


@dataclass(frozen=True, eq=False)
class JointFriction:
    """Friction of one joint, arm side: the sigmoid pair of thesis eqs. (4.2)–(4.3).

    Attributes:
        coulomb: Coulomb level τ_C [Nm] (the sigmoids span −τ_C … +τ_C).
        slope: Sigmoid slope A [s/rad].
        half_width: Half-width B between the two sigmoids [rad/s].
        viscous: Viscous coefficient c [Nm s/rad].
        noise_std: Velocity-independent standard deviation of the friction torque [Nm].
    """

    coulomb: float
    slope: float
    half_width: float
    viscous: float
    noise_std: float

    def __post_init__(self) -> None:
        for name in ("coulomb", "half_width", "viscous", "noise_std"):
            object.__setattr__(self, name, check.real(name, getattr(self, name), minimum=0.0))
        object.__setattr__(self, "slope", check.real("slope", self.slope, minimum=0, strict=True))


@dataclass(frozen=True, eq=False)
class Joint:
    """One revolute joint of a serial arm and the link it moves.

    Exactly one of ``dh`` and ``origin`` places the joint. Limits are on the joint
    reading q; torques and inertias are arm side except ``rotor_inertia``.

    Attributes:
        name: Joint name.
        link: Mass properties of the link moved by this joint, in the link frame
            (the DH frame i, or the joint frame for ``origin`` joints).
        position_limits: (min, max) joint reading [rad].
        velocity_limit: Maximum |q̇| [rad/s].
        torque_limit: Maximum |τ| arm side [Nm].
        gear_ratio: Motor turns per joint turn (sign = motor direction), non-zero.
        rotor_inertia: Motor rotor inertia J_m, motor side [kg m²]; the arm sees G_r² J_m.
        torque_constant: Current-to-torque constant K, arm side [Nm/A]: a drive that
            reports motor current i applies τ = K·i at the joint; None when the drive
            reports torque (or K is unknown).
        friction: Friction parameters of the joint.
        dh: Standard DH row, for DH-described arms.
        origin: URDF-style joint placement and axis, for chain-described arms.
    """

    name: str
    link: LinkInertial
    position_limits: tuple[float, float]
    velocity_limit: float
    torque_limit: float
    friction: JointFriction
    gear_ratio: float = 1.0
    rotor_inertia: float = 0.0
    torque_constant: float | None = None
    dh: DHParameters | None = None
    origin: JointOrigin | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise check.fail("name", f"must be a non-empty string, got {check.short(self.name)}")
        if (self.dh is None) == (self.origin is None):
            raise check.fail("dh", "exactly one of 'dh' and 'origin' must place the joint")
        low, high = check.real_array("position_limits", self.position_limits, (2,))
        if low >= high:
            raise check.fail("position_limits", f"min {low:g} must be below max {high:g}")
        object.__setattr__(self, "position_limits", (float(low), float(high)))
        for name in ("velocity_limit", "torque_limit"):
            value = check.real(name, getattr(self, name), minimum=0.0, strict=True)
            object.__setattr__(self, name, value)
        gear = check.real("gear_ratio", self.gear_ratio)
        if gear == 0.0:
            raise check.fail("gear_ratio", "must be non-zero")
        object.__setattr__(self, "gear_ratio", gear)
        rotor = check.real("rotor_inertia", self.rotor_inertia, minimum=0.0)
        object.__setattr__(self, "rotor_inertia", rotor)
        if self.torque_constant is not None:
            constant = check.real("torque_constant", self.torque_constant, minimum=0, strict=True)
            object.__setattr__(self, "torque_constant", constant)

    @property
    def reflected_rotor_inertia(self) -> float:
        """Rotor inertia seen at the joint, ``G_r² J_m`` [kg m²]."""
        return self.gear_ratio**2 * self.rotor_inertia


@dataclass(frozen=True, eq=False)
class RobotDescription:
    """A serial arm of revolute joints, from base to flange.

    Attributes:
        name: Human-readable robot name.
        joints: The joints from the base (joint 1) to the flange.
        base: Pose of the base frame (DH frame 0, or the chain root) in the world.
        flange: Flange frame in the last link frame (identity: the last DH frame).
        tcp: Tool centre point in the flange frame (identity: the flange itself); the tool
            speed limit, the virtual constraints and the tool wrench act there.
        gravity: Gravity acceleration in the world frame [m/s²].
        home_position: Joint readings of the home pose [rad], inside the limits
            (default: zero, clipped into the limits).
    """

    name: str
    joints: tuple[Joint, ...]
    base: Placement = field(default_factory=Placement)
    flange: Placement = field(default_factory=Placement)
    tcp: Placement = field(default_factory=Placement)
    gravity: FloatArray = field(default_factory=lambda: np.array([0.0, 0.0, -9.81]))
    home_position: FloatArray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise check.fail("name", f"must be a non-empty string, got {check.short(self.name)}")
        object.__setattr__(self, "joints", tuple(self.joints))
        if not self.joints:
            raise check.fail("joints", "a robot needs at least one joint")
        if len({joint.dh is None for joint in self.joints}) != 1:
            raise check.fail("joints", "all joints must use 'dh', or all 'origin', not a mix")
        names = [joint.name for joint in self.joints]
        if len(set(names)) != len(names):
            raise check.fail("joints", f"joint names must be unique, got {names}")
        object.__setattr__(self, "gravity", check.real_array("gravity", self.gravity, (3,)))
        if self.home_position is not None:
            home = check.real_array("home", self.home_position, (len(self.joints),))
            outside = np.flatnonzero((home < self.q_min) | (home > self.q_max))
            if outside.size:
                joint = self.joints[outside[0]].name
                raise check.fail(
                    "home", f"{joint} at {home[outside[0]]:g} rad is outside its limits"
                )
            object.__setattr__(self, "home_position", home)

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return len(self.joints)

    @property
    def uses_dh(self) -> bool:
        """Whether the kinematics is a standard DH table (else URDF-style joint origins)."""
        return self.joints[0].dh is not None

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names from the base."""
        return tuple(joint.name for joint in self.joints)

    @cached_property
    def q_min(self) -> FloatArray:
        """Lower position limits [rad], shape (n,)."""
        return self._stack(lambda joint: joint.position_limits[0])

    @cached_property
    def q_max(self) -> FloatArray:
        """Upper position limits [rad], shape (n,)."""
        return self._stack(lambda joint: joint.position_limits[1])

    @cached_property
    def velocity_limits(self) -> FloatArray:
        """Joint speed limits [rad/s], shape (n,)."""
        return self._stack(lambda joint: joint.velocity_limit)

    @cached_property
    def torque_limits(self) -> FloatArray:
        """Joint torque limits, arm side [Nm], shape (n,)."""
        return self._stack(lambda joint: joint.torque_limit)

    @cached_property
    def gear_ratios(self) -> FloatArray:
        """Gear ratios (motor turns per joint turn), shape (n,)."""
        return self._stack(lambda joint: joint.gear_ratio)

    @cached_property
    def rotor_inertias(self) -> FloatArray:
        """Rotor inertias J_m, motor side [kg m²], shape (n,)."""
        return self._stack(lambda joint: joint.rotor_inertia)

    @cached_property
    def reflected_rotor_inertias(self) -> FloatArray:
        """Rotor inertias seen at the joints ``G_r² J_m`` [kg m²], shape (n,)."""
        return self._stack(lambda joint: joint.reflected_rotor_inertia)

    @cached_property
    def torque_constants(self) -> FloatArray | None:
        """Current-to-torque constants K, arm side [Nm/A], shape (n,); None if one is unknown."""
        if any(joint.torque_constant is None for joint in self.joints):
            return None
        return self._stack(lambda joint: float(joint.torque_constant))  # type: ignore[arg-type]

    @property
    def torque_constant(self) -> FloatArray | None:
        """:attr:`torque_constants` by the name SPEC §10 gives it (``ur10e.torque_constant``)."""
        return self.torque_constants

    @cached_property
    def masses(self) -> FloatArray:
        """Link masses [kg], shape (n,)."""
        return self._stack(lambda joint: joint.link.mass)

    @property
    def total_mass(self) -> float:
        """Total moving mass [kg]."""
        return float(np.sum(self.masses))

    def with_payload(self, mass: float, com: ArrayLike = (0.0, 0.0, 0.0)) -> RobotDescription:
        """This robot carrying a point mass rigidly at the flange, lumped into the last link.

        Args:
            mass: Payload mass [kg], >= 0.
            com: Its position in the flange frame [m].
        """
        mass = check.real("payload mass", mass, minimum=0.0)
        if mass == 0.0:
            return self
        link = self.joints[-1].link
        at = self.flange.translation + self.flange.rotation @ check.real_array("com", com, (3,))
        total = link.mass + mass
        centre = (link.mass * link.com + mass * at) / total
        inertia = (link.inertia + _point_inertia(link.mass, link.com - centre)
                   + _point_inertia(mass, at - centre))  # fmt: skip
        carried = dataclasses.replace(link, mass=total, com=centre, inertia=inertia)
        last = dataclasses.replace(self.joints[-1], link=carried)
        return dataclasses.replace(self, joints=(*self.joints[:-1], last))

    def home(self) -> FloatArray:
        """Joint readings of the home pose [rad] (a fresh, writable array)."""
        if self.home_position is not None:
            return self.home_position.copy()
        return np.clip(np.zeros(self.n_joints), self.q_min, self.q_max)

    def _stack(self, get: Callable[[Joint], float]) -> FloatArray:
        array = np.array([get(joint) for joint in self.joints], dtype=float)
        array.setflags(write=False)
        return array


def _point_inertia(mass: float, offset: FloatArray) -> FloatArray:
    """Inertia of a point mass at ``offset`` from a point [kg m²] (parallel-axis term)."""
    return mass * (float(offset @ offset) * np.eye(3) - np.outer(offset, offset))
