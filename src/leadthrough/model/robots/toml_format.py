"""Read and write robot descriptions as TOML.

Layout (every length in m, angle in rad, torque in Nm, arm side)::

    name = "My arm"
    gravity = [0.0, 0.0, -9.81]          # optional, world frame [m/s²]
    home = [0.0, ...]                    # optional home pose, joint readings [rad]
    [base]                               # optional: xyz and rpy, or a 3×3 rotation
    xyz = [0.0, 0.0, 0.0]
    rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    [flange]                             # optional, in the last link frame
    xyz = [0.0, 0.0, 0.0]
    [tcp]                                # optional tool centre point, in the flange frame
    xyz = [0.0, 0.0, 0.15]

    [[joints]]
    name = "joint_1"
    position_limits = [-2.94, 2.94]      # joint reading [rad]
    velocity_limit = 3.14                # [rad/s]
    torque_limit = 30.0                  # arm side [Nm]
    gear_ratio = 100.0                   # optional, default 1
    rotor_inertia = 8.2e-6               # optional, motor side [kg m²], default 0
    torque_constant = 10.0               # optional, arm side [Nm/A]: τ = K·i for current drives
    dh = { d = 0.11, a = 0.03, alpha = 1.5707963267948966, offset = -3.141592653589793 }
    # or: origin = { xyz = [...], rpy = [...], axis = [0, 0, 1] }
    friction = { coulomb = 1.5, slope = 5e3, half_width = 2e-3, viscous = 1.1, noise_std = 0.07 }
    link = { mass = 1.58, com = [...], inertia = [[...], [...], [...]] }

Errors name the file and the field: ``yumi.toml: joints[3].link.mass: must be > 0``.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping, Set
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w

from leadthrough.errors import RobotDescriptionError
from leadthrough.model.description import (
    DHParameters,
    Joint,
    JointFriction,
    JointOrigin,
    LinkInertial,
    Placement,
    RobotDescription,
    rpy_to_rotation,
)
from leadthrough.validation import fail, real_array, within

_JOINT_KEYS = {
    "required": {"name", "position_limits", "velocity_limit", "torque_limit", "friction", "link"},
    "optional": {"gear_ratio", "rotor_inertia", "torque_constant", "dh", "origin"},
}
_FRICTION_KEYS = {"coulomb", "slope", "half_width", "viscous", "noise_std"}


def load_robot(path: str | Path) -> RobotDescription:
    """Load and validate a robot description from a TOML file.

    Raises:
        RobotDescriptionError: The file is missing, not TOML, or a field is wrong; the
            message names the file and the field.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as error:
        raise RobotDescriptionError(str(path), "", f"cannot read: {error.strerror}") from None
    except UnicodeDecodeError:
        raise RobotDescriptionError(str(path), "", "not a text file (UTF-8 expected)") from None
    except tomllib.TOMLDecodeError as error:
        raise RobotDescriptionError(str(path), "", f"not valid TOML: {error}") from None
    with within("", source=str(path)):
        return robot_from_dict(data)


def robot_from_dict(data: Mapping[str, Any]) -> RobotDescription:
    """Build a RobotDescription from the parsed TOML layout of this module."""
    optional = {"gravity", "base", "flange", "tcp", "home"}
    table = _keys(data, "", required={"name", "joints"}, optional=optional)
    joints_data = table["joints"]
    if not isinstance(joints_data, list) or not joints_data:
        raise fail("joints", "expected a non-empty array of [[joints]] tables")
    joints = []
    for index, joint_data in enumerate(joints_data):
        with within(f"joints[{index}]"):
            joints.append(_joint(joint_data))
    kwargs: dict[str, Any] = {}
    for name in ("base", "flange", "tcp"):
        if name in table:
            with within(name):
                kwargs[name] = _placement(table[name], optional={"xyz"})
    if "gravity" in table:
        kwargs["gravity"] = table["gravity"]
    if "home" in table:
        kwargs["home_position"] = table["home"]
    return RobotDescription(name=table["name"], joints=tuple(joints), **kwargs)


def save_robot(robot: RobotDescription, path: str | Path) -> None:
    """Write ``robot`` as TOML that :func:`load_robot` reads back to an equal description."""
    Path(path).write_text(tomli_w.dumps(robot_to_dict(robot)), encoding="utf-8")


