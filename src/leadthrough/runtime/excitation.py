"""The friction identification experiment of thesis §4.1.1, on any robot interface.

One joint at a time moves back and forth with a triangular velocity (a square-wave
acceleration) while the others hold their pose; the log keeps what a real robot
gives: time, joint readings, velocities and the measured motor torque. Two runs per
joint by default: the thesis' slow one (0.2 rad/s, 0.1 Hz) and a faster, wider one
whose stroke spans much of the joint range, for viscous friction and the position
dependence of the Coulomb level (§4.1.3). Runs are centred on the middle of the joint
range. Between runs the joint moves to the next start with a minimum-jerk motion.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from leadthrough.control.tracking import BANDWIDTH, JointTracker, pd_gains, period_bandwidth
from leadthrough.errors import ParameterError
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics
from leadthrough.progress import Progress
from leadthrough.runtime.interface import RobotInterface
from leadthrough.trajectories import (
    minimum_jerk_acceleration,
    minimum_jerk_phase,
    triangular_velocity,
)
from leadthrough.validation import real


@dataclass(frozen=True)
class ExcitationRun:
    """One triangular-velocity run of a joint.

    Attributes:
        peak_velocity: Peak joint speed v̂ [rad/s].
        frequency: Frequency of the velocity wave f [Hz]; 0 chooses the one that makes
            the stroke ``max_stroke`` (a fraction of the joint range).
        cycles: Number of back-and-forth cycles [–].
        max_stroke: Largest stroke as a fraction of the joint range [–].
    """

    peak_velocity: float = 0.2
    frequency: float = 0.1
    cycles: int = 2
    max_stroke: float = 0.5

    def __post_init__(self) -> None:
        real("peak_velocity", self.peak_velocity, minimum=0.0, strict=True, error=ParameterError)
        real("frequency", self.frequency, minimum=0.0, error=ParameterError)
        real("cycles", self.cycles, minimum=1.0, error=ParameterError)
        real("max_stroke", self.max_stroke, minimum=0.0, strict=True, error=ParameterError)

    def frequency_for(self, joint_range: float) -> float:
        """Frequency [Hz] on a joint of ``joint_range`` [rad]: stroke ≤ ``max_stroke``."""
        slowest = self.peak_velocity / (4.0 * self.max_stroke * joint_range)
        return max(self.frequency, slowest)


#: The thesis' run and a faster, wider one.
DEFAULT_RUNS = (
    ExcitationRun(peak_velocity=0.2, frequency=0.1, cycles=2),
    ExcitationRun(peak_velocity=0.6, frequency=0.0, cycles=1, max_stroke=0.45),
)


@dataclass(frozen=True, eq=False)
class ExcitationLog:
    """What the robot reported during one run (arrays of N samples).

    Attributes:
        joint: The excited joint (0-based).
        label: Name of the run.
        t: Time [s], (N,).
        q: Joint readings [rad], (N, n).
        qd: Joint velocities [rad/s], (N, n).
        tau: Measured motor torque, arm side [Nm], (N, n).
    """

    joint: int
    label: str
    t: FloatArray
    q: FloatArray
    qd: FloatArray
    tau: FloatArray


def excite_joint(
    robot: RobotInterface,
    dynamics: Dynamics,
    joint: int,
    run: ExcitationRun,
    hold: FloatArray,
    progress: Progress | None = None,
) -> ExcitationLog:
    """Move to the start of ``run`` on ``joint``, then log one run centred mid-range.

    Args:
        robot: The robot (twin or hardware) to excite.
        dynamics: Model for the tracking feed-forward.
        joint: Joint to move (0-based); the others hold ``hold``.
        run: The velocity wave.
        hold: Pose of the other joints [rad].
        progress: Optional progress bar, advanced in simulated seconds.
    """
    description = dynamics.robot
    low, high = description.q_min[joint], description.q_max[joint]
    frequency = run.frequency_for(high - low)
    stroke = run.peak_velocity / (4.0 * frequency)
    start = hold.copy()
    start[joint] = 0.5 * (low + high) - 0.5 * stroke
    tracker = JointTracker(dynamics, period_bandwidth(BANDWIDTH, robot.dt, pd_gains()))
    _move_to(robot, tracker, start, progress)
    return _run_wave(robot, tracker, joint, run, frequency, start, progress)


def _move_to(
    robot: RobotInterface, tracker: JointTracker, goal: FloatArray, progress: Progress | None
) -> None:
    """Minimum-jerk joint motion from the current pose to ``goal``, then a short settle."""
    state = robot.read_state()
    origin = state.q.copy()
    duration = max(1.0, 2.5 * float(np.max(np.abs(goal - origin))))  # ≤ 0.75 rad/s peak
    steps = round((duration + 0.5) / robot.dt)
    for k in range(steps):
        t = k * robot.dt
        phase, rate = minimum_jerk_phase(t, duration)
        delta = goal - origin
        command = tracker.torque(state.q, state.qd, origin + phase * delta, rate * delta,
                                 minimum_jerk_acceleration(t, duration) * delta)  # fmt: skip
        robot.send_torque(command)
        state = robot.read_state()
        if progress:
            progress.advance(robot.dt)


def _run_wave(
    robot: RobotInterface,
    tracker: JointTracker,
    joint: int,
    run: ExcitationRun,
    frequency: float,
    start: FloatArray,
    progress: Progress | None,
) -> ExcitationLog:
    """Follow the triangular velocity on ``joint`` for ``run.cycles`` periods, logging."""
    steps = round(run.cycles / frequency / robot.dt)
    log: dict[str, list[float | FloatArray]] = {"t": [], "q": [], "qd": [], "tau": []}
    q_ref, qd_ref, qdd_ref = start.copy(), np.zeros_like(start), np.zeros_like(start)
    state = robot.read_state()
    t0 = state.t
    for k in range(steps):
        offset, velocity, acceleration = triangular_velocity(k * robot.dt, run.peak_velocity,
                                                             frequency)  # fmt: skip
        q_ref[joint], qd_ref[joint], qdd_ref[joint] = start[joint] + offset, velocity, acceleration
        robot.send_torque(tracker.torque(state.q, state.qd, q_ref, qd_ref, qdd_ref))
        state = robot.read_state()
        tau = state.tau_measured
        if tau is None:
            raise ParameterError("robot", "stopped measuring its torques during an excitation")
        for name, value in (("t", state.t - t0), ("q", state.q), ("qd", state.qd), ("tau", tau)):
            log[name].append(value)
        if progress:
            progress.advance(robot.dt)
    label = f"joint {joint + 1}, {run.peak_velocity:g} rad/s at {frequency:.3g} Hz"
    return ExcitationLog(joint, label, **{name: np.array(values) for name, values in log.items()})


def plan_duration(
    dynamics: Dynamics, joints: Sequence[int], runs: Sequence[ExcitationRun]
) -> float:
    """Upper estimate of the simulated time of :func:`friction_experiment` [s]."""
    robot = dynamics.robot
    total = 0.0
    for joint in joints:
        joint_range = robot.q_max[joint] - robot.q_min[joint]
        for run in runs:
            total += run.cycles / run.frequency_for(joint_range) + 0.5 + max(1.0, 2.5 * joint_range)
    return total


def friction_experiment(
    robot: RobotInterface,
    dynamics: Dynamics,
    joints: Sequence[int] | None = None,
    runs: Sequence[ExcitationRun] = DEFAULT_RUNS,
    progress: bool | None = None,
) -> list[ExcitationLog]:
    """Excite each joint in turn with each run; the others hold the home pose.

    Args:
        robot: The robot (twin or hardware).
        dynamics: Model of the robot for the tracking feed-forward.
        joints: Joints to excite (0-based; default all).
        runs: Velocity waves per joint.
        progress: Show a progress bar (default: when stderr is a terminal).

    Returns:
        One log per (joint, run), in order.
    """
    joints = list(range(robot.n_joints)) if joints is None else list(joints)
    home = dynamics.robot.home()
    bar = Progress(plan_duration(dynamics, joints, runs), "exciting joints", enabled=progress)
    logs = []
    for joint in joints:
        for run in runs:
            logs.append(excite_joint(robot, dynamics, joint, run, home, bar))
    bar.close()
    return logs
