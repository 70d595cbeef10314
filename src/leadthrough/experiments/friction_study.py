"""Friction identification end to end: excite (twin or logs), fit, compare, curves for figures.

This is what ``leadthrough identify`` runs. The result object holds everything the
figures of thesis §4.1 show (Figs. 4.2, 4.3, 4.5, 4.6), computed here, so that the
plotting code only draws.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from leadthrough.friction.identification import (
    FitReport,
    FrictionSamples,
    fit_friction,
    friction_samples,
    log_field,
)
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.runtime.excitation import friction_experiment


@dataclass(frozen=True, eq=False)
class FrictionStudy:
    """An identification and what it is compared with.

    Attributes:
        logs: The excitation logs (raw, as the robot reported them).
        samples: Filtered samples with the rigid-body torque removed.
        model: The identified friction model.
        report: Fit quality.
        seconds: Wall time of experiment and fit [s].
        simulated_seconds: Robot time of the experiment [s] (0 for logs from a file).
        truth: The twin's true sliding friction ``(τ_C at mid-range, c)`` [Nm, Nm s/rad],
            when the logs come from the twin.
        robot: The description the logs belong to.
    """

    logs: list
    samples: FrictionSamples
    model: FrictionModel
    report: FitReport
    seconds: float
    simulated_seconds: float
    truth: tuple[FloatArray, FloatArray] | None
    robot: RobotDescription

    def errors(self) -> tuple[FloatArray, FloatArray] | None:
        """Relative errors of the identified Coulomb level (mid-range) and viscous coefficient.

        NaN where the true value is 0 (e.g. a twin without viscous friction on a joint).
        """
        if self.truth is None:
            return None
        coulomb, viscous = self.truth
        mid = 0.5 * (self.robot.q_min + self.robot.q_max)
        with np.errstate(divide="ignore", invalid="ignore"):  # a true value of 0: NaN
            return self.model.coulomb_level(mid) / coulomb - 1.0, self.model.viscous / viscous - 1.0

    def joint_samples(self, joint: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(q, q̇, τ_f) of the logs in which ``joint`` moved, for that joint."""
        mine = self.samples.moved[:, joint]
        return (self.samples.q[mine, joint], self.samples.qd[mine, joint],
                self.samples.tau_friction[mine, joint])  # fmt: skip

    def raw_samples(self, joint: int) -> tuple[FloatArray, FloatArray]:
        """Raw (q̇, τ) of the logs that excited ``joint``: velocity [rad/s], motor torque [Nm].

        Every log's, where no log excited it alone (a run that moved several joints).
        """
        mine = [log for log in self.logs if _excited_joint(log) == joint] or list(self.logs)
        return (np.concatenate([log_field(log, "qd")[:, joint] for log in mine]),
                np.concatenate([log_field(log, "tau")[:, joint] for log in mine]))  # fmt: skip

    def model_curves(self, joint: int, velocities: FloatArray) -> dict[str, FloatArray]:
        """Mean, std and the sigmoid pair of ``joint`` at mid-range over ``velocities``."""
        qd = np.zeros((len(velocities), self.model.n_joints))
        qd[:, joint] = velocities
        upper, lower = self.model.bounds(qd)
        return {"mean": self.model.mean(qd)[:, joint], "std": self.model.std(qd)[:, joint],
                "upper": upper[:, joint], "lower": lower[:, joint]}  # fmt: skip

    def coulomb_over_position(self, joint: int, positions: FloatArray) -> FloatArray:
        """Identified Coulomb level τ_C(q) of ``joint`` over ``positions`` [Nm]."""
        q = np.tile(self.model.position_mid, (len(positions), 1))
        q[:, joint] = positions
        return self.model.coulomb_level(q)[:, joint]


def _excited_joint(log: object) -> int:
    """The joint a log excites: its ``joint`` attribute, else the one that moved most."""
    joint = getattr(log, "joint", None)
    return int(np.argmax(np.ptp(log_field(log, "q"), axis=0))) if joint is None else joint


def run_friction_study(
    robot: RobotDescription,
    *,
    logs: Sequence | None = None,
    twin_config: object | None = None,
    joints: Sequence[int] | None = None,
    progress: bool | None = None,
) -> FrictionStudy:
    """Identify the friction of ``robot`` from ``logs``, or from the experiment on the twin.

    Args:
        robot: The description (its dynamics remove gravity and inertia).
        logs: Logs of a real robot (or saved ones); when None the experiment runs on a
            twin built with ``twin_config``.
        twin_config: :class:`~leadthrough.twin.simulator.TwinConfig` of that twin.
        joints: Joints to identify (0-based, default all).
        progress: Show a progress bar during the experiment.
    """
    dynamics = Dynamics(robot)
    start = time.perf_counter()
    truth, simulated = None, 0.0
    if logs is None:
        from leadthrough.twin.simulator import DigitalTwin

        twin = DigitalTwin(robot, twin_config)
        logs = friction_experiment(twin, dynamics, joints, progress=progress)
        params = twin.friction.params
        mid = 0.5 * (robot.q_min + robot.q_max)
        truth, simulated = (params.coulomb_level(mid), params.viscous), twin.time
    samples = friction_samples(logs, dynamics)
    model, report = fit_friction(samples, dynamics, joints)
    seconds = time.perf_counter() - start
    return FrictionStudy(list(logs), samples, model, report, seconds, simulated, truth, robot)
