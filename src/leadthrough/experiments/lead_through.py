"""Experiments of thesis ch. 4.3 and 6 on the twin, made rigorous with a simulated operator.

The same hand pulls the tool along the same path with no compensation (gravity only),
passive and active lead-through, so the operator's effort can be compared exactly,
which the thesis could not do with one arm (its Fig. 6.7). Also: release and stay,
the end-stop runaway of §6.3.2, high and low virtual damping (Figs. 6.4–6.5), the
feed-forward torques of passive lead-through (Fig. 4.8) and a long stability session.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from leadthrough.control.calibration import Calibration, CalibrationParameters
from leadthrough.control.feedforward import GravityCompensation
from leadthrough.control.lead_through import LeadThrough
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.experiments.guiding import release_figures
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.runtime.interface import Controller, JointState
from leadthrough.twin.mjcf import Payload
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.operator import During, JointHand, Operator
from leadthrough.twin.paths import JointMinimumJerk
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.runner import SimulationResult, simulate
from leadthrough.twin.scenarios import scenario
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

PATHS = ("line", "circle", "point_to_point")
#: The operator grabs the arm once lead-through has calibrated, in every mode alike [s].
GRAB_TIME = CalibrationParameters().duration
MODES = ("none", "passive", "active")


class Recorder:
    """Wraps a LeadThrough and keeps what it computed each period (for figures)."""

    def __init__(self, controller: LeadThrough) -> None:
        self.controller = controller
        self.dt, self.supervisor = controller.dt, controller.supervisor  # for the control loop
        names = ("gravity", "friction", "dither", "estimate", "operator", "command")
        self.log: dict[str, list[FloatArray]] = {name: [] for name in names}

    def step(self, state: JointState) -> FloatArray:
        """Step the controller on the robot's sample and record its parts."""
        command = self.controller.step(state)
        parts = self.controller.last_feed_forward
        zeros = np.zeros_like(command)
        values = {"gravity": parts.gravity if parts else zeros,
                  "friction": parts.friction if parts else zeros,
                  "dither": parts.dither if parts else zeros,
                  "estimate": self.controller.tau_ext_hat,
                  "operator": self.controller.operator_torque, "command": command}  # fmt: skip
        for name, value in values.items():
            # copies: the controller updates some of its arrays in place every period
            self.log[name].append(np.array(value, dtype=float))
        return command

    def drop_first(self, count: int) -> None:
        """Forget the first ``count`` periods (before the operator grabbed the arm)."""
        for values in self.log.values():
            del values[:count]

    def arrays(self) -> dict[str, FloatArray]:
        """The log as arrays (N, n)."""
        return {name: np.array(values) for name, values in self.log.items()}


def _controller(
    robot: RobotDescription,
    mode: str,
    friction: FrictionModel | None,
    parameters: LeadThroughParameters | None,
):
    if mode == "none":
        return GravityCompensation(Dynamics(robot))
    return Recorder(LeadThrough(robot, mode, friction=friction, parameters=parameters,
                                calibrate=True))  # fmt: skip


@dataclass(frozen=True, eq=False)
class GuidedRun:
    """The hand guiding the tool along a path with one controller.

    Attributes:
        path: Path name.
        mode: ``"none"``, ``"passive"`` or ``"active"``.
        simulation: Signals of the run.
        rms_force: RMS hand force over the path's duration [N].
        peak_force: Largest hand force [N].
        path_error: RMS distance of the flange from the hand's reference [m].
        completion_time: First time the flange is within 2 cm of the path's end [s]
            (NaN if never).
        log: What the controller computed (empty for ``"none"``).
    """

    path: str
    mode: str
    simulation: SimulationResult
    rms_force: float
    peak_force: float
    path_error: float
    completion_time: float
    log: dict[str, FloatArray]


