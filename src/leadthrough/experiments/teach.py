"""Teach and replay on the twin: recording a guided session, replaying a recording."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from leadthrough.control.lead_through import LeadThrough
from leadthrough.control.replay import Replayer, plan_replay, replay_errors
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.runtime.recording import SessionRecorder, read_recording
from leadthrough.twin.operator import During
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.runner import SimulationResult, simulate
from leadthrough.twin.scenarios import scenario
from leadthrough.twin.simulator import DigitalTwin


class RecordingController:
    """Runs a LeadThrough and records every period taught, and the supervisor's events.

    The start-up calibration's motion is not part of what was taught: it is not recorded.
    """

    def __init__(self, controller: LeadThrough, recorder: SessionRecorder) -> None:
        self.controller, self.recorder = controller, recorder
        self._time, self._events = 0.0, 0

    def step(self, q: FloatArray, qd: FloatArray, tau_measured: FloatArray) -> FloatArray:
        """Control and record one period."""
        command = self.controller.step(q, qd, tau_measured)
        c = self.controller
        if not c.calibrating:
            self.recorder.record(self._time, q, qd, tau_measured, c.tau_ext_hat, c.std, c.mode,
                                 c.state.value)  # fmt: skip
        for event in c.supervisor.events[self._events :]:
            self.recorder.event(event.t, event.kind, event.detail)
        self._events = len(c.supervisor.events)
        self._time += c.dt
        return command


def teach_on_twin(
    robot: RobotDescription,
    out: Path,
    path: str = "line",
    mode: str = "active",
    duration: float | None = None,
    friction_file: Path | None = None,
    seed: int = 0,
) -> str:
    """A simulated hand guides the twin along ``path``; record it to ``out``; a summary."""
    friction = FrictionModel.load(friction_file) if friction_file else None
    chosen = scenario(path, robot, replace(REALISTIC_TWIN, seed=seed))
    controller = LeadThrough(robot, mode, chosen.config.control_dt, friction)
    grab = controller.calibration_time  # the hand grabs the arm once it is ready
    twin = DigitalTwin(robot, chosen.config, During(chosen.operator, grab), chosen.q0)
    out.parent.mkdir(parents=True, exist_ok=True)
    with SessionRecorder(out, robot, {"mode": mode, "path": path, "dt": twin.dt}) as recorder:
        sim = simulate(twin, RecordingController(controller, recorder),
                       grab + (duration or chosen.duration))  # fmt: skip
    force = sim.operator_force
    return (f"taught '{path}' in {mode} mode: {len(sim.t)} samples, operator force RMS "
            f"{np.sqrt(np.mean(force**2)):.2f} N (peak {force.max():.1f} N), supervisor "
            f"{controller.state.value}\nrecording: {out}")  # fmt: skip


def replay_recording(
    robot: RobotDescription,
    t: FloatArray,
    q: FloatArray,
    friction: FrictionModel | None,
    twin_config: object,
    time_scale: float = 1.0,
) -> tuple[SimulationResult, dict, Replayer]:
    """Plan and replay a recorded joint path on a twin started where the path starts."""
    from leadthrough.control.replay import ReplayParameters

    dynamics = Dynamics(robot)
    plan = plan_replay(t, q, dynamics, friction, ReplayParameters(time_scale=time_scale))
    twin = DigitalTwin(robot, twin_config, q0=q[0])
    replayer = Replayer(plan, dynamics, friction, twin.dt)
    sim = simulate(twin, replayer, plan.t[-1] + replayer.parameters.approach_time + 1.0)
    errors = replay_errors(plan, sim.q_true, sim.t, dynamics, sim.flange_position,
                           replayer.parameters.approach_time)  # fmt: skip
    return sim, errors, replayer


def replay_on_twin(recording_path: Path, out: Path, time_scale: float = 1.0, seed: int = 0) -> str:
    """Replay a recording on the twin; write a figure; a summary with the errors."""
    recording = read_recording(recording_path)
    config = replace(REALISTIC_TWIN, seed=seed + 1)
    sim, errors, _ = replay_recording(recording.robot, recording.t, recording.q, None, config,
                                      time_scale)  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    _figure(recording.robot, recording.q, sim, out / "replay.png")
    partial = "" if recording.complete else " (recovered from an unfinished recording)"
    joint, tool = 1000 * errors["joint_rms"], 1000 * errors["tool_rms"]
    return (f"replayed {recording_path}{partial}: joint RMS {joint:.2f} mrad, tool RMS "
            f"{tool:.2f} mm\nfigure: {out / 'replay.png'}")  # fmt: skip


def _figure(robot: RobotDescription, q: FloatArray, sim: SimulationResult, path: Path) -> None:
    from leadthrough.plots import pyplot

    plt = pyplot()
    dynamics = Dynamics(robot)
    taught = np.array([dynamics.pose(row)[:3, 3] for row in q])
    figure, axis = plt.subplots(figsize=(6, 5), constrained_layout=True)
    axis.plot(taught[:, 0], taught[:, 1], lw=2.5, label="recorded")
    axis.plot(sim.flange_position[:, 0], sim.flange_position[:, 1], "--", label="replayed")
    axis.set_xlabel("x [m]")
    axis.set_ylabel("y [m]")
    axis.axis("equal")
    axis.legend()
    figure.savefig(path, dpi=100)
    plt.close(figure)
