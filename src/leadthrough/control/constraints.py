"""Virtual constraints on the tool during lead-through (thesis ch. 7, SPEC §6).

Each constraint is a spring–damper that acts only where it is violated and returns a
force on the tool centre point (TCP, ``robot.tcp``; the flange without a tool) in world
axes [N]; :func:`constraint_torque` maps the sum to the joints with the TCP's ``Jᵀ``.
In active mode the torque drives the admittance model (so the references, and with them
the arm, respect the constraint); in passive mode it is added to the command.
"""

from __future__ import annotations

import math
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

#: Three floats: a point, a velocity or a force in world axes.
Triple = tuple[float, float, float]


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

    def force(self, position: ArrayLike, velocity: ArrayLike) -> FloatArray:
        """Force on the TCP [N], world axes, for its position [m] and velocity [m/s]."""
        return np.array(self._force(_triple(position), _triple(velocity)))

    @abstractmethod
    def _force(self, position: Triple, velocity: Triple) -> Triple:
        """:meth:`force` on three floats each (a control period's few µs: no small arrays)."""

    def _push(self, violation: float, direction: Triple, velocity: Triple) -> Triple:
        """Spring along ``direction`` (unit, pointing back inside) plus damping along it."""
        approach = min(_dot(direction, velocity), 0.0)  # only while moving further out
        push = self.stiffness * violation - self.damping * approach
        return push * direction[0], push * direction[1], push * direction[2]


@dataclass(frozen=True)
class Plane(VirtualConstraint):
    """Keep the tool on a plane (both sides are walls): draw on a table, slide on a line.

    Attributes:
        point: A point of the plane [m].
        normal: Its normal (any length).
    """

    point: ArrayLike = (0.0, 0.0, 0.0)
    normal: ArrayLike = (0.0, 0.0, 1.0)
    _plane: tuple[Triple, Triple] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        normal = real_array("normal", self.normal, (3,), error=ParameterError)
        if np.linalg.norm(normal) == 0.0:
            raise ParameterError("normal", "must not be zero")
        object.__setattr__(self, "normal", normal / np.linalg.norm(normal))
        object.__setattr__(
            self, "point", real_array("point", self.point, (3,), error=ParameterError)
        )
        object.__setattr__(self, "_plane", (_triple(self.normal), _triple(self.point)))

    def _force(self, position: Triple, velocity: Triple) -> Triple:
        """Pull back onto the plane: −(k d + c v·n) n, d the signed distance."""
        normal, point = self._plane
        offset = _difference(position, point)
        push = -self.stiffness * _dot(normal, offset) - self.damping * _dot(normal, velocity)
        return push * normal[0], push * normal[1], push * normal[2]


@dataclass(frozen=True)
class Box(VirtualConstraint):
    """Keep the tool inside an axis-aligned box.

    Attributes:
        lower: Lower corner [m].
        upper: Upper corner [m].
    """

    lower: ArrayLike = (-1.0, -1.0, -1.0)
    upper: ArrayLike = (1.0, 1.0, 1.0)
    _corners: tuple[Triple, Triple] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        lower = real_array("lower", self.lower, (3,), error=ParameterError)
        upper = real_array("upper", self.upper, (3,), error=ParameterError)
        if np.any(lower >= upper):
            raise ParameterError("upper", "every coordinate must exceed lower's")
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)
        object.__setattr__(self, "_corners", (_triple(lower), _triple(upper)))

    def _force(self, position: Triple, velocity: Triple) -> Triple:
        """Push back through each face that is crossed."""
        lower, upper = self._corners
        total = [0.0, 0.0, 0.0]
        for axis in range(3):  # _push along the face's inward axis, one coordinate at a time
            below, above = lower[axis] - position[axis], position[axis] - upper[axis]
            if below > 0:  # pushed back along +axis
                total[axis] += self.stiffness * below - self.damping * min(velocity[axis], 0.0)
            if above > 0:  # pushed back along −axis
                total[axis] -= self.stiffness * above - self.damping * min(-velocity[axis], 0.0)
        return total[0], total[1], total[2]


@dataclass(frozen=True)
class KeepOutSphere(VirtualConstraint):
    """Keep the tool out of a sphere (an obstacle, a person's head).

    Attributes:
        center: Centre [m].
        radius: Radius [m], > 0.
    """

    center: ArrayLike = (0.0, 0.0, 0.0)
    radius: float = 0.1
    _center: Triple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(
            self, "center", real_array("center", self.center, (3,), error=ParameterError)
        )
        real("radius", self.radius, minimum=0.0, strict=True, error=ParameterError)
        object.__setattr__(self, "_center", _triple(self.center))

    def _force(self, position: Triple, velocity: Triple) -> Triple:
        """Push radially outwards while inside."""
        offset = _difference(position, self._center)
        distance = math.sqrt(_dot(offset, offset))
        if distance >= self.radius:
            return 0.0, 0.0, 0.0
        outward = (offset[0] / distance, offset[1] / distance, offset[2] / distance) if (
            distance > 1e-9) else (0.0, 0.0, 1.0)  # fmt: skip
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
    position, velocity = _triple(model.tool_pose[:3, 3]), _triple(jacobian @ qd)
    total = [0.0, 0.0, 0.0]
    for constraint in constraints:
        for axis, value in enumerate(constraint._force(position, velocity)):
            total[axis] += value
    force = np.array(total)
    return jacobian.T @ force, force


def _triple(vector: ArrayLike) -> Triple:
    array = vector if isinstance(vector, np.ndarray) else np.asarray(vector, dtype=float)
    x, y, z = array.tolist()
    return float(x), float(y), float(z)


def _dot(a: Triple, b: Triple) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _difference(a: Triple, b: Triple) -> Triple:
    return a[0] - b[0], a[1] - b[1], a[2] - b[2]