def guided_run(
    robot: RobotDescription,
    path: str,
    mode: str,
    friction: FrictionModel | None = None,
    config: TwinConfig = REALISTIC_TWIN,
    parameters: LeadThroughParameters | None = None,
    controller_for: Callable[[DigitalTwin], Controller] | None = None,
) -> GuidedRun:
    """One path with one controller on the twin.

    ``controller_for(twin)`` builds another controller than ``mode``'s (for analysis, e.g.
    one that reads the twin's truth); ``mode`` then only labels the run.
    """
    chosen = scenario(path, robot, config)
    twin = _grabbing_twin(robot, chosen.config, chosen.operator, chosen.q0)
    if controller_for is None:
        controller = _controller(robot, mode, friction, parameters)
    else:
        controller = controller_for(twin)
    sim = _after_grab(twin, controller, chosen.duration)
    reference = chosen.operator.path
    targets = np.array([reference.position(t) for t in sim.t])
    distance = np.linalg.norm(sim.flange_position - targets, axis=1)
    on_path = sim.t <= reference.duration
    force = sim.operator_force
    end = np.linalg.norm(sim.flange_position - reference.position(reference.duration), axis=1)
    done = np.flatnonzero((end < 0.02) & (sim.t > 0.5 * reference.duration))
    log = controller.arrays() if isinstance(controller, Recorder) else {}
    return GuidedRun(path, mode, sim, float(np.sqrt(np.mean(force[on_path] ** 2))),
                     float(force.max()), float(np.sqrt(np.mean(distance**2))),
                     float(sim.t[done[0]]) if done.size else np.nan, log)  # fmt: skip


@dataclass(frozen=True, eq=False)
class EffortComparison:
    """Every path with every mode.

    Attributes:
        runs: ``runs[path][mode]``.
    """

    runs: dict[str, dict[str, GuidedRun]]

    def ratio(self, path: str, mode: str = "active", reference: str = "passive") -> float:
        """RMS hand force of ``mode`` over that of ``reference`` on ``path``."""
        return self.runs[path][mode].rms_force / self.runs[path][reference].rms_force

    def table(self) -> str:
        """Markdown table of effort, path error and completion time ("–": never completed)."""
        lines = ["| path | mode | RMS force [N] | peak [N] | path error RMS [mm] "
                 "| at the end after [s] | RMS vs passive |",
                 "|---|---|---:|---:|---:|---:|---:|"]  # fmt: skip
        for path, runs in self.runs.items():
            for mode, run in runs.items():
                done = f"{run.completion_time:.2f}" if np.isfinite(run.completion_time) else "–"
                lines.append(f"| {path} | {mode} | {run.rms_force:.2f} | {run.peak_force:.1f} | "
                             f"{1000 * run.path_error:.1f} | {done} | "
                             f"{self.ratio(path, mode):.2f} |")  # fmt: skip
        lines.append("\n*at the end after*: when the tool first came within 2 cm of the path's "
                     "end (after half the path's time); –: it never did, the hand's spring "
                     "stretched against the friction and inertia the controller left.")  # fmt: skip
        return "\n".join(lines)


def effort_comparison(
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    config: TwinConfig = REALISTIC_TWIN,
) -> EffortComparison:
    """Fig. 6.7, rigorously: the same hand on the same paths, three controllers."""
    runs = {path: {mode: guided_run(robot, path, mode, friction, config) for mode in MODES}
            for path in PATHS}  # fmt: skip
    return EffortComparison(runs)


def _guided(
    robot: RobotDescription,
    config: TwinConfig,
    operator: Operator,
    q0: FloatArray,
    controller: Controller,
    duration: float,
    release: float = np.inf,
) -> SimulationResult:
    """The operator grabs the arm once lead-through is ready, acts, lets go.

    The operator grabs at :data:`GRAB_TIME` and lets go ``release`` [s] later; the
    signals are returned from the grab on, with t = 0 at the grab.
    """
    return _after_grab(_grabbing_twin(robot, config, operator, q0, release), controller, duration)


def _grabbing_twin(
    robot: RobotDescription,
    config: TwinConfig,
    operator: Operator,
    q0: FloatArray,
    release: float = np.inf,
) -> DigitalTwin:
    """The twin at ``q0``; ``operator`` grabs at :data:`GRAB_TIME`, lets go ``release`` later."""
    return DigitalTwin(robot, config, During(operator, GRAB_TIME, GRAB_TIME + release), q0)


def _after_grab(twin: DigitalTwin, controller: Controller, duration: float) -> SimulationResult:
    """Run until ``duration`` [s] after the grab; the signals from the grab on (t = 0 there)."""
    whole = simulate(twin, controller, GRAB_TIME + duration)
    sim = whole.after(GRAB_TIME)
    if isinstance(controller, Recorder):
        controller.drop_first(len(whole.t) - len(sim.t))
    return sim


