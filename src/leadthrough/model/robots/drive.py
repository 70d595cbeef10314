"""Drive data a URDF does not carry: from a per-robot TOML file, else stated assumptions.

A URDF describes links and limits; gear ratios, rotor inertias, friction sigmoids, torque
constants and a home pose are not in it. :func:`complete_drive_data` fills them from a
drive data file (per-joint lists, each number with its source in the file's comments)
and assumes what is still missing, scaled by each joint's torque limit from the arms
whose numbers are public, with **one** :class:`AssumedDriveDataWarning` naming every
assumed quantity:

==================  =====================================  ==================================
quantity            assumed                                public numbers it is taken from
==================  =====================================  ==================================
gear ratio          100                                    YuMi ±100/101, UR10e 101
reflected rotor     2e-3 s² · τ_max [kg m²]                YuMi 2.6e-4…2.7e-3, UR10e up to
inertia G_r² J_m                                           1.1e-2, Panda 1.1e-3…8.3e-3 per Nm
Coulomb level τ_C   0.03 · τ_max [Nm]                      YuMi 1.3…5 %, UR10e 3.3…4 %
viscous c           0.02 s/rad · τ_max [Nm s/rad]          YuMi 0.003…0.037, UR10e 0.04…0.07
friction noise σ    0.05 · τ_C [Nm] (also when the data    thesis Table 4.1
                    give τ_C but not σ)
home pose           0 where 0 is ≥ 10 % of the range       —
                    inside the limits, else mid-range
==================  =====================================  ==================================

A home pose, given or assumed, at which the tool cannot move in every direction (the
smallest singular value of its translational Jacobian below :data:`SINGULAR_HOME` of the
largest, e.g. an arm pointing straight up) is named in the same warning: the operator
grabs the arm there first.
"""

from __future__ import annotations

import dataclasses
import tomllib
import warnings
from collections.abc import Mapping
from collections.abc import Set as AbstractSet
from pathlib import Path
from typing import Any

import numpy as np

from leadthrough.errors import RobotDescriptionError
from leadthrough.model.description import Joint, JointFriction, RobotDescription

__all__ = [
    "ASSUMED_GEAR_RATIO",
    "COULOMB_PER_TORQUE_LIMIT",
    "HOME_MARGIN",
    "INERTIA_PER_TORQUE_LIMIT",
    "VISCOUS_PER_TORQUE_LIMIT",
    "AssumedDriveDataWarning",
    "complete_drive_data",
    "read_drive_data",
    "with_drive_data",
]

#: Gear ratio assumed for a joint without drive data (harmonic drives of 100:1 and 101:1).
ASSUMED_GEAR_RATIO = 100.0
#: Reflected rotor inertia per Nm of torque limit [kg m²/Nm = s²] assumed without data.
INERTIA_PER_TORQUE_LIMIT = 2e-3
#: Coulomb level as a fraction of the torque limit assumed without data.
COULOMB_PER_TORQUE_LIMIT = 0.03
#: Viscous coefficient per Nm of torque limit [s/rad] assumed without data.
VISCOUS_PER_TORQUE_LIMIT = 0.02
#: Sigmoid slope A [s/rad], half-width B [rad/s] and noise (fraction of τ_C) assumed
#: without data: the thesis' Table 4.1 values.
ASSUMED_SLOPE, ASSUMED_HALF_WIDTH, ASSUMED_NOISE_FRACTION = 5e3, 2e-3, 0.05
#: The zero reading is home for a joint if it is this fraction of the range inside.
HOME_MARGIN = 0.1

#: A home where gravity takes more than this share of a joint's torque limit is named [–].
HEAVY_HOME = 0.8
#: A home where the tool Jacobian's smallest singular value over its largest is below this
#: is near a singularity, when it is not elsewhere in the limits [–]: there a hand's push
#: along the weak direction barely moves the arm.
SINGULAR_HOME = 0.05

_FRICTION_KEYS = ("coulomb", "viscous", "slope", "half_width", "noise_std")
_DRIVE_KEYS = ("gear_ratio", "rotor_inertia", "torque_constant")
_ALL_KEYS = (*_DRIVE_KEYS, *_FRICTION_KEYS, "lower", "upper", "home", "assumed")
#: What a drive data file or an argument can supply (``friction`` as a whole).
QUANTITIES = ("gear_ratio", "rotor_inertia", "friction", "home")


