"""The serial chain of a description as joint frames: the one place where DH becomes frames.

Every simulator or dynamics library we build (Pinocchio, MuJoCo) consumes a
:class:`SerialChain`: per joint, its frame in the previous joint's frame at q = 0, its
rotation axis, and the pose of the link frame (where the inertial is given) in the
joint frame. A standard DH row (thesis eq. 3.1)

    A_i = Rz(q_i + offset_i) · Tz(d_i) · Tx(a_i) · Rx(alpha_i)

splits into a joint rotating about z by q_i, preceded by the constant Rz(offset_i),
and followed by the constant link transform F_i = Tz(d_i) Tx(a_i) Rx(alpha_i). So
joint i+1 sits at F_i · Rz(offset_{i+1}) in joint frame i, and link frame i is F_i.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from leadthrough.model.description import DHParameters, FloatArray, RobotDescription


@dataclass(frozen=True, eq=False)
class SerialChain:
    """Joint frames of a serial arm, all as 4×4 homogeneous matrices.

    Attributes:
        joint_in_parent: (n, 4, 4) joint i frame in joint i−1 frame at q = 0 (joint 1 in
            the world, base included).
        axes: (n, 3) unit rotation axes, each in its joint frame.
        link_in_joint: (n, 4, 4) link i frame (where its inertial is given) in joint i frame.
        flange_in_last_joint: (4, 4) flange frame in the last joint frame.
    """

    joint_in_parent: FloatArray
    axes: FloatArray
    link_in_joint: FloatArray
    flange_in_last_joint: FloatArray


def rot_z(angle: float) -> FloatArray:
    """Homogeneous rotation about z by ``angle`` [rad]."""
    c, s = np.cos(angle), np.sin(angle)
    matrix = np.eye(4)
    matrix[:2, :2] = [[c, -s], [s, c]]
    return matrix


def dh_link_transform(dh: DHParameters) -> FloatArray:
    """Constant part of a DH row, ``Tz(d) · Tx(a) · Rx(alpha)``, as a 4×4 matrix."""
    ca, sa = np.cos(dh.alpha), np.sin(dh.alpha)
    return np.array(
        [
            [1.0, 0.0, 0.0, dh.a],
            [0.0, ca, -sa, 0.0],
            [0.0, sa, ca, dh.d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def serial_chain(robot: RobotDescription) -> SerialChain:
    """Joint frames of ``robot``, from its DH table or its URDF-style joint origins."""
    n = robot.n_joints
    joint_in_parent = np.empty((n, 4, 4))
    link_in_joint = np.empty((n, 4, 4))
    axes = np.empty((n, 3))
    previous = robot.base.homogeneous
    for i, joint in enumerate(robot.joints):
        if joint.dh is not None:
            joint_in_parent[i] = previous @ rot_z(joint.dh.offset)
            link_in_joint[i] = dh_link_transform(joint.dh)
            axes[i] = (0.0, 0.0, 1.0)
            previous = link_in_joint[i]
        else:
            assert joint.origin is not None  # RobotDescription guarantees dh or origin
            joint_in_parent[i] = previous @ joint.origin.placement.homogeneous
            link_in_joint[i] = np.eye(4)
            axes[i] = joint.origin.axis
            previous = np.eye(4)
    flange = link_in_joint[-1] @ robot.flange.homogeneous
    return SerialChain(joint_in_parent, axes, link_in_joint, flange)
