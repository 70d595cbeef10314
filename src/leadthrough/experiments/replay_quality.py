"""Replay on the guiding benchmark's plant family: does the tracking hold on unseen arms?

The replay's tracking (``control/replay.py``) was first measured on the reference twin
only. Here a taught path (:func:`taught_path`: minimum-jerk moves between four poses around
home, two pauses, every joint 0.2–0.4 rad) is planned on the nominal model and replayed on
each plant of ``benchmarks/guiding_quality.py`` (:func:`~leadthrough.twin.plants.sample_plant`:
masses, friction physics and levels, delays of 1–2 periods, a velocity low-passed at
15–40 Hz, drive gains and offsets), starting at the path's start, at the control period
``dt``. Figures per plant: whether the supervisor faulted, the joint and tool-path RMS and
largest errors while the path runs (:func:`~leadthrough.control.replay.replay_errors`), and
the fastest joint [rad/s].
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from leadthrough.control.replay import Replayer, ReplayParameters, plan_replay, replay_errors
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.safety.supervisor import SupervisorState
from leadthrough.trajectories import minimum_jerk_phase
from leadthrough.twin.plants import sample_plant
from leadthrough.twin.runner import simulate
from leadthrough.twin.sensors import SensorModel
from leadthrough.twin.simulator import DigitalTwin

#: The taught path's pieces: rest, move, pause, move, pause, move, rest [s] (6 s in all).
PIECES = (("rest", 0.2), ("move", 1.5), ("rest", 0.5), ("move", 1.5), ("rest", 0.5),
          ("move", 1.6), ("rest", 0.2))  # fmt: skip
#: How far and which way each joint moves in the taught path [rad] (the YuMi's seven joints;
#: another arm's take them in turn).
STROKES = (0.3, -0.25, 0.4, 0.3, -0.35, 0.3, -0.2)


@dataclass(frozen=True)
class ReplayFigures:
    """How one replay on one plant went.

    Attributes:
        plant: ``"dry #1"`` and the like.
        delay: The plant's delay [periods].
        faulted: Whether the supervisor latched a fault.
        joint_rms: Joint RMS error while the path runs [rad].
        joint_max: Largest joint error there [rad].
        tool_rms: Flange path RMS error there [m].
        peak_speed: Fastest joint during the whole run [rad/s].
    """

    plant: str
    delay: int
    faulted: bool
    joint_rms: float
    joint_max: float
    tool_rms: float
    peak_speed: float


def taught_path(robot: RobotDescription, dt: float = 0.004) -> tuple[FloatArray, FloatArray]:
    """A 6 s taught path sampled every ``dt`` [s]: times [s] and joint angles [rad].

    Minimum-jerk moves between four poses around home (the first ``n`` of
    :data:`STROKES`, at most 0.15 of each joint's range), read through the twin's encoder
    quantisation.
    """
    n, home = robot.n_joints, robot.home()
    strokes = np.resize(np.asarray(STROKES), n)
    strokes = np.sign(strokes) * np.minimum(np.abs(strokes), 0.15 * (robot.q_max - robot.q_min))
    poses = [home - strokes / 2, home + strokes / 2, home - strokes / 4 * (-1.0) ** np.arange(n),
             home + strokes / 3]  # fmt: skip
    t = np.arange(round(sum(duration for _, duration in PIECES) / dt) + 1) * dt
    q, start, pose = np.empty((len(t), n)), 0.0, 0
    for kind, duration in PIECES:
        inside = (t >= start - 1e-9) & (t < start + duration - 1e-9)
        if kind == "move":
            phase, _ = minimum_jerk_phase(t[inside] - start, duration)
            q[inside] = poses[pose] + np.outer(phase, poses[pose + 1] - poses[pose])
            pose += 1
        else:
            q[inside] = poses[pose]
        start += duration
    q[t >= start - 1e-9] = poses[-1]
    quantum = SensorModel().quantum(robot)
    return t, np.round(q / quantum) * quantum


def replay_on_plant(
    robot: RobotDescription,
    seed: int,
    physics: str,
    dt: float = 0.004,
    parameters: ReplayParameters | None = None,
) -> ReplayFigures:
    """Replay :func:`taught_path` on the guiding benchmark's plant ``physics`` #``seed``.

    Planned on the nominal model with the description's friction, replayed at the period
    ``dt`` [s] from the path's start.
    """
    dynamics = Dynamics(robot)
    t, q = taught_path(robot)
    plan = plan_replay(t, q, dynamics, parameters=parameters)
    plant = sample_plant(robot, seed, physics)
    twin = DigitalTwin(robot, replace(plant.config, control_dt=dt), q0=q[0])
    replayer = Replayer(plan, dynamics, dt=twin.dt)
    run = simulate(twin, replayer, plan.parameters.approach_time + plan.duration + 0.6,
                   progress=False)  # fmt: skip
    errors = replay_errors(plan, run.q_true, run.t, dynamics, run.flange_position)
    return ReplayFigures(
        plant=f"{physics} #{seed}",
        delay=plant.config.delay_periods,
        faulted=replayer.supervisor.state is SupervisorState.FAULT,
        joint_rms=errors["joint_rms"],
        joint_max=errors["joint_max"],
        tool_rms=errors["tool_rms"],
        peak_speed=float(np.abs(run.qd_true).max()),
    )