class AssumedDriveDataWarning(UserWarning):
    """A robot's drive data (gear ratios, rotor inertias, friction, home) were assumed."""


def read_drive_data(path: str | Path, n_joints: int) -> dict[str, Any]:
    """The per-joint lists (and ``home``, ``assumed``) of a drive data TOML file.

    Raises:
        RobotDescriptionError: The file is unreadable, has an unknown key or a list
            without one number per joint; the message names the file and the key.
    """
    source = str(path)
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise RobotDescriptionError(source, "", f"cannot read drive data: {error}") from None
    unknown = sorted(set(data) - set(_ALL_KEYS))
    if unknown:
        raise RobotDescriptionError(source, unknown[0], "unknown drive data key")
    assumed = data.get("assumed", [])
    if not isinstance(assumed, list) or not all(isinstance(item, str) for item in assumed):
        raise RobotDescriptionError(source, "assumed", "needs a list of strings")
    for key, values in data.items():
        if key == "assumed":
            continue
        if not isinstance(values, list) or len(values) != n_joints:
            raise RobotDescriptionError(source, key, f"needs a list of {n_joints} numbers")
        if not all(isinstance(value, int | float) for value in values):
            raise RobotDescriptionError(source, key, "needs numbers")
    return data


def with_drive_data(robot: RobotDescription, path: str | Path) -> RobotDescription:
    """``robot`` with the drive data of a TOML file; nothing assumed, nothing warned.

    Keys (all optional): ``gear_ratio``, ``rotor_inertia`` [kg m², motor side],
    ``torque_constant`` [Nm/A, arm side], friction ``coulomb`` [Nm], ``viscous``
    [Nm s/rad], ``slope`` [s/rad], ``half_width`` [rad/s], ``noise_std`` [Nm], position
    limits ``lower`` and ``upper`` [rad], and ``home`` [rad]. Each list has one value per
    joint, base first. ``assumed`` lists (as short strings) what the file itself assumes,
    named by :func:`complete_drive_data`.

    Raises:
        RobotDescriptionError: The file is unreadable, a list has the wrong length or a
            value is invalid.
    """
    return _applied(robot, read_drive_data(path, robot.n_joints), path)


def _applied(robot: RobotDescription, data: dict[str, Any], path: str | Path) -> RobotDescription:
    """``robot`` with the drive data ``data`` read from ``path``; errors name the file."""
    try:
        return _apply(robot, data)
    except RobotDescriptionError as error:
        raise RobotDescriptionError(str(path), "", str(error)) from None


def _limit_notes(robot: RobotDescription, assumed: Mapping[str, tuple[float, float]]) -> list[str]:
    """A note naming the joints whose position limits are still the ``assumed`` ones."""
    kept = [joint.name for joint in robot.joints
            if assumed.get(joint.name) == tuple(joint.position_limits)]  # fmt: skip
    if not kept:
        return []
    limits = ", ".join(f"[{assumed[name][0]:.3g}, {assumed[name][1]:.3g}]" for name in kept)
    return [f"position limits {limits} rad of the continuous joint(s) {', '.join(kept)}"]


