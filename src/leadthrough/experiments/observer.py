"""Experiments of thesis ch. 5 on the twin: estimate vs truth, blind spot, dithering, variants.

Each experiment runs the passive feed-forward (gravity, Coulomb compensation, optional
dither) on the twin with one or more observers listening to the same signals, and
returns a result object; the figures are in :mod:`leadthrough.plots.observer`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np

from leadthrough.control.dither import DitherParameters
from leadthrough.control.feedforward import PassiveFeedForward
from leadthrough.estimation.classical import ClassicalMomentumObserver
from leadthrough.estimation.observer import MomentumObserver
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.twin.operator import JointHand, Operator, TorqueProfile, ramp, step
from leadthrough.twin.paths import JointMinimumJerk
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.runner import SimulationResult, simulate
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

ObserverFactory = Callable[[Dynamics, FrictionModel, float], object]

#: The observers compared: both Kalman variants and the classical baseline.
OBSERVERS: dict[str, ObserverFactory] = {
    "kalman_time_varying": lambda d, f, dt: MomentumObserver(d, f, dt, variant="time_varying"),
    "kalman_two_level": lambda d, f, dt: MomentumObserver(d, f, dt, variant="two_level"),
    "classical": lambda d, f, dt: ClassicalMomentumObserver(d, f, dt),
}


class ObservedFeedForward:
    """Passive feed-forward on the robot, observers listening; logs their estimates.

    Args:
        feed_forward: The feed-forward that drives the arm.
        observers: Observers by name, all fed the measured torque minus the dither.
    """

    def __init__(self, feed_forward: PassiveFeedForward, observers: Mapping[str, object]):
        self.feed_forward = feed_forward
        self.observers = dict(observers)
        self.log: dict[str, list[FloatArray]] = {f"{k}_{s}": [] for k in self.observers
                                                 for s in ("estimate", "std")}  # fmt: skip
        self.log["dither"] = []

    def step(self, q: FloatArray, qd: FloatArray, tau_measured: FloatArray) -> FloatArray:
        """Feed-forward command [Nm]; every observer updated with the measured torque."""
        torques = self.feed_forward.step(q, qd)
        observed_input = tau_measured - torques.dither_in_measurement
        for name, observer in self.observers.items():
            self.log[f"{name}_estimate"].append(observer.update(q, qd, observed_input))
            self.log[f"{name}_std"].append(observer.std)
        self.log["dither"].append(torques.dither)
        return torques.total


@dataclass(frozen=True, eq=False)
class ObserverRun:
    """A twin run with observers: the simulation and every observer's estimate and std.

    Attributes:
        simulation: Signals of the run (ground truth included).
        estimates: Estimated external torque per observer [Nm], (N, n).
        stds: Reported standard deviation per observer [Nm], (N, n) (NaN if none).
        dither: Dither torque commanded [Nm], (N, n).
        joint: The joint the experiment is about.
    """

    simulation: SimulationResult
    estimates: dict[str, FloatArray]
    stds: dict[str, FloatArray]
    dither: FloatArray
    joint: int

    def moving(self, threshold: float = 0.01) -> np.ndarray:
        """Samples where the joint moves faster than ``threshold`` [rad/s] (true velocity)."""
        return np.abs(self.simulation.qd_true[:, self.joint]) > threshold

    def accuracy(self, name: str) -> dict[str, float]:
        """While moving: RMS error [Nm], peak true torque [Nm], their ratio, ±2 std coverage."""
        j, moving = self.joint, self.moving()
        truth = self.simulation.tau_ext[:, j]
        error = self.estimates[name][moving, j] - truth[moving]
        rms = float(np.sqrt(np.mean(error**2)))
        peak = float(np.max(np.abs(truth)))
        inside = np.abs(error) <= 2.0 * self.stds[name][moving, j]
        return {"rms_error": rms, "peak_torque": peak, "rms_over_peak": rms / peak,
                "within_2_std": float(np.mean(inside))}  # fmt: skip


def _run(
    robot: RobotDescription,
    friction: FrictionModel,
    operator: Operator,
    duration: float,
    joint: int,
    config: TwinConfig = REALISTIC_TWIN,
    dither: DitherParameters | None = None,
    q0: FloatArray | None = None,
) -> ObserverRun:
    dynamics = Dynamics(robot)
    twin = DigitalTwin(robot, config, operator, q0)
    dt = twin.dt
    observers = {name: make(dynamics, friction, dt) for name, make in OBSERVERS.items()}
    controller = ObservedFeedForward(PassiveFeedForward(dynamics, friction, dt, dither=dither),
                                     observers)  # fmt: skip
    simulation = simulate(twin, controller, duration)
    log = {key: np.array(values) for key, values in controller.log.items()}
    return ObserverRun(
        simulation,
        {name: log[f"{name}_estimate"] for name in observers},
        {name: log[f"{name}_std"] for name in observers},
        log["dither"],
        joint,
    )


def single_joint_guiding(
    robot: RobotDescription,
    friction: FrictionModel,
    joint: int = 0,
    config: TwinConfig = REALISTIC_TWIN,
    stroke: float = 0.4,
    duration: float = 8.0,
) -> ObserverRun:
    """Fig. 5.2: a hand turns one joint out by ``stroke`` and back; estimate vs truth."""
    home = robot.home()
    out = JointMinimumJerk(home[joint], home[joint] + stroke, duration=0.4 * duration)
    back = JointMinimumJerk(home[joint] + stroke, home[joint], duration=0.4 * duration)
    hand = _there_and_back(JointHand(joint, out, max_torque=6.0),
                           JointHand(joint, back, max_torque=6.0), 0.5 * duration)  # fmt: skip
    return _run(robot, friction, hand, duration, joint, config)


class _there_and_back(Operator):  # noqa: N801 - reads as a phrase
    """One operator until ``switch`` [s], then another (time shifted to start at 0)."""

    def __init__(self, first: Operator, second: Operator, switch: float) -> None:
        self.first, self.second, self.switch = first, second, switch

    def joint_torque(self, t: float, q: FloatArray, qd: FloatArray) -> FloatArray:
        """Torque of the operator active at ``t``."""
        if t < self.switch:
            return self.first.joint_torque(t, q, qd)
        return self.second.joint_torque(t - self.switch, q, qd)


@dataclass(frozen=True, eq=False)
class StepResponse:
    """Response of each observer to a torque step that starts a joint moving.

    Attributes:
        run: The underlying run.
        step_time: When the step is applied [s].
        amplitude: Step size [Nm].
        motion_start: When the joint starts moving (true speed above 0.01 rad/s) [s].
        rise_after_motion: Per observer, time from motion start to 63 % of the step [s].
    """

    run: ObserverRun
    step_time: float
    amplitude: float
    motion_start: float
    rise_after_motion: dict[str, float]


def torque_step_response(
    robot: RobotDescription,
    friction: FrictionModel,
    joint: int = 0,
    amplitude_over_breakaway: float = 1.5,
    config: TwinConfig = REALISTIC_TWIN,
) -> StepResponse:
    """A step of 1.5× the joint's breakaway torque: how fast each estimate follows."""
    step_time = 0.5
    amplitude = amplitude_over_breakaway * 1.3 * float(friction.coulomb[joint])
    operator = TorqueProfile(joint, (step(step_time, amplitude),))
    run = _run(robot, friction, operator, step_time + 0.6, joint, config)
    t = run.simulation.t
    moving = np.flatnonzero(run.moving() & (t >= step_time))
    start = float(t[moving[0]]) if moving.size else np.nan
    rise = {}
    for name, estimate in run.estimates.items():
        reached = np.flatnonzero((estimate[:, joint] >= 0.63 * amplitude) & (t >= step_time))
        rise[name] = float(t[reached[0]] - start) if reached.size else np.inf
    return StepResponse(run, step_time, amplitude, start, rise)


