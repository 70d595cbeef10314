"""The control loop on a robot: read, step, send, once per period, timed and safe (SPEC §7).

The only loop: hardware, the twin (:func:`leadthrough.twin.runner.simulate`), teaching,
replay, the experiments and the demo all run through it, so the path that runs on a
robot is the path the tests run. It drives any controller (:class:`~leadthrough.LeadThrough`,
a replay) on any :class:`~leadthrough.runtime.interface.RobotInterface` (a hardware driver,
the twin)::

    arm = lt.robots.yumi()
    driver = MyYuMiDriver(...)                  # implements RobotInterface, dt = its period
    report = lt.control_loop(driver, lt.LeadThrough(arm, dt=driver.dt), duration=60.0)
    print(report.summary())

The robot's sample (:class:`JointState`, with the robot's time stamp) is handed to the
controller as it is (``step(state)``; a controller whose ``step`` takes (q, q̇, τ) gets
those), so the robot's clock is the controller's. A controller with a ``dt`` must run at
the robot's period (a 4 ms controller on a 1 ms robot is refused).

Before the first sample the controller's ``warm_up()`` (if it has one) compiles every
kernel its step will call, on a copy of it, so that no compilation falls into a period.
Each period the controller's compute time is measured, from the sample arriving to the
command leaving; on a robot with a wall clock one longer than the period is a missed
deadline, counted and logged by the controller's supervisor (``supervisor.record_cycle``).
A simulated driver (``wall_clock=False``) paces nothing in real time: compute times are
still measured and reported, not held against the period. What runs after the command
is sent is off the critical path: the controller's own ``after_period(state, command)``
(if it has one: a teaching session records there), then the caller's ``after_period``.

No exception escapes without the safe stop first: on Ctrl-C, an error of the robot, the
controller or ``after_period``, the supervisor latches a fault naming the cause, the arm
gets the safe stop (braking, then gravity hold) for ``stop_time`` and the robot is closed
(brakes on); a safe stop that cannot be sent is logged as a ``safe_stop_failed`` event.
Ctrl-C then ends the loop normally (``report.ended`` says so); any other error is raised
again. A controller without a supervisor gets no safe stop: the robot is closed.

A loop that ends by itself (``duration``, ``until``) brings the arm to rest the same way
(``hold_at_end``): the supervisor latches "the loop ended", the safe stop runs for
``stop_time``, and the robot is left commanded with its gravity hold, not closed (a drive
that holds the last command it got must not hold a guiding torque nobody supervises: the
arm ended at 1.4 rad/s went on 125 mrad under it, against 22 mrad stopped). ``reset()``
the controller before guiding again. The twin's ``simulate`` passes ``hold_at_end=False``:
its runs go on where the last one ended.
"""

from __future__ import annotations

import inspect
import math
import time
from array import array
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from leadthrough.errors import ParameterError
from leadthrough.model.description import FloatArray
from leadthrough.runtime.interface import JointState, RobotInterface
from leadthrough.safety.supervisor import SafetySupervisor
from leadthrough.validation import real


class SupervisedController(Protocol):
    """A controller whose commands pass a safety supervisor (LeadThrough, a replay)."""

    supervisor: SafetySupervisor

    def step(self, state: JointState) -> FloatArray:
        """Torque command [Nm] for the robot's sample (t [s], q [rad], q̇ [rad/s], τ [Nm])."""
        ...


@dataclass(frozen=True)
class LoopReport:
    """How a control loop went.

    Attributes:
        periods: Control periods run (the safe stop after an interruption not included).
        overruns: Periods whose compute time exceeded the control period (0 without a
            wall clock).
        compute_median: Median compute time of one period [s].
        compute_max: Longest compute time of one period [s].
        period: The control period [s].
        ended: ``"finished"`` (duration reached), ``"stopped"`` (``until`` said so),
            :data:`STRANDED` (the robot closed), or what interrupted the loop.
        warm_up: Time the controller's ``warm_up`` took before the first sample [s].
    """

    periods: int
    overruns: int
    compute_median: float
    compute_max: float
    period: float
    ended: str
    warm_up: float = 0.0

    @property
    def interrupted(self) -> bool:
        """Whether the operator stopped the loop (Ctrl-C) before it ended by itself."""
        return self.ended == OPERATOR_STOP

    def summary(self) -> str:
        """One line: periods, compute times against the period, overruns, how it ended."""
        return (f"{self.periods} periods of {1e3 * self.period:g} ms: compute median "
                f"{1e6 * self.compute_median:.0f} µs, max {1e6 * self.compute_max:.0f} µs, "
                f"{self.overruns} overruns; {self.ended}")  # fmt: skip


