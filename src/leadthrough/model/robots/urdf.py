"""Load a serial arm from a URDF file into a RobotDescription.

The URDF is parsed by Pinocchio (fixed joints merged into their parents). The chain
from the root to ``tip`` becomes the arm; any other moving joint (fingers, a second
arm) is locked at its neutral position, its links merged into the link that carries
it. URDF carries no gear ratios, rotor inertias, friction sigmoids or home pose: they
come from the arguments, a drive data file, the URDF ``<dynamics friction damping>``
(as Coulomb level and viscous coefficient, when any is non-zero), and what is still
missing is assumed with one warning naming it (:mod:`leadthrough.model.robots.drive`).
A continuous joint (a UR's or a Kinova's) becomes a revolute one of
:data:`CONTINUOUS_LIMIT` either way (one turn, as UR's controllers limit theirs), stated in
that warning; drive data ``lower`` and ``upper`` set other limits. Without ``tip``, a chain
that ends in a joint named as a gripper's (an SO-101's or a Z1's jaw) is warned about
(:class:`GripperJointWarning`), naming the link to give as the tip instead.
"""

from __future__ import annotations

import difflib
import math
import re
import warnings
from collections.abc import Sequence
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pinocchio as pin

from leadthrough.errors import RobotDescriptionError
from leadthrough.model.description import (
    Joint,
    JointFriction,
    JointOrigin,
    LinkInertial,
    Placement,
    RobotDescription,
)
from leadthrough.model.robots.drive import complete_drive_data
from leadthrough.model.robots.urdf_check import check_urdf
from leadthrough.validation import within

_REVOLUTE = {
    "JointModelRX": np.array([1.0, 0.0, 0.0]),
    "JointModelRY": np.array([0.0, 1.0, 0.0]),
    "JointModelRZ": np.array([0.0, 0.0, 1.0]),
}

#: Position limit given to a continuous (unbounded) joint either way from zero [rad].
CONTINUOUS_LIMIT = 2.0 * math.pi
#: Pinocchio's joint models that are not revolute, by what a URDF calls them.
_OTHER_KINDS = {"JointModelPX": "prismatic", "JointModelPY": "prismatic",
                "JointModelPZ": "prismatic", "JointModelPrismaticUnaligned": "prismatic",
                "JointModelFreeFlyer": "floating", "JointModelPlanar": "planar"}  # fmt: skip

#: A joint name that says the joint moves a gripper's fingers or jaw, not the arm.
_GRIPPER_NAME = re.compile(r"grip|finger|jaw|claw", re.IGNORECASE)


class GripperJointWarning(UserWarning):
    """A URDF loaded without ``tip`` ends in a joint whose name says it is a gripper's."""


#: Sigmoid shape given to URDF friction, which has no such parameters (Table 4.1 values).
DEFAULT_SLOPE = 5e3
DEFAULT_HALF_WIDTH = 2e-3


