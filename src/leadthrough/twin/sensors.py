"""What the robot's sensors and drives do to the truth: quantisation, noise, ripple, limits.

Thesis §3.1.2 and §5.2.1: the research interface of the YuMi reports joint positions
from the motor encoders (through the gearbox), joint velocities with a noise of about
1e−4 rad/s, and the motor torque actually applied; drives saturate at the torque
limits and the motors' torque ripples with the motor angle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.validation import real


@dataclass(frozen=True)
class SensorModel:
    """Imperfections of the sensors and drives.

    Attributes:
        encoder_counts: Encoder counts per motor revolution; the joint quantum is
            2π / (counts · |gear ratio|) [rad] (2¹⁴ counts and a gear of 100 give 3.8 µrad).
        velocity_noise_std: White noise on the reported joint velocity [rad/s]
            (thesis §5.2.1: 1e−4).
        torque_noise_std: White noise on the measured motor torque, arm side [Nm].
        torque_ripple: Relative amplitude of the motor torque ripple [–].
        ripple_periods_per_motor_turn: Ripple harmonic per motor revolution [–].
    """

    encoder_counts: int = 2**14
    velocity_noise_std: float = 1e-4
    torque_noise_std: float = 0.005
    torque_ripple: float = 0.02
    ripple_periods_per_motor_turn: int = 6

    def __post_init__(self) -> None:
        real("encoder_counts", self.encoder_counts, minimum=1.0)
        real("velocity_noise_std", self.velocity_noise_std, minimum=0.0)
        real("torque_noise_std", self.torque_noise_std, minimum=0.0)
        real("torque_ripple", self.torque_ripple, minimum=0.0)

    def quantum(self, robot: RobotDescription) -> FloatArray:
        """Joint-side encoder resolution [rad], shape (n,)."""
        return 2.0 * np.pi / (self.encoder_counts * np.abs(robot.gear_ratios))


class Drives:
    """Torque path of the drives: saturation at the limits, then ripple with motor angle."""

    def __init__(self, robot: RobotDescription, model: SensorModel) -> None:
        self.limits = robot.torque_limits
        self.harmonic = model.ripple_periods_per_motor_turn * robot.gear_ratios
        self.ripple = model.torque_ripple

    def applied(self, command: FloatArray, q: FloatArray) -> FloatArray:
        """Motor torque reaching the joints [Nm] for ``command`` at joint angles ``q``."""
        saturated = np.clip(command, -self.limits, self.limits)
        return saturated * (1.0 + self.ripple * np.sin(self.harmonic * q))


class Sensors:
    """Turn true joint states into what the robot reports (seeded noise)."""

    def __init__(self, robot: RobotDescription, model: SensorModel, rng: np.random.Generator):
        self.model = model
        self.quantum = model.quantum(robot)
        self.rng = rng
        self.n = robot.n_joints

    def joint_position(self, q_true: FloatArray) -> FloatArray:
        """Encoder reading: the true angle rounded to the joint-side quantum [rad]."""
        return np.round(q_true / self.quantum) * self.quantum

    def joint_velocity(self, qd_true: FloatArray) -> FloatArray:
        """Reported velocity: the true one plus white noise [rad/s]."""
        return qd_true + self.rng.normal(0.0, self.model.velocity_noise_std, self.n)

    def motor_torque(self, tau_applied: FloatArray) -> FloatArray:
        """Measured motor torque: the applied one plus white noise [Nm]."""
        return tau_applied + self.rng.normal(0.0, self.model.torque_noise_std, self.n)