def control_loop(
    robot: RobotInterface,
    controller: Any,
    duration: float | None = None,
    until: Callable[[JointState], bool] | None = None,
    after_period: Callable[[JointState, FloatArray], None] | None = None,
    stop_time: float = 0.5,
    wall_clock: bool = True,
    hold_at_end: bool = True,
) -> LoopReport:
    """Run ``controller`` on ``robot`` until ``duration`` has passed or ``until`` says so.

    Args:
        robot: The robot; ``send_torque`` returns when the next sample is due.
        controller: Stepped once per period with the robot's sample (see the module
            docstring); with a ``supervisor``, its deadlines and safe stop are used.
        duration: How long to run [s]; None runs until ``until`` or Ctrl-C.
        until: Called with each new sample; True ends the loop (before stepping).
        after_period: Called after each command is sent (and after the controller's own
            ``after_period``), with the sample and the command (recording, display); its
            errors bring the safe stop like any other.
        stop_time: How long the safe stop is commanded after an interruption, or at the
            end [s].
        wall_clock: Whether the robot runs in real time (hardware): then a compute time
            above the period is an overrun. False for a simulated driver (the twin).
        hold_at_end: Whether a loop that ends by itself brings the arm to rest with the
            supervisor's safe stop and leaves it held (the module docstring); False
            leaves the last command with the robot, for a caller that goes on stepping.

    Returns:
        What happened; the robot is left commanded (not closed) when the loop ends by
        itself, with its gravity hold unless ``hold_at_end`` is False; safe-stopped and
        closed when it was interrupted.

    Raises:
        ParameterError: A bad duration or stop time, or a controller whose ``dt`` is not
            the robot's period.
    """
    real("stop_time", stop_time, minimum=0.0, error=ParameterError)
    if duration is not None:
        real("duration", duration, minimum=0.0, error=ParameterError)
    check_period(controller, robot)
    step = stepper(controller)
    periods = None if duration is None else round(duration / robot.dt)
    supervisor: SafetySupervisor | None = getattr(controller, "supervisor", None)
    controller_after = getattr(controller, "after_period", None)  # its work off the timed path
    overruns_before = supervisor.overruns if supervisor is not None else 0
    compute = array("d")
    ended, k, t, warmed = "finished", 0, None, 0.0
    try:
        warm_up = getattr(controller, "warm_up", None)  # compile its kernels now, not in a period
        warmed = float(warm_up()) if callable(warm_up) else 0.0
        state = robot.read_state()
        while periods is None or k < periods:
            t = state.t
            if until is not None and until(state):
                ended = "stopped"
                break
            start = time.perf_counter()
            command = step(state)
            elapsed = time.perf_counter() - start
            robot.send_torque(command)
            compute.append(elapsed)
            k += 1
            start = time.perf_counter()
            if controller_after is not None:
                controller_after(state, command)
            if after_period is not None:
                after_period(state, command)
            # the work of the cycle, the sending aside (a driver may block in it until the
            # next tick): a recorder's flush after the command delays the next sample
            if wall_clock and supervisor is not None:
                supervisor.record_cycle(state.t, elapsed + time.perf_counter() - start)
            if supervisor is not None and supervisor.stranded:  # nothing to hold it with
                ended = STRANDED
                supervisor.log("closed", STRANDED)
                _close(robot, supervisor)
                break
            state = robot.read_state()
    except BaseException as error:  # Ctrl-C included: the safe stop comes first
        ended = _interruption(error)
        if supervisor is None:
            _close(robot, None)
        else:
            _safe_stop(robot, supervisor, ended, stop_time, t)
        if not isinstance(error, KeyboardInterrupt):
            raise
    else:
        if hold_at_end and supervisor is not None and ended != STRANDED:
            _safe_stop(robot, supervisor, f"the loop ended ({ended}): arm held", stop_time, t,
                       close=False)  # fmt: skip
    times = np.frombuffer(compute, dtype=float) if compute else np.zeros(1)
    overruns = supervisor.overruns - overruns_before if supervisor is not None else 0
    return LoopReport(k, overruns, float(np.median(times)), float(times.max()), robot.dt,
                      ended, warmed)  # fmt: skip