@dataclass(frozen=True, eq=False)
class ReleaseResult:
    """What the arm does after the operator lets go.

    Attributes:
        simulation: Signals of the run.
        release: When the hand let go [s].
        stop_time: From the release until every joint is slower than 0.01 rad/s for good,
            vibration above 4 Hz aside (:func:`~.guiding.release_figures`) [s].
        drift: Largest joint motion from 0.5 s after the release to the end [rad].
    """

    simulation: SimulationResult
    release: float
    stop_time: float
    drift: float


def release_and_stay(
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    config: TwinConfig = REALISTIC_TWIN,
    parameters: LeadThroughParameters | None = None,
    mode: str = "active",
    rest: float = 10.0,
) -> ReleaseResult:
    """A hand pulls the tool 15 cm, lets go at speed; measure the stop and the drift."""
    chosen = scenario("line", robot, config)
    release = 0.75 * chosen.operator.path.duration  # while the tool still moves
    controller = _controller(robot, mode, friction, parameters)
    sim = _guided(robot, config, chosen.operator, chosen.q0, controller, release + 0.5 + rest,
                  release)  # fmt: skip
    return ReleaseResult(sim, release, *release_figures(sim, release))


@dataclass(frozen=True, eq=False)
class EndStopResult:
    """A joint pushed into its end-stop and let go (thesis §6.3.2, Fig. 6.6).

    Attributes:
        simulation: Signals of the run.
        joint: The joint.
        release: When the hand let go [s].
        travel_after_release: How far the joint moved on its own after the release [rad].
        log: What the controller computed.
    """

    simulation: SimulationResult
    joint: int
    release: float
    travel_after_release: float
    log: dict[str, FloatArray]


def end_stop(
    robot: RobotDescription,
    parameters: LeadThroughParameters | None = None,
    friction: FrictionModel | None = None,
    joint: int = 6,
    config: TwinConfig = REALISTIC_TWIN,
) -> EndStopResult:
    """A hand turns ``joint`` past its upper limit, holds it there, and lets go."""
    start = robot.home()
    target = robot.q_max[joint] + 0.3
    hand = JointHand(joint, JointMinimumJerk(start[joint], target, duration=2.0),
                     stiffness=5.0, max_torque=1.0)  # fmt: skip
    release = 3.0
    controller = _controller(robot, "active", friction, parameters)
    sim = _guided(robot, config, hand, start, controller, release + 4.0, release)
    angle = sim.q_true[:, joint]
    after = sim.t >= release
    travel = float(np.max(np.abs(angle[after] - angle[after][0])))
    return EndStopResult(sim, joint, release, travel, controller.arrays())


def damping_runs(
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    joint: int = 6,
    config: TwinConfig = REALISTIC_TWIN,
) -> dict[str, GuidedRun]:
    """Figs. 6.4–6.5: a hand turns one joint with high and with low virtual damping."""
    runs = {}
    for label, damping_time in (("high damping", 0.05), ("low damping", 3.0)):
        parameters = LeadThroughParameters(damping_time=damping_time)
        runs[label] = _joint_run(robot, joint, friction, config, parameters)
    return runs


def _joint_run(robot: RobotDescription, joint: int, friction: FrictionModel | None,
               config: TwinConfig, parameters: LeadThroughParameters) -> GuidedRun:  # fmt: skip
    home = robot.home()
    hand = JointHand(joint, JointMinimumJerk(home[joint], home[joint] + 0.6, duration=2.0))
    controller = _controller(robot, "active", friction, parameters)
    sim = _guided(robot, config, hand, home, controller, 3.0)
    torque = sim.tau_operator[:, joint]
    return GuidedRun(f"joint {joint + 1}", "active", sim, float(np.sqrt(np.mean(torque**2))),
                     float(np.abs(torque).max()), np.nan, np.nan, controller.arrays())  # fmt: skip


def passive_feed_forward(
    robot: RobotDescription, friction: FrictionModel | None = None,
    config: TwinConfig = REALISTIC_TWIN,
) -> GuidedRun:  # fmt: skip
    """Fig. 4.8: gravity and friction feed-forward while a hand guides the passive arm."""
    return guided_run(robot, "point_to_point", "passive", friction, config)


