"""Teaching on any robot: the control loop with a session recorder (SPEC §8).

The same function teaches a hardware arm and the twin: any
:class:`~leadthrough.runtime.interface.RobotInterface` runs through
:func:`~leadthrough.runtime.loop.control_loop`, and every period taught is recorded::

    controller = lt.LeadThrough(arm, "active", dt=driver.dt, calibrate=True)
    report = teach(driver, controller, "session.mcap", duration=60.0)   # or until Ctrl-C
    print(report.summary())

The start-up calibration's motion is not part of what was taught: it is not recorded.
Session time is the robot's clock from the first sample; the supervisor's events are
recorded on it too. Ctrl-C ends the session with the safe stop, and the recording is
finalised (complete) either way.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from leadthrough.control.lead_through import LeadThrough
from leadthrough.errors import RecordingError
from leadthrough.logs.sample import JointState
from leadthrough.model.description import FloatArray
from leadthrough.runtime.interface import RobotInterface
from leadthrough.runtime.loop import LoopReport, control_loop
from leadthrough.runtime.recording import SessionRecorder


class TeachingSession:
    """A LeadThrough whose taught periods are recorded once each command has gone out.

    ``step(state)`` controls; ``after_period(state, command)``, the control loop's
    callback after the command is sent, records: the file's writes and flushes stay off
    the timed path to the motors.

    Attributes:
        controller: The lead-through controller.
        recorder: Where each period goes.
        recorded: Periods written so far.
        time: Session time of the latest period [s] (robot clock, from the first sample).

    Args:
        controller: The lead-through controller.
        recorder: An open session recorder.
    """

    def __init__(self, controller: LeadThrough, recorder: SessionRecorder) -> None:
        self.controller, self.recorder = controller, recorder
        self.dt, self.supervisor = controller.dt, controller.supervisor  # for the control loop
        self.recorded = 0
        self.time = 0.0
        self._t0: float | None = None
        self._last_recorded = -math.inf  # the session time of the latest row recorded [s]
        self._events = 0

    def warm_up(self) -> float:
        """The controller's warm-up (:meth:`LeadThrough.warm_up`), before the first period."""
        return self.controller.warm_up()

    def step(self, state: JointState) -> FloatArray:
        """The controller's command for one period on the robot's sample [Nm]."""
        return self.controller.step(state)

    def after_period(self, state: JointState, command: FloatArray) -> None:
        """Record the period just sent (unless calibrating) and the supervisor's events.

        A sample that does not come after the latest recorded (out of order, or repeated)
        or that is not one reading per joint is stepped (the supervisor judges it) but not
        recorded: a recording's rows are the arm's path in time. An out-of-order sample
        recorded before made the whole session unreplayable ("time not increasing"), and
        one with a joint too few ended the session on the recorder's error (a review).
        """
        if self._t0 is None:
            self._t0 = float(state.t)
        self.time = float(state.t) - self._t0
        c = self.controller
        n = c.robot.n_joints
        readable = np.shape(state.q) == np.shape(state.qd) == (n,)
        if not c.calibrating and readable and self.time > self._last_recorded:
            tau = np.full(n, np.nan) if state.tau_measured is None else state.tau_measured
            self.recorder.record(self.time, state.q, state.qd, tau, c.tau_ext_hat, c.std, c.mode,
                                 c.state.value, c.tool_wrench, c.enabling)  # fmt: skip
            self.recorded += 1
            self._last_recorded = self.time
        self.record_events()

    def record_events(self) -> None:
        """Record the supervisor's events not recorded yet, on the session clock.

        Events from before the first sample (the controller's construction) are at 0.
        """
        events = self.controller.supervisor.events
        t0 = 0.0 if self._t0 is None else self._t0
        for event in events[self._events :]:
            self.recorder.event(max(event.t - t0, 0.0), event.kind, event.detail)
        self._events = len(events)


@dataclass(frozen=True)
class TeachingReport:
    """How a teaching session went.

    Attributes:
        loop: The control loop's report (periods, compute times, how it ended).
        recorded: Periods recorded (the calibration's not counted).
        seconds: Session time taught and recorded [s].
        path: The recording.
    """

    loop: LoopReport
    recorded: int
    seconds: float
    path: Path

    def summary(self) -> str:
        """Two lines: what was recorded where, and the loop's summary."""
        return (f"recorded {self.recorded} periods ({self.seconds:.1f} s) to {self.path}\n"
                f"{self.loop.summary()}")  # fmt: skip


def teach(
    robot: RobotInterface,
    controller: LeadThrough,
    path: str | os.PathLike[str],
    duration: float | None = None,
    parameters: dict[str, Any] | None = None,
    wall_clock: bool = True,
    *,
    overwrite: bool = False,
) -> TeachingReport:
    """Teach ``robot`` with ``controller`` for ``duration`` [s] (None: until Ctrl-C), recorded.

    Args:
        robot: Any robot driver (the twin included).
        controller: The lead-through controller, at the robot's period.
        path: The recording to write (MCAP; ``<path>.part`` until finished).
        duration: How long to run [s], calibration included; None: until Ctrl-C.
        parameters: Free-form session parameters stored in the file (mode and dt added).
        wall_clock: False for a simulated driver (see :func:`control_loop`).
        overwrite: Replace an existing recording at ``path`` (else a RecordingError, before
            the arm moves: a session that recorded nothing replaced 750 taught rows).

    Returns:
        The report; the recording is complete even after Ctrl-C (the safe stop ran).
    """
    if Path(path).exists() and not overwrite:
        raise RecordingError(str(path), "exists; pass overwrite=True to replace it")
    stored = {"mode": controller.mode, "dt": controller.dt} | (parameters or {})
    with SessionRecorder(path, controller.robot, stored) as recorder:
        session = TeachingSession(controller, recorder)
        report = control_loop(robot, session, duration, wall_clock=wall_clock)
        session.record_events()  # the safe stop's, after an interruption
    return TeachingReport(report, session.recorded, session.recorded * controller.dt, Path(path))
