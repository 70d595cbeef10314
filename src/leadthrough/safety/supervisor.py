"""The safety supervisor: always on, the last stage on the path to the motors (SPEC §7).

Every controller sends its torque through one :class:`SafetySupervisor`, once per period::

    if supervisor.check(t, q, qd, tau_measured):
        tau_desired = controller.step(q, qd, tau_measured)
    tau = supervisor.command(t, q, qd, tau_desired)   # always finite, within the limits

It saturates the torque, brakes joints above their speed limit and, while teaching, a
tool above 250 mm/s (ISO 10218-1 reduced speed), adds soft walls inside the position
limits, and latches a FAULT on non-finite, frozen or out-of-range sensor data or a
non-finite command: then the safe stop (gravity hold with damping, then gravity hold
alone, no feedback) until ``reset()``. No exception escapes ``check`` or ``command``.
Messages number the joints from 1 at the base.

Cost: the bounds are computed once, in the constructor; a good sample is validated with
one vectorised comparison per call, and the reasons, events and per-joint loops only run
when something is wrong (a fault, a wall, a joint or the tool too fast).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.errors import ParameterError
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.validation import real


class SupervisorState(StrEnum):
    """Mode of the supervisor: teaching (tool speed limited), holding, or latched fault."""

    TEACHING = "teaching"
    HOLDING = "holding"
    FAULT = "fault"


@dataclass(frozen=True)
class SafetyEvent:
    """One entry of the supervisor's log.

    Attributes:
        t: Time of the control period it happened in [s].
        kind: ``"fault"``, ``"tool_speed"``, ``"joint_speed"``, ``"soft_limit"``, ``"calibration"``,
            ``"overrun"``, ``"reset"`` or ``"mode"``.
        detail: One line saying what happened, with the joint and the value.
    """

    t: float
    kind: str
    detail: str


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
        stale_periods: A joint whose q and q̇ are bit-identical for this many consecutive
            samples has a frozen encoder (≥ 2; 0 turns the check off, for noiseless mocks).
        torque_reading_margin: Measured torques beyond this × the torque limit are out of range.
        velocity_reading_margin: Velocities beyond this × the speed limit are out of range.
        position_reading_margin: Positions this far beyond the hard limits are out of range [rad].
        safe_stop_damping_time: Duration of the damped hold after a fault [s], then no damping.
    """

    tool_speed_limit: float = 0.25
    joint_speed_fraction: float = 1.0
    braking_time: float = 0.05
    soft_limit_margin: float = 0.1
    wall_torque_fraction: float = 0.5
    wall_damping_time: float = 0.05
    stale_periods: int = 25
    torque_reading_margin: float = 1.5
    velocity_reading_margin: float = 2.0
    position_reading_margin: float = 0.1
    safe_stop_damping_time: float = 0.5

    def __post_init__(self) -> None:
        for name in ("tool_speed_limit", "braking_time", "soft_limit_margin", "wall_damping_time"):
            real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)
        for name in ("joint_speed_fraction", "wall_torque_fraction"):
            value = real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)
            if value > 1.0:
                raise ParameterError(name, f"must be in (0, 1], got {value:g}")
        for name in ("torque_reading_margin", "velocity_reading_margin"):
            real(name, getattr(self, name), minimum=1.0, error=ParameterError)
        for name in ("position_reading_margin", "safe_stop_damping_time"):
            real(name, getattr(self, name), minimum=0.0, error=ParameterError)
        stale = self.stale_periods
        is_integer = isinstance(stale, int | np.integer) and not isinstance(stale, bool)
        if not is_integer or stale < 0 or stale == 1:
            raise ParameterError("stale_periods", f"must be an integer ≥ 2 or 0, got {stale!r}")