def complete_drive_data(
    robot: RobotDescription,
    missing: set[str],
    drive_data: str | Path | None = None,
    assumed_limits: Mapping[str, tuple[float, float]] | None = None,
) -> RobotDescription:
    """``robot`` with ``drive_data`` applied and what is still ``missing`` assumed.

    Args:
        robot: A description whose ``missing`` quantities (of :data:`QUANTITIES`) hold
            placeholders (e.g. a URDF's gear ratio 1 and rotor inertia 0).
        missing: Quantities the description does not know.
        drive_data: Drive data TOML file (see :func:`with_drive_data`), or None.
        assumed_limits: Position limits [rad] the caller assumed, by joint name (e.g. of
            continuous joints): stated in the warning for the joints whose limits the
            drive data leave as they are.

    Warns:
        AssumedDriveDataWarning: Once, naming every quantity assumed (by this function
            or by the drive data file's ``assumed`` list) and the assumed values, a
            home near a singularity (:data:`SINGULAR_HOME`), and one where gravity takes
            most of a joint's torque limit (:data:`HEAVY_HOME`).
    """
    assumed_by_file: list[str] = []
    data: dict[str, Any] = {}
    if drive_data is not None:
        data = read_drive_data(drive_data, robot.n_joints)
        robot = _applied(robot, data, drive_data)
        assumed_by_file = list(data.get("assumed", []))
        missing = missing - _supplied(data)
        if "coulomb" in data and "noise_std" not in data:  # σ = 0: no noise band at all
            missing = missing | {"noise_std"}
    given = {key: data[key] for key in _FRICTION_KEYS if key in data}
    robot, notes = _assume(robot, missing, set(given))
    if "friction" in missing and given:  # the file's own friction values stand
        robot = _apply(robot, given)
    notes = [*_limit_notes(robot, assumed_limits or {}), *notes]
    if assumed_by_file:
        notes.append(f"{', '.join(assumed_by_file)} (stated in {Path(str(drive_data)).name})")
    parts = ["drive data assumed (no public numbers): " + "; ".join(notes)] if notes else []
    parts += _singular_home(robot) + _heavy_home(robot)
    if parts:
        warnings.warn(f"{robot.name}: " + "; ".join(parts), AssumedDriveDataWarning, stacklevel=3)
    return robot


def _supplied(data: dict[str, Any]) -> set[str]:
    """The :data:`QUANTITIES` a drive data file supplies."""
    supplied = {key for key in ("gear_ratio", "rotor_inertia", "home") if key in data}
    return supplied | ({"friction"} if "coulomb" in data else set())


def _apply(robot: RobotDescription, data: dict[str, Any]) -> RobotDescription:
    """``robot`` with the per-joint lists of ``data`` replacing its values."""
    joints = []
    for i, joint in enumerate(robot.joints):
        changed = {key: float(data[key][i]) for key in _FRICTION_KEYS if key in data}
        friction = dataclasses.replace(joint.friction, **changed)
        drive: dict[str, Any] = {key: float(data[key][i]) for key in _DRIVE_KEYS if key in data}
        lower, upper = joint.position_limits
        limits = (float(data["lower"][i]) if "lower" in data else lower,
                  float(data["upper"][i]) if "upper" in data else upper)  # fmt: skip
        joints.append(dataclasses.replace(joint, friction=friction, position_limits=limits,
                                          **drive))  # fmt: skip
    home = np.array(data["home"], dtype=float) if "home" in data else robot.home_position
    return dataclasses.replace(robot, joints=tuple(joints), home_position=home)


def _assume(
    robot: RobotDescription, missing: set[str], kept: AbstractSet[str] = frozenset()
) -> tuple[RobotDescription, list[str]]:
    """``robot`` with the ``missing`` quantities assumed, and a note per quantity.

    ``kept``: friction keys the drive data give (``viscous`` without ``coulomb``): not
    named as assumed; the caller applies them over the assumed friction.
    """
    notes = []
    limits = robot.torque_limits
    joints = list(robot.joints)
    if "gear_ratio" in missing:
        joints = [_with_gear(joint, ASSUMED_GEAR_RATIO) for joint in joints]
        notes.append(f"gear ratio {ASSUMED_GEAR_RATIO:g}")
    if "rotor_inertia" in missing:
        reflected = INERTIA_PER_TORQUE_LIMIT * limits
        joints = [
            dataclasses.replace(joint, rotor_inertia=float(r / joint.gear_ratio**2))
            for joint, r in zip(joints, reflected, strict=True)
        ]
        notes.append(f"reflected rotor inertia {_values(reflected)} kg m² "
                     f"({INERTIA_PER_TORQUE_LIMIT:g} s² × torque limit)")  # fmt: skip
    if "friction" in missing:
        joints = [dataclasses.replace(joint, friction=_assumed_friction(joint)) for joint in joints]
        note = (f"Coulomb friction {_values(COULOMB_PER_TORQUE_LIMIT * limits)} Nm "
                f"({COULOMB_PER_TORQUE_LIMIT:g} × torque limit)")  # fmt: skip
        if "viscous" not in kept:
            note += f", viscous {_values(VISCOUS_PER_TORQUE_LIMIT * limits)} Nm s/rad"
        notes.append(note)
    if "noise_std" in missing:
        noise = ASSUMED_NOISE_FRACTION * np.array([joint.friction.coulomb for joint in joints])
        joints = [dataclasses.replace(joint, friction=dataclasses.replace(joint.friction,
                                                                          noise_std=float(s)))
                  for joint, s in zip(joints, noise, strict=True)]  # fmt: skip
        notes.append(f"friction noise σ {_values(noise)} Nm ({ASSUMED_NOISE_FRACTION:g} × τ_C)")
    home = robot.home_position
    if "home" in missing:
        home = _assumed_home(robot.q_min, robot.q_max)
        notes.append(f"home {_values(home)} rad")
    return dataclasses.replace(robot, joints=tuple(joints), home_position=home), notes


