"""Check a URDF's joints and links before Pinocchio parses them.

The URDF parser under Pinocchio (urdfdom) prints what is wrong with a joint on stderr
and then only says that the text "does not contain a valid URDF model". The checks here
follow its rules for what :func:`leadthrough.model.robots.from_urdf` reads (joint type,
parent and child links, origin, axis, limits, dynamics; a link's inertial), and the
signs Pinocchio requires, so that a mistake is one line naming the file, the joint or
link and the value::

    arm.urdf: joint 'slide': <limit effort="abc"> is not a number

Visual and collision elements, ``<mimic>``, ``<safety_controller>`` and
``<calibration>`` are not read by leadthrough and not checked here. Whether an inertia
is positive definite is checked on each arm joint's link once the links fixed to it are
merged (:class:`~leadthrough.model.description.LinkInertial`): a link off the arm, or
the fixed base, may carry an inertia that Pinocchio loads and the arm never uses.
"""

from __future__ import annotations

import math
import re
from xml.etree import ElementTree

from leadthrough.errors import RobotDescriptionError
from leadthrough.validation import fail, within

#: A number as the URDF parser reads one: decimal, optional exponent; no nan, no inf.
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
#: The joint types of the URDF format.
_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
#: Joints that need ``<limit effort velocity>``: a continuous one too, which leadthrough
#: loads as a revolute one and whose torque and speed limits it needs.
_NEEDS_LIMIT = ("revolute", "continuous", "prismatic")
_INERTIA = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
#: The largest limit of a revolute joint [rad]: two turns either way. A URDF gives angles in
#: radians; limits written in degrees (±170) are far beyond it.
_LARGEST_ANGLE = 4.0 * math.pi
#: Limits beyond this [rad] are not degrees (ten turns of them) but a file's way to say
#: "none" (±1e16 on example-robot-data's rotors): they load as they are.
_NO_LIMIT = 3600.0
#: The farthest a moving joint, or a link's centre of mass, may sit from its parent's
#: frame [m]. A URDF gives lengths in metres; written in millimetres, an arm's offsets
#: (90–900 mm) are far beyond it. A fixed joint is not checked: it may place the arm in a
#: large cell.
_LONGEST_OFFSET = 10.0


def check_urdf(root: ElementTree.Element, source: str) -> None:
    """Raise for the first malformed joint or link of the URDF ``root``.

    Args:
        root: The ``<robot>`` element.
        source: The file, for the message.

    Raises:
        RobotDescriptionError: Naming ``source``, the joint (``joint 'panda_joint3'``)
            or link and what is wrong: a name given twice, an unknown joint type, a
            parent or child link that the file does not define, a ``<limit>`` missing
            on a moving joint or without ``effort`` and ``velocity``, a value that is not
            a finite number or not as many as it needs (``<axis xyz="1 0">``), a
            negative effort, velocity, damping, friction or mass; a revolute joint's
            limit beyond two turns (degrees?), a moving joint's origin or a centre of mass
            more than 10 m from its frame (millimetres?).
    """
    if root.tag == "robot" and root.get("name") is None:
        raise RobotDescriptionError(source, "", "<robot> has no name")
    elements = {"link": root.findall("link"), "joint": root.findall("joint")}
    names = {kind: [str(e.get("name")) for e in found] for kind, found in elements.items()}
    for kind, named in names.items():
        twice = next((name for i, name in enumerate(named) if name in named[:i]), None)
        if twice is not None:
            raise RobotDescriptionError(source, f"{kind} {twice!r}", "defined twice")
    for joint, name in zip(elements["joint"], names["joint"], strict=True):
        with within(f"joint {name!r}", source=source):
            _check_joint(joint, set(names["link"]))
    _check_tree(elements["joint"], names["link"], source)
    for link, name in zip(elements["link"], names["link"], strict=True):
        with within(f"link {name!r}", source=source):
            _check_inertial(link.find("inertial"))


def _check_joint(joint: ElementTree.Element, links: set[str]) -> None:
    """Raise for the first malformed field of ``joint`` (see :func:`check_urdf`)."""
    kind = joint.get("type")
    if kind not in _TYPES:
        raise fail("", f"type {kind!r} is not a URDF joint type ({', '.join(_TYPES)})")
    for side in ("parent", "child"):
        element = joint.find(side)
        link = None if element is None else element.get("link")
        if link is None:
            raise fail("", f"has no <{side} link>")
        if link not in links:
            raise fail("", f'<{side} link="{link}"> names no link of the file')
    _numbers(joint.find("origin"), "xyz", 3)
    _numbers(joint.find("origin"), "rpy", 3)
    if kind not in ("fixed", "floating"):  # the parser reads no axis of theirs
        _numbers(joint.find("axis"), "xyz", 3)
    limit = joint.find("limit")
    if limit is None and kind in _NEEDS_LIMIT:
        raise fail("", f"a {kind} joint needs <limit effort velocity>: its torque and speed limits")
    for attribute in ("effort", "velocity", "lower", "upper"):
        required, minimum = (True, 0.0) if attribute in ("effort", "velocity") else (False, None)
        _numbers(limit, attribute, required=required, minimum=minimum)
    if kind in _NEEDS_LIMIT:
        _check_units(joint, kind)
    dynamics = joint.find("dynamics")
    if dynamics is not None and not {"damping", "friction"} & set(dynamics.attrib):
        raise fail("", "<dynamics> has neither damping nor friction")
    for attribute in ("damping", "friction"):
        _numbers(dynamics, attribute, minimum=0.0)


