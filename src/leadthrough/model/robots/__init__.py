"""Robot descriptions: the shipped YuMi, TOML files and URDFs.

Example:
    >>> import leadthrough as lt
    >>> robot = lt.robots.yumi()
    >>> robot.n_joints
    7
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from leadthrough.model.description import RobotDescription
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
    "yumi",
]

#: Names of the descriptions shipped with the package.
SHIPPED = {"yumi": "yumi_left.toml"}


def yumi() -> RobotDescription:
    """The ABB YuMi left arm of the thesis (Appendix A inertials, Table 4.1 friction)."""
    with resources.as_file(resources.files(__package__) / "data" / SHIPPED["yumi"]) as path:
        return load_robot(path)


def from_toml(path: str | Path) -> RobotDescription:
    """Load a robot description from a TOML file (same as :func:`load_robot`)."""
    return load_robot(path)


def load(name_or_path: str | Path, tip: str | None = None) -> RobotDescription:
    """Load a shipped robot by name (``"yumi"``), a ``.toml`` or a ``.urdf`` file."""
    if str(name_or_path) in SHIPPED:
        return yumi()
    if Path(name_or_path).suffix.lower() == ".urdf":
        return from_urdf(name_or_path, tip=tip)
    return load_robot(name_or_path)
