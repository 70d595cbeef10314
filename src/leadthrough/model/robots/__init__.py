"""Robot descriptions: the shipped arms, TOML files and URDFs.

Example:
    >>> import leadthrough as lt
    >>> lt.robots.names()
    ['yumi', 'panda', 'ur5', 'ur10e']
    >>> lt.robots.yumi().n_joints
    7
"""

from __future__ import annotations

from pathlib import Path

from leadthrough.model.description import RobotDescription
from leadthrough.model.robots.drive import (
    AssumedDriveDataWarning,
    complete_drive_data,
    with_drive_data,
)
from leadthrough.model.robots.registry import REGISTERED, load, names, panda, ur5, ur10e, yumi
from leadthrough.model.robots.toml_format import (
    load_robot,
    robot_from_dict,
    robot_to_dict,
    save_robot,
)
from leadthrough.model.robots.urdf import GripperJointWarning, from_urdf

__all__ = [
    "REGISTERED",
    "AssumedDriveDataWarning",
    "GripperJointWarning",
    "complete_drive_data",
    "from_toml",
    "from_urdf",
    "load",
    "load_robot",
    "names",
    "panda",
    "robot_from_dict",
    "robot_to_dict",
    "save_robot",
    "ur5",
    "ur10e",
    "with_drive_data",
    "yumi",
]


def from_toml(path: str | Path) -> RobotDescription:
    """Load a robot description from a TOML file (same as :func:`load_robot`)."""
    return load_robot(path)
