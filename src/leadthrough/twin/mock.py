"""A robot of decoupled damped joints, integrated exactly: the smallest plant for unit tests."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import InputShapeError
from leadthrough.model.description import FloatArray
from leadthrough.runtime.interface import JointState, RobotInterface


class MockRobot(RobotInterface):
    """Decoupled joints ``I q̈ = τ − b q̇`` integrated exactly per period, for unit tests.

    Records every command in :attr:`commands`.

    Args:
        n_joints: Number of joints.
        dt: Control period [s].
        inertia: Joint inertia [kg m²], scalar or (n,).
        damping: Joint viscous damping [Nm s/rad], scalar or (n,).
        q0: Initial joint positions [rad].
    """

    def __init__(
        self,
        n_joints: int,
        dt: float = 0.004,
        inertia: ArrayLike = 0.1,
        damping: ArrayLike = 0.5,
        q0: ArrayLike | None = None,
    ) -> None:
        self.n_joints = n_joints
        self.dt = dt
        self.inertia = np.broadcast_to(np.asarray(inertia, dtype=float), (n_joints,)).copy()
        self.damping = np.broadcast_to(np.asarray(damping, dtype=float), (n_joints,)).copy()
        self.t = 0.0
        self.q = np.zeros(n_joints) if q0 is None else np.array(q0, dtype=float)
        self.qd = np.zeros(n_joints)
        self.tau = np.zeros(n_joints)
        self.commands: list[FloatArray] = []

    def read_state(self) -> JointState:
        """The exact state of the mock joints."""
        return JointState(self.t, self.q.copy(), self.qd.copy(), self.tau.copy())

    def send_torque(self, tau: ArrayLike) -> None:
        """Integrate one period with the torque held constant (exact for this linear plant)."""
        tau = np.asarray(tau, dtype=float)
        if tau.shape != (self.n_joints,):
            raise InputShapeError("tau", (self.n_joints,), tau.shape)
        self.commands.append(tau.copy())
        rate = self.damping / self.inertia
        decay = np.exp(-rate * self.dt)
        qd_final = tau / self.damping
        qd_next = qd_final + (self.qd - qd_final) * decay
        self.q = self.q + qd_final * self.dt + (self.qd - qd_final) * (1.0 - decay) / rate
        self.qd = qd_next
        self.tau = tau
        self.t += self.dt
