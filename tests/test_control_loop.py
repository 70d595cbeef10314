"""The control loop on a robot (SPEC §7): periods, deadlines, Ctrl-C and robot errors."""

import time

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.errors import ParameterError
from leadthrough.runtime.loop import STRANDED
from leadthrough.safety.supervisor import SupervisorState
from leadthrough.twin.operator import During, Hand
from leadthrough.twin.paths import Line
from leadthrough.twin.simulator import DigitalTwin

ROBOT = lt.robots.yumi()


class ClosableTwin(DigitalTwin):
    """The twin, remembering whether it was closed and failing on request."""

    def __init__(self, *args, fail_at: float = np.inf, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.closed, self.fail_at = False, fail_at

    def send_torque(self, tau) -> None:
        """Fail like a lost connection once the twin's clock reaches ``fail_at``."""
        if self.time >= self.fail_at:
            raise ConnectionError("robot connection lost")
        super().send_torque(tau)

    def close(self) -> None:
        """Record the close."""
        self.closed = True


class Slow:
    """A controller that takes ``delay`` [s] longer than it should every other period."""

    def __init__(self, controller: lt.LeadThrough, delay: float) -> None:
        self.controller, self.supervisor, self.delay = controller, controller.supervisor, delay
        self.calls = 0

    def step(self, q, qd, tau_measured):
        """Step the controller, late every other time."""
        self.calls += 1
        if self.calls % 2 == 0:
            time.sleep(self.delay)
        return self.controller.step(q, qd, tau_measured)


def controller() -> lt.LeadThrough:
    """Passive lead-through, no calibration (the tests start guiding at once)."""
    return lt.LeadThrough(ROBOT, "passive", parameters=LeadThroughParameters(calibration=None))


def pulling_hand(stop: float) -> During:
    """A hand pulling the tool 20 cm sideways in 1 s, letting go at ``stop`` [s]."""
    start = lt.Dynamics(ROBOT).pose(ROBOT.home())[:3, 3]
    return During(Hand(Line(start, start + np.array([0.0, 0.2, 0.0]), duration=1.0)), 0.0, stop)


def test_loop_runs_the_periods_and_reports_the_compute_time():
    """0.2 s at 250 Hz is 50 periods, each command sent; the report agrees with the supervisor."""
    twin, ctl, sent = ClosableTwin(ROBOT), controller(), []
    report = lt.control_loop(twin, ctl, duration=0.2, after_period=lambda s, c: sent.append(c))
    assert report.periods == len(sent) == 50
    assert twin.time == pytest.approx(0.2 + 0.5)  # then the hold at the end, stop_time
    assert report.ended == "finished" and not twin.closed
    assert report.overruns == ctl.supervisor.overruns
    assert 0.0 < report.compute_median <= report.compute_max
    assert "50 periods of 4 ms" in report.summary()


def test_until_ends_the_loop_before_stepping():
    """The loop ends at the first sample ``until`` accepts."""
    report = lt.control_loop(ClosableTwin(ROBOT), controller(), until=lambda s: s.t >= 0.1 - 1e-9)
    assert report.ended == "stopped"
    assert report.periods == 25


def test_missed_deadlines_are_counted_and_logged():
    """A step that takes longer than the period is an overrun, each one counted."""
    slow = Slow(controller(), delay=0.006)  # 6 ms > 4 ms
    report = lt.control_loop(ClosableTwin(ROBOT), slow, duration=0.08)  # 20 periods
    assert report.overruns == slow.supervisor.overruns >= 10
    assert report.compute_max > 0.004
    assert any(event.kind == "overrun" for event in slow.supervisor.events)


def test_work_after_the_command_counts_in_the_cycle():
    """A recorder's 6 ms after the command delays the next sample: an overrun, counted.

    Before, only the step was timed: ``teach``'s flush and fsync at 1 kHz (1–6 ms every
    0.1 s on a Panda) missed deadlines that nothing counted.
    """
    ctl = controller()
    report = lt.control_loop(ClosableTwin(ROBOT), ctl, duration=0.08,
                             after_period=lambda s, c: time.sleep(0.006))  # fmt: skip
    assert report.overruns == ctl.supervisor.overruns >= 10
    assert report.compute_max < 0.004  # the step itself is quick


def test_ctrl_c_brings_the_moving_arm_to_the_safe_stop_and_closes_the_robot():
    """Ctrl-C while a hand drags the arm: fault with the reason, the arm stopped and held."""
    twin, ctl = ClosableTwin(ROBOT, operator=pulling_hand(stop=0.4)), controller()

    def interrupt(state, command) -> None:
        if state.t >= 0.4 - 1e-9:
            moving.append(np.max(np.abs(state.qd)))
            raise KeyboardInterrupt

    moving = []

    report = lt.control_loop(twin, ctl, after_period=interrupt, stop_time=0.5)
    assert "Ctrl-C" in report.ended and report.periods == 101
    assert ctl.state is SupervisorState.FAULT and "Ctrl-C" in ctl.supervisor.fault_reason
    assert twin.closed
    assert moving[0] > 0.1  # [rad/s]
    assert np.max(np.abs(twin.truth.qd)) < 0.01  # stopped within the 0.5 s of the safe stop


class InterruptedAgain(ClosableTwin):
    """A twin whose reading is interrupted once by Ctrl-C at ``again`` [s] (a second one)."""

    def __init__(self, *args, again: float, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.again, self.sent_after = again, 0

    def read_state(self):
        """Raise KeyboardInterrupt once, at ``again``."""
        if self.again <= self.time:
            self.again = np.inf
            raise KeyboardInterrupt
        return super().read_state()

    def send_torque(self, tau) -> None:
        """Count what is sent once the second Ctrl-C came."""
        self.sent_after += self.again == np.inf
        super().send_torque(tau)


def test_a_second_ctrl_c_does_not_cut_the_safe_stop_short():
    """Ctrl-C, then another 40 ms into the safe stop: it goes on, the arm stops, logged.

    Before, the second one ended the stop after 3 periods and the robot was closed with
    the arm still moving at 0.30 rad/s (a review, on a Panda at 1 kHz).
    """
    twin = InterruptedAgain(ROBOT, operator=pulling_hand(stop=0.4), again=0.44)
    ctl = controller()

    def interrupt(state, command) -> None:
        if state.t >= 0.4 - 1e-9:
            raise KeyboardInterrupt

    try:
        report = lt.control_loop(twin, ctl, after_period=interrupt, stop_time=0.5)
    except KeyboardInterrupt:  # as pytest would take it: the whole session stopped
        pytest.fail("the second Ctrl-C escaped the safe stop")
    assert "Ctrl-C" in report.ended and twin.closed
    assert twin.sent_after >= 100  # the rest of the 0.5 s stop: 115 periods at 4 ms
    assert np.max(np.abs(twin.truth.qd)) < 0.01
    assert any("Ctrl-C during the safe stop" in e.detail for e in ctl.supervisor.events)


class LastCommandHeld(ClosableTwin):
    """The twin as a drive that holds the last torque it got until the next one comes."""

    def send_torque(self, tau) -> None:
        """Send ``tau`` and keep it."""
        self.last = np.array(tau, dtype=float)
        super().send_torque(tau)

    def coast(self, seconds: float) -> None:
        """Nobody sends anything for ``seconds``: the drive holds the last torque."""
        for _ in range(round(seconds / self.dt)):
            super().send_torque(self.last)


@pytest.mark.parametrize("hold_at_end", [True, False])
def test_a_loop_that_ends_leaves_the_arm_held_not_guided(hold_at_end):
    """The loop ends while a hand drags the arm at 1.4 rad/s: stopped and held, supervised.

    A drive that holds its last command (2 s of it here, the hand gone as the loop ends)
    carried the arm 125 mrad on under the guiding torque nobody supervised, 22 mrad with
    the safe stop. ``hold_at_end=False`` (the twin's ``simulate``, which goes on) keeps it.
    """
    start = lt.Dynamics(ROBOT).pose(ROBOT.home())[:3, 3]
    line = Line(start, start + np.array([0.0, 0.3, 0.0]), duration=1.0)
    twin = LastCommandHeld(ROBOT, operator=During(Hand(line), 0.0, 0.6))
    ctl, guided = lt.LeadThrough(ROBOT, "active"), []
    report = lt.control_loop(
        twin,
        ctl,
        duration=0.6,
        hold_at_end=hold_at_end,
        after_period=lambda s, c: guided.append(twin.truth.q.copy()),
    )
    assert report.ended == "finished" and not twin.closed
    twin.coast(2.0)
    travel = np.max(np.abs(twin.truth.q - guided[-1]))  # [rad], from the loop's last period
    if hold_at_end:
        assert ctl.state is SupervisorState.FAULT and "loop ended" in ctl.supervisor.fault_reason
        assert travel < 0.05
    else:
        assert ctl.state is SupervisorState.TEACHING
        assert travel > 0.1  # what the hold at the end prevents


def test_a_robot_error_is_raised_after_the_safe_stop():
    """A lost connection: the fault names it, the robot is closed, the error reaches the caller."""
    twin, ctl = ClosableTwin(ROBOT, fail_at=0.1), controller()
    with pytest.raises(ConnectionError, match="connection lost"):
        lt.control_loop(twin, ctl, duration=1.0)
    assert ctl.state is SupervisorState.FAULT
    assert "ConnectionError: robot connection lost" in ctl.supervisor.fault_reason
    assert twin.closed


class CloseFails(ClosableTwin):
    """A twin whose close raises, as a driver's on a socket already gone."""

    def close(self) -> None:
        """Raise as the socket's close does."""
        super().close()
        raise OSError("Bad file descriptor")


def test_a_close_that_raises_does_not_hide_the_error_that_ended_the_loop():
    """The lost connection reaches the caller, the close's error is an event.

    Before, the close's OSError replaced the ConnectionError (a review).
    """
    twin, ctl = CloseFails(ROBOT, fail_at=0.1), controller()
    with pytest.raises(ConnectionError, match="connection lost"):
        lt.control_loop(twin, ctl, duration=1.0)
    assert twin.closed
    (failed,) = [e.detail for e in ctl.supervisor.events if e.kind == "close_failed"]
    assert failed == "the robot's close raised OSError: Bad file descriptor"


class JointTooFew(ClosableTwin):
    """A driver that reports one joint too few, from its first sample."""

    def read_state(self) -> lt.JointState:
        """The twin's sample without its last joint."""
        state = super().read_state()
        return lt.JointState(state.t, state.q[:-1], state.qd[:-1], state.tau_measured[:-1])


def test_a_fault_with_nothing_to_hold_closes_the_robot():
    """Samples a joint too few from the first: no position to hold, the robot closed at once.

    Before, the loop sent zero torque for its whole duration (a Panda fell 3 rad; a review).
    """
    twin, ctl = JointTooFew(ROBOT), controller()
    report = lt.control_loop(twin, ctl, duration=1.0, wall_clock=False)
    assert report.ended == STRANDED and report.periods == 1
    assert twin.closed and ctl.state is SupervisorState.FAULT


@pytest.mark.parametrize(("name", "value"), [("duration", -1.0), ("stop_time", float("nan"))])
def test_bad_loop_settings_are_refused(name, value):
    """A negative duration or a NaN stop time names the setting."""
    with pytest.raises(ParameterError, match=name):
        lt.control_loop(ClosableTwin(ROBOT), controller(), **{name: value})


class _InterruptedAt:
    """A passive controller whose ``count``-th step is a Ctrl-C."""

    def __init__(self, robot: lt.RobotDescription, count: int) -> None:
        self.controller = lt.LeadThrough(robot, "passive")
        self.dt, self.supervisor = self.controller.dt, self.controller.supervisor
        self.count = count

    def step(self, state):
        self.count -= 1
        if self.count == 0:
            raise KeyboardInterrupt
        return self.controller.step(state)


def test_ctrl_c_in_a_simulation_stops_the_arm_then_is_raised():
    """A simulated run cut by Ctrl-C: the safe stop first, then the interruption goes on.

    A partial simulation is no result (the command line then prints one line); a robot's
    loop instead returns its report (``interrupted``), and teaching keeps its recording.
    """
    from leadthrough.twin.runner import simulate

    controller = _InterruptedAt(ROBOT, 10)
    with pytest.raises(KeyboardInterrupt, match=r"stopped at 0\.04 s of 1 s"):
        simulate(DigitalTwin(ROBOT), controller, 1.0)
    assert any("Ctrl-C" in event.detail for event in controller.supervisor.events)
