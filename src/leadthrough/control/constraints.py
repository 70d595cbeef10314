"""Virtual constraints on the tool during lead-through (thesis ch. 7, SPEC §6).

Each constraint is a spring–damper that acts only where it is violated and returns a
force on the tool centre point (TCP, ``robot.tcp``; the flange without a tool) in world
axes [N]; :func:`constraint_torque` maps the sum to the joints with the TCP's ``Jᵀ``.
In active mode the torque drives the admittance model (so the references, and with them
the arm, respect the constraint); in passive mode it is added to the command.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import ParameterError
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics
from leadthrough.model.snapshot import ModelSnapshot
from leadthrough.validation import real, real_array

#: The world axes, unit vectors (rows).
_AXES = np.eye(3)
_AXES.setflags(write=False)


@dataclass(frozen=True)
class VirtualConstraint(ABC):
    """A spring–damper keeping the tool centre point where it belongs.

    Attributes:
        stiffness: Spring [N/m] per metre of violation.
        damping: Damper [N s/m] on the velocity along the violated direction.
    """

    stiffness: float = field(default=3000.0, kw_only=True)
    damping: float = field(default=60.0, kw_only=True)

    def __post_init__(self) -> None:
        real("stiffness", self.stiffness, minimum=0.0, error=ParameterError)
        real("damping", self.damping, minimum=0.0, error=ParameterError)

    @abstractmethod
    def force(self, position: FloatArray, velocity: FloatArray) -> FloatArray:
        """Force on the TCP [N], world axes, for its position [m] and velocity [m/s]."""

    def _push(self, violation: float, direction: FloatArray, velocity: FloatArray) -> FloatArray:
        """Spring along ``direction`` (unit, pointing back inside) plus damping along it."""
        approach = min(float(direction @ velocity), 0.0)  # only while moving further out
        return (self.stiffness * violation - self.damping * approach) * direction


@dataclass(frozen=True)
class Plane(VirtualConstraint):
    """Keep the tool on a plane (both sides are walls): draw on a table, slide on a line.

    Attributes:
        point: A point of the plane [m].
        normal: Its normal (any length).
    """

    point: ArrayLike = (0.0, 0.0, 0.0)
    normal: ArrayLike = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        normal = real_array("normal", self.normal, (3,), error=ParameterError)
        if np.linalg.norm(normal) == 0.0:
            raise ParameterError("normal", "must not be zero")
        object.__setattr__(self, "normal", normal / np.linalg.norm(normal))
        object.__setattr__(
            self, "point", real_array("point", self.point, (3,), error=ParameterError)
        )

    def force(self, position: FloatArray, velocity: FloatArray) -> FloatArray:
        """Pull back onto the plane."""
        normal, point = np.asarray(self.normal, dtype=float), np.asarray(self.point, dtype=float)
        distance = float(normal @ (position - point))
        inward = -np.sign(distance) * normal if distance else normal
        damping = -self.damping * float(normal @ velocity) * normal
        return self.stiffness * abs(distance) * inward + damping


@dataclass(frozen=True)
class Box(VirtualConstraint):
    """Keep the tool inside an axis-aligned box.

    Attributes:
        lower: Lower corner [m].
        upper: Upper corner [m].
    """

    lower: ArrayLike = (-1.0, -1.0, -1.0)
    upper: ArrayLike = (1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        super().__post_init__()
        lower = real_array("lower", self.lower, (3,), error=ParameterError)
        upper = real_array("upper", self.upper, (3,), error=ParameterError)
        if np.any(lower >= upper):
            raise ParameterError("upper", "every coordinate must exceed lower's")
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)

    def force(self, position: FloatArray, velocity: FloatArray) -> FloatArray:
        """Push back through each face that is crossed."""
        lower, upper = np.asarray(self.lower, dtype=float), np.asarray(self.upper, dtype=float)
        total = np.zeros(3)
        for axis, unit in enumerate(_AXES):
            below, above = lower[axis] - position[axis], position[axis] - upper[axis]
            if below > 0:
                total += self._push(below, unit, velocity)
            if above > 0:
                total += self._push(above, -unit, velocity)
        return total


@dataclass(frozen=True)
class KeepOutSphere(VirtualConstraint):
    """Keep the tool out of a sphere (an obstacle, a person's head).

    Attributes:
        center: Centre [m].
        radius: Radius [m], > 0.
    """

    center: ArrayLike = (0.0, 0.0, 0.0)
    radius: float = 0.1

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(
            self, "center", real_array("center", self.center, (3,), error=ParameterError)
        )
        real("radius", self.radius, minimum=0.0, strict=True, error=ParameterError)

    def force(self, position: FloatArray, velocity: FloatArray) -> FloatArray:
        """Push radially outwards while inside."""
        offset = position - np.asarray(self.center, dtype=float)
        distance = float(np.linalg.norm(offset))
        if distance >= self.radius:
            return np.zeros(3)
        outward = offset / distance if distance > 1e-9 else np.array([0.0, 0.0, 1.0])
        return self._push(self.radius - distance, outward, velocity)


def constraint_torque(
    constraints: Sequence[VirtualConstraint],
    dynamics: Dynamics,
    q: FloatArray,
    qd: FloatArray,
    model: ModelSnapshot | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Joint torque ``Jᵀ F`` [Nm] of all constraints, and the total force F [N] (world).

    ``J`` is the TCP's; ``model`` is the model at (q, q̇) computed this period, if the
    caller has it.
    """
    if not constraints:
        return np.zeros(dynamics.n), np.zeros(3)
    if model is None:
        model = dynamics.snapshot(q, qd)
    jacobian = model.tool_jacobian[:3]
    position, velocity = model.tool_pose[:3, 3], jacobian @ qd
    force = sum((c.force(position, velocity) for c in constraints), np.zeros(3))
    return jacobian.T @ force, force
