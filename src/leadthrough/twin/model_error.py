"""Model-error knobs: make the twin's true robot differ from the controller's description.

Reality never matches the data sheet. The twin is built from a *perturbed* copy of
the description (link masses and centres of mass, a payload at the flange, friction
scaled), all drawn from a seeded generator, while controllers keep the nominal one.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from leadthrough.model.description import RobotDescription
from leadthrough.twin.mjcf import Payload
from leadthrough.validation import fail, real


@dataclass(frozen=True)
class ModelError:
    """How far the true robot is from its description.

    Attributes:
        mass_error: Each link mass (and its inertia) is scaled by 1 + U(−e, e) [–].
        com_error: Each centre of mass moves by U(−e, e) per axis [m].
        payload: Optional payload rigidly attached at the flange.
        friction_scale: True Coulomb, static and viscous friction are this multiple of the
            description's [–].
        mass_scale: Every link mass (and inertia) is also this multiple of the description's,
            a systematic error on top of the random one [–].
    """

    mass_error: float = 0.0
    com_error: float = 0.0
    payload: Payload | None = None
    friction_scale: float = 1.0
    mass_scale: float = 1.0

    def __post_init__(self) -> None:
        real("mass_error", self.mass_error, minimum=0.0)
        if self.mass_error >= 1.0:
            raise fail("mass_error", f"must be below 1 (a fraction), got {self.mass_error:g}")
        real("com_error", self.com_error, minimum=0.0)
        real("friction_scale", self.friction_scale, minimum=0.0, strict=True)
        real("mass_scale", self.mass_scale, minimum=0.0, strict=True)
        if self.payload is not None:
            real("payload.mass", self.payload.mass, minimum=0.0, strict=True)


def perturbed_robot(
    robot: RobotDescription, error: ModelError, rng: np.random.Generator
) -> RobotDescription:
    """A copy of ``robot`` with link masses, inertias and COMs drawn around the nominal ones."""
    if error.mass_error == 0.0 and error.com_error == 0.0 and error.mass_scale == 1.0:
        return robot
    n = robot.n_joints
    scales = error.mass_scale * (1.0 + rng.uniform(-error.mass_error, error.mass_error, n))
    shifts = rng.uniform(-error.com_error, error.com_error, (n, 3))
    joints = []
    for joint, scale, shift in zip(robot.joints, scales, shifts, strict=True):
        link = dataclasses.replace(
            joint.link,
            mass=joint.link.mass * scale,
            com=joint.link.com + shift,
            inertia=joint.link.inertia * scale,
        )
        joints.append(dataclasses.replace(joint, link=link))
    return dataclasses.replace(robot, joints=tuple(joints))
