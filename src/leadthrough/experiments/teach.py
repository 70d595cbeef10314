"""Teach and replay on the twin: recording a guided session, replaying a recording.

Work is bounded: a session or a replay simulates at most :data:`MAX_SECONDS`, and a replay's
time scale lies in :data:`TIME_SCALE_RANGE`. Nothing is partial in silence: teaching without
identified friction warns, and a recording recovered from a damaged or unfinished file is
replayed only when asked for (``partial=True``).
"""

from __future__ import annotations

import signal
import threading
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np

from leadthrough.control.lead_through import LeadThrough
from leadthrough.control.replay import Replayer, plan_replay, replay_errors
from leadthrough.errors import ParameterError, RecordingError
from leadthrough.experiments.bounds import MAX_SECONDS, TIME_SCALE_RANGE
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.runtime.interface import JointState
from leadthrough.runtime.recording import Recording, SessionRecorder, read_recording
from leadthrough.runtime.teaching import TeachingSession
from leadthrough.twin.operator import During
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.runner import SimulationResult, simulate
from leadthrough.twin.scenarios import scenario
from leadthrough.twin.simulator import DigitalTwin
from leadthrough.validation import real


class UnidentifiedFrictionWarning(UserWarning):
    """Teaching uses the robot file's nominal friction, not an identified model."""


class RecordingController(TeachingSession):
    """A :class:`~leadthrough.runtime.teaching.TeachingSession` that Ctrl-C ends between periods.

    The start-up calibration's motion is not part of what was taught: it is not recorded.
    """

    def __init__(self, controller: LeadThrough, recorder: SessionRecorder) -> None:
        super().__init__(controller, recorder)
        self.interrupted = False  # set by Ctrl-C: the next period stops the session

    def step(self, state: JointState) -> FloatArray:
        """Control and record one period.

        Raises:
            KeyboardInterrupt: :attr:`interrupted` was set (Ctrl-C): raised between two periods,
                so that every period recorded is whole.
        """
        if self.interrupted:
            raise KeyboardInterrupt
        return super().step(state)


def teach_on_twin(
    robot: RobotDescription,
    out: Path,
    path: str = "line",
    mode: str = "active",
    duration: float | None = None,
    friction_file: Path | None = None,
    seed: int = 0,
    *,
    overwrite: bool = False,
) -> str:
    """A simulated hand guides the twin along ``path``; record it to ``out``; a summary.

    Args:
        robot: The arm taught.
        out: The recording to write (MCAP).
        path: Scenario the simulated hand follows: ``line``, ``circle`` or ``point_to_point``.
        mode: ``active`` or ``passive`` lead-through.
        duration: Seconds taught after the start-up calibration, in (0, MAX_SECONDS]
            (default: the path's).
        friction_file: Identified friction (TOML); without it the robot file's nominal
            friction is used and an :class:`UnidentifiedFrictionWarning` says so.
        seed: Seed of the twin's noise.
        overwrite: Replace an existing recording ``out`` (else a RecordingError).

    Raises:
        KeyboardInterrupt: Ctrl-C; the message says where the (complete) recording of what was
            taught until then is.
    """
    if duration is not None:
        real("duration", duration, minimum=0.0, strict=True, error=ParameterError)
        _at_most("duration", duration, MAX_SECONDS)
    if out.exists() and not overwrite:
        raise RecordingError(str(out), "exists; pass overwrite=True (--force) to replace it")
    friction = FrictionModel.load(friction_file) if friction_file else None
    if friction is None:
        warnings.warn(f"no identified friction: teaching {robot.name} with its file's nominal "
                      "friction, which makes guiding heavier; identify it first (leadthrough "
                      "identify) and pass the friction.toml (--friction)",
                      UnidentifiedFrictionWarning, stacklevel=2)  # fmt: skip
    chosen = scenario(path, robot, replace(REALISTIC_TWIN, seed=seed))
    controller = LeadThrough(robot, mode, chosen.config.control_dt, friction, calibrate=True)
    grab = controller.calibration_time  # the hand grabs the arm once it is ready
    twin = DigitalTwin(robot, chosen.config, During(chosen.operator, grab), chosen.q0)
    out.parent.mkdir(parents=True, exist_ok=True)
    with SessionRecorder(out, robot, {"mode": mode, "path": path, "dt": twin.dt}) as recorder:
        recording = RecordingController(controller, recorder)
        # the file's close too: a second Ctrl-C while it closed left a .part behind
        with _stop_on_ctrl_c(recording):
            try:
                sim = simulate(twin, recording, grab + (duration or chosen.duration))
            except KeyboardInterrupt:
                recording.interrupted = True
            if recording.interrupted:  # the control loop may also end normally on Ctrl-C
                recorder.event(recording.time, "interrupted", "Ctrl-C: the session was ended")
            recorder.close()
    if recording.recorded == 0:  # an empty file would only block the next --out
        out.unlink(missing_ok=True)
    if recording.interrupted:
        raise KeyboardInterrupt(_interrupted(out, recording.recorded, controller.dt))
    if recording.recorded == 0:
        events = controller.supervisor.events
        why = events[-1].detail if events else "the session ended before the calibration did"
        raise RecordingError(str(out), f"nothing was taught or recorded ({why}); no file "
                             "written")  # fmt: skip
    force, supervisor = sim.operator_force, controller.supervisor
    if supervisor.fault_reason is not None:  # the arm was held from then on: say so
        faults = [event for event in supervisor.events if event.kind == "fault"]
        when = f" at {faults[0].t:.2f} s" if faults else ""
        warnings.warn(f"the supervisor stopped the arm{when}: {supervisor.fault_reason}; the "
                      f"recording holds the safe stop from then on", stacklevel=2)  # fmt: skip
    return (f"taught '{path}' in {mode} mode: {recording.recorded} samples, operator force RMS "
            f"{np.sqrt(np.mean(force**2)):.2f} N (peak {force.max():.1f} N), supervisor "
            f"{controller.state.value}\nrecording: {out}")  # fmt: skip


