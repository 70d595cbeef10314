"""The momentum observer run over a recorded log, with the model's torque uncertainty.

:func:`observe_log` replays a :class:`~leadthrough.logs.log.JointLog` through
:class:`~leadthrough.estimation.observer.MomentumObserver` at the log's own rate and
:func:`detect_contacts` runs the online :class:`ContactDetector` on the result.

**A joint at rest is read from its torque balance.** The Kalman observer takes the friction
at rest as white noise of the stiction band's size, which a push must outlast to be read:
on a UR10e's shoulder (τ_C 12 Nm) the estimate followed a push with a time constant of ~4 s.
A logged arm is mostly held by its own position controller (a UR in its normal mode, a
Panda), whose motors answer a push at rest; friction there is a reaction that holds what the
balance leaves, up to breakaway, not noise to average. So where a joint rests the estimate
is the first-order momentum residual (:class:`~.classical.ClassicalMomentumObserver`, the
balance with the friction's mean, 0 at rest, read at a 20 ms time constant), and where it
slides the Kalman observer's, weighted by the friction model's sliding share ``1 −
v_C(q̇) / v_C(0)`` (the share of the stiction band the motion has left: 0 at rest, 1
past its sigmoids; v_C the Coulomb uncertainty, eq. (4.5)). Its std is the Kalman
observer's and, where the joint rests, the friction that holds it: anywhere within the
stiction band, ``v_C(0) / √3`` (without it, the base of a held UR10e whose shoulder swung
read 17 Nm of coupling and stiction for 0.3 s as a contact). On a public UR10e log whose
pose is held while a person pushes (``collision/ur-20_01_22-push_pose_1.csv`` of the source
repository of ``../shared/realdata/ur10e``): three of its four pushes found, one before
(45–62 Nm on the shoulder read as 10–22). A torque-controlled arm in lead-through is another matter:
its motors hold gravity and nothing else, so a push at rest goes into stiction unseen;
the controller's observer is the Kalman one alone.

Irregular time stamps (real logs jitter by tens of percent) are handled by resampling
q, q̇ and τ linearly onto a uniform grid at the log's median period, the rate the
observer runs at; the result and the events are in the log's own time base. A gap with
rows missing is not resampled across: :func:`observe_runs` observes each gap-free run.

The observer's std covers the friction it models as noise; a real arm's model is also
wrong in ways that are not white noise (link inertials, drive gains, friction levels).
That **model uncertainty** is added to the observer's std, per joint and sample::

    σ_model² = (ε_rb |τ_rb|)² + (ε_f |τ_f|)² + (ε_g G_rms)²,     σ² = σ_observer² + σ_model²

with τ_rb = τ − τ_f + τ̂_ext the rigid-body torque the model must explain, τ_f the
friction model's mean, ε_rb the relative rigid-body model error and ε_f the friction
model's relative error, ε_g G_rms an error of the gravity torque that stays where the
gravity torque crosses zero (G_rms: the joint's gravity torque scale over its range;
the nominal UR10e URDF is 8.7 Nm RMS off on joint 2, also where G ≈ 0). Because the
observer low-passes model errors, σ_model is held at its recent peak and decays with
the time constant ``hold_time``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from leadthrough.errors import LeadthroughError, ParameterError
from leadthrough.estimation.classical import ClassicalMomentumObserver
from leadthrough.estimation.contacts import ContactDetector, ContactEvent, ContactParameters
from leadthrough.estimation.observer import MomentumObserver, ObserverParameters
from leadthrough.friction.model import FrictionModel
from leadthrough.logs.log import MAX_GAP, JointLog, as_joint_log
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.validation import real


class LogInputError(LeadthroughError, ValueError):
    """A log cannot be observed (no torque and no current, too short, wrong joint count)."""


@dataclass(frozen=True)
class ModelUncertainty:
    """How wrong the model may be, as a std added to the observer's (module docstring).

    Attributes:
        rigid_body: ε_rb, relative error of the rigid-body torque [–] (0.1: a model not
            identified on this arm; an identified one is nearer 0.05).
        friction: ε_f, relative error of the friction torque [–]; None takes the
            friction model's ``relative_error``.
        hold_time: Decay time of the held peak of σ_model [s].
        friction_hold_time: Decay time of the held peak of the friction error [s].
        stop_hold_time: Decay time of the friction a stopped joint may keep [s].
        gravity: ε_g, an error of the gravity torque that does not vanish where the
            gravity torque does (a centre of mass off by some mm shifts its zero), as a
            fraction of the joint's gravity torque scale :func:`gravity_scale` [–].
    """

    rigid_body: float = 0.1
    friction: float | None = None
    hold_time: float = 1.0
    friction_hold_time: float = 1.0
    stop_hold_time: float = 3.0
    gravity: float = 0.1

    def __post_init__(self) -> None:
        real("rigid_body", self.rigid_body, minimum=0.0, error=ParameterError)
        real("gravity", self.gravity, minimum=0.0, error=ParameterError)
        if self.friction is not None:
            real("friction", self.friction, minimum=0.0, error=ParameterError)
        real("hold_time", self.hold_time, minimum=0.0, error=ParameterError)
        real("friction_hold_time", self.friction_hold_time, minimum=0.0, error=ParameterError)
        real("stop_hold_time", self.stop_hold_time, minimum=0.0, error=ParameterError)


@dataclass(frozen=True, eq=False)
class ObservedLog:
    """The observer's output over a log, on the uniform grid it ran on.

    Attributes:
        t: Sample times [s], uniform at the log's median period, log's time base.
        q: Joint readings [rad], (N, n), interpolated.
        qd: Joint velocities [rad/s], (N, n), interpolated.
        tau: Measured joint torque, arm side [Nm], (N, n) (K·i for current logs).
        tau_ext: Estimated external torque [Nm], (N, n), SPEC §1 sign.
        std_observer: The observer's own std of ``tau_ext`` [Nm], (N, n).
        std_model: Model uncertainty σ_model [Nm], (N, n).
        source: The log's source.
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    tau: FloatArray
    tau_ext: FloatArray
    std_observer: FloatArray
    std_model: FloatArray
    source: str = ""

    @property
    def std(self) -> FloatArray:
        """Total std of ``tau_ext``: observer and model combined [Nm], (N, n)."""
        return np.hypot(self.std_observer, self.std_model)

    @property
    def dt(self) -> float:
        """The period the observer ran at [s]."""
        return float(self.t[1] - self.t[0])


