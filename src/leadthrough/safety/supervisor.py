"""The safety supervisor: always on, the last stage on the path to the motors (SPEC §7).

Every controller sends its torque through one :class:`SafetySupervisor`, once per period::

    if supervisor.check(t, q, qd, tau_measured):
        tau_desired = controller.step(q, qd, tau_measured)
    tau = supervisor.command(t, q, qd, tau_desired)   # always finite, within the limits

It saturates the torque, brakes joints above their speed limit and, while teaching, a
tool centre point (TCP) above 250 mm/s (ISO 10218-1 reduced speed), adds soft walls inside
the position limits, and latches a FAULT on non-finite, frozen or out-of-range sensor data or a
non-finite command: then the safe stop (gravity hold with damping, then gravity hold
alone, no feedback) until ``reset()``. No exception escapes ``check`` or ``command``.
Messages number the joints from 1 at the base.

Cost: the bounds are computed once, in the constructor; a good sample is validated and its
encoders counted in one compiled call (:meth:`.checks.FrozenEncoders.count`), the command
is limited in another (:mod:`.command`: saturation, joint and tool braking, walls,
finiteness), and the reasons and events are only spelled out when something is wrong (a
fault, a wall, a joint or the tool too fast). The readable NumPy code of the command path
(``compiled = False``) is the reference the tests hold the compiled one to.

The settings and bounds are in :mod:`.limits`, the sample checks in :mod:`.checks`, the
braking torques, walls and safe-stop hold in :mod:`.braking`, the log (one event per
episode) in :mod:`.events`; this module holds the state machine.
"""

from __future__ import annotations

import math
from enum import StrEnum

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.errors import ParameterError, failure
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics
from leadthrough.model.snapshot import ModelSnapshot
from leadthrough.safety import braking
from leadthrough.safety.checks import (
    OUT_OF_RANGE,
    RATE_WINDOW,
    FrozenEncoders,
    VelocityUnits,
    as_floats,
    clock_stopped,
    command_problem,
    floats,
    in_range,
    jump_problem,
    sample_rate_problem,
    sample_reason,
    seconds,
    time_problem,
    trusted_velocity,
    within_bounds,
)
from leadthrough.safety.command import (
    BAD_INPUT,
    NOT_FINITE,
    bound_rows,
    reference_torque,
    supervised_torque,
)
from leadthrough.safety.events import EventLog, SafetyEvent
from leadthrough.safety.limits import SafetyLimits, SafetyParameters
from leadthrough.validation import real


class SupervisorState(StrEnum):
    """Mode of the supervisor: teaching (tool speed limited), holding, or latched fault."""

    TEACHING = "teaching"
    HOLDING = "holding"
    FAULT = "fault"


