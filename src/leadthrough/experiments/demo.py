"""``leadthrough demo``: the product end to end on the simulated YuMi.

1. identify the friction of the twin (the experiment of thesis §4.1.1);
2. a simulated operator teaches a path with active lead-through: guiding, a pause, a
   circle, a press on a table; the session is recorded (MCAP) as it happens;
3. the recording is read back, planned (filtered, pauses as waypoints, limits checked)
   and replayed on the twin;
4. a Markdown report with figures is written.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from leadthrough.control.lead_through import LeadThrough
from leadthrough.experiments.friction_study import run_friction_study
from leadthrough.experiments.guiding import tool_vibration, vibration_within
from leadthrough.experiments.teach import RecordingController, replay_recording
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.runtime.recording import SessionRecorder, read_recording
from leadthrough.twin.operator import Hand
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.runner import SimulationResult, simulate
from leadthrough.twin.session_operator import Action, ScriptedOperator, TeachingSession
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

#: What the simulated operator does while teaching (times in s).
TEACHING_SECONDS = 22.0


def teaching_actions(robot: RobotDescription) -> list[Action]:
    """Guide the tool 15 cm, pause, draw a circle, press on the table, lift it back."""
    session = TeachingSession()
    every = {action.label: action for action in session.actions(robot)}
    line, circle = every["pull the tool 15 cm"], every["draw a circle"]
    press, lift = every["press the tool on the table"], every["lift the tool back"]
    return [
        replace(line, start=1.5, stop=5.0),  # after the 1.3 s start-up calibration
        replace(circle, start=6.5, stop=13.5),
        replace(press, start=14.0, stop=18.0),
        replace(lift, start=18.5, stop=21.5),
    ]


@dataclass(frozen=True, eq=False)
class DemoResult:
    """Everything the report shows.

    Attributes:
        friction: The identified friction model.
        taught: The teaching run on the twin (ground truth included).
        passive: The same session guided in passive mode (not recorded): what the
            operator would have felt and taught without the observer in the loop.
        estimate: Recorded estimate of the operator torque [Nm], (N, n).
        estimate_std: Its standard deviation [Nm], (N, n).
        events: Supervisor events (t, kind, detail).
        replayed: The replay run on the twin.
        replay_error: Replay errors (joint RMS [rad], tool RMS [m], ...).
        recording_path: Where the session was recorded.
        seconds: Wall time of each stage [s].
    """

    friction: FrictionModel
    taught: SimulationResult
    passive: SimulationResult
    estimate: FloatArray
    estimate_std: FloatArray
    events: list
    replayed: SimulationResult
    replay_error: dict
    recording_path: Path
    seconds: dict[str, float]


def run_demo(out: Path, robot: RobotDescription, config: TwinConfig = REALISTIC_TWIN,
             say=print) -> DemoResult:  # fmt: skip
    """Identify, teach (recorded), replay; return what the report needs."""
    out.mkdir(parents=True, exist_ok=True)
    seconds: dict[str, float] = {}
    clock = time.perf_counter()
    say("1/4 identifying the friction of the twin (thesis §4.1.1) …")
    friction = run_friction_study(robot, twin_config=config, progress=True).model
    friction.save(out / "friction.toml")
    seconds["identification"] = time.perf_counter() - clock

    clock = time.perf_counter()
    say("2/4 a simulated operator teaches a path with active lead-through (recorded) …")
    table = TeachingSession().table(robot)
    teach_config = replace(config, table=table)
    twin = DigitalTwin(robot, teach_config, ScriptedOperator(teaching_actions(robot)))
    path = out / "session.mcap"
    controller = LeadThrough(robot, "active", twin.dt, friction, calibrate=True)
    with SessionRecorder(path, robot, {"mode": "active", "dt": twin.dt}) as recorder:
        taught = simulate(twin, RecordingController(controller, recorder), TEACHING_SECONDS)
    twin = DigitalTwin(robot, teach_config, ScriptedOperator(teaching_actions(robot)))
    passive = simulate(twin, LeadThrough(robot, "passive", twin.dt, friction, calibrate=True),
                       TEACHING_SECONDS)  # fmt: skip
    seconds["teaching"] = time.perf_counter() - clock

    clock = time.perf_counter()
    say(f"3/4 replaying the recorded path ({path.name}) …")
    recording = read_recording(path)
    taught = taught.after(recording.t[0], restart_clock=False)  # from the end of the calibration
    passive = passive.after(recording.t[0], restart_clock=False)  # the same calibration time
    replay_config = replace(teach_config, seed=config.seed + 1)
    replayed, errors, _ = replay_recording(robot, recording.t, recording.q, friction, replay_config)
    seconds["replay"] = time.perf_counter() - clock
    return DemoResult(friction, taught, passive, recording.tau_ext_hat, recording.tau_ext_std,
                      recording.events, replayed, errors, path, seconds)  # fmt: skip


def tool_path(dynamics: Dynamics, q: FloatArray) -> FloatArray:
    """Flange positions [m] (N, 3) of joint paths (N, n)."""
    return np.array([dynamics.pose(row)[:3, 3] for row in q])


def hand_force_rms(run: SimulationResult) -> float:
    """RMS of the operator's hand force over a session [N] (the report's effort figure)."""
    return float(np.sqrt(np.mean(run.operator_force**2)))


def path_smoothness(taught: SimulationResult, actions: list[Action]) -> dict[str, float]:
    """How smooth the taught tool path is, against the path the operator meant [m/s].

    ``taught``: RMS tool velocity above 4 Hz (:func:`~.guiding.tool_vibration`) over the
    session; ``intended``: the same figure of the hands' own paths (:func:`intended_velocity`);
    ``speed``: the RMS tool speed, for scale.
    """
    dt = float(taught.t[1] - taught.t[0])
    velocity = np.gradient(taught.flange_position, dt, axis=0)
    intended = intended_velocity(taught, actions)
    return {"taught": tool_vibration(velocity, dt), "intended": tool_vibration(intended, dt),
            "speed": float(np.sqrt(np.mean(np.sum(velocity**2, axis=1))))}  # fmt: skip


def intended_velocity(run: SimulationResult, actions: list[Action]) -> FloatArray:
    """The velocity of the paths the hands followed [m/s], (N, 3), zero between actions.

    Each action's path rebuilt from where the flange was when it began (an action that
    turns a joint, not a hand on the tool, has no path: zero).
    """
    intended = np.zeros_like(run.flange_position)
    for during, hand, start in hands_on_tool(run, actions):
        intended[during] = hand.path.velocity(run.t[during] - start)
    return intended


def intended_position(run: SimulationResult, actions: list[Action]) -> FloatArray:
    """Where the hands pulled the flange [m, world], (N, 3); NaN between actions.

    The paths of :func:`intended_velocity`: what the operator meant, against which the
    taught path (``run.flange_position``) shows how the arm followed.
    """
    intended = np.full_like(run.flange_position, np.nan)
    for during, hand, start in hands_on_tool(run, actions):
        intended[during] = hand.path.position(run.t[during] - start)
    return intended


def hands_on_tool(
    run: SimulationResult, actions: list[Action]
) -> Iterator[tuple[NDArray[np.intp], Hand, float]]:
    """Each action's samples, its hand and start [s]: hands on the tool only.

    Each hand is rebuilt from where the flange was when its action began (an action that
    turns a joint is not a hand on the tool).
    """
    for action in actions:
        during = np.flatnonzero((run.t >= action.start) & (run.t < action.stop))
        if during.size == 0:
            continue
        first = during[0]
        operator = action.make(run.flange_position[first], run.q_true[first])
        if isinstance(operator, Hand):  # a hand on the tool (not one turning a joint)
            yield during, operator, action.start


@dataclass(frozen=True)
class ActionFigures:
    """How one action of a session went: its smoothness and the hand's effort.

    Attributes:
        label: What the hand did.
        vibration: RMS tool velocity above 4 Hz over the action [m/s]
            (:func:`~.guiding.vibration_within`, filtered over the whole session).
        intended: The same of the path the hand followed [m/s].
        force: RMS hand force over the action [N].
    """

    label: str
    vibration: float
    intended: float
    force: float


def figures_by_action(run: SimulationResult, actions: list[Action]) -> list[ActionFigures]:
    """:class:`ActionFigures` of each action of ``run``, in the order of ``actions``.

    Where in a session the taught path is not smooth: a press's impact on a table shakes
    the tool whatever guides it, a line should not.
    """
    dt = float(run.t[1] - run.t[0])
    windows = [(run.t >= action.start) & (run.t < action.stop) for action in actions]
    velocity = np.gradient(run.flange_position, dt, axis=0)
    taught = vibration_within(velocity, dt, windows)
    intended = vibration_within(intended_velocity(run, actions), dt, windows)
    force = [float(np.sqrt(np.mean(run.operator_force[w] ** 2))) if np.any(w) else np.nan
             for w in windows]  # fmt: skip
    return [ActionFigures(action.label, float(a), float(b), f)
            for action, a, b, f in zip(actions, taught, intended, force, strict=True)]  # fmt: skip