def measured_torque(log: JointLog, robot: RobotDescription) -> FloatArray:
    """The log's joint torque, arm side [Nm]: ``log.tau``, else K·i from its currents.

    Raises:
        LogInputError: The log has neither, or currents and the robot no torque constants.
    """
    where = log.source or "log"
    if log.n_joints != robot.n_joints:
        raise LogInputError(f"{where}: {log.n_joints} joints, but {robot.name} has "
                            f"{robot.n_joints}")  # fmt: skip
    torque = log.joint_torque(robot.torque_constants)
    if torque is not None:
        return torque
    if log.current is None:
        raise LogInputError(f"{where}: the log has neither joint torques nor motor currents")
    raise LogInputError(f"{where}: the log has motor currents but {robot.name} has "
                        "no torque constants (Joint.torque_constant) for τ = K·i")  # fmt: skip


def resample(log: JointLog, torque: FloatArray) -> tuple[FloatArray, ...]:
    """(t, q, q̇, τ) linearly interpolated onto a uniform grid at the median period."""
    if log.n_samples < 3:
        raise LogInputError(f"{log.source or 'log'}: {log.n_samples} samples, need at least 3")
    period = log.median_period
    t = log.t[0] + period * np.arange(int(np.floor(log.duration / period + 1e-9)) + 1)

    def interpolate(values: FloatArray) -> FloatArray:
        return np.column_stack([np.interp(t, log.t, column) for column in values.T])

    return t, interpolate(log.q), interpolate(log.qd), interpolate(torque)


