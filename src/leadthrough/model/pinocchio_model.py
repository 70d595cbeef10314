"""Build a Pinocchio model from a robot description (via its :class:`SerialChain`)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from leadthrough.model.chain import serial_chain
from leadthrough.model.description import FloatArray, RobotDescription

FLANGE_FRAME = "flange"
TCP_FRAME = "tcp"

_AXIS_JOINTS = {0: pin.JointModelRX, 1: pin.JointModelRY, 2: pin.JointModelRZ}


def revolute_joint(axis: FloatArray) -> pin.JointModel:
    """The Pinocchio revolute joint about ``axis`` (unit vector in the joint frame)."""
    for index, joint_type in _AXIS_JOINTS.items():
        if np.allclose(axis, np.eye(3)[index]):
            return joint_type()
    return pin.JointModelRevoluteUnaligned(np.asarray(axis, dtype=float))


def build_model(robot: RobotDescription) -> pin.Model:
    """A Pinocchio model of ``robot``: one revolute joint per joint, base in the world.

    Link inertials go to their joints, the reflected rotor inertia ``G_r² J_m`` becomes
    the joint armature (so it lands on the diagonal of M), limits and gravity are
    copied, and frames ``link_1`` … ``link_n``, ``flange`` and ``tcp`` (the tool centre
    point, ``robot.tcp`` in the flange frame) are added.
    """
    chain = serial_chain(robot)
    model = pin.Model()
    model.name = robot.name
    parent = 0
    for i, joint in enumerate(robot.joints):
        joint_id = model.addJoint(
            parent, revolute_joint(chain.axes[i]), pin.SE3(chain.joint_in_parent[i]), joint.name
        )
        link_in_joint = pin.SE3(chain.link_in_joint[i])
        inertial = joint.link
        inertia_in_link = pin.Inertia(inertial.mass, inertial.com, inertial.inertia)
        model.appendBodyToJoint(joint_id, link_in_joint.act(inertia_in_link), pin.SE3.Identity())
        model.addFrame(pin.Frame(f"link_{i + 1}", joint_id, link_in_joint, pin.FrameType.BODY))
        parent = joint_id
    flange = pin.SE3(chain.flange_in_last_joint)
    model.addFrame(pin.Frame(FLANGE_FRAME, parent, flange, pin.FrameType.OP_FRAME))
    tcp = flange * pin.SE3(robot.tcp.homogeneous)
    model.addFrame(pin.Frame(TCP_FRAME, parent, tcp, pin.FrameType.OP_FRAME))
    model.armature = robot.reflected_rotor_inertias.copy()
    model.lowerPositionLimit = robot.q_min.copy()
    model.upperPositionLimit = robot.q_max.copy()
    model.velocityLimit = robot.velocity_limits.copy()
    model.effortLimit = robot.torque_limits.copy()
    model.gravity = pin.Motion(robot.gravity, np.zeros(3))
    return model