def _at_most(name: str, value: float, limit: float) -> None:
    if value > limit:
        raise ParameterError(name, f"at most {limit:g} s of simulation, got {value:.4g} s")


@contextmanager
def _stop_on_ctrl_c(recording: RecordingController) -> Iterator[None]:
    """Ctrl-C stops the session between two periods (in the main thread; elsewhere as usual)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def stop(signum: int, frame: object) -> None:
        recording.interrupted = True

    previous = signal.signal(signal.SIGINT, stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _interrupted(out: Path, recorded: int, dt: float) -> str:
    if recorded == 0:
        return f"during the start-up calibration: nothing was taught, no file written ({out})"
    return f"the {recorded * dt:.1f} s taught so far are recorded, complete, in {out}"


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
                           replayer.approach_time)  # fmt: skip
    return sim, errors, replayer


def replay_on_twin(
    recording_path: Path,
    out: Path,
    time_scale: float = 1.0,
    seed: int = 0,
    *,
    partial: bool = False,
) -> str:
    """Replay a recording on the twin; write a figure; a summary with the errors.

    Args:
        recording_path: The recording (MCAP).
        out: Directory of the figure.
        time_scale: Replay duration over taught duration, within TIME_SCALE_RANGE; the replay
            simulates at most MAX_SECONDS.
        partial: Replay what was recovered of an unfinished or damaged recording (else such a
            recording is a RecordingError that says how much of it was recovered).
        seed: Seed of the twin's noise (the twin runs with ``seed + 1``).
    """
    low, high = TIME_SCALE_RANGE
    real("time_scale", time_scale, minimum=low, error=ParameterError)
    if time_scale > high:
        raise ParameterError("time_scale", f"must be at most {high:g}, got {time_scale:g}")
    recording = read_recording(recording_path)
    if not recording.complete and not partial:
        raise RecordingError(str(recording_path), f"{recording.recovery}; replay what was "
                             "recovered with --partial (partial=True)")  # fmt: skip
    t, q, cut = _until_a_fault(recording)
    if len(t) < 2:
        raise RecordingError(str(recording_path), f"holds {len(t)} samples{cut}: nothing "
                             "to replay")  # fmt: skip
    _at_most("replay", time_scale * float(t[-1] - t[0]), MAX_SECONDS)
    config = replace(REALISTIC_TWIN, seed=seed + 1)
    sim, errors, replayer = replay_recording(recording.robot, t, q, None, config, time_scale)
    out.mkdir(parents=True, exist_ok=True)
    _figure(recording.robot, recording.q, sim, out / "replay.png")
    partial = ("" if recording.complete else f" ({recording.recovery})") + cut
    joint, tool = 1000 * errors["joint_rms"], 1000 * errors["tool_rms"]
    return (f"replayed {recording_path}{partial}: joint RMS {joint:.2f} mrad, tool RMS "
            f"{tool:.2f} mm\n{_safety(replayer, sim, recording.robot)}\n"
            f"figure: {out / 'replay.png'}")  # fmt: skip


def _safety(replayer: Replayer, sim: SimulationResult, robot: RobotDescription) -> str:
    """One line: what the supervisor did during the replay, and the largest torque used.

    A replay the supervisor braked or held off a soft limit, or one at its torque limit,
    does not follow the plan: its errors say how far, this line says why (a UR5 replayed at
    its shortest time scale ran joint 4 at 3.58 rad/s, 12 % over its limit, braked, with
    "joint RMS 4.07 mrad" printed alone).
    """
    events = [e for e in replayer.supervisor.events if e.kind not in ("mode", "reset")]
    used = np.max(np.abs(sim.tau_command) / robot.torque_limits, axis=0)
    joint = int(np.argmax(used))
    torque = f"largest torque {used[joint]:.0%} of joint {joint + 1}'s limit"
    if not events:
        return f"safety: no event, {torque}"
    kinds = ", ".join(sorted({event.kind for event in events}))
    count = f"{len(events)} event{'s' if len(events) > 1 else ''}"
    return f"safety: {count} ({kinds}; first: {events[0].detail}), {torque}"


def _until_a_fault(recording: Recording) -> tuple[FloatArray, FloatArray, str]:
    """(t, q) taught before the supervisor's first fault, and what was cut ("" if nothing).

    After a fault the recording holds the safe stop, not what the hand taught: replayed, it
    was a path nobody guided (0.26 rad of motion under the stop, replayed silently).
    """
    faulted = np.flatnonzero(np.asarray(recording.state) == "fault")
    if faulted.size == 0:
        return recording.t, recording.q, ""
    first = int(faulted[0])
    when = float(recording.t[first] - recording.t[0])
    return (
        recording.t[:first],
        recording.q[:first],
        f" (up to its fault at {when:.2f} s: the safe stop after it is not replayed)",
    )


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