def observe_log(
    log: JointLog,
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    uncertainty: ModelUncertainty | None = None,
    observer: ObserverParameters | None = None,
) -> ObservedLog:
    """Run the momentum observer over a log at its own rate.

    Args:
        log: The run (``tau``, or ``current`` and the robot's torque constants).
        robot: The arm's model (nominal or identified).
        friction: Its friction model; None takes the robot's.
        uncertainty: The model uncertainty added to the observer's std.
        observer: Observer tuning (default: the thesis' values).

    Raises:
        LogInputError: No torque in the log, a joint count that does not match, too short.
    """
    torque = measured_torque(log, robot)
    t, q, qd, tau = resample(log, torque)
    friction = friction or FrictionModel.from_robot(robot)
    uncertainty = uncertainty or ModelUncertainty()
    dynamics, dt = Dynamics(robot), float(t[1] - t[0])
    estimator = MomentumObserver(dynamics, friction, dt=dt, parameters=observer)
    balance = ClassicalMomentumObserver(dynamics, friction, dt=dt)  # where a joint rests
    sliding_reading, std_observer = np.zeros_like(q), np.zeros_like(q)
    resting_reading = np.zeros_like(q)
    for k in range(t.size):
        sliding_reading[k] = estimator.update(q[k], qd[k], tau[k])
        std_observer[k] = estimator.std
        resting_reading[k] = balance.update(q[k], qd[k], tau[k])
    # the share of the stiction band the motion has left: 0 at rest, 1 past the sigmoids
    stiction_band = friction.coulomb_uncertainty(0.0 * qd, q)
    band = friction.coulomb_uncertainty(qd, q) / stiction_band
    sliding = 1.0 - np.nan_to_num(band)  # a joint without a Coulomb level (0 / 0): 1
    tau_ext = sliding * sliding_reading + (1.0 - sliding) * resting_reading
    # read from the balance, a resting joint's estimate carries the friction holding it:
    # anywhere within the stiction band, std v_C(0) / √3
    std_observer = np.sqrt(std_observer**2 + (1.0 - sliding) * stiction_band**2 / 3.0)
    friction_mean = friction.mean(qd, q)
    relative = friction.relative_error if uncertainty.friction is None else uncertainty.friction
    rigid = held_peak(
        uncertainty.rigid_body * np.abs(tau - friction_mean + tau_ext), dt, uncertainty.hold_time
    )
    sliding = held_peak(relative * np.abs(friction_mean), dt, uncertainty.friction_hold_time)
    stopped = stop_memory(friction_mean, qd, q[0], friction, dt, uncertainty.stop_hold_time)
    # the observer starts from τ̂ = 0 in an unknown friction state: τ_C while it converges
    start = np.outer(np.exp(-(t - t[0]) / max(uncertainty.hold_time, dt)),
                     friction.coulomb_level(q[0]))  # fmt: skip
    floor = uncertainty.gravity * gravity_scale(robot)
    std_model = np.sqrt(rigid**2 + sliding**2 + stopped**2 + start**2 + floor**2)
    return ObservedLog(t, q, qd, tau, tau_ext, std_observer, std_model, log.source)


def observe_runs(
    log: JointLog,
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    uncertainty: ModelUncertainty | None = None,
) -> list[ObservedLog]:
    """:func:`observe_log` over each gap-free run of ``log`` of at least 3 samples.

    A gap longer than :data:`~leadthrough.logs.log.MAX_GAP` has rows missing: resampled
    across it the observer would run on interpolated data, so it starts afresh after it.

    Raises:
        LogInputError: As :func:`observe_log`, or no run of 3 samples between gaps.
    """
    runs = [run for run in log.runs() if run.n_samples >= 3]
    if not runs and log.n_samples >= 3:
        raise LogInputError(f"{log.source or 'log'}: no 3 samples in a row without a gap in "
                            f"time of more than {MAX_GAP:g} s")  # fmt: skip
    if not runs:
        return [observe_log(log, robot, friction, uncertainty)]  # its error: too short
    return [observe_log(run, robot, friction, uncertainty) for run in runs]


def joined(runs: Sequence[ObservedLog]) -> ObservedLog:
    """Observed runs of one log end to end (the grid is uniform within each run only)."""

    def end_to_end(name: str) -> FloatArray:
        return np.concatenate([getattr(run, name) for run in runs])

    return ObservedLog(end_to_end("t"), end_to_end("q"), end_to_end("qd"), end_to_end("tau"),
                       end_to_end("tau_ext"), end_to_end("std_observer"),
                       end_to_end("std_model"), runs[0].source)  # fmt: skip


def gravity_scale(robot: RobotDescription, poses: int = 256) -> FloatArray:
    """RMS of each joint's gravity torque over seeded poses across its range [Nm], (n,).

    The scale of the gravity torque a joint carries anywhere in its workspace (a
    property of the arm, not of a log); ranges are clipped to ±π.
    """
    rng = np.random.default_rng(0)
    low, high = np.maximum(robot.q_min, -np.pi), np.minimum(robot.q_max, np.pi)
    dynamics = Dynamics(robot)
    gravity = np.array([dynamics.gravity(q) for q in rng.uniform(low, high, (poses, low.size))])
    return np.sqrt(np.mean(gravity**2, axis=0))