def _check_units(joint: ElementTree.Element, kind: str | None) -> None:
    """Raise if a moving joint's limits or origin read as degrees or millimetres.

    Loaded as they were, limits of ±170 "rad" let the arm turn for ever and an origin of
    136 "m" made the UR5's shoulder hold 30 000 Nm, with no word.
    """
    limit = joint.find("limit")
    if kind == "revolute" and limit is not None:
        for attribute in ("lower", "upper"):
            text = limit.get(attribute)
            if text is not None and _LARGEST_ANGLE < abs(float(text)) <= _NO_LIMIT:
                raise fail("", f'<limit {attribute}="{text}"> is more than two turns: a URDF '
                           f"gives radians (was it written in degrees?)")  # fmt: skip
    _check_offset(joint.find("origin"), "a joint")


def _check_offset(origin: ElementTree.Element | None, what: str) -> None:
    """Raise if ``origin``'s xyz is farther than :data:`_LONGEST_OFFSET` from its frame."""
    text = None if origin is None else origin.get("xyz")
    if text is None:
        return
    distance = math.hypot(*map(float, text.split()))
    if distance > _LONGEST_OFFSET:
        reason = (f'<origin xyz="{text}"> puts {what} {distance:.3g} m from its parent\'s '
                  "frame: a URDF gives metres (was it written in millimetres?)")  # fmt: skip
        raise fail("", reason)


def _check_tree(joints: list[ElementTree.Element], links: list[str], source: str) -> None:
    """Raise unless the joints join the links into one tree: one root, one parent each.

    A link that is the child of two joints, or a loop of joints, made Pinocchio's parser
    crash the process (a segmentation fault, nothing printed) or urdfdom print on stderr
    and say only "not a valid URDF".
    """
    parent_joint: dict[str, str] = {}
    children: dict[str, list[str]] = {link: [] for link in links}
    for joint in joints:
        name = str(joint.get("name"))
        parent, child = (str(joint.find(side).get("link")) for side in ("parent", "child"))  # type: ignore[union-attr]
        if child in parent_joint:
            raise RobotDescriptionError(source, f"link {child!r}", f"is the child of joints "
                                        f"{parent_joint[child]!r} and {name!r}: a URDF is a "
                                        "tree, each link has one parent")  # fmt: skip
        parent_joint[child] = name
        children[parent].append(child)
    roots = [link for link in links if link not in parent_joint]
    if not roots:
        raise RobotDescriptionError(source, "", "every link is some joint's child: the joints "
                                    "form a loop (a URDF is a tree)")  # fmt: skip
    if len(roots) != 1:
        found = ", ".join(repr(root) for root in roots) or "none"
        raise RobotDescriptionError(source, "", f"the joints join the links into {len(roots)} "
                                    f"trees, not one (root links: {found})")  # fmt: skip
    reached, stack = {roots[0]}, [roots[0]]
    while stack:
        for child in children[stack.pop()]:
            if child not in reached:
                reached.add(child)
                stack.append(child)
    loop = [link for link in links if link not in reached]
    if loop:
        raise RobotDescriptionError(source, f"link {loop[0]!r}", f"is on a loop of joints, "
                                    f"not below the root link {roots[0]!r}")  # fmt: skip


def _check_inertial(inertial: ElementTree.Element | None) -> None:
    """Raise for the first malformed field of a link's ``<inertial>`` (none: nothing to check)."""
    if inertial is None:
        return
    _numbers(inertial.find("origin"), "xyz", 3)
    _numbers(inertial.find("origin"), "rpy", 3)
    _check_offset(inertial.find("origin"), "the centre of mass")
    mass, inertia = inertial.find("mass"), inertial.find("inertia")
    for tag, element in (("mass", mass), ("inertia", inertia)):
        if element is None:
            raise fail("", f"<inertial> has no <{tag}>")
    _numbers(mass, "value", required=True, minimum=0.0)
    for name in _INERTIA:
        _numbers(inertia, name, required=True)


def _numbers(
    element: ElementTree.Element | None,
    attribute: str,
    count: int = 1,
    *,
    required: bool = False,
    minimum: float | None = None,
) -> None:
    """Raise unless ``element``'s ``attribute`` is ``count`` finite numbers (or absent).

    Raises:
        RobotDescriptionError: The attribute is absent though ``required`` (and
            ``element`` present), or it is not ``count`` finite numbers (``nan`` and
            ``inf`` are not), or one is below ``minimum``; quoting it.
    """
    text = None if element is None else element.get(attribute)
    if element is None or text is None:
        if required and element is not None:
            raise fail("", f"<{element.tag}> has no {attribute}")
        return
    shown = f'<{element.tag} {attribute}="{text}">'
    pieces = text.split()
    if len(pieces) != count:
        raise fail("", f"{shown} is not a number" if count == 1
                   else f"{shown}: expected {count} numbers, got {len(pieces)}")  # fmt: skip
    for piece in pieces:
        what = "a number" if not _NUMBER.fullmatch(piece) else "finite"
        if what == "a number" or not math.isfinite(float(piece)):
            raise fail("", f"{shown} is not {what}" if count == 1
                       else f"{shown}: {piece!r} is not {what}")  # fmt: skip
    if minimum is not None and min(map(float, pieces)) < minimum:
        raise fail("", f"{shown} must not be negative")
