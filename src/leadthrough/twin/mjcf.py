"""Generate the MuJoCo model (MJCF) of the twin from a robot description.

Nothing here is hand-written per robot: bodies, joints and inertials come from the
description's :class:`~leadthrough.model.chain.SerialChain`, so that the twin and the
controller's Pinocchio model share one source. Body frames are the joint frames;
each link inertial is moved from its link frame into its body frame. The rotor
inertia ``G_r² J_m`` becomes the joint armature. Joint friction and damping are zero
in the MJCF: the twin applies its own friction physics (``twin.friction``).

Geometry is simple: capsules between joint origins for pictures (no collisions
between links), a collidable tool tip at the flange, and an optional table.
"""

from __future__ import annotations

from dataclasses import dataclass
from xml.etree import ElementTree

import numpy as np

from leadthrough.model.chain import SerialChain, serial_chain
from leadthrough.model.description import FloatArray, RobotDescription

FLANGE_SITE = "flange"
TOOL_GEOM = "tool_tip"
TABLE_GEOM = "table"
#: Radius of the links' visual capsules [m] (the tool's capsule has half of it).
LINK_RADIUS = 0.03
#: Length of the tool's capsule along the flange's z axis [m], its rounded end aside.
TOOL_LENGTH = 0.06


def tool_tip_depth(link_radius: float = LINK_RADIUS) -> float:
    """How far along the flange's z axis the tool's tip reaches [m]: capsule and rounded end."""
    return TOOL_LENGTH + 0.5 * link_radius


@dataclass(frozen=True)
class TableSurface:
    """A horizontal table the tool can touch.

    Attributes:
        height: Height of the table top in the world frame [m].
        stiffness_time_constant: MuJoCo contact ``solref`` time constant [s]: smaller is
            stiffer (0.002 s is a hard, wooden table seen through a compliant tool).
        friction: Sliding friction coefficient of the table top [–].
    """

    height: float
    stiffness_time_constant: float = 0.002
    friction: float = 0.3

    @classmethod
    def below_tool(cls, flange: FloatArray, gap: float) -> TableSurface:
        """A table ``gap`` [m] below the tip of a tool pointing down from ``flange`` [m, world]."""
        return cls(height=float(flange[2]) - tool_tip_depth() - gap)


@dataclass(frozen=True)
class Payload:
    """A rigid payload carried at the flange (a model-error knob).

    Attributes:
        mass: Payload mass [kg].
        com: Centre of mass in the flange frame [m].
    """

    mass: float
    com: tuple[float, float, float] = (0.0, 0.0, 0.05)


def _vec(values: FloatArray) -> str:
    return " ".join(f"{value:.12g}" for value in np.ravel(values))


def _quat(rotation: FloatArray) -> str:
    """MuJoCo quaternion (w, x, y, z) of a rotation matrix."""
    import mujoco

    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation, dtype=float).ravel())
    return _vec(quat)


def _full_inertia(inertia: FloatArray) -> str:
    """MJCF ``fullinertia`` order: Ixx Iyy Izz Ixy Ixz Iyz."""
    return _vec([inertia[0, 0], inertia[1, 1], inertia[2, 2],
                 inertia[0, 1], inertia[0, 2], inertia[1, 2]])  # fmt: skip


def _sub(parent: ElementTree.Element, tag: str, **attributes: str) -> ElementTree.Element:
    return ElementTree.SubElement(parent, tag, {k: v for k, v in attributes.items() if v})


def mjcf_from_description(
    robot: RobotDescription,
    *,
    physics_dt: float = 0.0005,
    table: TableSurface | None = None,
    payload: Payload | None = None,
    link_radius: float = LINK_RADIUS,
) -> str:
    """MJCF text of ``robot`` for MuJoCo.

    Args:
        robot: The (possibly perturbed) true robot.
        physics_dt: Physics time step [s] (2 kHz by default, as the thesis' joint loops).
        table: Optional table surface for contact tests.
        payload: Optional payload at the flange.
        link_radius: Radius of the visual capsules [m].
    """
    chain = serial_chain(robot)
    root = ElementTree.Element("mujoco", model=robot.name)
    _sub(root, "compiler", angle="radian", autolimits="true")
    _sub(root, "option", timestep=f"{physics_dt:.12g}", integrator="implicitfast",
         gravity=_vec(robot.gravity))  # fmt: skip
    _assets(root)
    world = _sub(root, "worldbody")
    _sub(world, "light", pos="0 0 3", dir="0 0 -1", directional="true")
    _sub(world, "geom", name="base", type="sphere", size=f"{link_radius * 1.5:g}",
         pos=_vec(robot.base.translation), material="base",
         contype="0", conaffinity="0")  # fmt: skip
    if table is not None:
        _table(world, table)
    parent = world
    for i in range(robot.n_joints):
        parent = _link_body(parent, chain, i, robot, link_radius)
    _tool(parent, chain.flange_in_last_joint, link_radius, payload)
    return ElementTree.tostring(root, encoding="unicode")


