"""Braking torques, soft walls and the safe-stop hold (SPEC §7), as pure functions.

Each returns a torque [Nm], arm side, shape (n,), and, where the supervisor logs an
episode, the joints it acts on; the supervisor sums, saturates and logs them.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics
from leadthrough.safety.limits import SafetyLimits


def walls(
    limits: SafetyLimits, q: FloatArray, qd: FloatArray, inertia: FloatArray, damping_time: float
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Spring-damper walls inside the position limits, pushing away from them.

    Args:
        limits: The supervisor's bounds (where the walls start, their stiffness).
        q: Joint positions [rad], finite, shape (n,).
        qd: Joint velocities [rad/s], shape (n,).
        inertia: Diagonal of M(q) [kg m²], shape (n,).
        damping_time: Wall damping is ``inertia / damping_time`` into the wall [s].

    Returns:
        The wall torque [Nm] and the joints inside a wall (beyond where it starts).
    """
    # q is finite, so this is exactly where `below > 0` or `above > 0` below
    inside = (q < limits.wall_low) | (q > limits.wall_high)
    if not inside.any():
        return np.zeros(q.shape), inside
    stiffness = limits.stiffness
    damping = inertia / damping_time
    below = np.maximum(limits.wall_low - q, 0.0)
    above = np.maximum(q - limits.wall_high, 0.0)
    push_up = np.where(below > 0.0, stiffness * below + damping * np.maximum(-qd, 0.0), 0.0)
    push_down = np.where(above > 0.0, stiffness * above + damping * np.maximum(qd, 0.0), 0.0)
    return push_up - push_down, inside


def joint_braking(
    limits: SafetyLimits, qd: FloatArray, inertia: FloatArray, braking_time: float
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Torque braking each joint faster than its speed limit, zero below.

    Args:
        limits: The supervisor's bounds (the joint speed limits).
        qd: Joint velocities [rad/s], finite, shape (n,).
        inertia: Diagonal of M(q) [kg m²], shape (n,).
        braking_time: Time constant of the braking [s].

    Returns:
        The braking torque [Nm] and the joints above their speed limit.
    """
    limit = limits.speed
    speed = np.abs(qd)
    fast = speed > limit  # q̇ is finite, so this is exactly `excess > 0`
    if not fast.any():
        return np.zeros(qd.shape), fast
    excess = np.maximum(speed - limit, 0.0)
    return -inertia * excess / braking_time * np.sign(qd), fast


def tool_braking(
    jacobian: FloatArray, mass: FloatArray, qd: FloatArray, limit: float, braking_time: float
) -> tuple[FloatArray, float]:
    """Torque braking the flange when faster than ``limit``, else zero.

    Args:
        jacobian: Flange Jacobian, translation rows first [m/rad], shape (6, n).
        mass: Joint-space inertia M(q) [kg m²], shape (n, n).
        qd: Joint velocities [rad/s], shape (n,).
        limit: Flange speed limit [m/s].
        braking_time: Time constant of the braking [s].

    Returns:
        The braking torque [Nm] and the flange speed [m/s].
    """
    velocity = jacobian[:3] @ qd
    speed = math.sqrt(velocity.dot(velocity))  # what np.linalg.norm computes
    if speed <= limit:
        return np.zeros(qd.shape), speed
    return -(1.0 - limit / speed) * (mass @ qd) / braking_time, speed


def safe_stop(
    dynamics: Dynamics,
    q: FloatArray,
    qd: FloatArray | None,
    braking_time: float,
    gravity: FloatArray | None = None,
) -> FloatArray:
    """Gravity hold at ``q``, damped against ``qd`` when given; zero where non-finite.

    Args:
        dynamics: Model of the arm (G(q), M(q)).
        q: The position to hold [rad], shape (n,).
        qd: Trusted joint velocities to damp [rad/s], shape (n,), or None (no damping).
        braking_time: The damping is ``M_ii / braking_time`` [s].
        gravity: The gravity torque to hold with at ``q`` [Nm] (default the model's G(q)).

    Returns:
        The hold torque [Nm], not yet saturated.
    """
    tau = dynamics.gravity(q) if gravity is None else np.asarray(gravity, dtype=float)
    if qd is not None:
        damping = dynamics.mass(q).diagonal() / braking_time
        tau = tau - damping * qd
    return np.where(np.isfinite(tau), tau, 0.0)