def check_period(controller: object, robot: RobotInterface) -> None:
    """Raise ParameterError (one line) when ``controller.dt`` is not the robot's period."""
    dt = getattr(controller, "dt", None)
    if dt is None or math.isclose(float(dt), float(robot.dt), rel_tol=1e-9, abs_tol=1e-12):
        return
    raise ParameterError("dt", f"the controller runs at {1e3 * dt:g} ms, the robot at "
                         f"{1e3 * robot.dt:g} ms: build it with dt=robot.dt")  # fmt: skip


def stepper(controller: Any) -> Callable[[JointState], FloatArray]:
    """``controller.step`` as a function of the robot's sample.

    ``step(state)`` when it takes one argument (the robot's time stamp reaches it), else
    ``step(q, qd, tau_measured)``.
    """
    step = controller.step
    try:
        parameters = list(inspect.signature(step).parameters.values())
    except (TypeError, ValueError):  # no signature to read: the positional form
        parameters = []
    positional = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    required = [p for p in parameters if p.kind in positional and p.default is p.empty]
    if len(required) == 1:
        return step  # type: ignore[no-any-return]
    return lambda state: step(state.q, state.qd, state.tau_measured)


#: :attr:`LoopReport.ended` when the operator pressed Ctrl-C.
OPERATOR_STOP = "interrupted by the operator (Ctrl-C)"
#: :attr:`LoopReport.ended` when a fault left no position to hold the arm at (the samples
#: never had a sound position: a joint too few from the first): the robot is closed, its
#: brakes on. Before, the loop sent zero torque for its whole duration and a Panda whose
#: driver reported 6 joints fell 3 rad (a review).
STRANDED = "a fault with no position ever read to hold the arm at: the robot was closed"


def _interruption(error: BaseException) -> str:
    if isinstance(error, KeyboardInterrupt):
        return OPERATOR_STOP
    return f"interrupted by an error: {type(error).__name__}: {error}"


def _safe_stop(
    robot: RobotInterface,
    supervisor: SafetySupervisor,
    reason: str,
    stop_time: float,
    t: float | None,
    close: bool = True,
) -> None:
    """Latch the fault, command the supervisor's safe stop for ``stop_time``, close the robot.

    ``t`` is the time of the latest sample [s] on the robot's clock (the fault's). A safe
    stop that cannot be sent (the robot gone) is logged as a ``safe_stop_failed`` event;
    the robot's brakes are then all there is. A Ctrl-C during it is logged and the stop goes
    on for its ``stop_time``. ``close`` False leaves the robot open, held.
    """
    supervisor.stop(reason, t)
    try:
        nothing = np.zeros(robot.n_joints)
        for _ in range(max(1, round(stop_time / robot.dt))):
            try:
                state = robot.read_state()
                # checked first: interrupted before any sample was stepped (in the warm-up,
                # or the first read failing), the supervisor has no good position to hold yet
                supervisor.check(state.t, state.q, state.qd, state.tau_measured)
                robot.send_torque(supervisor.command(state.t, state.q, state.qd, nothing))
            except KeyboardInterrupt:  # a second Ctrl-C: the stop goes on (it ended it, and
                # the robot was closed with the arm still moving at 0.3 rad/s)
                supervisor.log("safe_stop", "Ctrl-C during the safe stop: it goes on")
    except Exception as error:
        supervisor.log("safe_stop_failed", f"the safe stop could not be sent: "
                       f"{type(error).__name__}: {error}; closing the robot")  # fmt: skip
        close = True
    finally:
        if close:
            _close(robot, supervisor)


def _close(robot: RobotInterface, supervisor: SafetySupervisor | None) -> None:
    """Close the robot; an error of its close is logged, not raised over the one that ended.

    A close that raised replaced the error that ended the loop (a connection reset seen as
    ``OSError: Bad file descriptor``), and after a Ctrl-C the loop raised it instead of
    returning its report (a review).
    """
    try:
        robot.close()
    except Exception as error:
        if supervisor is not None:
            supervisor.log("close_failed", f"the robot's close raised "
                           f"{type(error).__name__}: {error}")  # fmt: skip