@dataclass(frozen=True, eq=False)
class BreakawayResult:
    """The torque a slowly rising push needs to start a joint, with and without dither.

    Attributes:
        runs: The runs, keyed ``"no_dither"`` and ``"dither"``.
        breakaway: True external torque when the joint started moving (1 mrad away from
            its start, far beyond the dither's vibration) [Nm], per key.
        detection_delay: How long after the push reaches half the Coulomb level the
            Kalman estimate does too [s], per key: the blind spot.
    """

    runs: dict[str, ObserverRun]
    breakaway: dict[str, float]
    detection_delay: dict[str, float]

    @property
    def ratio(self) -> float:
        """Breakaway torque with dither over without."""
        return self.breakaway["dither"] / self.breakaway["no_dither"]


def breakaway_with_and_without_dither(
    robot: RobotDescription,
    friction: FrictionModel,
    joint: int = 0,
    config: TwinConfig = REALISTIC_TWIN,
    dither: DitherParameters | None = None,
) -> BreakawayResult:
    """Figs. 5.5–5.6: a push rising at 0.5 τ_C per second, once without and once with dither."""
    coulomb = float(friction.coulomb[joint])
    operator = TorqueProfile(joint, (ramp(0.5, 0.5 + 4.0, 2.0 * coulomb),))
    runs, breakaway, delay = {}, {}, {}
    for key, setting in (
        ("no_dither", None),
        ("dither", dither or DitherParameters.never_parked()),
    ):
        run = _run(robot, friction, operator, 4.0, joint, config, dither=setting)
        t, truth = run.simulation.t, run.simulation.tau_ext[:, joint]
        estimate = run.estimates["kalman_time_varying"][:, joint]
        runs[key] = run
        angle = run.simulation.q_true[:, joint]
        breakaway[key] = float(truth[_first(np.abs(angle - angle[0]) > 1e-3)])
        half = t[_first(truth >= 0.5 * coulomb)]  # an estimate's start-up transient is no push
        delay[key] = float(t[_first((estimate >= 0.5 * coulomb) & (t >= half))] - half)
    return BreakawayResult(runs, breakaway, delay)