def held_peak(values: FloatArray, dt: float, hold_time: float) -> FloatArray:
    """Running peak of ``values`` (N, n) that decays as exp(−t / hold_time) [same units]."""
    decay = float(np.exp(-dt / hold_time)) if hold_time > 0 else 0.0
    held = values.copy()
    for k in range(1, held.shape[0]):
        np.maximum(held[k], decay * held[k - 1], out=held[k])
    return held


def stop_memory(
    friction_mean: FloatArray,
    qd: FloatArray,
    position: FloatArray,
    friction: FrictionModel,
    dt: float,
    hold: float,
) -> FloatArray:
    """Per sample, the friction a joint at rest may still hold since it last slid [Nm].

    A joint that stops keeps an unknown static friction, often near the sliding level it
    had; the friction model says 0 at rest. So at rest the last sliding |τ_f| is kept as
    an uncertainty, decaying as exp(−t / hold); while the joint slides it is 0. At the
    start of the data the static friction is unknown: the Coulomb level τ_C(q).
    """
    sliding = np.abs(qd) > friction.half_width + 5.0 / friction.slope
    decay = float(np.exp(-dt / hold)) if hold > 0 else 0.0
    memory = np.zeros_like(friction_mean)
    last = np.array(friction.coulomb_level(position), dtype=float)
    for k in range(friction_mean.shape[0]):
        last = np.where(sliding[k], np.abs(friction_mean[k]), decay * last)
        memory[k] = np.where(sliding[k], 0.0, last)
    return memory


def run_detector(
    observed: ObservedLog, parameters: ContactParameters | None = None
) -> list[ContactEvent]:
    """The online contact detector fed with an observed log, period by period."""
    detector = ContactDetector(observed.tau_ext.shape[1], parameters)
    std = observed.std
    for k in range(observed.t.size):
        detector.update(float(observed.t[k]), observed.tau_ext[k], std[k])
    detector.finish()
    return list(detector.events)


def detect_contacts(
    log: object,
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    parameters: ContactParameters | None = None,
    uncertainty: ModelUncertainty | None = None,
) -> list[ContactEvent]:
    """Contacts in a log: the momentum observer at the log's rate, then the detector.

    Args:
        log: The run (``tau``, or ``current`` and the robot's torque constants): a
            JointLog, or a mapping or object with its arrays (:func:`~.logs.log.as_joint_log`).
        robot: The arm's model: nominal (``lt.robots.ur10e()``) or identified.
        friction: Its friction model; None takes the robot's.
        parameters: Detector thresholds (see :class:`ContactParameters`).
        uncertainty: Model uncertainty added to the observer's std.

    Returns:
        The events, in time order, each with start and end [s] in the log's time base,
        the joints (0-based) and the peak estimated torque per joint [Nm]; none spans a
        gap in time (:func:`observe_runs`).

    Raises:
        LogInputError: No torque in the log, a joint count that does not match, too short.
    """
    return events_of(observe_runs(as_joint_log(log), robot, friction, uncertainty), parameters)


def events_of(
    runs: Sequence[ObservedLog], parameters: ContactParameters | None = None
) -> list[ContactEvent]:
    """The contacts of each observed run (:func:`run_detector`), in time order."""
    return [event for run in runs for event in run_detector(run, parameters)]


def false_alarm_table(
    observed: Sequence[ObservedLog], sigmas: float = 2.0
) -> dict[str, FloatArray]:
    """False-alarm level per joint over runs where nothing touches the arm.

    Returns:
        ``rms`` and ``peak`` of τ̂_ext [Nm], ``median_std`` [Nm], ``exceed``, the
        fraction of samples with |τ̂_ext| > ``sigmas`` std [–], and ``z_rms``, the RMS
        of τ̂_ext / std [–] (≈ 1 for an honest std, ≪ 1 for one wider than the errors
        it covers), each shape (n,).
    """
    tau = np.concatenate([o.tau_ext for o in observed])
    std = np.concatenate([o.std for o in observed])
    return {"rms": np.sqrt(np.mean(tau**2, axis=0)), "peak": np.max(np.abs(tau), axis=0),
            "median_std": np.median(std, axis=0),
            "exceed": np.mean(np.abs(tau) > sigmas * std, axis=0),
            "z_rms": np.sqrt(np.mean((tau / std) ** 2, axis=0))}  # fmt: skip
