"""The linear-in-parameters joint torque model of an arm, and its parameters ↔ description.

Per sample and joint i (SPEC §1 with the motor torque measured as g_i K_i i_i)::

    Y_i(q, q̇, q̈) π + I_a,i q̈_i + τ_C,i φ_i(q̇_i) + c_i q̇_i + o_i = g_i τ_i

``Y`` is Pinocchio's joint-torque regressor and ``π`` the 10 inertial parameters of each
link in its joint frame ``[m, m c, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz]`` (inertia about
the joint origin); ``I_a`` the reflected rotor inertia (armature); ``φ`` the mean of the
project's friction model for a unit Coulomb level (its sigmoid shape kept); ``o`` a torque
offset (a current-sensor bias, not friction); ``g = 1 + δg`` the drive-gain scale on the
logged torque τ = K i. The unknowns ``x = [π, I_a, τ_C, c, o, δg]`` enter linearly.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin

from leadthrough.friction.model import FrictionModel
from leadthrough.model.chain import serial_chain
from leadthrough.model.description import FloatArray, JointFriction, LinkInertial, RobotDescription
from leadthrough.model.pinocchio_model import build_model

#: Names of the per-joint parameter blocks after the 10 n inertial parameters.
BLOCKS = ("armature", "coulomb", "viscous", "offset")


def inertial_parameters(robot: RobotDescription) -> FloatArray:
    """The 10 n inertial parameters π of ``robot`` (joint frames), (10 n,)."""
    model = build_model(robot)
    return np.concatenate(
        [model.inertias[i + 1].toDynamicParameters() for i in range(robot.n_joints)]
    )


def regressor_rows(
    robot: RobotDescription,
    friction: FrictionModel,
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
) -> FloatArray:
    """The regressor of every sample, (N n, 14 n): rows sample-major, joints inside."""
    model = build_model(robot)
    data = model.createData()
    n = robot.n_joints
    unit = replace_friction_level(friction)
    phi = unit.mean(qd)
    eye = np.eye(n)
    rows = np.empty((len(q), n, 14 * n))
    for k in range(len(q)):
        rows[k, :, : 10 * n] = pin.computeJointTorqueRegressor(model, data, q[k], qd[k], qdd[k])
    blocks = (qdd, phi, qd, np.ones_like(qd))
    for b, values in enumerate(blocks):
        rows[:, :, 10 * n + b * n : 10 * n + (b + 1) * n] = eye[None] * values[:, :, None]
    return rows.reshape(len(q) * n, 14 * n)


def replace_friction_level(friction: FrictionModel) -> FrictionModel:
    """``friction`` with a unit Coulomb level and no viscous term or position dependence."""
    n = friction.n_joints
    return FrictionModel(coulomb=np.ones(n), slope=friction.slope, half_width=friction.half_width,
                         viscous=np.zeros(n), noise_std=friction.noise_std)  # fmt: skip


def link_inertial(robot: RobotDescription, joint: int, parameters: FloatArray) -> LinkInertial:
    """The link inertial (link frame) of 10 parameters π in the joint frame.

    Physically inconsistent values are projected: a mass below 1 % of the nominal is
    raised to it, and the inertia about the centre of mass gets eigenvalues ≥ 1e-6 kg m²
    that satisfy the triangle inequality (a real body's).
    """
    nominal = robot.joints[joint].link
    mass = max(float(parameters[0]), 0.01 * nominal.mass)
    com_joint = np.asarray(parameters[1:4]) / mass
    ixx, ixy, iyy, ixz, iyz, izz = parameters[4:10]
    about_origin = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    skew = pin.skew(com_joint)
    about_com = about_origin + mass * skew @ skew  # parallel axis: I_o = I_c − m [c]²
    link_in_joint = pin.SE3(serial_chain(robot).link_in_joint[joint])
    inertia = pin.Inertia(mass, com_joint, _consistent(about_com))
    in_link = link_in_joint.actInv(inertia)
    return LinkInertial(in_link.mass, np.array(in_link.lever), np.array(in_link.inertia))


def _consistent(inertia: FloatArray) -> FloatArray:
    """Nearest inertia with eigenvalues ≥ 1e-6 kg m² obeying the triangle inequality."""
    values, vectors = np.linalg.eigh(0.5 * (inertia + inertia.T))
    values = np.maximum(values, 1e-6)
    for i in range(3):
        values[i] = min(values[i], values.sum() - values[i])
    return (vectors * values) @ vectors.T


def described(
    robot: RobotDescription,
    x: FloatArray,
    friction: FrictionModel,
    noise_std: FloatArray,
    gain: FloatArray,
) -> RobotDescription:
    """``robot`` carrying the identified parameters ``x`` (layout of :func:`regressor_rows`)."""
    n = robot.n_joints
    block = {name: x[10 * n + b * n : 10 * n + (b + 1) * n] for b, name in enumerate(BLOCKS)}
    joints = []
    for i, joint in enumerate(robot.joints):
        constant = joint.torque_constant
        joints.append(replace(
            joint,
            link=link_inertial(robot, i, x[10 * i : 10 * i + 10]),
            rotor_inertia=max(float(block["armature"][i]), 0.0) / joint.gear_ratio**2,
            friction=JointFriction(coulomb=max(float(block["coulomb"][i]), 0.0),
                                   slope=float(friction.slope[i]),
                                   half_width=float(friction.half_width[i]),
                                   viscous=max(float(block["viscous"][i]), 0.0),
                                   noise_std=float(noise_std[i])),
            torque_constant=None if constant is None else constant * float(gain[i]),
        ))  # fmt: skip
    return replace(robot, joints=tuple(joints))


def parameters_of(robot: RobotDescription, offset: FloatArray) -> FloatArray:
    """``x`` (layout of :func:`regressor_rows`) of what ``robot`` carries, and ``offset``.

    Of a :func:`described` description, the parameters as saved, not as fitted: a
    negative τ_C, c or rotor inertia held at 0, inertials made physical.
    """
    friction = [joint.friction for joint in robot.joints]
    return np.concatenate([inertial_parameters(robot), robot.reflected_rotor_inertias,
                           [f.coulomb for f in friction], [f.viscous for f in friction],
                           offset])  # fmt: skip