def _first(mask: np.ndarray) -> int:
    """Index of the first True (the last index if none)."""
    hits = np.flatnonzero(mask)
    return int(hits[0]) if hits.size else len(mask) - 1


@dataclass(frozen=True, eq=False)
class DitherSweep:
    """Velocity noise and tool vibration against dither frequency (Figs. 5.3–5.4).

    Attributes:
        frequencies: Dither frequencies [Hz].
        velocity_noise: RMS of the measured joint velocities at rest [rad/s], per frequency.
        tool_vibration: RMS over time of the 6-norm of the flange acceleration (eq. 5.21)
            [m/s², rad/s² mixed as in the thesis], per frequency.
        drift: Largest net joint displacement, mean of the last 0.5 s against the start
            [rad] (the dither must not move the arm).
    """

    frequencies: FloatArray
    velocity_noise: FloatArray
    tool_vibration: FloatArray
    drift: FloatArray


def dither_frequency_sweep(
    robot: RobotDescription,
    friction: FrictionModel,
    frequencies: FloatArray | None = None,
    config: TwinConfig = REALISTIC_TWIN,
    duration: float = 2.0,
) -> DitherSweep:
    """Dither all joints of the arm at rest at each frequency; measure noise and vibration."""
    frequencies = np.arange(1.0, 21.0, 1.0) if frequencies is None else np.asarray(frequencies)
    noise, vibration, drift = [], [], []
    for frequency in frequencies:
        run = _run(robot, friction, Operator(), duration, 0, config,
                   dither=DitherParameters.never_parked(frequency=float(frequency)))  # fmt: skip
        sim = run.simulation
        settled = sim.t > 0.5
        noise.append(float(np.sqrt(np.mean(sim.qd[settled] ** 2))))
        vibration.append(_tool_vibration(sim, settled))
        final = sim.q_true[sim.t > sim.t[-1] - 0.5].mean(axis=0)
        drift.append(float(np.max(np.abs(final - sim.q_true[0]))))
    return DitherSweep(frequencies, np.array(noise), np.array(vibration), np.array(drift))


def _tool_vibration(sim: SimulationResult, mask: np.ndarray) -> float:
    """RMS of ‖a‖₆ (eq. 5.21) of the flange's linear acceleration and the joints' angular one."""
    dt = sim.t[1] - sim.t[0]
    linear = np.gradient(np.gradient(sim.flange_position, dt, axis=0), dt, axis=0)
    angular = np.gradient(np.gradient(sim.q_true[:, -3:], dt, axis=0), dt, axis=0)
    norm6 = np.sum(np.concatenate([linear, angular], axis=1) ** 6, axis=1) ** (1 / 6)
    return float(np.sqrt(np.mean(norm6[mask] ** 2)))


def identified_without_position(friction: FrictionModel) -> FrictionModel:
    """The model with its position dependence removed (to keep the cable effect unmodelled).

    Its relative error grows by the dropped variation, |k₁| + |k₂|.
    """
    zeros = np.zeros(friction.n_joints)
    dropped = np.abs(friction.position_linear) + np.abs(friction.position_quadratic)
    return replace(friction, position_linear=zeros, position_quadratic=zeros,
                   relative_error=friction.relative_error + dropped)  # fmt: skip


__all__ = [
    "OBSERVERS",
    "BreakawayResult",
    "DitherSweep",
    "ObserverRun",
    "StepResponse",
    "breakaway_with_and_without_dither",
    "dither_frequency_sweep",
    "identified_without_position",
    "single_joint_guiding",
    "torque_step_response",
]