def from_urdf(
    path: str | Path,
    tip: str | None = None,
    *,
    gear_ratios: Sequence[float] | None = None,
    rotor_inertias: Sequence[float] | None = None,
    friction: Sequence[JointFriction] | None = None,
    drive_data: str | Path | None = None,
) -> RobotDescription:
    """Load the serial arm from the URDF root to the link ``tip``.

    Args:
        path: URDF file.
        tip: Name of the link (or frame) that is the flange. Without it the moving
            joints must form one chain, whose last joint frame is the flange.
        gear_ratios: Gear ratio per chain joint.
        rotor_inertias: Motor-side rotor inertia per chain joint [kg m²].
        friction: Friction per chain joint (default from the URDF ``<dynamics>``).
        drive_data: Drive data TOML file (per-joint gear ratios, rotor inertias,
            torque constants, friction, home; see :func:`with_drive_data`). Values in it
            replace those of the URDF and of the arguments.

    Warns:
        AssumedDriveDataWarning: Once, naming what neither the arguments, the URDF nor
            the drive data give (gear ratios, rotor inertias, friction, home pose) and
            what is assumed instead.
        GripperJointWarning: Without ``tip``, the arm is taken up to the link that two or
            more joints named as a gripper's hang from (the Panda's hand); or the chain's
            last joint is named as a
            gripper's (``grip``, ``finger``, ``jaw``, ``claw``): it would be guided as an
            arm joint.

    Raises:
        RobotDescriptionError: The file is unreadable, not a URDF, ``tip`` is unknown,
            the joints do not form a serial chain of revolute joints, or a value is
            invalid; the message names the file and the joint.
    """
    source = str(path)
    if not Path(path).is_file():
        raise RobotDescriptionError(source, "", "no such file")
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise RobotDescriptionError(source, "", f"cannot read it ({error})") from None
    try:
        root = _xml(text)
        check_urdf(root, source)
        text, continuous = _bounded_continuous_joints(text, root)
        tip = tip if tip is not None else _hand_of_the_gripper(root, source)
        text = _without_tools_beyond(text, tip)
        full = pin.buildModelFromXML(text)
    except RobotDescriptionError:
        raise  # a malformed joint or link, named
    except (ValueError, RuntimeError) as error:
        raise RobotDescriptionError(source, "", f"not a valid URDF ({error})") from None
    with within("", source=source):
        chain_ids, tip_frame = _chain(full, tip)
        _no_mimic_on_chain(root, [str(full.names[i]) for i in chain_ids])
        if tip is None:
            _warn_gripper_joint(text, str(full.names[chain_ids[-1]]), source)
        model = _lock_off_chain(full, chain_ids)
        joints = _joints(model, gear_ratios, rotor_inertias, friction)
        flange = _flange(model, tip_frame)
        robot = RobotDescription(name=full.name or Path(path).stem, joints=joints, flange=flange)
    missing = {"home"}
    missing |= {"gear_ratio"} if gear_ratios is None else set()
    missing |= {"rotor_inertia"} if rotor_inertias is None else set()
    urdf_friction = any(joint.friction.coulomb > 0.0 for joint in robot.joints)
    missing |= {"friction"} if friction is None and not urdf_friction else set()
    assumed = {name: (-CONTINUOUS_LIMIT, CONTINUOUS_LIMIT) for name in continuous}
    return complete_drive_data(robot, missing, drive_data, assumed)


def _xml(text: str) -> ElementTree.Element:
    """The root element of ``text``; a ValueError if ``text`` is not XML."""
    try:
        return ElementTree.fromstring(text)
    except ElementTree.ParseError as error:
        raise ValueError(str(error)) from None


def _bounded_continuous_joints(text: str, root: ElementTree.Element) -> tuple[str, set[str]]:
    """URDF ``text`` with each continuous joint made revolute within ±:data:`CONTINUOUS_LIMIT`.

    ``root`` is ``text`` parsed (changed in place where a joint is). Its ``<limit>``
    (which :func:`check_urdf` requires) keeps its effort and velocity (a URDF's
    continuous joint ignores ``lower`` and ``upper``). Returns the text and the names of
    the joints changed; unchanged text when there are none.
    """
    continuous = [joint for joint in root.findall("joint") if joint.get("type") == "continuous"]
    if not continuous:
        return text, set()
    for joint in continuous:
        joint.set("type", "revolute")
        limit = joint.find("limit")
        assert limit is not None, "check_urdf requires a continuous joint's <limit>"
        limit.set("lower", f"{-CONTINUOUS_LIMIT!r}")
        limit.set("upper", f"{CONTINUOUS_LIMIT!r}")
    names = {str(joint.get("name")) for joint in continuous}
    return ElementTree.tostring(root, encoding="unicode"), names


def _without_tools_beyond(text: str, tip: str | None) -> str:
    """URDF ``text`` without what is bolted beyond the link ``tip`` (unchanged without).

    The tip is the flange: a body fixed to it by a ``fixed`` joint (a hand, a tool), and
    everything that body carries, is a tool or a payload, not the arm. Pinocchio would
    fold its inertia into the last link: ``tip="panda_link8"`` then carried the Franka
    hand's 0.76 kg, and a Panda without it (the Gaz et al. run) read a payload of −0.76
    kg. Moving parts of the tip link itself (a gripper's fingers when the tip is its
    hand) stay, locked at their neutral position.
    """
    if tip is None:
        return text
    root = ElementTree.fromstring(text)
    joints = list(root.iter("joint"))
    children: dict[str, list[ElementTree.Element]] = {}
    for joint in joints:
        parent = joint.find("parent")
        if parent is not None:
            children.setdefault(str(parent.get("link")), []).append(joint)
    beyond = [j for j in children.get(tip, []) if j.get("type") == "fixed"]
    if not beyond:
        return text
    links = {str(link.get("name")): link for link in root.iter("link")}
    removed_joints: list[ElementTree.Element] = []
    while beyond:
        joint = beyond.pop()
        removed_joints.append(joint)
        child = joint.find("child")
        name = "" if child is None else str(child.get("link"))
        if name in links:
            root.remove(links.pop(name))
        beyond.extend(children.get(name, []))
    for joint in removed_joints:
        root.remove(joint)
    return ElementTree.tostring(root, encoding="unicode")