def _assets(root: ElementTree.Element) -> None:
    asset = _sub(root, "asset")
    _sub(asset, "texture", type="skybox", builtin="gradient", rgb1="0.55 0.65 0.8",
         rgb2="0.1 0.1 0.15", width="256", height="256")  # fmt: skip
    _sub(asset, "material", name="link", rgba="0.85 0.85 0.88 1")
    _sub(asset, "material", name="joint", rgba="0.9 0.45 0.1 1")
    _sub(asset, "material", name="base", rgba="0.3 0.3 0.35 1")
    _sub(asset, "material", name="tool", rgba="0.2 0.5 0.9 1")
    _sub(asset, "material", name="table", rgba="0.55 0.45 0.35 1")


def _table(world: ElementTree.Element, table: TableSurface) -> None:
    _sub(world, "geom", name=TABLE_GEOM, type="box", size="1 1 0.02",
         pos=f"0.4 0 {table.height - 0.02:.12g}", material="table",
         friction=f"{table.friction:g} 0.005 0.0001",
         solref=f"{table.stiffness_time_constant:g} 1", contype="1", conaffinity="1")  # fmt: skip


def _link_body(
    parent: ElementTree.Element, chain: SerialChain, i: int, robot: RobotDescription, radius: float
) -> ElementTree.Element:
    """Body of joint i+1: hinge at its origin, inertial from the link frame, visuals."""
    joint = robot.joints[i]
    placement = chain.joint_in_parent[i]
    body = _sub(parent, "body", name=f"link_{i + 1}", pos=_vec(placement[:3, 3]),
                quat=_quat(placement[:3, :3]))  # fmt: skip
    low, high = joint.position_limits
    _sub(body, "joint", name=joint.name, type="hinge", axis=_vec(chain.axes[i]),
         range=f"{low:.12g} {high:.12g}", armature=f"{joint.reflected_rotor_inertia:.12g}",
         solreflimit="0.005 1")  # fmt: skip
    link = chain.link_in_joint[i]
    rotation = link[:3, :3]
    _sub(body, "inertial", pos=_vec(rotation @ joint.link.com + link[:3, 3]),
         mass=f"{joint.link.mass:.12g}",
         fullinertia=_full_inertia(rotation @ joint.link.inertia @ rotation.T))  # fmt: skip
    _sub(body, "geom", type="sphere", size=f"{radius * 1.15:g}", material="joint",
         contype="0", conaffinity="0", mass="0")  # fmt: skip
    child = chain.joint_in_parent[i + 1][:3, 3] if i + 1 < len(robot.joints) else None
    end = child if child is not None else chain.flange_in_last_joint[:3, 3]
    if np.linalg.norm(end) > 1e-6:
        _sub(body, "geom", type="capsule", fromto=f"0 0 0 {_vec(end)}", size=f"{radius:g}",
             material="link", contype="0", conaffinity="0", mass="0")  # fmt: skip
    return body


def _tool(
    body: ElementTree.Element, flange: FloatArray, radius: float, payload: Payload | None
) -> None:
    """Flange site, collidable tool tip along the flange z axis (:func:`tool_tip_depth`), load."""
    frame = _sub(body, "body", name="flange", pos=_vec(flange[:3, 3]), quat=_quat(flange[:3, :3]))
    _sub(frame, "site", name=FLANGE_SITE, size="0.01")
    _sub(frame, "geom", name=TOOL_GEOM, type="capsule", fromto=f"0 0 0 0 0 {TOOL_LENGTH:g}",
         size=f"{radius * 0.5:g}", material="tool", contype="1", conaffinity="1", mass="0",
         condim="3")  # fmt: skip
    if payload is not None:
        _sub(frame, "inertial", pos=_vec(np.asarray(payload.com)), mass=f"{payload.mass:.12g}",
             diaginertia=_vec(np.full(3, 1e-5 + payload.mass * 1e-4)))  # fmt: skip
