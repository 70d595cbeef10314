"""The robot interface: what a controller sees of a robot, simulated or real.

A hardware driver, the digital twin and the test mock all implement
:class:`RobotInterface`: read the joint state, send a torque command, once per
control period. Controllers never see more than this (SPEC §9), so the same
controller object runs in tests, against the twin and on a robot::

    state = robot.read_state()
    while running:
        tau = controller.step(state.q, state.qd, state.tau_measured)
        robot.send_torque(tau)      # returns when the next state is due
        state = robot.read_state()
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import InputShapeError
from leadthrough.model.description import FloatArray


@dataclass(frozen=True, eq=False)
class JointState:
    """One sample of the joint sensors.

    Attributes:
        t: Time of the sample [s].
        q: Joint readings (encoders, quantised) [rad], shape (n,).
        qd: Joint velocities as the robot reports them (noisy) [rad/s], shape (n,).
        tau_measured: Motor torque actually applied, as measured, arm side [Nm], shape (n,).
    """

    t: float
    q: FloatArray
    qd: FloatArray
    tau_measured: FloatArray


class Controller(Protocol):
    """Anything that turns a joint state into a torque command, once per period."""

    def step(self, q: FloatArray, qd: FloatArray, tau_measured: FloatArray | None) -> FloatArray:
        """Torque command, arm side [Nm], for the state q [rad], q̇ [rad/s], τ [Nm]."""
        ...


class RobotInterface(ABC):
    """A robot driven in torque at a fixed control period.

    Attributes:
        dt: Control period [s].
        n_joints: Number of joints n.
    """

    dt: float
    n_joints: int

    @abstractmethod
    def read_state(self) -> JointState:
        """The latest joint state sample."""

    @abstractmethod
    def send_torque(self, tau: ArrayLike) -> None:
        """Command motor torques, arm side [Nm], held until the next command.

        Returns when the next state is due: on hardware at the next tick of its clock,
        on the twin after simulating one control period.
        """

    def close(self) -> None:  # noqa: B027 - optional hook, nothing to release by default
        """Release the robot (brakes on, connection closed). Default: nothing to do."""


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
