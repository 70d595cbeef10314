"""The control loop on a robot: read, step, send, once per period, timed and safe (SPEC §7).

One function drives any supervised controller (:class:`~leadthrough.LeadThrough`, a
replay) on any :class:`~leadthrough.runtime.interface.RobotInterface` (a hardware driver, the
twin)::

    arm = lt.robots.yumi()
    driver = MyYuMiDriver(...)                  # implements RobotInterface
    report = lt.control_loop(driver, lt.LeadThrough(arm), duration=60.0)
    print(report.summary())

Each period the controller's compute time is measured, from the sample arriving to the
command leaving; one longer than the period is a missed deadline, counted and logged by
the controller's supervisor (``supervisor.record_cycle``). What runs after the command is
sent (``after_period``, e.g. a recorder) is off the critical path.

No exception escapes without the safe stop first: on Ctrl-C, an error of the robot, the
controller or ``after_period``, the supervisor latches a fault naming the cause, the arm
gets the safe stop (braking, then gravity hold) for ``stop_time`` and the robot is closed
(brakes on). Ctrl-C then ends the loop normally (``report.ended`` says so); any other
error is raised again.
"""

from __future__ import annotations

import time
from array import array
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from leadthrough.errors import ParameterError
from leadthrough.model.description import FloatArray
from leadthrough.runtime.interface import JointState, RobotInterface
from leadthrough.safety.supervisor import SafetySupervisor
from leadthrough.validation import real


class SupervisedController(Protocol):
    """A controller whose commands pass a safety supervisor (LeadThrough, a replay)."""

    supervisor: SafetySupervisor

    def step(self, q: FloatArray, qd: FloatArray, tau_measured: FloatArray | None) -> FloatArray:
        """Torque command [Nm] for the state q [rad], q̇ [rad/s], τ [Nm]."""
        ...


@dataclass(frozen=True)
class LoopReport:
    """How a control loop went.

    Attributes:
        periods: Control periods run (the safe stop after an interruption not included).
        overruns: Periods whose compute time exceeded the control period.
        compute_median: Median compute time of one period [s].
        compute_max: Longest compute time of one period [s].
        period: The control period [s].
        ended: ``"finished"`` (duration reached), ``"stopped"`` (``until`` said so) or
            what interrupted the loop.
    """

    periods: int
    overruns: int
    compute_median: float
    compute_max: float
    period: float
    ended: str

    def summary(self) -> str:
        """One line: periods, compute times against the period, overruns, how it ended."""
        return (f"{self.periods} periods of {1e3 * self.period:g} ms: compute median "
                f"{1e6 * self.compute_median:.0f} µs, max {1e6 * self.compute_max:.0f} µs, "
                f"{self.overruns} overruns; {self.ended}")  # fmt: skip


def control_loop(
    robot: RobotInterface,
    controller: SupervisedController,
    duration: float | None = None,
    until: Callable[[JointState], bool] | None = None,
    after_period: Callable[[JointState, FloatArray], None] | None = None,
    stop_time: float = 0.5,
) -> LoopReport:
    """Run ``controller`` on ``robot`` until ``duration`` has passed or ``until`` says so.

    Args:
        robot: The robot; ``send_torque`` returns when the next sample is due.
        controller: Supervised controller, stepped once per period.
        duration: How long to run [s]; None runs until ``until`` or Ctrl-C.
        until: Called with each new sample; True ends the loop (before stepping).
        after_period: Called after each command is sent, with the sample and the command
            (recording, display); its errors bring the safe stop like any other.
        stop_time: How long the safe stop is commanded after an interruption [s].

    Returns:
        What happened; the robot is left commanded (not closed) when the loop ends
        normally, safe-stopped and closed when it was interrupted.
    """
    real("stop_time", stop_time, minimum=0.0, error=ParameterError)
    if duration is not None:
        real("duration", duration, minimum=0.0, error=ParameterError)
    periods = None if duration is None else round(duration / robot.dt)
    supervisor = controller.supervisor
    overruns_before = supervisor.overruns
    compute = array("d")
    ended, k = "finished", 0
    try:
        state = robot.read_state()
        while periods is None or k < periods:
            if until is not None and until(state):
                ended = "stopped"
                break
            start = time.perf_counter()
            command = controller.step(state.q, state.qd, state.tau_measured)
            elapsed = time.perf_counter() - start
            robot.send_torque(command)
            supervisor.record_cycle(state.t, elapsed)
            compute.append(elapsed)
            k += 1
            if after_period is not None:
                after_period(state, command)
            state = robot.read_state()
    except BaseException as error:  # Ctrl-C included: the safe stop comes first
        ended = _interruption(error)
        _safe_stop(robot, supervisor, ended, stop_time)
        if not isinstance(error, KeyboardInterrupt):
            raise
    times = np.frombuffer(compute, dtype=float) if compute else np.zeros(1)
    return LoopReport(k, supervisor.overruns - overruns_before, float(np.median(times)),
                      float(times.max()), robot.dt, ended)  # fmt: skip


def _interruption(error: BaseException) -> str:
    if isinstance(error, KeyboardInterrupt):
        return "interrupted by the operator (Ctrl-C)"
    return f"interrupted by an error: {type(error).__name__}: {error}"


def _safe_stop(
    robot: RobotInterface, supervisor: SafetySupervisor, reason: str, stop_time: float
) -> None:
    """Latch the fault, command the supervisor's safe stop for ``stop_time``, close the robot."""
    supervisor.stop(reason)
    try:
        nothing = np.zeros(robot.n_joints)
        for _ in range(max(1, round(stop_time / robot.dt))):
            state = robot.read_state()
            robot.send_torque(supervisor.command(state.t, state.q, state.qd, nothing))
    except Exception:  # a robot that cannot be commanded any more: its brakes are all we have
        pass
    finally:
        robot.close()
