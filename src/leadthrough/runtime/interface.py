"""The robot interface: what a controller sees of a robot, simulated or real.

A hardware driver, the digital twin and the test mock (:mod:`leadthrough.twin.mock`)
implement :class:`RobotInterface`: read the joint state, send a torque command, once per
control period. Controllers never see more than this (SPEC §9), so the same
controller object runs in tests, against the twin and on a robot::

    state = robot.read_state()
    while running:
        tau = controller.step(state)  # or step(state.q, state.qd, state.tau_measured)
        robot.send_torque(tau)        # returns when the next state is due
        state = robot.read_state()

``step(state)`` (``LeadThrough``'s, as :func:`~leadthrough.runtime.loop.control_loop`
calls it) takes the robot's time stamp and enabling device with it; the positional form
has neither.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Protocol

from numpy.typing import ArrayLike

from leadthrough.logs.sample import JointState
from leadthrough.model.description import FloatArray

__all__ = ["Controller", "JointState", "RobotInterface"]


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
