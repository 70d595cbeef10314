"""Torque a description predicts for a log, and its error against the measurement.

Models with different drive gains K predict different torques for the same current, so
the error is measured in the log's own torque units: a model with torque constants K_m
predicts the current τ̂ / K_m, which the log's gains K_log turn into K_log τ̂ / K_m. The
error is then ``τ_log − (K_log / K_m) τ̂``, comparable across models.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import ParameterError
from leadthrough.friction.model import FrictionModel
from leadthrough.identification.smoothing import smooth_derivative
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics

#: Smoothing of the held-out signals [s] (the identification's default).
BANDWIDTH = 0.03


def predict_torque(
    log: Any,
    robot: RobotDescription,
    offset: ArrayLike | None = None,
    bandwidth: float = BANDWIDTH,
) -> FloatArray:
    """Joint torque ``M q̈ + C q̇ + G + mean friction + offset`` along ``log`` [Nm], (N, n)."""
    t = np.asarray(log.t, dtype=float)
    qd, qdd = smooth_derivative(t, log.qd, bandwidth)
    dynamics = Dynamics(robot)
    rigid = np.array([dynamics.inverse_dynamics(*row) for row in zip(log.q, qd, qdd, strict=True)])
    friction = FrictionModel.from_robot(robot).mean(qd)
    return rigid + friction + (0.0 if offset is None else np.asarray(offset, dtype=float))


def prediction_error(
    log: Any,
    robot: RobotDescription,
    offset: ArrayLike | None = None,
    bandwidth: float = BANDWIDTH,
) -> FloatArray:
    """Measured minus predicted torque in the log's torque units [Nm], (N, n)."""
    measured = log_torque(log, robot)
    if measured is None:
        where = getattr(log, "source", "") or "the log"
        raise ParameterError("log", f"{where} has no joint torque (nor currents with K)")
    predicted = predict_torque(log, robot, offset, bandwidth)
    return measured - gain_ratio(log, robot) * predicted


def log_torque(log: Any, robot: RobotDescription) -> FloatArray | None:
    """The log's joint torque [Nm], (N, n): ``tau``, else K·i with ``robot``'s constants.

    None when the log has neither (a log type without :meth:`JointLog.joint_torque`
    gives its ``tau``).
    """
    if hasattr(log, "joint_torque"):
        return log.joint_torque(robot.torque_constants)
    tau = getattr(log, "tau", None)
    return None if tau is None else np.asarray(tau, dtype=float)


def gain_ratio(log: Any, robot: RobotDescription) -> FloatArray:
    """K_log / K_robot per joint (1 without currents or torque constants), (n,)."""
    constants = robot.torque_constants
    current = getattr(log, "current", None)
    if constants is None or current is None or log.tau is None:
        return np.ones(log.q.shape[1])
    k_log = np.sum(log.tau * current, axis=0) / np.maximum(np.sum(current**2, axis=0), 1e-12)
    return k_log / constants


def rms(error: FloatArray) -> FloatArray:
    """RMS per joint of an (N, n) error [same unit]."""
    return np.sqrt(np.mean(np.square(error), axis=0))