def _chain(model: pin.Model, tip: str | None) -> tuple[list[int], str | None]:
    """Joint ids from the root to ``tip`` (or of the only chain when ``tip`` is None)."""
    if tip is not None:
        if not model.existFrame(tip):
            known = list(dict.fromkeys(frame.name for frame in model.frames))
            close = difflib.get_close_matches(tip, known, n=3, cutoff=0.5)
            hint = f"; did you mean {', '.join(map(repr, close))}?" if close else ""
            raise RobotDescriptionError("", "tip", f"no link or frame named {tip!r}{hint}")
        joint_id = model.frames[_frame_id(model, tip)].parentJoint
    else:
        joint_id = _single_leaf(model)
    chain = []
    while joint_id != 0:
        chain.append(joint_id)
        joint_id = model.parents[joint_id]
    if not chain:
        raise RobotDescriptionError("", "tip", "no moving joint between the root and the tip")
    return chain[::-1], tip


def _no_mimic_on_chain(root: ElementTree.Element, chain: list[str]) -> None:
    """Raise if a joint of the arm's chain mimics another (a finger's off the chain may).

    Each arm joint is driven and guided on its own; a ``<mimic>`` joint on the chain was
    loaded as an independent joint, silently.
    """
    for joint in root.findall("joint"):
        mimic = joint.find("mimic")
        if mimic is not None and joint.get("name") in chain:
            raise RobotDescriptionError("", f"joint {joint.get('name')!r}", f"mimics "
                                        f"{mimic.get('joint')!r}: a joint of the arm between "
                                        "its root and tip must move on its own")  # fmt: skip


def _frame_id(model: pin.Model, name: str) -> int:
    """The frame called ``name``: the link's where a joint has the same name (a Z1's)."""
    if model.existFrame(name, pin.FrameType.BODY):
        return int(model.getFrameId(name, pin.FrameType.BODY))
    return next(i for i, frame in enumerate(model.frames) if frame.name == name)


def _warn_gripper_joint(text: str, joint: str, source: str) -> None:
    """Warn if the chain's last ``joint`` is named as a gripper's (fingers, jaw).

    Without ``tip`` the chain runs to the last moving joint, and on arms whose gripper
    is one jaw joint at the end of the chain (an SO-101, a Z1) that is the gripper's:
    the controller would guide it as an arm joint. The warning names the link the
    joint hangs from, the flange to give as ``tip``.
    """
    if not _GRIPPER_NAME.search(joint):
        return
    joints = ElementTree.fromstring(text).iter("joint")
    element = next((j.find("parent") for j in joints if j.get("name") == joint), None)
    parent = "" if element is None else f" (tip={element.get('link')!r})"
    warnings.warn(f"{source}: the chain ends in joint {joint!r}, which its name says is a "
                  f"gripper's; name the flange link{parent} to guide the arm without it",
                  GripperJointWarning, stacklevel=3)  # fmt: skip


def _hand_of_the_gripper(root: ElementTree.Element, source: str) -> str | None:
    """The link two or more gripper joints hang from, taken as the tip (warned), or None.

    Without ``tip``, fingers that branch off the arm's last link (the Panda of
    ``example-robot-data``: two finger joints on ``panda_hand``) made the arm no serial
    chain, an error. The joints' names say they are a gripper's (:data:`_GRIPPER_NAME`);
    when they all hang from one link, the arm is taken up to it, the fingers locked.
    """
    moving = ("revolute", "continuous", "prismatic")
    gripper = [joint for joint in root.findall("joint") if joint.get("type") in moving
               and _GRIPPER_NAME.search(str(joint.get("name")))]  # fmt: skip
    parents = {str(joint.find("parent").get("link")) for joint in gripper}  # type: ignore[union-attr]
    if len(gripper) < 2 or len(parents) != 1:
        return None
    hand = parents.pop()
    names = ", ".join(repr(joint.get("name")) for joint in gripper)
    warnings.warn(f"{source}: joints {names} are a gripper's, their names say: the arm is "
                  f"taken up to the link they hang from (tip={hand!r}), the gripper locked; "
                  "name another tip to choose", GripperJointWarning, stacklevel=3)  # fmt: skip
    return hand