class SafetySupervisor:
    """Limits, braking, walls, sensor checks and the safe stop, for one arm.

    Attributes:
        state: Current mode; starts in HOLDING.
        fault_reason: Why the latched fault happened (the first reason), else None.
        events: Log of what happened, one entry per episode (not per period).
        overruns: Number of control periods that missed their deadline.
        max_tool_speed: Largest TCP speed seen while teaching [m/s].

    Args:
        dynamics: Model of the arm (limits, M(q), G(q), TCP Jacobian); replace it with
            :meth:`use_model`, which keeps ``robot`` and the bounds in step.
        dt: Control period [s], at most ``parameters.max_time_gap``.
        parameters: Safety settings (read once, here, with the robot's limits).

    Raises:
        ParameterError: ``dt`` not a positive number, or longer than ``max_time_gap``.
    """

    #: Run the sample check and the command path compiled (:meth:`.checks.FrozenEncoders.count`,
    #: :mod:`.command`); False runs the readable NumPy reference (``_sample_problem`` then
    #: ``FrozenEncoders.update``; :func:`.command.reference_torque`), which the tests compare it to.
    compiled = True

    def __init__(
        self, dynamics: Dynamics, dt: float = 0.004, parameters: SafetyParameters | None = None
    ) -> None:
        self.n = dynamics.n
        self.dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
        self.parameters = parameters or SafetyParameters()
        gap = self.parameters.max_time_gap
        if gap is not None and self.dt > gap:  # each period would be a time stamp jump
            raise ParameterError("dt", f"{self.dt:g} s is longer than the safety's max_time_gap "
                                       f"{gap:g} s: every period would be a fault")  # fmt: skip
        self.use_model(dynamics)
        self._encoders = FrozenEncoders(self.n, self.parameters.stale_periods,
                                       self.parameters.stale_speed)  # fmt: skip
        self.state = SupervisorState.HOLDING
        self.fault_reason: str | None = None
        self._log_book = EventLog()
        self.overruns = 0
        self.max_tool_speed = 0.0
        self._t = 0.0  # the latest finite time stamp [s]
        self._t_checked: float | None = None  # the latest checked stamp (None: none yet)
        self._stalled = 0  # samples since a checked stamp last came after the latest
        self._rate_window: tuple[float, int] | None = None  # (first stamp [s], samples since)
        self._stop_periods = 0  # periods of the safe stop sent since the fault
        # the safe stop holds with gravity_scale · G(q) + gravity_offset (correct_gravity)
        self.gravity_scale: FloatArray | None = None  # [–]
        self.gravity_offset: FloatArray | None = None  # [Nm]
        self._q_last_good: FloatArray | None = None
        self._velocity_units = VelocityUnits(dynamics.n)
        # the latest two sound positions [rad] and the time between them [s]: a reading
        # jumps from the latest (jump_problem), and their rate is the safe stop's velocity
        # once the velocity readings are untrusted
        self._q_sound: FloatArray | None = None
        self._q_sound_before: FloatArray | None = None
        self._sound_interval = self.dt
        self._velocity_untrusted = False  # a velocity reading was out of range or unit
        self._in_overrun = False
        p = self.parameters
        self._command_scalars = np.array([p.tool_speed_limit, p.braking_time,
                                          p.wall_damping_time])  # fmt: skip
        self._inside, self._fast = np.zeros(self.n, dtype=bool), np.zeros(self.n, dtype=bool)
        self._clear_episodes()

    @property
    def events(self) -> list[SafetyEvent]:
        """Log of what happened, one entry per episode (not per period)."""
        return self._log_book.events

    @property
    def stranded(self) -> bool:
        """A fault is latched and no sound position was ever read: nothing to hold the arm at.

        The safe stop then sends zero torque; the robot's brakes are all that can hold it
        (``control_loop`` closes the robot).
        """
        return self.state is SupervisorState.FAULT and self._q_last_good is None

    def use_model(self, dynamics: Dynamics) -> None:
        """Supervise with the model ``dynamics`` from now on (e.g. after a payload).

        ``robot``, ``dynamics`` and the bounds always describe the same arm.

        Raises:
            ParameterError: ``dynamics`` has another number of joints.
        """
        if dynamics.n != self.n:
            raise ParameterError("dynamics", f"has {dynamics.n} joints, the supervisor {self.n}")
        self.dynamics = dynamics
        self.robot = dynamics.robot
        self._limits = SafetyLimits.of(self.robot, self.parameters)
        self._bounds = bound_rows(self._limits)  # for the compiled command path

    def teach(self) -> None:
        """Switch to TEACHING (tool speed limited); ignored while in FAULT."""
        self._set_mode(SupervisorState.TEACHING)

    def hold(self) -> None:
        """Switch to HOLDING; ignored while in FAULT."""
        self._set_mode(SupervisorState.HOLDING)

    def correct_gravity(self, scale: FloatArray | None, offset: FloatArray | None) -> None:
        """Hold the arm in a safe stop with ``scale · G(q) + offset`` [–, Nm] (None: G(q)).

        The gravity the controller holds the arm with once a start-up calibration measured
        its error (``LeadThrough.gravity_correction``): the safe stop holds it with the
        same, not with the model the calibration found off (on a UR10e whose masses were
        15 % heavier than modelled, 5.5 Nm on shoulder and elbow).
        """
        self.gravity_scale = None if scale is None else np.array(scale, dtype=float)
        self.gravity_offset = None if offset is None else np.array(offset, dtype=float)

    def stop(self, reason: str, t: float | None = None) -> None:
        """Latch FAULT with ``reason`` from outside (Ctrl-C, a robot error): the safe stop.

        From the next :meth:`command` on, the arm gets the safe stop until :meth:`reset`.

        Args:
            reason: One line saying what happened.
            t: Time of the sample the fault belongs to [s], on the robot's clock; default
                the time of the latest sample seen (the event's time).
        """
        if t is not None:
            self._clock(t)
        self._fault(reason)

    def log(self, kind: str, detail: str, t: float | None = None) -> None:
        """Add an event from outside (e.g. the control loop's), at ``t`` [s] or the latest."""
        self._log_book.add(self._t if t is None else t, kind, detail)

    def reset(self) -> None:
        """Clear a latched fault and go to HOLDING; start afresh.

        The frozen-encoder counters restart, and the last good position and time stamp
        are forgotten: a safe stop before the next good sample must not hold the arm
        against gravity at a pose it has left, and a pause before the reset is no gap.
        """
        self.state = SupervisorState.HOLDING
        self.fault_reason = None
        self._q_last_good = self._q_sound = self._q_sound_before = None
        self._velocity_units.clear()
        self._velocity_untrusted = False
        self._t_checked, self._stalled, self._rate_window = None, 0, None
        self._clear_episodes()
        self._log("reset", "supervisor reset: holding")

    def check(
        self, t: object, q: ArrayLike, qd: ArrayLike, tau_measured: ArrayLike | None = None
    ) -> bool:
        """Validate one sensor sample; a bad one latches FAULT with the reason.

        Args:
            t: Time of the sample [s]: a finite number, at most ``max_time_gap`` after the
                latest sample's and not more than that before it
                (:func:`~.checks.time_problem`), else a fault; so is a clock that stops
                (:func:`~.checks.clock_stopped`).
            q: Joint readings [rad], shape (n,).
            qd: Joint velocities [rad/s], shape (n,).
            tau_measured: Measured joint torques, arm side [Nm], shape (n,), or None.

        Returns:
            True when the sample is good and no fault is latched.
        """
        position: FloatArray | None = None
        previous = self._t_checked  # the stamp of the sample checked before this one
        try:
            late = self._time_problem(t)  # and the latest time, if t is a finite number
            position, velocity = floats(q), as_floats(qd)  # q is kept: a copy
            tau = None if tau_measured is None else as_floats(tau_measured)
            limits, count = self._limits, OUT_OF_RANGE
            if self.compiled:  # range check and encoder count in one compiled call
                count = self._encoders.count(position, velocity, tau, limits.sample_low,
                                             limits.sample_high)  # fmt: skip
            if count == OUT_OF_RANGE:  # spell out why (the NumPy reference, step by step)
                problem = self._sample_problem(position, velocity, tau)
                problem = problem or self._encoders.update(position, velocity, tau)
            else:
                problem = self._encoders.reason(count)
            interval = self.dt if previous is None else max(self._t - previous, self.dt)
            if problem is None and self._q_sound is not None and previous is not None:
                problem = jump_problem(position, self._q_sound, limits.speed, interval)
                units = self._velocity_units.update(position, velocity, interval)
                self._velocity_untrusted |= units is not None
                problem = problem or units
            self._follow_position(position, velocity, interval, problem is None)
        except Exception as error:  # nothing may escape on the motor path
            problem, late = failure("sensor check", error), None
        if problem is None:  # a good position is held in a safe stop, whatever its time
            self._q_last_good = position
        elif self._q_last_good is None and self._position_sound(position):
            self._q_last_good = position  # nothing held yet: the reading that is sound
        elif self._q_last_good is not None and position is not None:
            self._hold_sound_joints(position)
        problem = problem or late
        if problem is not None:
            self._fault(problem)
            return False
        return self.state is not SupervisorState.FAULT

    def _follow_position(
        self, position: FloatArray, velocity: FloatArray, interval: float, sound: bool
    ) -> None:
        """Keep the latest sound positions; note velocity readings that cannot be trusted.

        Kept from every sound position, whatever the velocity read with it: a safe stop
        whose velocity readings are the fault (finite and out of range, or not the
        positions' rate) damps on the positions' rate instead (:meth:`_safe_stop`). Damped
        on velocities in degrees per second, 57× too strong, a Panda's safe stop drove it
        2.9 rad to its joint limit at full torque (a review). ``interval``: the time since
        the sample before [s]; ``sound``: the sample passed every check.
        """
        if not (sound or self._position_sound(position)):
            return
        self._sound_interval = interval
        self._q_sound_before, self._q_sound = self._q_sound, position
        if sound:
            return
        low, high = self._limits.sample_low, self._limits.sample_high
        if velocity.shape != position.shape:
            self._velocity_untrusted = True
        elif not within_bounds(velocity, low, high, self.n) and np.isfinite(velocity).all():
            self._velocity_untrusted = True  # a number out of range: the unit (a NaN: a glitch)

    def _position_rate(self) -> FloatArray:
        """The latest two sound positions' rate [rad/s] (0 before there are two)."""
        if self._q_sound is None or self._q_sound_before is None:
            return np.zeros(self.n)
        return (self._q_sound - self._q_sound_before) / self._sound_interval

    def _hold_sound_joints(self, position: FloatArray) -> None:
        """Hold each joint whose reading is a finite number within its range where it reads.

        A bad sample (a joint's reading wrapped, a velocity in another unit) leaves the
        other joints' positions sound: the safe stop's gravity follows them. Held where the
        whole sample was last good, a Panda that a hand kept pulling after its joint 1 read
        2π off fell 2.3 rad at up to 17 rad/s, its hold's gravity a pose it had left (a
        review). A wrapped joint's 2π changes no gravity torque.
        """
        held = self._q_last_good
        if held is None or position.shape != held.shape:
            return
        limits = self._limits
        sound = np.isfinite(position) & (position >= limits.q_low) & (position <= limits.q_high)
        self._q_last_good = np.where(sound, position, held)

    def _position_sound(self, position: FloatArray | None) -> bool:
        """Whether ``position`` [rad] is one finite reading per joint within its range.

        A first sample whose other readings are bad (a NaN torque) still says where the
        arm is: the safe stop holds it there against gravity. Before, it held nothing (zero
        torque): the arm dropped 0.2–0.5 mrad before the next sample.
        """
        if position is None:  # not read (``floats`` gives floats when it is)
            return False
        return in_range((position,), self._limits.q_low, self._limits.q_high, self.n)

    def _time_problem(self, t: object) -> str | None:
        """Why the stamp ``t`` cannot be used, or None; keeps the latest stamp.

        Takes ``t`` as the latest time (:meth:`_clock`) if it is a finite number.
        :func:`~.checks.time_problem` against the latest stamp,
        :func:`~.checks.clock_stopped`, and :func:`~.checks.sample_rate_problem` once the
        stamps span :data:`~.checks.RATE_WINDOW`.
        """
        gap = self.parameters.max_time_gap
        value = seconds(t)
        problem = time_problem(t, self._t_checked, gap, value)
        if value is None:
            return problem
        self._t = value
        if problem is None and self._t_checked is not None:
            self._note_lost_samples(value - self._t_checked)
        if self._t_checked is None or value > self._t_checked:
            self._t_checked, self._stalled = value, 0
        else:
            self._stalled += 1
        return problem or clock_stopped(self._stalled, self.dt, gap) or self._rate(value)

    def _note_lost_samples(self, elapsed: float) -> None:
        """An event for samples lost between two stamps ``elapsed`` [s] apart, if any.

        Beyond :data:`LOST_SAMPLES` periods (a stamp's jitter within the rate check stays
        below it) and within ``max_time_gap`` (beyond it is a fault): the drive held its
        last command meanwhile. At 1 kHz, 250 lost samples passed without a word.
        """
        if elapsed > LOST_SAMPLES * self.dt:
            lost = round(elapsed / self.dt) - 1
            self._log("samples_lost", f"no sample for {elapsed * 1e3:.3g} ms ({lost} "
                      "periods lost): the drive held its last command")  # fmt: skip

    def _rate(self, t: float) -> str | None:
        """Why the stamps' mean period over the window ending at ``t`` [s] is not ``dt``."""
        if self._rate_window is None:
            self._rate_window = (t, 0)
            return None
        first, samples = self._rate_window
        samples += 1
        if t - first < RATE_WINDOW:
            self._rate_window = (first, samples)
            return None
        self._rate_window = (t, 0)
        return sample_rate_problem(t - first, samples, self.dt, self.parameters.rate_tolerance)

    def command(
        self,
        t: object,
        q: ArrayLike,
        qd: ArrayLike,
        tau_desired: ArrayLike,
        model: ModelSnapshot | None = None,
    ) -> FloatArray:
        """The torque actually sent to the motors [Nm], arm side, shape (n,).

        Always finite and within ± the torque limits: the safe stop in FAULT, else the
        saturated desired torque plus the soft-limit walls and the braking torques.

        Args:
            t: Time of the period [s] (one that is not a finite number is not taken:
                :meth:`check` says why).
            q: Joint readings [rad], shape (n,).
            qd: Joint velocities [rad/s], shape (n,).
            tau_desired: The controller's torque [Nm], shape (n,).
            model: The model at (q, q̇) computed this period (``dynamics.snapshot``), if
                the caller has it; else it is computed here.
        """
        try:
            self._clock(t)
            if self.state is not SupervisorState.FAULT:
                tau = self._supervised(floats(q), as_floats(qd), as_floats(tau_desired), model)
                if tau is not None:
                    self._encoders.sent(tau)
                    return tau
        except Exception as error:  # nothing may escape on the motor path
            self._fault(failure("command", error))
        tau = self._safe_stop(qd)
        self._encoders.sent(tau)
        return tau

    def record_cycle(self, t: float, duration: float) -> None:
        """Count the deadlines one control cycle missed when it took longer than ``dt``.

        A cycle of ``duration`` delays its command and leaves ``⌈duration / dt⌉ − 1``
        periods without a new one: each counts (at 1 kHz a Panda's 5 ms last calibration
        period counted once, for four periods the robot held the command before).

        Args:
            t: Time of the period [s].
            duration: Wall-clock time the cycle took [s] (NaN counts as one overrun).
        """
        overrun = not duration <= self.dt
        if overrun:
            missed = math.ceil(duration / self.dt) - 1 if math.isfinite(duration) else 1
            self.overruns += max(missed, 1)
            if not self._in_overrun:
                detail = f"control cycle took {duration * 1e3:.3g} ms > {self.dt * 1e3:.3g} ms"
                self._log_book.add(t, "overrun", detail)
        self._in_overrun = overrun

    def _supervised(
        self, q: FloatArray, qd: FloatArray, tau_desired: FloatArray, model: ModelSnapshot | None
    ) -> FloatArray | None:
        """The supervised torque [Nm], or None after latching a fault (bad input or torque).

        One compiled pass (:func:`.command.supervised_torque`) when the model is given and
        the shapes fit; else, and for a bad input (to spell out why), the NumPy reference
        (:func:`.command.reference_torque`). Then the events of both, alike.
        """
        n, teaching = self.n, self.state is SupervisorState.TEACHING
        status = BAD_INPUT
        if (self.compiled and model is not None and q.shape == (n,) and qd.shape == (n,)
                and tau_desired.shape == (n,)):  # fmt: skip
            out, inside, fast = np.empty(n), self._inside, self._fast
            status, speed, any_fast, any_inside = supervised_torque(q, qd, tau_desired,
                model.mass, model.gravity, model.tool_jacobian, self._bounds,
                self._command_scalars, teaching, out, inside, fast)  # fmt: skip
        if status == BAD_INPUT:
            if self._input_problem(q, qd, tau_desired) is not None:
                return None
            model = model or self.dynamics.snapshot(q, qd)
            status, speed, out, inside, fast = reference_torque(self._limits,
                self._command_scalars, q, qd, tau_desired, model.mass, model.gravity,
                model.tool_jacobian, teaching)  # fmt: skip
            any_fast, any_inside = bool(fast.any()), bool(inside.any())
        self._q_last_good = q
        episodes = self._log_book
        if any_fast or episodes.under_way("joint_speed"):
            self._log_joint_speed(qd, fast.copy())
        if teaching and (speed > self.max_tool_speed or speed > self.parameters.tool_speed_limit
                         or episodes.under_way("tool_speed")):  # fmt: skip
            self._log_tool_speed(speed)  # (else: no new largest speed, no episode to open or end)
        if any_inside or episodes.under_way("soft_limit"):
            self._log_walls(q, inside.copy())
        if status == NOT_FINITE:
            self._fault("non-finite safety torque")
            return None
        return out

    def _log_walls(self, q: FloatArray, inside: NDArray[np.bool_]) -> None:
        """One event for each joint that entered a wall this period."""
        limits, robot = self._limits, self.robot
        for i in self._log_book.started("soft_limit", inside):
            lower = q[i] < limits.wall_low[i]
            side, hard = ("lower", robot.q_min[i]) if lower else ("upper", robot.q_max[i])
            detail = f"joint {i + 1} entered the {side} soft limit at {q[i]:.4g} rad"
            self._log("soft_limit", f"{detail} (hard limit {hard:.4g} rad)")

    def _log_joint_speed(self, qd: FloatArray, fast: NDArray[np.bool_]) -> None:
        """One event for each joint that became too fast this period."""
        speed = self._limits.speed
        for i in self._log_book.started("joint_speed", fast):
            detail = f"joint {i + 1} speed {abs(qd[i]):.4g} rad/s above {speed[i]:.4g} rad/s"
            self._log("joint_speed", f"{detail}: braking")

    def _log_tool_speed(self, speed: float) -> None:
        """Keep the largest tool speed [m/s]; an event when it goes above the limit."""
        limit = self.parameters.tool_speed_limit
        if speed > self.max_tool_speed:
            self.max_tool_speed = speed
        if self._log_book.began("tool_speed", speed > limit):
            self._log("tool_speed", f"tool speed {speed:.3g} m/s above {limit:.3g} m/s: braking")

    def _safe_stop(self, qd: object) -> FloatArray:
        """Gravity hold at the last good position, damped for the first part of the stop.

        The damped part is the stop's first ``safe_stop_damping_time`` of periods, counted
        as they are sent: not by the robot's clock, which a fault may be about (a stamp
        from the past, or a Unix clock when the stop comes before the first sample, left
        the stop undamped from its first or second period).
        """
        p = self.parameters
        damped = self._stop_periods * self.dt < p.safe_stop_damping_time
        self._stop_periods += 1
        try:
            if self._q_last_good is None:  # no valid position ever read: nothing to hold
                return np.zeros(self.n)
            frozen = self._encoders.frozen()
            velocity = trusted_velocity(qd, self._limits.qd_bound, frozen) if damped else None
            if damped and self._velocity_untrusted:  # the readings are the fault: positions
                velocity = self._position_rate()
            q = self._q_last_good
            gravity = self.dynamics.gravity(q)
            if self.gravity_scale is not None and self.gravity_offset is not None:
                gravity = self.gravity_scale * gravity + self.gravity_offset
            hold = braking.safe_stop(self.dynamics, q, velocity, p.braking_time, gravity)
            return self._limits.saturated(hold)
        except Exception as error:  # the last resort must return a torque: zero, and say so
            if self._log_book.began("safe_stop_failed", True):
                self._log("safe_stop_failed", f"safe stop failed ({type(error).__name__}: "
                          f"{error}): zero torque sent")  # fmt: skip
            return np.zeros(self.n)

    def _sample_problem(self, q: FloatArray, qd: FloatArray, tau: FloatArray | None) -> str | None:
        """Why a sample is invalid (shape, non-finite, out of range), or None.

        The reason is only spelled out for a bad sample, and not while a fault is
        latched (``_fault`` would drop it): then it is a placeholder.
        """
        limits = self._limits
        readings = (q, qd) if tau is None else (q, qd, tau)
        if in_range(readings, limits.sample_low, limits.sample_high, self.n):
            return None
        if self.state is SupervisorState.FAULT:
            return _UNEXPLAINED
        return sample_reason(limits, q, qd, tau)

    def _input_problem(self, q: FloatArray, qd: FloatArray, tau_desired: FloatArray) -> str | None:
        """Why (q [rad], q̇ [rad/s], τ_desired [Nm]) cannot be supervised, latched as a fault."""
        limits = self._limits
        if in_range((q, qd, tau_desired), limits.command_low, limits.command_high, self.n):
            return None
        problem = sample_reason(limits, q, qd, None) or command_problem(tau_desired, self.n)
        if problem is not None:
            self._fault(problem)
        return problem

    def _set_mode(self, mode: SupervisorState) -> None:
        if self.state in (SupervisorState.FAULT, mode):
            return
        self.state = mode
        self._log_book.end("tool_speed")
        self._log("mode", f"mode {mode.value}")

    def _clock(self, t: object) -> None:
        """Take ``t`` as the latest time [s] if it is a finite number; else keep the last."""
        value = seconds(t)
        if value is not None:
            self._t = value

    def _fault(self, reason: str) -> None:
        """Latch FAULT with ``reason``; the first reason is kept until reset."""
        if self.state is SupervisorState.FAULT:
            return
        self.state = SupervisorState.FAULT
        self.fault_reason = reason
        self._stop_periods = 0
        self._log("fault", reason)

    def _log(self, kind: str, detail: str) -> None:
        self._log_book.add(self._t, kind, detail)

    def _clear_episodes(self) -> None:
        self._encoders.clear()
        self._log_book.clear()


#: Time between two stamps [periods] beyond which samples count as lost (an event): above
#: the 1.8 periods two stamps jittered ±40 % can be apart.
LOST_SAMPLES = 2.5
#: Placeholder reason while a fault is latched: ``_fault`` keeps the first reason only.
_UNEXPLAINED = "invalid sample"
