"""Replay of a taught path (SPEC §8): plan it, check it, track it behind the supervisor.

:func:`plan_replay` resamples a recorded joint path, smooths it without phase lag,
stretches it in time, cuts it at the operator's pauses and checks its positions, speeds
and torques against the limits *before* anything moves; :class:`Replayer` approaches its
start, tracks it (model feed-forward + PID, through the safety supervisor) and holds its
end; :func:`replay_errors` says how closely a replay followed it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import cast

import numpy as np
from numpy.polynomial import polynomial
from numpy.typing import ArrayLike

from leadthrough.control.tracking import JointTracker, pd_gains, period_bandwidth
from leadthrough.control.warm_up import exercise
from leadthrough.errors import ParameterError, ReplayError, failure
from leadthrough.friction.model import FrictionModel
from leadthrough.logs.sample import JointState, joint_state
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.model.snapshot import ModelSnapshot
from leadthrough.safety.supervisor import SafetySupervisor, SupervisorState
from leadthrough.trajectories import minimum_jerk_acceleration, minimum_jerk_phase
from leadthrough.validation import real

#: Time the replayer holds the last pose before it reports :attr:`Replayer.done` [s].
SETTLE_TIME = 0.5
#: The integral torque is clamped to ± this multiple of each joint's Coulomb level [–].
INTEGRAL_LIMIT = 2.0
#: A recording that ends moving is brought to rest at this deceleration [rad/s²] ...
STOP_ACCELERATION = 1.0
#: ... over at least this long [s] (:func:`_stopped`), from its velocity over its last
#: ``STOP_WINDOW`` [s].
STOP_MIN_TIME = 0.5
STOP_WINDOW = 0.1


@dataclass(frozen=True)
class ReplayParameters:
    """Settings of a replay.

    Attributes:
        smoothing_time: Time constant τ of the zero-phase low-pass of the taught path [s]
            (2nd-order Butterworth at 1 / (2π τ), run forward and backward); 0: none.
        time_scale: Replay duration over taught duration [–]: > 1 slower, < 1 faster.
        pause_speed: Every joint slower than this [rad/s], as taught, ...
        pause_time: ... for at least this long [s], as taught, is a pause (a waypoint).
        approach_time: Shortest duration of the minimum-jerk move to the path start [s];
            longer where the arm is far from it (:attr:`Replayer.approach_time`).
        approach_speed: Largest share of a joint's speed limit the approach may reach [–]
            (a minimum-jerk move peaks at 1.875 × its mean speed).
        max_tracking_error: Farthest any joint may be from its reference [rad]; farther
            is a fault with the safe stop (something holds the arm: a person, an obstacle).
        margin: The path must stay this far inside the position limits [rad] (the
            supervisor's soft walls start ``soft_limit_margin`` inside them).
        limit_share: The planned speeds and torques stay within this share of the joints'
            limits [–]: the tracking's own overshoot and its PD's torque take the rest. At
            the limits themselves a UR5's joint 4 ran 12 % over its speed limit and the
            supervisor braked it (a review).
        bandwidth: Bandwidth of the tracking PD at 250 Hz and faster [Hz] (see
            :class:`JointTracker`); at a slower rate, what the loop's delay allows
            (:func:`~leadthrough.control.tracking.period_bandwidth`: 2.8 Hz at 125 Hz).
        integral_time: Integral action ``K_I = K_P / integral_time`` [s] for the friction
            the model lacks (stiction, the cable effect), at ``bandwidth``; where the
            period lowers the bandwidth, the time grows as much (the loop keeps its
            shape); 0 turns it off.
    """

    smoothing_time: float = 0.05
    time_scale: float = 1.0
    pause_speed: float = 0.01
    pause_time: float = 0.3
    approach_time: float = 2.0
    approach_speed: float = 0.2
    max_tracking_error: float = 0.1
    margin: float = 0.02
    limit_share: float = 0.85
    bandwidth: float = 4.0
    integral_time: float = 0.1

    def __post_init__(self) -> None:
        for name in ("smoothing_time", "approach_time", "margin", "integral_time"):
            real(name, getattr(self, name), minimum=0.0, error=ParameterError)
        share = real("limit_share", self.limit_share, minimum=0.0, strict=True,
                     error=ParameterError)  # fmt: skip
        if share > 1.0:
            raise ParameterError("limit_share", f"must be at most 1 (the limits), got {share:g}")
        for name in (
            "time_scale",
            "pause_speed",
            "pause_time",
            "bandwidth",
            "approach_speed",
            "max_tracking_error",
        ):
            real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)


@dataclass(frozen=True, eq=False)
class ReplayPlan:
    """A checked path to replay, uniformly sampled (N samples of n joints).

    Attributes:
        t: Plan time from the path start [s], (N,), uniform.
        q: Joint reference [rad], (N, n).
        qd: Joint velocity reference [rad/s], (N, n).
        qdd: Joint acceleration reference [rad/s²], (N, n).
        waypoints: Index of the middle of each pause inside the path.
        segments: ``(start, stop)`` index ranges of motion between pauses, ``q[start:stop]``.
        tau_required: Torque the path needs, ``M q̈ + C q̇ + G + mean_f(q̇)`` [Nm], (N, n).
        parameters: The settings it was planned with.
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    waypoints: list[int]
    segments: list[tuple[int, int]]
    tau_required: FloatArray
    parameters: ReplayParameters = field(default_factory=ReplayParameters)

    @property
    def duration(self) -> float:
        """Duration of the path [s]."""
        return float(self.t[-1])

    def reference(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Reference (q [rad], q̇ [rad/s], q̈ [rad/s²]) at plan time ``t`` [s], held at the ends."""
        if t <= 0.0 or t >= self.duration:
            rest = np.zeros_like(self.q[0])
            return (self.q[0] if t <= 0.0 else self.q[-1]).copy(), rest, rest.copy()
        position = t / self.t[1]
        i = min(int(position), len(self.t) - 2)
        w = position - i
        q, qd, qdd = ((1.0 - w) * a[i] + w * a[i + 1] for a in (self.q, self.qd, self.qdd))
        return q, qd, qdd


def plan_replay(
    t: ArrayLike,
    q: ArrayLike,
    dynamics: Dynamics,
    friction: FrictionModel | None = None,
    parameters: ReplayParameters | None = None,
) -> ReplayPlan:
    """Plan the replay of a recorded joint path, and check it before anything moves.

    Args:
        t: Recording times [s], (N,), increasing (a repeated stamp keeps its first sample).
        q: Recorded joint readings [rad], (N, n).
        dynamics: Model of the arm (limits, inverse dynamics).
        friction: Friction model for the required torque; default the description's.
        parameters: Replay settings.

    Returns:
        The plan, from time 0, sampled at the recording's median period × ``time_scale``.

    Raises:
        ReplayError: A malformed recording (shape, < 2 samples, non-finite, time not
            increasing), or a path beyond a position, speed or torque limit (one line
            naming the joint, the time, the value and the limit).
    """
    p = parameters or ReplayParameters()
    friction = friction or FrictionModel.from_robot(dynamics.robot)
    t, q = _checked_recording(t, q, dynamics.n)
    dt = float(np.median(np.diff(t)))
    taught_t = np.arange(int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1, dtype=float) * dt
    taught_t, q_taught = _stopped(
        taught_t, np.column_stack([np.interp(taught_t, t - t[0], x) for x in q.T]), p.pause_speed
    )
    q_smooth = _smooth(q_taught, dt, p.smoothing_time)
    qd_taught = np.gradient(q_smooth, dt, axis=0)
    qd, qdd = qd_taught / p.time_scale, np.gradient(qd_taught, dt, axis=0) / p.time_scale**2
    waypoints, segments = _pauses(np.abs(qd_taught).max(axis=1) < p.pause_speed, dt, p.pause_time)
    gravity = np.array([dynamics.gravity(x) for x in q_smooth])
    dynamic = np.array([dynamics.inverse_dynamics(*x) for x in zip(q_smooth, qd, qdd, strict=True)])
    dynamic -= gravity  # M q̈ + C q̇: it scales as 1/s² when the path is slowed by s
    tau = gravity + dynamic + friction.mean(qd, q_smooth)
    plan = ReplayPlan(taught_t * p.time_scale, q_smooth, qd, qdd, waypoints, segments, tau, p)
    _check_limits(plan, dynamics.robot, friction, dynamic, gravity)
    return plan


def _stopped(t: FloatArray, q: FloatArray, still: float) -> tuple[FloatArray, FloatArray]:
    """The path (t [s] uniform, q [rad]) brought to rest if it ends moving faster than ``still``.

    A recording cut while the arm moved (Ctrl-C mid-motion, a recovered ``.part``) ended
    its reference at full speed: the replay then stopped in one period (60 rad/s², 12.7 Nm
    on joint 2 where the path needed 5.6). The path goes on along its last velocity ``v``,
    decaying as ``v (1 − s/T)²`` (no step in velocity or acceleration at the end), over
    ``T`` long enough to decelerate at :data:`STOP_ACCELERATION`; the plan's limits are
    checked on it as on the rest.
    """
    if len(t) < 3:
        return t, q
    dt = float(t[1] - t[0])
    # the last velocity: a line through the last 0.1 s (an encoder's steps read no speed)
    window = min(len(t), max(3, round(STOP_WINDOW / dt)))
    x = t[-window:] - t[-window:].mean()
    velocity = x @ (q[-window:] - q[-window:].mean(axis=0)) / (x @ x)
    fastest = float(np.max(np.abs(velocity)))
    if fastest <= still:
        return t, q
    duration = max(STOP_MIN_TIME, 2.0 * fastest / STOP_ACCELERATION)
    s = np.arange(1, int(np.ceil(duration / dt)) + 1) * dt
    travel = s - s**2 / duration + s**3 / (3.0 * duration**2)  # ∫ (1 − s/T)² ds
    tail = q[-1] + np.outer(np.minimum(travel, duration / 3.0), velocity)
    return np.concatenate([t, t[-1] + s]), np.vstack([q, tail])


def _checked_recording(t: ArrayLike, q: ArrayLike, n: int) -> tuple[FloatArray, FloatArray]:
    """The recording as float arrays, or a ReplayError saying what is wrong with it."""
    try:
        t, q = np.asarray(t, dtype=float), np.asarray(q, dtype=float)
    except (TypeError, ValueError) as error:
        raise ReplayError(f"recording is not numeric: {error}") from None
    if t.ndim != 1 or q.shape != (len(t), n):
        raise ReplayError(f"expected shapes t (N,) and q (N, {n}), got {t.shape} and {q.shape}")
    if len(t) < 2:
        raise ReplayError(f"a path needs at least 2 samples, got {len(t)}")
    bad_t = np.flatnonzero(~np.isfinite(t))
    if bad_t.size:
        raise ReplayError(f"time t[{bad_t[0]}] is {t[bad_t[0]]}")
    bad = np.argwhere(~np.isfinite(q))
    if bad.size:
        k, j = bad[0]
        raise ReplayError(f"joint {j + 1} reading at t = {t[k]:.4g} s (sample {k}) is {q[k, j]}",
                          int(j) + 1)  # fmt: skip
    steps = np.flatnonzero(np.diff(t) < 0.0)
    if steps.size:
        k = steps[0]
        raise ReplayError(f"time not increasing: t[{k + 1}] = {t[k + 1]:.6g} s after t[{k}]")
    # a stamp repeated (a coarse clock, which the supervisor takes while teaching): its first
    # sample stands for it; before, the whole recording was refused
    first = np.concatenate([[True], np.diff(t) > 0.0])
    if np.count_nonzero(first) < 2:
        raise ReplayError(f"a path needs at least 2 times, got {np.count_nonzero(first)}")
    return t[first], q[first]


def _smooth(q: FloatArray, dt: float, smoothing_time: float) -> FloatArray:
    """Zero-phase 2nd-order Butterworth at 1 / (2π τ) along the time axis (forward-backward).

    The path is first continued at each end by the cubic fitted over its last 4 τ, so
    that the ends keep their value, slope and curvature.
    """
    cutoff = 1.0 / (2.0 * np.pi * smoothing_time) if smoothing_time > 0.0 else np.inf
    if cutoff >= 0.45 / dt or len(q) < 4:  # nothing to remove below the Nyquist frequency
        return q.copy()
    from scipy.signal import butter, filtfilt  # at call time: a slow import

    b, a = butter(2, cutoff, fs=1.0 / dt)
    pad = round(6.0 * smoothing_time / dt) + 6
    fit = min(len(q), round(4.0 * smoothing_time / dt) + 4)
    extended = np.concatenate([_continued(q[:fit][::-1], pad)[::-1], q, _continued(q[-fit:], pad)])
    return filtfilt(b, a, extended, axis=0, padtype=None)[pad:-pad]


def _continued(end: FloatArray, count: int) -> FloatArray:
    """``count`` samples that continue ``end`` (samples, n) along its least-squares cubic."""
    s = np.arange(len(end)) / len(end)
    cubic = polynomial.polyfit(s, end, min(3, len(end) - 1))
    return cast(FloatArray, polynomial.polyval((len(end) + np.arange(count)) / len(end), cubic).T)


def _pauses(slow: np.ndarray, dt: float, pause_time: float) -> tuple[list, list]:
    """Waypoints (middles of the pauses inside the path) and the motion segments between."""
    edges = np.diff(np.concatenate([[0], slow.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    long_enough = (stops - starts) * dt >= pause_time - 1e-9
    pauses = list(zip(starts[long_enough].tolist(), stops[long_enough].tolist(), strict=True))
    waypoints = [(a + b - 1) // 2 for a, b in pauses if a > 0 and b < len(slow)]
    bounds = [0, *[i for pause in pauses for i in pause], len(slow)]
    segments = [(a, b) for a, b in zip(bounds[::2], bounds[1::2], strict=True) if b > a]
    return waypoints, segments


def _check_limits(plan: ReplayPlan, robot: RobotDescription, friction: FrictionModel,
                  dynamic: FloatArray, gravity: FloatArray) -> None:  # fmt: skip
    """Raise ReplayError naming the first violation: of position, then speed, then torque.

    Speed and torque are checked against ``limit_share`` of the limits; for them it
    suggests the smallest time_scale, on a 5 % grid up to 20× the plan's, that passes both
    (slowed by s: q̇ → q̇/s, ``M q̈ + C q̇`` → ``/s²``).
    """
    margin, share = plan.parameters.margin, plan.parameters.limit_share
    speed, torque = share * robot.velocity_limits, share * robot.torque_limits
    checks = (("position", plan.q, robot.q_min + margin, robot.q_max - margin, "rad"),
              ("speed", plan.qd, -speed, speed, "rad/s"),
              ("torque", plan.tau_required, -torque, torque, "Nm"))  # fmt: skip
    for kind, values, low, high, unit in checks:
        beyond = (values < low) | (values > high)
        if not beyond.any():
            continue
        k, j = np.argwhere(beyond)[0]  # the earliest sample, its lowest joint
        limit = low[j] if values[k, j] < low[j] else high[j]
        where = f"joint {j + 1} {kind} {values[k, j]:.4g} {unit} at t = {plan.t[k]:.3f} s is"
        if kind == "position":
            raise ReplayError(f"{where} beyond its limit {limit:.4g} {unit} ({margin:g} rad "
                              "inside the joint range)", int(j) + 1)  # fmt: skip
        reason = (f"{where} beyond {share:.0%} of its limit {abs(limit) / share:.4g} {unit} (the "
                  "tracking needs the rest)")  # fmt: skip
        needed = None
        for slower in 1.05 ** np.arange(1, 63):
            tau = gravity + dynamic / slower**2 + friction.mean(plan.qd / slower, plan.q)
            if np.all(np.abs(plan.qd) <= slower * speed) and np.all(np.abs(tau) <= torque):
                needed = float(plan.parameters.time_scale * slower)
                break
        advice = ("not even 20 times slower passes" if needed is None
                  else f"replay slower, time_scale >= {needed:.3g}")  # fmt: skip
        if needed is None and np.any(np.abs(gravity) > torque):  # holding alone is too much
            at, joint = np.argwhere(np.abs(gravity) > torque)[0]
            advice = (f"holding the pose of t = {plan.t[at]:.3f} s against gravity alone takes "
                      f"joint {joint + 1} {abs(gravity[at, joint]):.4g} Nm: no time scale "
                      "helps")  # fmt: skip
        raise ReplayError(f"{reason}: {advice}", int(j) + 1, needed)


class Replayer:
    """Replays a plan: ``tau_cmd = replayer.step(state)`` once per period.

    Time comes from the robot's samples (``state.t``, any origin): the replay's clock
    starts at the first sample. The positional form ``step(q, qd, tau_measured)`` counts
    periods of ``dt`` instead.

    A minimum-jerk move from the first pose read to the path start (``approach_time``),
    then the path, then a hold of its last pose::

        τ = G(q) + M(q) q̈_ref + K_P e + K_D ė + K_I ∫e + mean_f(q̇_ref + e K_P / K_D)

    with ``e = q_ref − q`` and the PD of :class:`JointTracker`. The friction is taken at
    the velocity the loop asks for, so a joint left behind (stuck after a pause) gets its
    Coulomb torque towards the reference; the integral, clamped to ±2 τ_C, takes what the
    friction model lacks (stiction, the cable effect). Every command goes through the
    supervisor, kept in HOLDING: replay is not teaching, so the 250 mm/s tool limit does
    not apply; the joint speed and torque limits and the soft walls do.

    Attributes:
        supervisor: The safety supervisor every command passes.
        integral: Integral torque [Nm], (n,).
        time: Time of the latest sample since the first one [s] (the approach starts at 0).

    Args:
        plan: A plan from :func:`plan_replay`.
        dynamics: Model of the arm.
        friction: Friction model for the feed-forward; default the description's.
        dt: Control period [s].
        parameters: Replay settings; default ``plan.parameters``.
        supervisor: Safety supervisor to use (switched to HOLDING); default a new one.
    """

    def __init__(
        self,
        plan: ReplayPlan,
        dynamics: Dynamics,
        friction: FrictionModel | None = None,
        dt: float = 0.004,
        parameters: ReplayParameters | None = None,
        supervisor: SafetySupervisor | None = None,
    ) -> None:
        if plan.q.shape[1] != dynamics.n:
            raise ReplayError(f"plan has {plan.q.shape[1]} joints, the robot {dynamics.n}")
        self.plan, self.dynamics = plan, dynamics
        self.friction = friction or FrictionModel.from_robot(dynamics.robot)
        self.dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
        self.parameters = p = parameters or plan.parameters
        self.supervisor = supervisor or SafetySupervisor(dynamics, self.dt)
        self.supervisor.hold()
        # the integral a fixed share of ω³, as at the bandwidth asked for (K_P / integral_time)
        share = 1.0 / (p.integral_time * 2.0 * np.pi * p.bandwidth) if p.integral_time else 0.0
        bandwidth = period_bandwidth(p.bandwidth, self.dt, pd_gains(1.0, share))
        self.tracker = JointTracker(dynamics, bandwidth, 1.0, plan.q[0])
        self.ki = self.tracker.kp * share * 2.0 * np.pi * bandwidth
        self.integral = np.zeros(dynamics.n)
        self._integral_limit = INTEGRAL_LIMIT * self.friction.coulomb
        self.time, self._steps = 0.0, 0
        self._t0: float | None = None  # the first sample's time on the robot's clock [s]
        self._start: FloatArray | None = None
        #: Duration of the approach to the path start [s]: ``parameters.approach_time``, or
        #: longer once the first sample shows the arm farther from the start than that
        #: allows at ``approach_speed`` of its joints' speed limits
        self.approach_time = p.approach_time
        self._progress = 0.0

    def reset(self) -> None:
        """Start the replay afresh from the next sample: a new approach from where the arm is.

        The supervisor's fault is cleared (HOLDING), the integral emptied, the clock and the
        approach restarted. Before, only the supervisor could be reset: the replay clock had
        run on through the fault, and the arm, 0.24 rad off a reference that had moved on,
        jumped to it at 2.7 rad/s (the path's 0.5 rad/s).
        """
        self.supervisor.reset()
        self.supervisor.hold()
        self.integral = np.zeros(self.dynamics.n)
        self.time, self._steps, self._t0, self._start = 0.0, 0, None, None
        self.approach_time, self._progress = self.parameters.approach_time, 0.0

    @property
    def progress(self) -> float:
        """Fraction of the path replayed, in [0, 1] (0 during the approach).

        It stops where a fault stopped the replay (it went on to 1 with the clock).
        """
        return self._progress

    def _progress_now(self) -> float:
        elapsed = self.time - self.approach_time
        return float(np.clip(elapsed / max(self.plan.duration, 1e-12), 0.0, 1.0))

    @property
    def faulted(self) -> bool:
        """Whether the supervisor stopped the replay (see ``supervisor.fault_reason``)."""
        return self.supervisor.state is SupervisorState.FAULT

    @property
    def done(self) -> bool:
        """Whether nothing more will be replayed (:attr:`faulted` tells why).

        The path is over and its last pose held for 0.5 s, or a fault stopped it.
        """
        end = self.approach_time + self.plan.duration + SETTLE_TIME
        return self.faulted or self.time >= end - 1e-9

    def warm_up(self) -> float:
        """Compile every kernel the step will call, on a replica; return the time [s].

        See :meth:`LeadThrough.warm_up <leadthrough.LeadThrough.warm_up>`.
        """
        robot = self.dynamics.robot
        replica = Replayer(self.plan, Dynamics(robot), self.friction, self.dt, self.parameters)
        return exercise(replica, self.plan.q[0].copy(), robot.velocity_limits)

    def _approach_time(self, start: FloatArray) -> float:
        """How long the approach from ``start`` [rad] takes [s] (:attr:`approach_time`).

        A minimum-jerk move of ``Δq`` in ``T`` peaks at ``1.875 Δq / T``: kept below
        ``approach_speed`` of each joint's speed limit. Before, it always took
        ``approach_time``: an arm 2.5 rad from the start moved at 2.3 rad/s, one 5.2 rad away
        at 4.4 rad/s against its 3.14 limit (the supervisor only braked it).
        """
        distance = np.abs(self.plan.q[0] - start)
        limit = self.parameters.approach_speed * self.dynamics.robot.velocity_limits
        return float(max(self.parameters.approach_time, np.max(1.875 * distance / limit)))

    def reference(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Reference (q [rad], q̇ [rad/s], q̈ [rad/s²]) at time ``t`` [s] since the first step."""
        approach = self.approach_time
        if t >= approach or self._start is None:
            return self.plan.reference(t - approach)
        phase, rate = minimum_jerk_phase(t, approach)
        distance = self.plan.q[0] - self._start
        acceleration = minimum_jerk_acceleration(t, approach) * distance
        return self._start + phase * distance, rate * distance, acceleration

    def step(
        self,
        q: JointState | ArrayLike,
        qd: ArrayLike | None = None,
        tau_measured: ArrayLike | None = None,
    ) -> FloatArray:
        """Motor torque command [Nm] for this period (always finite, within the limits).

        Args:
            q: The joint readings q [rad], (n,); or the robot's sample, a
                :class:`JointState` (t [s], q [rad], q̇ [rad/s], τ [Nm]), and nothing else.
            qd: Joint velocities [rad/s], (n,) (with q only).
            tau_measured: Measured motor torque [Nm], (n,), or None (only checked; with q
                only).

        An exception inside the step latches the supervisor's fault naming it, and the
        safe stop is returned this period.
        """
        sample = joint_state(q, qd, tau_measured, self._steps * self.dt)
        t, q, qd, tau_measured = sample.t, sample.q, sample.qd, sample.tau_measured
        self._steps += 1
        if self._t0 is None:
            self._t0 = float(t)
        self.time = float(t) - self._t0
        if not self.faulted:
            self._progress = self._progress_now()
        supervisor, zeros = self.supervisor, np.zeros(self.dynamics.n)
        if not supervisor.check(t, q, qd, tau_measured):
            return supervisor.command(t, q, qd, zeros)
        try:
            model = self.dynamics.snapshot(q, qd)
            desired = self._desired(model)
        except Exception as error:  # the safe stop this period, and the fault says what failed
            supervisor.stop(failure("replay", error), t)
            return supervisor.command(t, q, qd, zeros)
        return supervisor.command(t, q, qd, desired, model)

    def _desired(self, model: ModelSnapshot) -> FloatArray:
        """The tracking torque [Nm] at the model's state and the replay time."""
        q, qd = model.q, model.qd
        if self._start is None:
            self._start = q.copy()
            self.approach_time = self._approach_time(self._start)
        q_ref, qd_ref, qdd_ref = self.reference(self.time)
        error, tracker = q_ref - q, self.tracker
        off = np.abs(error)
        if np.max(off) > self.parameters.max_tracking_error:
            joint = int(np.argmax(off))
            raise ReplayError(f"joint {joint + 1} is {off[joint]:.3f} rad off its reference, more "
                              f"than {self.parameters.max_tracking_error:g} rad: is the arm held "
                              "or blocked?")  # fmt: skip
        self.integral = np.clip(self.integral + self.ki * error * self.dt,
                                -self._integral_limit, self._integral_limit)  # fmt: skip
        asked = qd_ref + tracker.kp / tracker.kd * error  # the velocity the PD asks for
        desired = tracker.torque(q, qd, q_ref, qd_ref, qdd_ref) + self.integral
        return desired + self.friction.mean(asked, q_ref)


def replay_errors(
    plan: ReplayPlan,
    q_measured: ArrayLike,
    t_measured: ArrayLike,
    dynamics: Dynamics | None = None,
    flange_position: ArrayLike | None = None,
    approach_time: float | None = None,
) -> dict[str, float]:
    """How closely a replay followed its plan, at equal plan time, within the path only.

    Args:
        plan: The plan replayed.
        q_measured: Joint angles during the replay [rad], (M, n).
        t_measured: Their times since the replayer's first step [s], (M,).
        dynamics: Model of the arm; with it, the tool-path errors too.
        flange_position: Measured flange positions in the world [m], (M, 3); default
            the forward kinematics of ``q_measured``.
        approach_time: Duration of the approach [s]; default the plan's.

    Returns:
        ``joint_rms`` (over all joints and samples) and ``joint_max`` [rad], ``samples``
        compared; with ``dynamics``, ``tool_rms`` and ``tool_max`` [m] of the flange.
    """
    q_measured, t_measured = np.asarray(q_measured, float), np.asarray(t_measured, float)
    if q_measured.shape != (len(t_measured), plan.q.shape[1]):
        raise ReplayError(f"expected q_measured of shape ({len(t_measured)}, "
                          f"{plan.q.shape[1]}), got {q_measured.shape}")  # fmt: skip
    approach = plan.parameters.approach_time if approach_time is None else approach_time
    t_plan = t_measured - approach
    inside = (t_plan >= 0.0) & (t_plan <= plan.duration + 1e-9)
    if not inside.any():
        raise ReplayError("no measured sample falls within the path")
    q_ref = np.column_stack([np.interp(t_plan[inside], plan.t, x) for x in plan.q.T])
    error = q_measured[inside] - q_ref
    result = {"joint_rms": float(np.sqrt(np.mean(error**2))), "samples": float(inside.sum()),
              "joint_max": float(np.max(np.abs(error)))}  # fmt: skip
    if dynamics is not None:
        measured = (np.asarray(flange_position, dtype=float)[inside] if flange_position is not None
                    else _flange_positions(dynamics, q_measured[inside]))  # fmt: skip
        distance = np.linalg.norm(measured - _flange_positions(dynamics, q_ref), axis=1)
        result["tool_rms"] = float(np.sqrt(np.mean(distance**2)))
        result["tool_max"] = float(np.max(distance))
    return result


def _flange_positions(dynamics: Dynamics, q: FloatArray) -> FloatArray:
    """Flange positions in the world [m], (M, 3), of joint angles q [rad], (M, n)."""
    return np.array([dynamics.pose(row)[:3, 3] for row in q])
