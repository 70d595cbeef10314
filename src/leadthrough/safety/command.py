"""The supervisor's command path in one compiled pass (SPEC §7).

:func:`supervised_torque` does, joint by joint, what :func:`reference_torque` does with the
NumPy functions of :mod:`.braking` (the readable reference, which the tests hold it to at
1e-12 over long random sequences): check the inputs, saturate the
desired torque, brake joints above their speed limit and a tool above its speed limit
(the braked joints get gravity compensation instead of the controller's torque), add the
soft walls, check that the result is finite and saturate it again. The supervisor keeps
the state machine and the events: the kernel only reports which joints are inside a wall
or too fast, and the tool speed.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from leadthrough.compiled import kernel
from leadthrough.model.description import FloatArray
from leadthrough.safety import braking
from leadthrough.safety.limits import SafetyLimits

#: Rows of :func:`bound_rows`, the per-joint bounds the kernel reads.
BOUND_ROWS = ("q_low", "q_high", "qd_bound", "torque_low", "torque", "speed", "wall_low",
              "wall_high", "stiffness")  # fmt: skip

#: Status of :func:`supervised_torque`: the torque is written; an input is out of range
#: (the caller spells out why and latches the fault); the torque is not finite.
GOOD, BAD_INPUT, NOT_FINITE = 0, 1, 2

_LARGEST = float(np.finfo(float).max)  # a desired torque beyond ± this is not finite


def bound_rows(limits: SafetyLimits) -> FloatArray:
    """The bounds of ``limits`` as one (9, n) array, rows :data:`BOUND_ROWS`."""
    return np.array([getattr(limits, name) for name in BOUND_ROWS])


@kernel
def supervised_torque(q, qd, tau_desired, mass, gravity, jacobian, bounds, scalars, teaching,
                      out, inside, fast):  # fmt: skip
    """The supervised torque [Nm] into ``out``; returns (status, tool speed [m/s], flags).

    Args:
        q: Joint readings [rad], (n,).
        qd: Joint velocities [rad/s], (n,).
        tau_desired: The controller's torque [Nm], (n,).
        mass: M(q) [kg m²], (n, n).
        gravity: G(q) [Nm], (n,).
        jacobian: TCP Jacobian, translation rows first [m/rad], (6, n).
        bounds: :func:`bound_rows` of the supervisor's limits.
        scalars: (tool speed limit [m/s], braking time [s], wall damping time [s]).
        teaching: Whether the tool speed is limited (TEACHING).
        out: Written with the torque when the status is :data:`GOOD`.
        inside: Written: the joints inside a wall.
        fast: Written: the joints above their speed limit.

    Returns:
        :data:`GOOD`, :data:`BAD_INPUT` (nothing else done) or :data:`NOT_FINITE`; the
        tool speed (0 when not teaching); whether a joint is too fast; whether one is
        inside a wall.
    """
    n = q.shape[0]
    for i in range(n):
        if not (bounds[0, i] <= q[i] <= bounds[1, i] and -bounds[2, i] <= qd[i] <= bounds[2, i]
                and -_LARGEST <= tau_desired[i] <= _LARGEST):  # fmt: skip
            return BAD_INPUT, 0.0, False, False
    limit, braking_time, damping_time = scalars[0], scalars[1], scalars[2]
    any_fast, any_inside = False, False
    for i in range(n):
        fast[i] = abs(qd[i]) > bounds[5, i]
        inside[i] = q[i] < bounds[6, i] or q[i] > bounds[7, i]
        any_fast = any_fast or fast[i]
        any_inside = any_inside or inside[i]
    speed = 0.0
    if teaching:
        squared = 0.0
        for row in range(3):
            velocity = 0.0
            for j in range(n):
                velocity += jacobian[row, j] * qd[j]
            squared += velocity * velocity
        speed = math.sqrt(squared)
    tool_on = teaching and speed > limit
    scale = -(1.0 - limit / speed) if tool_on else 0.0
    finite = True
    for i in range(n):
        tau = min(max(tau_desired[i], bounds[3, i]), bounds[4, i])
        brake = 0.0  # joint braking plus tool braking
        if any_fast:
            excess = max(abs(qd[i]) - bounds[5, i], 0.0)
            sign = 1.0 if qd[i] > 0.0 else (-1.0 if qd[i] < 0.0 else 0.0)
            brake = -mass[i, i] * excess / braking_time * sign
        if tool_on:
            momentum = 0.0
            for j in range(n):
                momentum += mass[i, j] * qd[j]
            brake = brake + scale * momentum / braking_time
        if (any_fast or tool_on) and brake != 0.0:
            tau = gravity[i]  # the brakes win on a braked joint
        wall = 0.0
        if any_inside:
            damping = mass[i, i] / damping_time
            below = max(bounds[6, i] - q[i], 0.0)
            above = max(q[i] - bounds[7, i], 0.0)
            up = bounds[8, i] * below + damping * max(-qd[i], 0.0) if below > 0.0 else 0.0
            down = bounds[8, i] * above + damping * max(qd[i], 0.0) if above > 0.0 else 0.0
            wall = up - down
        if any_inside or any_fast or tool_on:
            tau = tau + (wall + brake)
        finite = finite and math.isfinite(tau)
        out[i] = tau
    if not finite:
        return NOT_FINITE, speed, any_fast, any_inside
    for i in range(n):
        out[i] = min(max(out[i], bounds[3, i]), bounds[4, i])
    return GOOD, speed, any_fast, any_inside


def reference_torque(
    limits: SafetyLimits,
    scalars: FloatArray,
    q: FloatArray,
    qd: FloatArray,
    tau_desired: FloatArray,
    mass: FloatArray,
    gravity: FloatArray,
    jacobian: FloatArray,
    teaching: bool,
) -> tuple[int, float, FloatArray, NDArray[np.bool_], NDArray[np.bool_]]:
    """:func:`supervised_torque` with the NumPy functions of :mod:`.braking`, inputs checked.

    Returns:
        The status (:data:`GOOD` or :data:`NOT_FINITE`), the tool speed [m/s] (0 when not
        teaching), the torque [Nm], the joints inside a wall and those above their speed.
    """
    limit, braking_time, damping_time = (float(value) for value in scalars)
    inertia = mass.diagonal()
    tau = limits.saturated(tau_desired)  # a huge command cannot swamp the safety
    brake, fast = braking.joint_braking(limits, qd, inertia, braking_time)
    speed = 0.0
    if teaching:
        tool, speed = braking.tool_braking(jacobian, mass, qd, limit, braking_time)
        if speed > limit:
            brake = brake + tool
    # while braking, the brakes win: the controller's torque on a braked joint is replaced
    # by gravity compensation, so no controller can push through the limit
    tau = np.where(brake != 0.0, gravity, tau)
    wall, inside = braking.walls(limits, q, qd, inertia, damping_time)
    tau = tau + (wall + brake)
    if np.count_nonzero(np.isfinite(tau)) != tau.size:
        return NOT_FINITE, speed, tau, inside, fast
    return GOOD, speed, limits.saturated(tau), inside, fast