def robot_to_dict(robot: RobotDescription) -> dict[str, Any]:
    """The TOML layout of ``robot`` as plain Python data."""
    table: dict[str, Any] = {"name": robot.name, "gravity": robot.gravity.tolist()}
    if robot.home_position is not None:
        table["home"] = robot.home_position.tolist()
    table["base"] = _placement_dict(robot.base)
    table["flange"] = _placement_dict(robot.flange)
    table["tcp"] = _placement_dict(robot.tcp)
    table["joints"] = [_joint_dict(joint) for joint in robot.joints]
    return table


def _keys(
    data: object, field: str, required: Set[str], optional: Set[str] = frozenset()
) -> Mapping[str, Any]:
    """Check that ``data`` is a table with all ``required`` and no unknown keys."""
    if not isinstance(data, Mapping):
        raise fail(field, f"expected a table, got {data!r}")
    missing = sorted(required - data.keys())
    if missing:
        raise fail(field, f"missing key {missing[0]!r}")
    unknown = sorted(data.keys() - required - optional)
    if unknown:
        raise fail(field, f"unknown key {unknown[0]!r}")
    return data


def _joint(data: object) -> Joint:
    table = _keys(data, "", _JOINT_KEYS["required"], _JOINT_KEYS["optional"])
    with within("link"):
        link = LinkInertial(**_keys(table["link"], "", {"mass", "com", "inertia"}))
    with within("friction"):
        friction = JointFriction(**_keys(table["friction"], "", _FRICTION_KEYS))
    placing: dict[str, Any] = {}
    if "dh" in table:
        with within("dh"):
            placing["dh"] = DHParameters(**_keys(table["dh"], "", {"d", "a", "alpha"}, {"offset"}))
    if "origin" in table:
        with within("origin"):
            placement = _placement(table["origin"], required={"axis"}, optional={"xyz"})
            placing["origin"] = JointOrigin(placement=placement, axis=table["origin"]["axis"])
    drive = ("gear_ratio", "rotor_inertia", "torque_constant")
    optional = {key: table[key] for key in drive if key in table}
    return Joint(
        name=table["name"],
        link=link,
        position_limits=table["position_limits"],
        velocity_limit=table["velocity_limit"],
        torque_limit=table["torque_limit"],
        friction=friction,
        **optional,
        **placing,
    )


def _placement(
    data: object, required: Set[str] = frozenset(), optional: Set[str] = frozenset()
) -> Placement:
    """A Placement from ``xyz`` and one of ``rpy`` or a 3×3 ``rotation``."""
    table = _keys(data, "", required, optional | {"xyz", "rpy", "rotation"})
    if "rpy" in table and "rotation" in table:
        raise fail("rotation", "give either 'rpy' or 'rotation', not both")
    rotation = np.eye(3)
    if "rpy" in table:
        with within("rpy"):
            rotation = rpy_to_rotation(real_array("", table["rpy"], (3,)))
    elif "rotation" in table:
        rotation = table["rotation"]
    return Placement(translation=table.get("xyz", np.zeros(3)), rotation=rotation)


def _placement_dict(placement: Placement) -> dict[str, Any]:
    return {"xyz": placement.translation.tolist(), "rotation": placement.rotation.tolist()}


def _joint_dict(joint: Joint) -> dict[str, Any]:
    table: dict[str, Any] = {
        "name": joint.name,
        "position_limits": list(joint.position_limits),
        "velocity_limit": joint.velocity_limit,
        "torque_limit": joint.torque_limit,
        "gear_ratio": joint.gear_ratio,
        "rotor_inertia": joint.rotor_inertia,
    }
    if joint.torque_constant is not None:
        table["torque_constant"] = joint.torque_constant
    if joint.dh is not None:
        dh = joint.dh
        table["dh"] = {"d": dh.d, "a": dh.a, "alpha": dh.alpha, "offset": dh.offset}
    if joint.origin is not None:
        table["origin"] = _placement_dict(joint.origin.placement) | {
            "axis": joint.origin.axis.tolist()
        }
    table["friction"] = {key: getattr(joint.friction, key) for key in sorted(_FRICTION_KEYS)}
    link = joint.link
    table["link"] = {"mass": link.mass, "com": link.com.tolist(), "inertia": link.inertia.tolist()}
    return table
