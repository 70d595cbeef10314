"""The robots shipped with the package, by name.

Each is a description file in ``data/`` (a TOML description, or a URDF with its drive
data TOML), shipped with its licence: the YuMi of the thesis, the Franka Emika Panda
(franka_description, Apache-2.0), the UR5 (ur_description, BSD) and the UR10e
(ur_e_description, BSD); the URDFs as packaged by example-robot-data (BSD-2).
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from leadthrough.errors import RobotDescriptionError
from leadthrough.model.description import RobotDescription
from leadthrough.model.robots.toml_format import load_robot
from leadthrough.model.robots.urdf import from_urdf

__all__ = ["REGISTERED", "Registered", "load", "names", "panda", "ur5", "ur10e", "yumi"]


@dataclass(frozen=True)
class Registered:
    """A shipped robot: its description file, flange link and drive data file.

    Attributes:
        name: Registry name (``lt.robots.load(name)``).
        description: File in ``data/`` (``.toml`` description or ``.urdf``).
        tip: Flange link of a URDF (None: the last joint frame).
        drive_data: Drive data TOML in ``data/`` for a URDF, or None.
        summary: One line: what it is and where its numbers come from.
    """

    name: str
    description: str
    tip: str | None = None
    drive_data: str | None = None
    summary: str = ""

    def load(self) -> RobotDescription:
        """The robot description (a fresh object)."""
        data = resources.files(__package__) / "data"
        with resources.as_file(data / self.description) as path:
            if self.drive_data is None:
                return load_robot(path)
            with resources.as_file(data / self.drive_data) as drive:
                return from_urdf(path, tip=self.tip, drive_data=drive)


#: The shipped robots by name, in the order ``leadthrough info`` lists them.
REGISTERED: dict[str, Registered] = {
    entry.name: entry
    for entry in (
        Registered("yumi", "yumi_left.toml",
                   summary="ABB YuMi left arm, 7 joints: thesis Appendix A/B, Table 4.1"),
        Registered("panda", "panda.urdf", "panda_hand", "panda_drive.toml",
                   summary="Franka Emika Panda, 7 joints: franka_description URDF, "
                           "friction of Gaz et al. 2019"),
        Registered("ur5", "ur5.urdf", "tool0", "ur5_drive.toml",
                   summary="Universal Robots UR5 (CB3), 6 joints: ur_description URDF, "
                           "drive data assumed"),
        Registered("ur10e", "ur10e.urdf", None, "ur10e_drive.toml",
                   summary="Universal Robots UR10e, 6 joints: ur_e_description URDF, "
                           "drive data of Mamedov & Mikhel 2020"),
    )
}  # fmt: skip


def names() -> list[str]:
    """Names of the shipped robots (``lt.robots.load(name)``)."""
    return list(REGISTERED)


def yumi() -> RobotDescription:
    """The ABB YuMi left arm of the thesis (Appendix A inertials, Table 4.1 friction).

    Example:
        >>> yumi().n_joints
        7
    """
    return REGISTERED["yumi"].load()


def panda() -> RobotDescription:
    """The Franka Emika Panda: franka_description URDF (Apache-2.0) plus its drive data.

    Drive data (``data/panda_drive.toml``, each number with its source): the linear
    friction of Gaz et al. (RA-L 2019, Table III) as Coulomb level and viscous
    coefficient, reflected rotor inertias of MuJoCo Menagerie's Panda, Franka's ready
    pose; the gear ratio and the sigmoid shape are assumed (warned). For identified
    inertials load another URDF with ``from_urdf(path, drive_data=...)``.
    """
    return REGISTERED["panda"].load()


def ur5() -> RobotDescription:
    """The Universal Robots UR5 (CB3): ur_description URDF (BSD), UR's home pose.

    Its gear ratios, rotor inertias and friction have no public numbers here: they are
    assumed from its torque limits, with a warning that names them.
    """
    return REGISTERED["ur5"].load()


def ur10e() -> RobotDescription:
    """The Universal Robots UR10e: ur_e_description URDF (BSD) plus its drive data.

    Drive data (``data/ur10e_drive.toml``, each number with its source): torque constants
    K [Nm/A] so that a log of motor currents gives ``τ = K·i``, gear ratios, reflected
    rotor inertias and linear friction as published by Mamedov & Mikhel (2020), and a home
    pose.
    """
    return REGISTERED["ur10e"].load()


def load(
    name_or_path: str | Path, tip: str | None = None, drive_data: str | Path | None = None
) -> RobotDescription:
    """A shipped robot by name (:func:`names`), a ``.toml`` or a ``.urdf`` file.

    Args:
        name_or_path: Registry name or description file.
        tip: Flange link of a URDF (needed when its tree branches).
        drive_data: Drive data TOML for a URDF (see :func:`from_urdf`).

    Raises:
        RobotDescriptionError: Unknown name, unreadable or invalid file; the message
            names the shipped robots or the file and field.
    """
    name = str(name_or_path)
    if name in REGISTERED:
        if tip is not None or drive_data is not None:
            raise RobotDescriptionError(name, "tip", "a shipped robot takes no tip or drive data")
        return REGISTERED[name].load()
    path = Path(name_or_path)
    if path.suffix.lower() == ".urdf":
        return from_urdf(path, tip=tip, drive_data=drive_data)
    if path.suffix.lower() != ".toml" and not path.exists():
        shipped = ", ".join(REGISTERED)
        raise RobotDescriptionError(name, "", f"no shipped robot or file of that name ({shipped})")
    if tip is not None or drive_data is not None:
        raise RobotDescriptionError(name, "tip", "a TOML description takes no tip or drive data "
                                                 "(it carries both)")  # fmt: skip
    return load_robot(path)
