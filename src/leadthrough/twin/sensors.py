"""What the robot's sensors and drives do to the truth: quantisation, noise, ripple, limits.

Thesis §3.1.2 and §5.2.1: the research interface of the YuMi reports joint positions
from the motor encoders (through the gearbox), joint velocities with a noise of about
1e−4 rad/s, and the motor torque actually applied; drives saturate at the torque
limits and the motors' torque ripples with the motor angle.

Interface errors of real arms, off by default (the plant sampler,
:mod:`leadthrough.twin.plants`, turns them on): a motor torque constant that differs
from the data sheet's (the drive applies ``gain · command`` and reports the torque it
believes, ``applied / gain``, plus an ``offset``), and a joint velocity obtained by
differencing the quantised encoder and low-pass filtering it, with the lag that brings.
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
        torque_gain: True over nominal motor torque constant per joint [–], shape (n,);
            None is 1 (the drive applies what is commanded and measures what it applies).
        torque_offset: Offset of the measured motor torque per joint [Nm]; None is 0.
        velocity_cutoff: Corner frequency [Hz] of the first-order low-pass on the
            differenced encoder angle; None reports the true velocity plus white noise.
        torque_sensor: Whether the drives report the torque they apply; False: a robot
            that measures none (``JointState.tau_measured`` is None).
    """

    encoder_counts: int = 2**14
    velocity_noise_std: float = 1e-4
    torque_noise_std: float = 0.005
    torque_ripple: float = 0.02
    ripple_periods_per_motor_turn: int = 6
    torque_gain: tuple[float, ...] | None = None
    torque_offset: tuple[float, ...] | None = None
    velocity_cutoff: float | None = None
    torque_sensor: bool = True

    def __post_init__(self) -> None:
        real("encoder_counts", self.encoder_counts, minimum=1.0)
        real("velocity_noise_std", self.velocity_noise_std, minimum=0.0)
        real("torque_noise_std", self.torque_noise_std, minimum=0.0)
        real("torque_ripple", self.torque_ripple, minimum=0.0)
        for gain in self.torque_gain or ():
            real("torque_gain", gain, minimum=0.0, strict=True)
        if self.velocity_cutoff is not None:
            real("velocity_cutoff", self.velocity_cutoff, minimum=0.0, strict=True)

    def quantum(self, robot: RobotDescription) -> FloatArray:
        """Joint-side encoder resolution [rad], shape (n,)."""
        return 2.0 * np.pi / (self.encoder_counts * np.abs(robot.gear_ratios))


class Drives:
    """Torque path of the drives: saturation at the limits, then ripple with motor angle."""

    def __init__(self, robot: RobotDescription, model: SensorModel) -> None:
        self.limits = robot.torque_limits
        self._low = -self.limits
        self.harmonic = model.ripple_periods_per_motor_turn * robot.gear_ratios
        self.ripple = model.torque_ripple
        self.gain = np.ones(robot.n_joints) if model.torque_gain is None else np.array(
            model.torque_gain)  # fmt: skip
        self._gain_error = bool(np.any(self.gain != 1.0))

    def applied(self, command: FloatArray, q: FloatArray) -> FloatArray:
        """Motor torque reaching the joints [Nm] for ``command`` at joint angles ``q``."""
        saturated = np.minimum(np.maximum(command, self._low), self.limits)  # np.clip, faster
        if self._gain_error:  # × 1 changes no bits: skipped for exact drives
            saturated = saturated * self.gain
        return saturated * (1.0 + self.ripple * np.sin(self.harmonic * q))


class Sensors:
    """Turn true joint states into what the robot reports (seeded noise)."""

    def __init__(
        self,
        robot: RobotDescription,
        model: SensorModel,
        rng: np.random.Generator,
        dt: float = 0.004,
    ) -> None:
        self.model = model
        self.quantum = model.quantum(robot)
        self.rng = rng
        self.n = robot.n_joints
        self.gain = np.ones(self.n) if model.torque_gain is None else np.array(model.torque_gain)
        self.offset = np.zeros(self.n) if model.torque_offset is None else np.array(
            model.torque_offset)  # fmt: skip
        self.dt = dt
        # / 1 + 0 changes no bits: skipped for drives without a torque constant error
        self._interface_error = bool(np.any(self.gain != 1.0) or np.any(self.offset != 0.0))
        self.reset()

    def reset(self) -> None:
        """Forget the velocity filter's state (the next reading starts it at rest)."""
        self._last_q: FloatArray | None = None
        self._velocity = np.zeros(self.n)

    def joint_position(self, q_true: FloatArray) -> FloatArray:
        """Encoder reading: the true angle rounded to the joint-side quantum [rad]."""
        return np.rint(q_true / self.quantum) * self.quantum  # np.round's bits, less overhead

    def joint_velocity(self, qd_true: FloatArray, q_true: FloatArray | None = None) -> FloatArray:
        """Reported velocity [rad/s], one call per control period ``dt``.

        Without ``velocity_cutoff``: the true one plus white noise. With it: the encoder
        reading of ``q_true`` differenced over ``dt`` and low-passed (first order), so it
        lags the truth by about ``dt / 2 + 1 / (2π f_c)``, plus the same white noise.
        (Without that noise a resting arm reports q and q̇ bit-identical period after
        period, as a real one may (the UR10e's logs do); the safety supervisor takes that
        for rest, not for a frozen encoder (:class:`~leadthrough.safety.checks.FrozenEncoders`).)
        """
        noise = self.rng.normal(0.0, self.model.velocity_noise_std, self.n)
        cutoff = self.model.velocity_cutoff
        if cutoff is None or q_true is None:
            return qd_true + noise
        q = self.joint_position(q_true)
        if self._last_q is not None:
            alpha = self.dt / (self.dt + 1.0 / (2.0 * np.pi * cutoff))
            self._velocity += alpha * ((q - self._last_q) / self.dt - self._velocity)
        self._last_q = q
        return self._velocity + noise

    def motor_torque(self, tau_applied: FloatArray) -> FloatArray:
        """Measured motor torque [Nm]: what the drive believes it applies, plus white noise.

        ``applied / torque_gain + torque_offset`` (the applied torque with the nominal
        torque constants and no offset).
        """
        believed = tau_applied / self.gain + self.offset if self._interface_error else tau_applied
        return believed + self.rng.normal(0.0, self.model.torque_noise_std, self.n)