def stability_session(
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    config: TwinConfig = REALISTIC_TWIN,
    parameters: LeadThroughParameters | None = None,
    operator_factory: Callable[[RobotDescription], Operator] | None = None,
    duration: float = 60.0,
) -> SimulationResult:
    """A long session (default 60 s) of guiding, pressing on a table and an end-stop."""
    from leadthrough.twin.session_operator import teaching_session_operator

    table_config = replace(config, table=teaching_session_operator.table(robot))
    operator = (operator_factory or teaching_session_operator)(robot)
    twin = DigitalTwin(robot, table_config, operator)
    return simulate(twin, _controller(robot, "active", friction, parameters), duration)


#: Plants the defaults are judged on (SPEC: masses ±5 %, friction ±20 %, an unknown payload).
PLANTS: dict[str, TwinConfig] = {
    "realistic (masses ±5 %, seed 1)": REALISTIC_TWIN,
    "every mass +5 %": replace(REALISTIC_TWIN, model_error=ModelError(mass_scale=1.05)),
    "every mass −5 %": replace(REALISTIC_TWIN, model_error=ModelError(mass_scale=0.95)),
    "friction −20 %": replace(REALISTIC_TWIN, seed=7, model_error=replace(
        REALISTIC_TWIN.model_error, friction_scale=0.8)),
    "friction +20 %": replace(REALISTIC_TWIN, seed=3, model_error=replace(
        REALISTIC_TWIN.model_error, friction_scale=1.2)),
    "0.5 kg payload": replace(REALISTIC_TWIN, model_error=replace(
        REALISTIC_TWIN.model_error, payload=Payload(0.5))),
}  # fmt: skip


@dataclass(frozen=True, eq=False)
class CalibrationCheck:
    """The start-up calibration on one plant, against the plant's truth.

    Attributes:
        plant: Plant name.
        calibration: What the calibration measured.
        true_gravity_error: ``G_model − G_true`` at the pose, payload included [Nm].
        true_friction_scale: True over modelled Coulomb level at the pose [–].
        true_payload: Payload the plant carries [kg].
    """

    plant: str
    calibration: Calibration
    true_gravity_error: FloatArray
    true_friction_scale: FloatArray
    true_payload: float


def calibration_checks(
    robot: RobotDescription, friction: FrictionModel | None = None
) -> list[CalibrationCheck]:
    """Calibrate on every plant of :data:`PLANTS`, nobody touching; keep the truth alongside."""
    checks = []
    for name, config in PLANTS.items():
        twin = DigitalTwin(robot, config)
        controller = LeadThrough(robot, friction=friction, calibrate=True)
        simulate(twin, controller, GRAB_TIME + 0.1)
        result = controller.calibration
        payload = config.model_error.payload
        carried = (twin.true_robot if payload is None
                   else twin.true_robot.with_payload(payload.mass, payload.com))  # fmt: skip
        true_gravity = Dynamics(carried).gravity(result.pose)
        modelled = controller.nominal_friction.coulomb_level(result.pose)
        true_scale = twin.friction.params.coulomb_level(result.pose) / modelled
        checks.append(CalibrationCheck(name, result, Dynamics(robot).gravity(result.pose)
                                       - true_gravity, true_scale,
                                       0.0 if payload is None else payload.mass))  # fmt: skip
    return checks


def robustness(
    robot: RobotDescription, friction: FrictionModel | None = None
) -> dict[str, ReleaseResult]:
    """Release and stay with the defaults on every plant of :data:`PLANTS`."""
    return {name: release_and_stay(robot, friction, config) for name, config in PLANTS.items()}


def plants_table(checks: list[CalibrationCheck], releases: dict[str, ReleaseResult]) -> str:
    """Markdown table: calibration errors and release-and-stay on every plant."""
    lines = ["| plant | payload measured / true [kg] | Coulomb level error, max [%] "
             "| gravity error, measured − true, max [Nm] | released: stopped after [s] "
             "| then drift [mrad] |",
             "|---|---:|---:|---:|---:|---:|"]  # fmt: skip
    for check in checks:
        result, release = check.calibration, releases[check.plant]
        scale = 100.0 * np.max(np.abs(result.friction_scale - check.true_friction_scale)
                               * result.measured)  # fmt: skip
        gravity = np.max(np.abs(result.gravity_error - check.true_gravity_error) * result.measured)
        lines.append(f"| {check.plant} | {result.payload:.2f} / {check.true_payload:.2f} | "
                     f"{scale:.1f} | {gravity:.3f} | {release.stop_time:.2f} | "
                     f"{1e3 * release.drift:.2f} |")  # fmt: skip
    return "\n".join(lines)
