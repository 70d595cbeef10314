"""The safety settings and the bounds they give for one robot, computed once (SPEC §7)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from leadthrough.errors import ParameterError
from leadthrough.logs.log import MAX_GAP
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.validation import real


@dataclass(frozen=True)
class SafetyParameters:
    """Safety settings.

    Attributes:
        tool_speed_limit: Flange speed limit while teaching [m/s] (ISO 10218-1: 0.25).
        joint_speed_fraction: Joint speed limits as a fraction of the robot's, in (0, 1].
        braking_time: Time constant of the braking torques and of the safe-stop damping [s].
        soft_limit_margin: The walls start this far inside each hard position limit [rad].
        wall_torque_fraction: Wall torque at the hard limit, fraction of the torque limit.
        wall_damping_time: Wall damping is ``M_ii / wall_damping_time`` into the wall [s].
        stale_periods: Repeats that make a reading stale (≥ 2; 0 turns the check off, for
            noiseless mocks): a joint whose q and q̇ are bit-identical for this many
            consecutive samples while q̇ exceeds ``stale_speed`` has a frozen encoder, and
            a whole sample so repeated, the measured torques included, is stale data. An
            arm at rest repeats its (q, q̇) exactly (:class:`~.checks.FrozenEncoders`).
        stale_speed: A joint whose velocity reading exceeds this moves [rad/s] (the
            controller's ``rest_velocity``).
        torque_reading_margin: Measured torques beyond this × the torque limit are out of range.
        velocity_reading_margin: Velocities beyond this × the speed limit are out of range.
        position_reading_margin: Positions this far beyond the hard limits are out of range [rad].
        safe_stop_damping_time: Duration of the damped hold after a fault [s], then no damping.
        max_time_gap: A sample stamped more than this after the one before (or before
            it: a clock reset) is a fault [s]:
            samples lost (the arm ran on its last command meanwhile), or a clock not in
            seconds (a driver stamping milliseconds jumps 4 s a period at 250 Hz, and the
            start-up calibration's integral took it whole: a kick to the torque limits).
            Their jitter reaches 34 ms on the public UR10e logs at 100 Hz. None: no check
            (a log replayed whose gaps are rows dropped as corrupted, up to 0.46 s there).
        rate_tolerance: The samples' time stamps must advance, on average over each second
            of them (:data:`~.checks.RATE_WINDOW`), by ``dt`` within this factor either way
            [–], else a fault: a controller built for another rate than the robot's
            (:func:`~.checks.sample_rate_problem`). Checked only on stamped samples (the
            positional ``step(q, q̇, τ)`` counts periods of ``dt``). None: no check.
    """

    tool_speed_limit: float = 0.25
    joint_speed_fraction: float = 1.0
    braking_time: float = 0.05
    soft_limit_margin: float = 0.1
    wall_torque_fraction: float = 0.5
    wall_damping_time: float = 0.05
    stale_periods: int = 25
    stale_speed: float = 0.01
    torque_reading_margin: float = 1.5
    velocity_reading_margin: float = 2.0
    position_reading_margin: float = 0.1
    safe_stop_damping_time: float = 0.5
    max_time_gap: float | None = MAX_GAP
    rate_tolerance: float | None = 1.5

    def __post_init__(self) -> None:
        for name in ("tool_speed_limit", "braking_time", "soft_limit_margin", "wall_damping_time"):
            real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)
        for name in ("joint_speed_fraction", "wall_torque_fraction"):
            value = real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)
            if value > 1.0:
                raise ParameterError(name, f"must be in (0, 1], got {value:g}")
        for name in ("torque_reading_margin", "velocity_reading_margin"):
            real(name, getattr(self, name), minimum=1.0, error=ParameterError)
        real("stale_speed", self.stale_speed, minimum=0.0, strict=True, error=ParameterError)
        if self.max_time_gap is not None:
            real("max_time_gap", self.max_time_gap, minimum=0.0, strict=True,
                 error=ParameterError)  # fmt: skip
        if self.rate_tolerance is not None:
            real("rate_tolerance", self.rate_tolerance, minimum=1.0, strict=True,
                 error=ParameterError)  # fmt: skip
        for name in ("position_reading_margin", "safe_stop_damping_time"):
            real(name, getattr(self, name), minimum=0.0, error=ParameterError)
        stale = self.stale_periods
        is_integer = isinstance(stale, int | np.integer) and not isinstance(stale, bool)
        if not is_integer or stale < 0 or stale == 1:
            raise ParameterError("stale_periods", f"must be an integer ≥ 2 or 0, got {stale!r}")


@dataclass(frozen=True, eq=False)
class SafetyLimits:
    """The supervisor's bounds, computed once from the robot and the settings.

    Attributes:
        torque: Torque limits [Nm], shape (n,); ``-torque`` is ``torque_low``.
        torque_low: Lower torque limits [Nm], shape (n,).
        q_low: Position readings below this are faults [rad], shape (n,).
        q_high: Position readings above this are faults [rad], shape (n,).
        qd_bound: Velocity readings beyond ± this are faults [rad/s], shape (n,).
        tau_bound: Torque readings beyond ± this are faults [Nm], shape (n,).
        speed: Joint speed limits, braked above [rad/s], shape (n,).
        speed_low: ``-speed`` [rad/s], shape (n,).
        wall_low: The lower soft walls start below this [rad], shape (n,).
        wall_high: The upper soft walls start above this [rad], shape (n,).
        stiffness: Wall stiffness [Nm/rad], shape (n,).
        sample_low: Lower bounds of (q, q̇, τ_measured) concatenated, shape (3n,).
        sample_high: Upper bounds of (q, q̇, τ_measured) concatenated, shape (3n,).
        command_low: Lower bounds of (q, q̇, τ_desired); τ_desired need only be finite.
        command_high: Upper bounds of (q, q̇, τ_desired), shape (3n,).
    """

    torque: FloatArray
    torque_low: FloatArray
    q_low: FloatArray
    q_high: FloatArray
    qd_bound: FloatArray
    tau_bound: FloatArray
    speed: FloatArray
    speed_low: FloatArray
    wall_low: FloatArray
    wall_high: FloatArray
    stiffness: FloatArray
    sample_low: FloatArray
    sample_high: FloatArray
    command_low: FloatArray
    command_high: FloatArray

    @classmethod
    def of(cls, robot: RobotDescription, p: SafetyParameters) -> SafetyLimits:
        """The bounds for ``robot`` with the settings ``p``."""
        margin = p.position_reading_margin
        q_low, q_high = robot.q_min - margin, robot.q_max + margin
        qd_bound = p.velocity_reading_margin * robot.velocity_limits
        tau_bound = p.torque_reading_margin * robot.torque_limits
        finite = np.full(robot.n_joints, np.finfo(float).max)  # only ±inf and NaN are beyond
        return cls(
            torque=robot.torque_limits,
            torque_low=-robot.torque_limits,
            q_low=q_low,
            q_high=q_high,
            qd_bound=qd_bound,
            tau_bound=tau_bound,
            speed=p.joint_speed_fraction * robot.velocity_limits,
            speed_low=-p.joint_speed_fraction * robot.velocity_limits,
            wall_low=robot.q_min + p.soft_limit_margin,
            wall_high=robot.q_max - p.soft_limit_margin,
            stiffness=p.wall_torque_fraction * robot.torque_limits / p.soft_limit_margin,
            sample_low=np.concatenate((q_low, -qd_bound, -tau_bound)),
            sample_high=np.concatenate((q_high, qd_bound, tau_bound)),
            command_low=np.concatenate((q_low, -qd_bound, -finite)),
            command_high=np.concatenate((q_high, qd_bound, finite)),
        )

    def saturated(self, tau: FloatArray) -> FloatArray:
        """``tau`` [Nm] clipped to ± the torque limits, as a new array.

        Same result as ``np.clip`` for a finite ``tau`` (the only kind passed here), at
        a third of its cost.
        """
        return np.minimum(np.maximum(tau, self.torque_low), self.torque)