def _single_leaf(model: pin.Model) -> int:
    """The last joint of the only chain, or an error naming where the tree branches."""
    children: dict[int, list[int]] = {}
    for joint_id in range(1, model.njoints):
        children.setdefault(model.parents[joint_id], []).append(joint_id)
    for parent, kids in children.items():
        if len(kids) > 1:
            names = ", ".join(repr(model.names[kid]) for kid in kids)
            where = "the root" if parent == 0 else f"joint {model.names[parent]!r}"
            raise RobotDescriptionError(
                "",
                "tip",
                f"not a serial chain: {where} carries joints {names}; name the flange link (tip=)",
            )
    return model.njoints - 1


def _lock_off_chain(model: pin.Model, chain: list[int]) -> pin.Model:
    locked = [joint_id for joint_id in range(1, model.njoints) if joint_id not in chain]
    if not locked:
        return model
    try:
        return pin.buildReducedModel(model, locked, pin.neutral(model))
    except ValueError as error:  # Pinocchio's, e.g. a joint and a link of one name
        shared = sorted({frame.name for frame in model.frames if
                         sum(other.name == frame.name for other in model.frames) > 1})  # fmt: skip
        why = (f"the name {shared[0]!r} is both a joint's and a link's (rename one)"
               if shared else str(error).splitlines()[0])  # fmt: skip
        raise RobotDescriptionError("", "tip", f"the joints off the chain cannot be locked: "
                                    f"{why}") from None  # fmt: skip


def _joints(
    model: pin.Model,
    gear_ratios: Sequence[float] | None,
    rotor_inertias: Sequence[float] | None,
    friction: Sequence[JointFriction] | None,
) -> tuple[Joint, ...]:
    n = model.njoints - 1
    gear = np.ones(n) if gear_ratios is None else np.asarray(gear_ratios, dtype=float)
    rotor = np.zeros(n) if rotor_inertias is None else np.asarray(rotor_inertias, dtype=float)
    for name, values in (("gear_ratios", gear), ("rotor_inertias", rotor)):
        if values.shape != (n,):
            raise RobotDescriptionError("", name, f"expected {n} values, got {values.shape}")
    if friction is not None and len(friction) != n:
        raise RobotDescriptionError("", "friction", f"expected {n} values, got {len(friction)}")
    joints = []
    for i in range(n):
        joint_id = i + 1
        with within(f"joints[{i}] ({model.names[joint_id]})"):
            joints.append(
                _joint(
                    model, joint_id, gear[i], rotor[i], None if friction is None else friction[i]
                )
            )
    return tuple(joints)


def _joint(
    model: pin.Model, joint_id: int, gear: float, rotor: float, friction: JointFriction | None
) -> Joint:
    joint_model = model.joints[joint_id]
    kind = joint_model.shortname()
    if kind in _REVOLUTE:
        axis = _REVOLUTE[kind]
    elif kind == "JointModelRevoluteUnaligned":
        axis = np.array(joint_model.extract().axis)
    else:
        what = _OTHER_KINDS.get(kind, kind)
        raise RobotDescriptionError("", "type", f"only revolute joints are supported, got a "
                                                f"{what} joint (make it fixed in the URDF, or end "
                                                "the arm before it: tip=)")  # fmt: skip
    v = joint_model.idx_v
    inertia = model.inertias[joint_id]
    if friction is None:
        coulomb = float(model.friction[v])
        friction = JointFriction(
            coulomb=coulomb,
            slope=DEFAULT_SLOPE,
            half_width=DEFAULT_HALF_WIDTH,
            viscous=float(model.damping[v]),
            noise_std=0.05 * coulomb,
        )
    placement = model.jointPlacements[joint_id]
    return Joint(
        name=model.names[joint_id],
        link=LinkInertial(inertia.mass, inertia.lever, inertia.inertia),
        position_limits=(model.lowerPositionLimit[v], model.upperPositionLimit[v]),
        velocity_limit=model.velocityLimit[v],
        torque_limit=model.effortLimit[v],
        friction=friction,
        gear_ratio=gear,
        rotor_inertia=rotor,
        origin=JointOrigin(Placement(placement.translation, placement.rotation), axis),
    )


def _flange(model: pin.Model, tip: str | None) -> Placement:
    """The tip frame in the last chain joint frame (identity without a tip)."""
    if tip is None:
        return Placement()
    placement = model.frames[_frame_id(model, tip)].placement
    return Placement(placement.translation, placement.rotation)