@dataclass(frozen=True, eq=False)
class _Limits:
    """The supervisor's bounds, computed once from the robot and the settings.

    Attributes:
        torque: Torque limits [Nm], shape (n,); ``-torque`` is ``torque_low``.
        torque_low: Lower torque limits [Nm], shape (n,).
        q_low: Position readings below this are faults [rad], shape (n,).
        q_high: Position readings above this are faults [rad], shape (n,).
        qd_bound: Velocity readings beyond ± this are faults [rad/s], shape (n,).
        tau_bound: Torque readings beyond ± this are faults [Nm], shape (n,).
        speed: Joint speed limits, braked above [rad/s], shape (n,).
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
    wall_low: FloatArray
    wall_high: FloatArray
    stiffness: FloatArray
    sample_low: FloatArray
    sample_high: FloatArray
    command_low: FloatArray
    command_high: FloatArray

    @classmethod
    def of(cls, robot: RobotDescription, p: SafetyParameters) -> _Limits:
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
            wall_low=robot.q_min + p.soft_limit_margin,
            wall_high=robot.q_max - p.soft_limit_margin,
            stiffness=p.wall_torque_fraction * robot.torque_limits / p.soft_limit_margin,
            sample_low=np.concatenate((q_low, -qd_bound, -tau_bound)),
            sample_high=np.concatenate((q_high, qd_bound, tau_bound)),
            command_low=np.concatenate((q_low, -qd_bound, -finite)),
            command_high=np.concatenate((q_high, qd_bound, finite)),
        )


class SafetySupervisor:
    """Limits, braking, walls, sensor checks and the safe stop, for one arm.

    Attributes:
        state: Current mode; starts in HOLDING.
        fault_reason: Why the latched fault happened (the first reason), else None.
        events: Log of what happened, one entry per episode (not per period).
        overruns: Number of control periods that missed their deadline.
        max_tool_speed: Largest flange speed seen while teaching [m/s].

    Args:
        dynamics: Model of the arm (limits, M(q), G(q), flange Jacobian).
        dt: Control period [s].
        parameters: Safety settings (read once, here, with the robot's limits).
    """

    def __init__(
        self, dynamics: Dynamics, dt: float = 0.004, parameters: SafetyParameters | None = None
    ) -> None:
        self.dynamics = dynamics
        self.robot = dynamics.robot
        self.n = dynamics.n
        self.dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
        self.parameters = parameters or SafetyParameters()
        self._limits = _Limits.of(self.robot, self.parameters)
        self.state = SupervisorState.HOLDING
        self.fault_reason: str | None = None
        self.events: list[SafetyEvent] = []
        self.overruns = 0
        self.max_tool_speed = 0.0
        self._t = 0.0
        self._fault_time = 0.0
        self._q_last_good: FloatArray | None = None
        self._in_overrun = False
        self._clear_episodes()

    def teach(self) -> None:
        """Switch to TEACHING (tool speed limited); ignored while in FAULT."""
        self._set_mode(SupervisorState.TEACHING)

    def hold(self) -> None:
        """Switch to HOLDING; ignored while in FAULT."""
        self._set_mode(SupervisorState.HOLDING)

    def stop(self, reason: str) -> None:
        """Latch FAULT with ``reason`` from outside (Ctrl-C, a robot error): the safe stop.

        From the next :meth:`command` on, the arm gets the safe stop until :meth:`reset`.
        """
        self._fault(reason)

    def reset(self) -> None:
        """Clear a latched fault and go to HOLDING; frozen-encoder counters restart."""
        self.state = SupervisorState.HOLDING
        self.fault_reason = None
        self._clear_episodes()
        self._log("reset", "supervisor reset: holding")

    def check(
        self, t: float, q: ArrayLike, qd: ArrayLike, tau_measured: ArrayLike | None = None
    ) -> bool:
        """Validate one sensor sample; a bad one latches FAULT with the reason.

        Args:
            t: Time of the sample [s].
            q: Joint readings [rad], shape (n,).
            qd: Joint velocities [rad/s], shape (n,).
            tau_measured: Measured joint torques, arm side [Nm], shape (n,), or None.

        Returns:
            True when the sample is good and no fault is latched.
        """
        try:
            self._t = float(t)
            q, qd = _floats(q), _floats(qd)
            tau = None if tau_measured is None else _floats(tau_measured)
            problem = self._sample_problem(q, qd, tau) or self._stale_problem(q, qd)
        except Exception as error:  # nothing may escape on the motor path
            problem = f"sensor check failed: {type(error).__name__}: {error}"
        if problem is not None:
            self._fault(problem)
            return False
        self._q_last_good = q
        return self.state is not SupervisorState.FAULT

    def command(self, t: float, q: ArrayLike, qd: ArrayLike, tau_desired: ArrayLike) -> FloatArray:
        """The torque actually sent to the motors [Nm], arm side, shape (n,).

        Always finite and within ± the torque limits: the safe stop in FAULT, else the
        saturated desired torque plus the soft-limit walls and the braking torques.

        Args:
            t: Time of the period [s].
            q: Joint readings [rad], shape (n,).
            qd: Joint velocities [rad/s], shape (n,).
            tau_desired: The controller's torque [Nm], shape (n,).
        """
        try:
            self._t = float(t)
            if self.state is not SupervisorState.FAULT:
                tau = self._supervised(_floats(q), _floats(qd), _floats(tau_desired))
                if tau is not None:
                    return tau
        except Exception as error:  # nothing may escape on the motor path
            self._fault(f"command failed: {type(error).__name__}: {error}")
        return self._safe_stop(qd)

    def record_cycle(self, t: float, duration: float) -> None:
        """Count a missed deadline when one control cycle took longer than ``dt``.

        Args:
            t: Time of the period [s].
            duration: Wall-clock time the cycle took [s] (NaN counts as an overrun).
        """
        overrun = not duration <= self.dt
        if overrun:
            self.overruns += 1
            if not self._in_overrun:
                detail = f"control cycle took {duration * 1e3:.3g} ms > {self.dt * 1e3:.3g} ms"
                self.events.append(SafetyEvent(float(t), "overrun", detail))
        self._in_overrun = overrun

    def _supervised(
        self, q: FloatArray, qd: FloatArray, tau_desired: FloatArray
    ) -> FloatArray | None:
        """The supervised torque [Nm], or None after latching a fault (bad input or torque)."""
        if self._input_problem(q, qd, tau_desired) is not None:
            return None
        self._q_last_good = q
        mass = self.dynamics.mass(q)
        inertia = mass.diagonal()
        tau = self._saturated(tau_desired)  # a huge command cannot swamp the safety
        braking = self._joint_braking(qd, inertia)
        if self.state is SupervisorState.TEACHING:
            braking = braking + self._tool_braking(q, qd, mass)
        braked = braking != 0.0
        if braked.any():
            # while braking, the brakes win: the controller's torque on a braked joint is
            # replaced by gravity compensation, so no controller can push through the limit
            tau = np.where(braked, self.dynamics.gravity(q), tau)
        tau += self._walls(q, qd, inertia) + braking
        if not np.isfinite(tau).all():
            self._fault("non-finite safety torque")
            return None
        return self._saturated(tau)

    def _saturated(self, tau: FloatArray) -> FloatArray:
        """``tau`` [Nm] clipped to ± the torque limits, as a new array.

        Same result as ``np.clip`` for a finite ``tau`` (the only kind passed here), at
        a third of its cost.
        """
        return np.minimum(np.maximum(tau, self._limits.torque_low), self._limits.torque)

    def _walls(self, q: FloatArray, qd: FloatArray, inertia: FloatArray) -> FloatArray:
        """Spring-damper walls inside the position limits [Nm], pushing away from them.

        Args:
            q: Joint positions [rad], finite, shape (n,).
            qd: Joint velocities [rad/s], shape (n,).
            inertia: Diagonal of M(q) [kg m²], shape (n,).
        """
        limits, robot = self._limits, self.robot
        # q is finite, so this is exactly where `below > 0` or `above > 0` below
        if not ((q < limits.wall_low) | (q > limits.wall_high)).any():
            self._active.pop("soft_limit", None)  # the episode, if any, is over
            return np.zeros(self.n)
        stiffness = limits.stiffness
        damping = inertia / self.parameters.wall_damping_time
        below = np.maximum(limits.wall_low - q, 0.0)
        above = np.maximum(q - limits.wall_high, 0.0)
        push_up = np.where(below > 0.0, stiffness * below + damping * np.maximum(-qd, 0.0), 0.0)
        push_down = np.where(above > 0.0, stiffness * above + damping * np.maximum(qd, 0.0), 0.0)
        for i in self._started("soft_limit", (below > 0.0) | (above > 0.0)):
            side, hard = ("lower", robot.q_min[i]) if below[i] > 0 else ("upper", robot.q_max[i])
            detail = f"joint {i + 1} entered the {side} soft limit at {q[i]:.4g} rad"
            self._log("soft_limit", f"{detail} (hard limit {hard:.4g} rad)")
        return push_up - push_down

    def _joint_braking(self, qd: FloatArray, inertia: FloatArray) -> FloatArray:
        """Torque [Nm] braking each joint faster than its speed limit, zero below.

        Args:
            qd: Joint velocities [rad/s], finite, shape (n,).
            inertia: Diagonal of M(q) [kg m²], shape (n,).
        """
        limit = self._limits.speed
        speed = np.abs(qd)
        fast = speed > limit  # q̇ is finite, so this is exactly `excess > 0`
        if not fast.any():
            self._active.pop("joint_speed", None)  # the episode, if any, is over
            return np.zeros(self.n)
        excess = np.maximum(speed - limit, 0.0)
        for i in self._started("joint_speed", fast):
            detail = f"joint {i + 1} speed {abs(qd[i]):.4g} rad/s above {limit[i]:.4g} rad/s"
            self._log("joint_speed", f"{detail}: braking")
        return -inertia * excess / self.parameters.braking_time * np.sign(qd)

    def _tool_braking(self, q: FloatArray, qd: FloatArray, mass: FloatArray) -> FloatArray:
        """Torque [Nm] braking the flange when faster than the teaching limit, else zero."""
        limit = self.parameters.tool_speed_limit
        velocity = self.dynamics.jacobian(q)[:3] @ qd
        speed = math.sqrt(velocity.dot(velocity))  # what np.linalg.norm computes
        self.max_tool_speed = max(self.max_tool_speed, speed)
        if self._began("tool_speed", speed > limit):
            self._log("tool_speed", f"tool speed {speed:.3g} m/s above {limit:.3g} m/s: braking")
        if speed <= limit:
            return np.zeros(self.n)
        return -(1.0 - limit / speed) * (mass @ qd) / self.parameters.braking_time

    def _safe_stop(self, qd: object) -> FloatArray:
        """Gravity hold at the last good position, damped for the first part of the stop."""
        p = self.parameters
        try:
            if self._q_last_good is None:  # no valid position ever read: nothing to hold
                return np.zeros(self.n)
            q = self._q_last_good
            tau = self.dynamics.gravity(q)
            if self._t - self._fault_time < p.safe_stop_damping_time:
                damping = self.dynamics.mass(q).diagonal() / p.braking_time
                tau = tau - damping * self._trusted_velocity(qd)
            return self._saturated(np.where(np.isfinite(tau), tau, 0.0))
        except Exception:  # the last resort must return a torque
            return np.zeros(self.n)

    def _trusted_velocity(self, qd: object) -> FloatArray:
        """The velocity reading [rad/s], zero where non-finite, out of range or frozen."""
        try:
            qd = _floats(qd)
        except (TypeError, ValueError):
            return np.zeros(self.n)
        if qd.shape != (self.n,):
            return np.zeros(self.n)
        bound = self._limits.qd_bound
        trusted = np.isfinite(qd) & (np.abs(qd) <= bound) & ~self._frozen()
        return np.where(trusted, qd, 0.0)

    def _sample_problem(self, q: FloatArray, qd: FloatArray, tau: FloatArray | None) -> str | None:
        """Why a sample is invalid (shape, non-finite, out of range), or None.

        The reason is only spelled out for a bad sample, and not while a fault is
        latched (``_fault`` would drop it): then it is a placeholder.
        """
        limits = self._limits
        readings = (q, qd) if tau is None else (q, qd, tau)
        if self._in_range(readings, limits.sample_low, limits.sample_high):
            return None
        if self.state is SupervisorState.FAULT:
            return _UNEXPLAINED
        return self._sample_reason(q, qd, tau)

    def _input_problem(self, q: FloatArray, qd: FloatArray, tau_desired: FloatArray) -> str | None:
        """Why (q [rad], q̇ [rad/s], τ_desired [Nm]) cannot be supervised, latched as a fault."""
        limits = self._limits
        if self._in_range((q, qd, tau_desired), limits.command_low, limits.command_high):
            return None
        problem = self._sample_reason(q, qd, None) or _command_problem(tau_desired, self.n)
        if problem is not None:
            self._fault(problem)
        return problem

    def _sample_reason(self, q: FloatArray, qd: FloatArray, tau: FloatArray | None) -> str | None:
        """The first problem of a sample, reading by reading and joint by joint, or None."""
        limits = self._limits
        speed, torque = limits.qd_bound, limits.tau_bound
        return (
            _reading_problem("position", q, limits.q_low, limits.q_high, "rad")
            or _reading_problem("velocity", qd, -speed, speed, "rad/s")
            or (None if tau is None else _reading_problem("torque", tau, -torque, torque, "Nm"))
        )

    def _in_range(
        self, readings: tuple[FloatArray, ...], low: FloatArray, high: FloatArray
    ) -> bool:
        """Whether every reading has shape (n,) and lies within [low, high] (NaN does not).

        Args:
            readings: Vectors in their units, each expected of shape (n,).
            low: Their lower bounds, concatenated in the same order, shape (k n,) with k at
                least the number of readings.
            high: Their upper bounds, likewise.
        """
        shape = (self.n,)
        for reading in readings:
            if reading.shape != shape:
                return False
        values = np.concatenate(readings)
        size = values.size
        return bool(((values >= low[:size]) & (values <= high[:size])).all())

    def _stale_problem(self, q: FloatArray, qd: FloatArray) -> str | None:
        """Count bit-identical (q, q̇) samples per joint; a frozen encoder's reason, or None."""
        n = self.n
        bits = np.concatenate((q, qd)).view(np.uint64)
        if self._previous_bits is None:
            self._runs = np.ones(n, dtype=int)
        else:
            same = bits == self._previous_bits
            self._runs = self._runs * (same[:n] & same[n:]) + 1  # a changed joint restarts at 1
        self._previous_bits = bits
        frozen = self._frozen()
        if not frozen.any():
            return None
        i = np.flatnonzero(frozen)[0]
        return f"joint {i + 1} encoder frozen: q and qd identical for {self._runs[i]} samples"

    def _frozen(self) -> NDArray[np.bool_]:
        """Joints whose encoder is frozen: ``stale_periods`` identical samples (0: none)."""
        periods = self.parameters.stale_periods
        if periods == 0:
            return np.zeros(self.n, dtype=bool)
        return self._runs >= periods

    def _began(self, key: str, active: bool) -> bool:
        """Whether the one-flag episode ``key`` became active this period."""
        if not active:
            self._active.pop(key, None)
            return False
        started = key not in self._active
        self._active[key] = _ACTIVE
        return started

    def _started(self, key: str, active: NDArray[np.bool_]) -> NDArray[np.intp]:
        """Indices where ``key`` became active this period (for one event per episode)."""
        if not active.any() and key not in self._active:
            return np.empty(0, dtype=np.intp)
        started = np.flatnonzero(active & ~self._active.get(key, np.zeros_like(active)))
        if not active.any():
            del self._active[key]
            return started
        self._active[key] = active
        return started

    def _set_mode(self, mode: SupervisorState) -> None:
        if self.state in (SupervisorState.FAULT, mode):
            return
        self.state = mode
        self._active.pop("tool_speed", None)
        self._log("mode", f"mode {mode.value}")

    def _fault(self, reason: str) -> None:
        """Latch FAULT with ``reason``; the first reason is kept until reset."""
        if self.state is SupervisorState.FAULT:
            return
        self.state = SupervisorState.FAULT
        self.fault_reason = reason
        self._fault_time = self._t
        self._log("fault", reason)

    def _log(self, kind: str, detail: str) -> None:
        self.events.append(SafetyEvent(self._t, kind, detail))

    def _clear_episodes(self) -> None:
        self._previous_bits: NDArray[np.uint64] | None = None
        self._runs = np.zeros(self.n, dtype=int)
        self._active: dict[str, NDArray[np.bool_]] = {}


#: Placeholder reason while a fault is latched: ``_fault`` keeps the first reason only.
_UNEXPLAINED = "invalid sample"

#: The stored state of an active one-flag episode (see ``_began``).
_ACTIVE = np.ones(1, dtype=bool)
_ACTIVE.setflags(write=False)


def _floats(value: object) -> FloatArray:
    """A fresh float array of ``value`` (the caller may reuse its buffer)."""
    return np.array(value, dtype=float)


def _reading_problem(
    kind: str, value: FloatArray, low: FloatArray, high: FloatArray, unit: str
) -> str | None:
    """Why one reading vector is invalid (shape, non-finite, outside [low, high]), or None."""
    if value.shape != low.shape:
        return f"{kind} reading has shape {value.shape}, expected {low.shape}"
    if np.all((value >= low) & (value <= high)):  # the usual case, one test (NaN fails it)
        return None
    bad = np.flatnonzero(~np.isfinite(value))
    if bad.size:
        return f"joint {bad[0] + 1} {kind} reading {value[bad[0]]}"
    bad = np.flatnonzero((value < low) | (value > high))
    if bad.size:
        i = bad[0]
        return (
            f"joint {i + 1} {kind} reading {value[i]:.4g} {unit} "
            f"outside [{low[i]:.4g}, {high[i]:.4g}] {unit}"
        )
    return None


def _command_problem(tau: FloatArray, n: int) -> str | None:
    """Why a controller's torque command is unusable (shape, non-finite), or None."""
    if tau.shape != (n,):
        return f"command has shape {tau.shape}, expected ({n},)"
    bad = np.flatnonzero(~np.isfinite(tau))
    return f"non-finite command on joint {bad[0] + 1}" if bad.size else None
