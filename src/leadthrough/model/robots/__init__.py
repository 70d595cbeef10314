"""Robot descriptions: the shipped YuMi, TOML files and URDFs.

Example:
    >>> import leadthrough as lt
    >>> robot = lt.robots.yumi()
    >>> robot.n_joints
    7
"""

from __future__ import annotations

import dataclasses
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from leadthrough.errors import RobotDescriptionError
from leadthrough.model.description import JointFriction, RobotDescription
from leadthrough.model.robots.toml_format import (
    load_robot,
    robot_from_dict,
    robot_to_dict,
    save_robot,
)
from leadthrough.model.robots.urdf import from_urdf

__all__ = [
    "from_toml",
    "from_urdf",
    "load",
    "load_robot",
    "robot_from_dict",
    "robot_to_dict",
    "save_robot",
    "ur10e",
    "with_drive_data",
    "yumi",
]

#: Names of the descriptions shipped with the package.
SHIPPED = {"yumi": "yumi_left.toml", "ur10e": "ur10e.urdf"}
#: Per-joint drive data file fields (each a list, one value per joint).
_DRIVE_FIELDS = ("gear_ratio", "rotor_inertia", "torque_constant", "coulomb", "viscous",
                 "slope", "half_width", "noise_std")  # fmt: skip


def yumi() -> RobotDescription:
    """The ABB YuMi left arm of the thesis (Appendix A inertials, Table 4.1 friction)."""
    with resources.as_file(resources.files(__package__) / "data" / SHIPPED["yumi"]) as path:
        return load_robot(path)


def ur10e() -> RobotDescription:
    """The Universal Robots UR10e: ur_e_description URDF (BSD) plus its drive data.

    Drive data (``data/ur10e_drive.toml``, each number with its source): torque constants
    K [Nm/A] so that a log of motor currents gives ``τ = K·i``, gear ratios, reflected
    rotor inertias and linear friction as published by Mamedov & Mikhel (2020), and a home
    pose.
    """
    data = resources.files(__package__) / "data"
    with resources.as_file(data / SHIPPED["ur10e"]) as urdf:
        robot = from_urdf(urdf)
    with resources.as_file(data / "ur10e_drive.toml") as drive:
        return with_drive_data(robot, drive)


def with_drive_data(robot: RobotDescription, path: str | Path) -> RobotDescription:
    """``robot`` with the drive data of a TOML file (per-joint lists, and ``home``).

    Keys (all optional): ``gear_ratio``, ``rotor_inertia`` [kg m², motor side],
    ``torque_constant`` [Nm/A, arm side], friction ``coulomb`` [Nm], ``viscous``
    [Nm s/rad], ``slope`` [s/rad], ``half_width`` [rad/s], ``noise_std`` [Nm], and
    ``home`` [rad]. Each list has one value per joint, base first.

    Raises:
        RobotDescriptionError: The file is unreadable or a list has the wrong length.
    """
    source = str(path)
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise RobotDescriptionError(source, "", f"cannot read drive data: {error}") from None
    unknown = sorted(set(data) - {*_DRIVE_FIELDS, "home"})
    if unknown:
        raise RobotDescriptionError(source, unknown[0], "unknown drive data key")
    n = robot.n_joints
    for key, values in data.items():
        if not isinstance(values, list) or len(values) != n:
            raise RobotDescriptionError(source, key, f"needs a list of {n} numbers")
    friction_keys = ("coulomb", "viscous", "slope", "half_width", "noise_std")
    drive_keys = ("gear_ratio", "rotor_inertia", "torque_constant")
    joints = []
    for i, joint in enumerate(robot.joints):
        changed = {key: float(data[key][i]) for key in friction_keys if key in data}
        friction = JointFriction(**{**joint.friction.__dict__, **changed})
        drive: dict[str, Any] = {key: float(data[key][i]) for key in drive_keys if key in data}
        joints.append(dataclasses.replace(joint, friction=friction, **drive))
    home = np.array(data["home"], dtype=float) if "home" in data else robot.home_position
    return dataclasses.replace(robot, joints=tuple(joints), home_position=home)


def from_toml(path: str | Path) -> RobotDescription:
    """Load a robot description from a TOML file (same as :func:`load_robot`)."""
    return load_robot(path)


def load(name_or_path: str | Path, tip: str | None = None) -> RobotDescription:
    """Load a shipped robot by name (``"yumi"``, ``"ur10e"``), a ``.toml`` or a ``.urdf`` file."""
    if str(name_or_path) in SHIPPED:
        return {"yumi": yumi, "ur10e": ur10e}[str(name_or_path)]()
    if Path(name_or_path).suffix.lower() == ".urdf":
        return from_urdf(name_or_path, tip=tip)
    return load_robot(name_or_path)