def _heavy_home(robot: RobotDescription) -> list[str]:
    """A note if gravity at home takes more than :data:`HEAVY_HOME` of a joint's torque limit.

    There the drives have little left for the operator's assist, the tracking and the safe
    stop: Talos' arm from example-robot-data holds 89 % of its first joint's limit at its
    assumed home, and sank 0.26–1.12 rad with nobody touching it on 4 of 16 plants (a
    review), with no word at load.
    """
    from leadthrough.model.dynamics import Dynamics  # the model's gravity (Pinocchio)

    share = np.abs(Dynamics(robot).gravity(robot.home())) / robot.torque_limits
    joint = int(np.argmax(share))
    if share[joint] <= HEAVY_HOME:
        return []
    return [f"at home joint {joint + 1} holds {share[joint]:.0%} of its torque limit against "
            "gravity: little is left to guide and stop the arm (a home where the arm hangs "
            "lower, or the drives' real limits, in the drive data)"]  # fmt: skip


def _singular_home(robot: RobotDescription) -> list[str]:
    """A note if the tool moves in fewer directions at home than the arm allows (else none).

    The smallest over the largest singular value of the tool's translational Jacobian,
    at home against its median over poses drawn within the limits: an arm that cannot
    move its tool in three directions anywhere (three joints, a tool on the last axis) is
    not near a singularity at home.
    """
    from leadthrough.model.dynamics import Dynamics  # the model's kinematics (Pinocchio)

    dynamics = Dynamics(robot)

    def spread(q: np.ndarray) -> tuple[float, np.ndarray]:
        values = np.linalg.svd(dynamics.jacobian(q)[:3], compute_uv=False)
        return float(values[-1] / max(values[0], 1e-12)), values

    poses = np.random.default_rng(0).uniform(robot.q_min, robot.q_max, (16, robot.n_joints))
    typical = float(np.median([spread(q)[0] for q in poses]))
    at_home, values = spread(robot.home())
    if not at_home < SINGULAR_HOME <= typical:
        return []
    return [f"the home {_values(robot.home())} rad is near a singularity (the tool's "
            f"Jacobian's singular values {_values(values)} m/rad): give one in the drive "
            "data (home), where the operator grabs the arm first"]  # fmt: skip


def _with_gear(joint: Joint, gear: float) -> Joint:
    """``joint`` with gear ratio ``gear``, its reflected rotor inertia unchanged."""
    rotor = joint.reflected_rotor_inertia / gear**2
    return dataclasses.replace(joint, gear_ratio=gear, rotor_inertia=rotor)


def _assumed_friction(joint: Joint) -> JointFriction:
    coulomb = COULOMB_PER_TORQUE_LIMIT * joint.torque_limit
    return JointFriction(
        coulomb=coulomb,
        slope=ASSUMED_SLOPE,
        half_width=ASSUMED_HALF_WIDTH,
        viscous=VISCOUS_PER_TORQUE_LIMIT * joint.torque_limit,
        noise_std=ASSUMED_NOISE_FRACTION * coulomb,
    )


def _assumed_home(q_min: np.ndarray, q_max: np.ndarray) -> np.ndarray:
    """Zero where zero is well inside the limits (:data:`HOME_MARGIN`), else mid-range."""
    margin = HOME_MARGIN * (q_max - q_min)
    inside = (q_min + margin <= 0.0) & (q_max - margin >= 0.0)
    return np.where(inside, 0.0, 0.5 * (q_min + q_max))


def _values(values: np.ndarray) -> str:
    return "[" + ", ".join(f"{value:.3g}" for value in values) + "]"
