"""One clock, one loop, one model per period (issue 12): what a hardware integrator relies on."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.constraints import Plane, constraint_torque
from leadthrough.control.dither import DitherParameters
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.errors import ParameterError, RecordingError
from leadthrough.estimation.observer import MomentumObserver
from leadthrough.runtime.interface import JointState, RobotInterface
from leadthrough.runtime.recording import read_recording
from leadthrough.runtime.teaching import teach
from leadthrough.safety.limits import SafetyParameters
from leadthrough.safety.supervisor import SupervisorState
from leadthrough.twin.mjcf import Payload
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.operator import During, Hand
from leadthrough.twin.paths import Line
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

ROBOT = lt.robots.yumi()
N = ROBOT.n_joints
UNIX_TIME = 1.7e9  # [s]


class ShiftedClock(RobotInterface):
    """The twin behind a driver whose clock starts at ``offset`` [s]; it keeps what it sent."""

    def __init__(self, twin: DigitalTwin, offset: float) -> None:
        self.twin, self.offset = twin, offset
        self.dt, self.n_joints = twin.dt, twin.n_joints
        self.sent: list[np.ndarray] = []
        self.closed = False

    def read_state(self) -> JointState:
        """The twin's sample, stamped on this driver's clock."""
        state = self.twin.read_state()
        return JointState(state.t + self.offset, state.q, state.qd, state.tau_measured)

    def send_torque(self, tau) -> None:
        """Send and remember."""
        self.sent.append(np.array(tau, dtype=float))
        self.twin.send_torque(tau)

    def close(self) -> None:
        """Remember the close."""
        self.closed = True


def pulled_twin() -> DigitalTwin:
    """The YuMi pulled 20 cm sideways in 1 s by a hand that does not let go."""
    start = lt.Dynamics(ROBOT).pose(ROBOT.home())[:3, 3]
    hand = Hand(Line(start, start + np.array([0.0, 0.2, 0.0]), duration=1.0))
    return DigitalTwin(ROBOT, operator=During(hand, 0.0, 10.0))


def interrupted_run(offset: float) -> tuple[ShiftedClock, lt.LeadThrough, lt.LoopReport]:
    """Passive guiding, Ctrl-C at 0.6 s while the arm moves; the driver's clock at ``offset``."""
    robot, controller = ShiftedClock(pulled_twin(), offset), lt.LeadThrough(ROBOT, "passive")

    def ctrl_c(state: JointState, command: np.ndarray) -> None:
        if state.t - offset >= 0.6 - 1e-4:  # 1.7e9 s carries 0.2 µs resolution
            raise KeyboardInterrupt

    report = lt.control_loop(robot, controller, duration=2.0, after_period=ctrl_c, wall_clock=False)
    return robot, controller, report


def test_a_unix_clock_keeps_the_damped_safe_stop():
    """Ctrl-C on a robot whose clock reads 1.7e9 s: the same damped stop as with t₀ = 0."""
    runs = {offset: interrupted_run(offset) for offset in (0.0, UNIX_TIME)}
    stops = {}
    for offset, (robot, controller, report) in runs.items():
        assert report.ended == "interrupted by the operator (Ctrl-C)" and robot.closed
        assert controller.state is SupervisorState.FAULT
        (fault,) = [e for e in controller.supervisor.events if e.kind == "fault"]
        assert fault.t == pytest.approx(offset + 0.6, abs=1e-6)  # on the robot's clock
        stops[offset] = np.array(robot.sent[report.periods :])
    np.testing.assert_allclose(stops[UNIX_TIME], stops[0.0], atol=1e-9)
    hold = lt.Dynamics(ROBOT).gravity(runs[UNIX_TIME][1].supervisor._q_last_good)
    assert np.max(np.abs(stops[UNIX_TIME][0] - hold)) > 0.05  # damping, not G alone


def test_the_controller_takes_time_from_the_sample():
    """step(state) stamps events and its clock with state.t; the positional form counts dt."""
    controller = lt.LeadThrough(ROBOT, "passive")
    q = ROBOT.home()
    for k in range(3):
        controller.step(JointState(UNIX_TIME + 0.004 * k, q, np.zeros(N), None))
    assert controller.time == UNIX_TIME + 0.008
    positional = lt.LeadThrough(ROBOT, "passive")
    for _ in range(3):
        positional.step(q, np.zeros(N))
    assert positional.time == pytest.approx(0.012)


@pytest.mark.parametrize(
    ("args", "reason"),
    [((JointState(0.0, ROBOT.home(), np.zeros(N), None), np.zeros(N)), "JointState alone"),
     ((ROBOT.home(), None, np.zeros(N)), "needs a JointState, or q and qd")],
)  # fmt: skip
def test_a_sample_the_step_cannot_read_is_a_fault_with_the_safe_stop(args, reason):
    """step(state, qd) or step(q) without q̇: the fault names it, the arm held where it was.

    Before, the positional form raised out of the step with no fault latched and nothing
    returned to send (the same sample as a JointState faulted).
    """
    controller, q = lt.LeadThrough(ROBOT, "passive"), ROBOT.home() + 0.1
    controller.step(JointState(0.0, q, np.zeros(N), None))
    command = controller.step(*args)
    assert controller.state is SupervisorState.FAULT
    assert "sample failed: ParameterError" in controller.supervisor.fault_reason
    assert reason in controller.supervisor.fault_reason
    np.testing.assert_allclose(command, lt.Dynamics(ROBOT).gravity(q), atol=1e-9)


def test_an_exception_inside_the_step_is_named_and_the_arm_stopped_that_period(monkeypatch):
    """An IndexError in the observer: fault naming it and where, safe stop returned at once."""
    controller = lt.LeadThrough(ROBOT, "active")
    q = ROBOT.home()
    controller.step(q, np.zeros(N))

    def broken(self, tau):
        raise IndexError("index 9 is out of bounds for axis 0 with size 7")

    monkeypatch.setattr(MomentumObserver, "_input", broken)
    qd = np.full(N, 0.05)
    command = controller.step(q, qd)
    reason = controller.supervisor.fault_reason
    assert controller.state is SupervisorState.FAULT
    assert reason.startswith("observer failed: IndexError: index 9 is out of bounds")
    assert "estimation/observer.py" in reason
    gravity, damping = lt.Dynamics(ROBOT).gravity(q), lt.Dynamics(ROBOT).mass(q).diagonal() / 0.05
    np.testing.assert_allclose(command, np.clip(gravity - damping * qd, -ROBOT.torque_limits,
                                                ROBOT.torque_limits), atol=1e-9)  # fmt: skip


def test_a_controller_at_another_period_than_the_robot_is_refused():
    """A 4 ms controller on a 1 ms robot: one-line error before anything is sent."""
    twin = DigitalTwin(ROBOT, TwinConfig(control_dt=0.001))
    with pytest.raises(
        ParameterError, match=r"controller runs at 4 ms, the robot at 1 ms"
    ) as error:
        lt.control_loop(twin, lt.LeadThrough(ROBOT, "passive", dt=0.004), duration=0.1)
    assert "\n" not in str(error.value)
    assert twin.time == 0.0


@pytest.mark.parametrize("delay", [1, 2, 3])
def test_one_delay_line_for_the_command_and_its_dither(monkeypatch, delay):
    """Without a torque reading the observer gets the command of k − delay minus its dither."""
    parameters = LeadThroughParameters(measurement_delay=delay)
    controller = lt.LeadThrough(ROBOT, "passive", parameters=parameters)
    seen, update = [], controller.observer.update

    def spying(q, qd, tau, model=None, terms=None, periods=1):
        seen.append(tau)
        return update(q, qd, tau, model, terms, periods=periods)

    monkeypatch.setattr(controller.observer, "update", spying)
    q, commands, dithers = ROBOT.home(), [], []
    rng = np.random.default_rng(0)
    for _ in range(30):  # velocity noise at rest: the encoders are alive, the dither on
        commands.append(controller.step(q, 1e-4 * rng.standard_normal(N)))
        dithers.append(controller.last_feed_forward.dither)
    assert np.count_nonzero(np.array(dithers)) > 0
    for k in range(delay, 30):
        np.testing.assert_array_equal(seen[k], commands[k - delay] - dithers[k - delay])
    np.testing.assert_array_equal(seen[delay - 1], 0.0)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"measurement_delay": 0}, "measurement_delay"),
        ({"measurement_delay": 1.5}, "measurement_delay"),
        ({"rest_velocity": 0.0}, "rest_velocity"),
        ({"unwind_time": 0.0}, "unwind_time"),
        ({"assist_speed_fraction": 1.5}, "assist_speed_fraction"),
        ({"dither": DitherParameters(moving_velocity=0.02)}, "rest_velocity"),
        ({"safety": SafetyParameters(stale_speed=0.02)}, "rest_velocity"),
    ],
)
def test_invalid_parameters_are_refused_at_construction(changes, message):
    """Integer delays from 1, one definition of at rest: one line naming the parameter."""
    with pytest.raises(ParameterError, match=message):
        LeadThroughParameters(**changes)


def test_rest_velocity_is_the_dithers_and_the_supervisors():
    """One definition of at rest: the dither and the stale-data check follow rest_velocity."""
    parameters = LeadThroughParameters(rest_velocity=0.02)
    assert parameters.dither.moving_velocity == parameters.safety.stale_speed == 0.02
    controller = lt.LeadThrough(ROBOT, parameters=parameters)
    assert controller.supervisor.parameters.stale_speed == 0.02


def test_bounds_that_would_invert_are_refused_against_the_robot():
    """limit_zone = 5 rad leaves nothing of the YuMi's joints: refused, naming the joint."""
    with pytest.raises(ParameterError, match=r"limit_zone: .* joint \d+'s range"):
        lt.LeadThrough(ROBOT, parameters=LeadThroughParameters(limit_zone=5.0))
    wide = SafetyParameters(soft_limit_margin=3.5)
    with pytest.raises(ParameterError, match="soft_limit_margin"):
        lt.LeadThrough(ROBOT, parameters=LeadThroughParameters(safety=wide))
    with pytest.raises(ParameterError, match="calibrate"):
        lt.LeadThrough(ROBOT, parameters=LeadThroughParameters(calibration=None), calibrate=True)
    with pytest.raises(ParameterError, match="constraints"):
        lt.LeadThrough(ROBOT, constraints=["a plane"])


def test_the_calibration_only_runs_when_asked_for():
    """LeadThrough(robot) guides at once; calibrate=True moves the arm first, for its duration."""
    quiet, moving = lt.LeadThrough(ROBOT), lt.LeadThrough(ROBOT, calibrate=True)
    assert not quiet.calibrating and quiet.calibration_time == 0.0
    assert moving.calibrating and moving.calibration_time > 0.5


def test_a_payload_changes_the_one_model_everywhere():
    """After set_payload the supervisor, observer and feed-forward share the loaded model."""
    controller = lt.LeadThrough(ROBOT, "passive")
    controller.set_payload(1.0, (0.0, 0.0, 0.05))
    dynamics = controller.dynamics
    assert (
        controller.supervisor.dynamics is dynamics and controller.supervisor.robot is dynamics.robot
    )
    assert controller.observer.dynamics is dynamics and controller.feed_forward.dynamics is dynamics
    assert dynamics.robot.total_mass == pytest.approx(ROBOT.total_mass + 1.0)


def test_a_reset_keeps_the_payload_and_a_calibration_weighs_what_is_beyond_it():
    """set_payload, a fault, reset(): the model still carries it; a calibration adds to it.

    Before, reset() rebuilt the model without the payload (0.70 and 1.01 Nm of gravity
    missing on joints 2 and 3 with 0.5 kg, in the controller and in its safe stop), and a
    calibration replaced it by the mass it weighed beyond it.
    """
    controller, q = lt.LeadThrough(ROBOT, "passive"), ROBOT.home()
    payload = Payload(0.5, (0.0, 0.0, 0.05))
    controller.set_payload(payload.mass, payload.com)
    loaded = lt.Dynamics(ROBOT.with_payload(payload.mass, payload.com)).gravity(q)
    controller.step(JointState(0.0, q, np.zeros(N), None))
    controller.step(JointState(0.004, np.full(N, np.nan), np.zeros(N), None))
    controller.reset()
    controller.step(JointState(0.008, q, np.zeros(N), None))
    np.testing.assert_allclose(controller.model.gravity, loaded)
    assert controller.supervisor.robot.total_mass == pytest.approx(ROBOT.total_mass + 0.5)
    weighed = lt.LeadThrough(ROBOT, "active", calibrate=True)
    weighed.set_payload(payload.mass, payload.com)
    twin = DigitalTwin(ROBOT, TwinConfig(model_error=ModelError(payload=payload)))
    simulate(twin, weighed, weighed.calibration_time + 0.1)
    assert weighed.calibration.accepted and abs(weighed.calibration.payload) < 0.05  # [kg]
    assert weighed.dynamics.robot.total_mass == pytest.approx(ROBOT.total_mass + 0.5, abs=0.05)


def test_the_safe_stop_holds_with_the_calibrated_gravity():
    """A calibration that read the masses 15 % off: the safe stop holds with G corrected.

    Before, guiding held the arm with the corrected G and the safe stop with the model's
    (on a UR10e twin whose masses were 15 % heavier, 5.5 Nm off on shoulder and elbow).
    """
    controller = lt.LeadThrough(ROBOT, "passive", calibrate=True)
    twin = DigitalTwin(ROBOT, TwinConfig(model_error=ModelError(mass_error=0.15), seed=3))
    simulate(twin, controller, controller.calibration_time + 0.1)
    assert controller.calibration.accepted
    state = twin.read_state()
    controller.supervisor.stop("test", state.t)
    still = [JointState(state.t + 0.004 * (k + 1), state.q, np.zeros(N), None) for k in range(130)]
    held = [controller.step(sample) for sample in still][-1]  # past the damped phase
    gravity = lt.Dynamics(controller.dynamics.robot).gravity(state.q)
    share = controller.gravity_share
    expected = (
        (1.0 - share) * gravity
        + share * controller.dynamics.gravity(controller.calibration.pose)
        - controller.calibration.bias
    )
    np.testing.assert_allclose(held, expected, atol=1e-9)
    assert np.max(np.abs(held - gravity)) > 0.05  # [Nm]: not the model's own G


def test_constraints_act_at_the_tool_centre_point():
    """A 15 cm tool: the plane pulls the tip, not the flange, back (Jᵀ F at the TCP)."""
    tool = lt.Dynamics(dataclasses.replace(ROBOT, tcp=lt.Placement([0.0, 0.0, 0.15])))
    q = ROBOT.home()
    tip = tool.tool_pose(q)[:3, 3]
    plane = Plane(point=tip + np.array([0.01, 0.0, 0.0]), normal=(1.0, 0.0, 0.0))  # tip 1 cm behind
    torque, force = constraint_torque([plane], tool, q, np.zeros(N))
    np.testing.assert_allclose(force, [3000.0 * 0.01, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(torque, tool.tool_jacobian(q)[:3].T @ force, atol=1e-12)
    assert np.max(np.abs(torque - tool.jacobian(q)[:3].T @ force)) > 0.1


def test_every_component_gets_the_same_snapshot(monkeypatch):
    """M(q), G(q) and the Jacobian are computed once per period (one snapshot)."""
    controller = lt.LeadThrough(ROBOT, "active")
    dynamics = controller.dynamics
    calls = {"snapshot": 0, "mass": 0, "gravity": 0, "jacobian": 0}
    for name in calls:
        original = getattr(dynamics, name)

        def counted(*args, _name=name, _original=original, **kwargs):
            calls[_name] += 1
            return _original(*args, **kwargs)

        monkeypatch.setattr(dynamics, name, counted)
    q = ROBOT.home()
    for _ in range(5):
        controller.step(q, np.full(N, 0.02))
    assert calls == {"snapshot": 5, "mass": 0, "gravity": 0, "jacobian": 0}


class WrenchLog:
    """Steps a LeadThrough and keeps its tool wrench each period."""

    def __init__(self, controller: lt.LeadThrough) -> None:
        self.controller, self.dt, self.supervisor = controller, controller.dt, controller.supervisor
        self.wrenches: list[lt.ToolWrench] = []

    def step(self, state: JointState) -> np.ndarray:
        """One period, and the wrench read."""
        command = self.controller.step(state)
        self.wrenches.append(self.controller.tool_wrench)
        return command


def test_the_tool_wrench_reads_the_hand_of_the_twin():
    """A hand pulls the tool (≈14 N RMS): F̂ = (Jᵀ)⁺ τ̂_ext within 25 %, inside its 3σ."""
    start = lt.Dynamics(ROBOT).pose(ROBOT.home())[:3, 3]
    hand = Hand(Line(start, start + np.array([0.0, 0.2, -0.1]), duration=1.5))
    log = WrenchLog(lt.LeadThrough(ROBOT, "passive"))
    sim = simulate(DigitalTwin(ROBOT, operator=During(hand, 0.0, 10.0)), log, 1.5)
    pulling = sim.t > 0.2  # the observer has settled
    estimate = np.array([w.vector for w in log.wrenches])[pulling]
    std = np.array([w.std for w in log.wrenches])[pulling]
    truth = sim.operator_wrench[pulling]  # at the flange = the TCP here, world axes
    error = np.linalg.norm(estimate[:, :3] - truth[:, :3], axis=1)
    size = np.sqrt(np.mean(np.sum(truth[:, :3] ** 2, axis=1)))
    assert size > 10.0
    assert np.sqrt(np.mean(error**2)) < 0.25 * size
    assert np.mean(np.abs(estimate - truth) <= 3.0 * std) > 0.99
    covariance = log.wrenches[-1].covariance
    np.testing.assert_allclose(covariance, covariance.T, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(covariance) > -1e-9)


def test_teaching_records_on_any_driver(tmp_path):
    """teach() on a driver: every period recorded with the tool wrench, events on its clock."""
    robot = ShiftedClock(pulled_twin(), UNIX_TIME)
    controller = lt.LeadThrough(ROBOT, "active")
    report = teach(robot, controller, tmp_path / "taught.mcap", duration=0.4, wall_clock=False)
    recording = read_recording(tmp_path / "taught.mcap")
    assert report.recorded == report.loop.periods == len(recording.t) == 100
    np.testing.assert_allclose(recording.t, np.arange(100) * 0.004, atol=1e-6)
    assert np.all(np.isfinite(recording.tool_wrench))
    assert recording.tool_wrench_covariance.shape == (100, 6, 6)
    assert all(0.0 <= event.t < 0.4 for event in recording.events)
    assert recording.complete and "recorded 100 periods" in report.summary()


def test_a_sample_out_of_order_is_stepped_not_recorded(tmp_path):
    """Two samples swapped by the driver: the recording's time still increases.

    Before, the swapped sample was recorded as it came, and the replay refused the whole
    session ("time not increasing"; a review).
    """

    class Swapped(ShiftedClock):
        def __init__(self, twin) -> None:
            super().__init__(twin, 0.0)
            self.held: JointState | None = None

        def read_state(self) -> JointState:
            state = super().read_state()
            if abs(state.t - 0.2) < 1e-9:  # hold this one back a period
                self.held = state
                self.twin.send_torque(self.sent[-1])
                return super().read_state()
            if self.held is not None:
                held, self.held = self.held, None
                return held
            return state

    path = tmp_path / "taught.mcap"
    report = teach(Swapped(pulled_twin()), lt.LeadThrough(ROBOT, "passive"), path,
                   duration=0.4, wall_clock=False)  # fmt: skip
    recording = read_recording(path)
    assert np.all(np.diff(recording.t) > 0.0)
    assert report.recorded == len(recording.t) == report.loop.periods - 1


def test_teaching_does_not_replace_a_recording_unless_asked(tmp_path):
    """A second session to the same file: refused before the arm moves, the first kept.

    Before, it was replaced (a session stopped in its calibration left 0 rows of 750).
    """
    path = tmp_path / "taught.mcap"
    teach(pulled_twin(), lt.LeadThrough(ROBOT, "passive"), path, duration=0.2, wall_clock=False)
    taught = read_recording(path).t.size
    twin = pulled_twin()
    with pytest.raises(RecordingError, match="exists; pass overwrite=True"):
        teach(twin, lt.LeadThrough(ROBOT, "passive"), path, duration=0.1, wall_clock=False)
    assert read_recording(path).t.size == taught and twin.time == 0.0
    teach(twin, lt.LeadThrough(ROBOT, "passive"), path, duration=0.1, wall_clock=False,
          overwrite=True)  # fmt: skip
    assert read_recording(path).t.size == 25


def test_a_ctrl_c_before_the_first_period_holds_the_arm_against_gravity():
    """Ctrl-C while the controller warms up: the safe stop holds the arm where it is.

    The loop's safe stop checks each sample it reads, so the supervisor knows a good pose
    even when no period was stepped; it sent zero torque before, and the YuMi sagged by up
    to 0.83 rad in the 0.5 s of the stop.
    """
    robot = ShiftedClock(DigitalTwin(ROBOT), 0.0)
    controller = lt.LeadThrough(ROBOT, "passive")
    start = robot.read_state().q

    def interrupted() -> float:
        raise KeyboardInterrupt

    controller.warm_up = interrupted  # type: ignore[method-assign]
    report = lt.control_loop(robot, controller, duration=1.0, wall_clock=False)
    assert report.periods == 0 and report.ended == "interrupted by the operator (Ctrl-C)"
    gravity = lt.Dynamics(ROBOT).gravity(start)
    np.testing.assert_allclose(robot.sent[0], gravity, atol=0.01)  # the hold, at once [Nm]
    assert np.max(np.abs(robot.read_state().q - start)) < 1e-3  # [rad]


def test_a_reset_forgets_the_pose_it_held():
    """After reset(), a first sample that is bad gets what a fresh controller sends.

    Before, the safe stop held gravity for the pose of before the reset: at another pose,
    torques of up to 3.6 Nm where the arm needed 2.1 Nm the other way.
    """
    q_before, q_after = ROBOT.home(), ROBOT.home() + np.array([0.8, -0.6, 0.4, 0.6, 0, 0, 0])
    bad = JointState(1.0, np.where(np.arange(N) == 6, np.nan, q_after), np.zeros(N), None)
    used = lt.LeadThrough(ROBOT, "passive")
    for k in range(5):
        used.step(JointState(0.004 * k, q_before, np.zeros(N), None))
    used.reset()
    fresh = lt.LeadThrough(ROBOT, "passive")
    np.testing.assert_array_equal(used.step(bad), fresh.step(bad))
    assert used.state is SupervisorState.FAULT and "joint 7 position" in str(
        used.supervisor.fault_reason
    )


@pytest.mark.parametrize(
    ("stamp", "reason"),
    [
        (np.nan, "time stamp nan is not a finite number"),
        (None, "time stamp None is not a finite number"),
        ("0.2", "time stamp '0.2' is not a finite number"),
        (1.2, r"time stamp jumped 1 s, from 0.200000 to 1.200000 s \(more than max_time_gap"),
    ],
    ids=["nan", "none", "string", "jump"],
)
def test_a_bad_time_stamp_is_a_fault_with_the_damped_stop(stamp, reason):
    """A time stamp that is not a finite number of seconds, or jumps, is a one-line fault.

    The arm moving at 0.3 rad/s gets the damped safe stop. Before, a NaN stamp reached the
    dither ("cannot convert float NaN to integer") and its NaN fault time left the stop
    undamped for good; None escaped step() as a TypeError; a string was taken.
    """
    controller, qd = lt.LeadThrough(ROBOT, "passive"), np.full(N, 0.3)
    q = ROBOT.home() + 0.004 * np.arange(52)[:, None] * qd  # the arm moving [rad]
    for k in range(51):
        controller.step(JointState(0.004 * k, q[k], qd, None))
    command = controller.step(JointState(stamp, q[51], qd, None))
    assert controller.state is SupervisorState.FAULT
    assert controller.supervisor.fault_reason is not None
    assert re.match(reason, controller.supervisor.fault_reason), controller.supervisor.fault_reason
    damping = command - lt.Dynamics(ROBOT).gravity(q[51])
    assert np.all(damping[:4] < -0.1)  # braking the motion [Nm], not G alone
    later = controller.step(JointState(0.208, q[51], qd, None))
    np.testing.assert_allclose(later, command, atol=1e-9)  # still damped, a good stamp after


@pytest.mark.parametrize("bad", ["q", "qd", "tau"])
def test_readings_that_are_not_numbers_latch_the_same_fault_in_both_forms(bad):
    """step("abc", qd, tau) latches the fault a JointState of "abc" does, a finite safe stop.

    Before, the positional form raised numpy's ValueError and left the controller teaching.
    """
    readings = {
        "q": ROBOT.home(),
        "qd": np.zeros(N),
        "tau": lt.Dynamics(ROBOT).gravity(ROBOT.home()),
    }
    readings[bad] = "abc"
    positional, stamped = lt.LeadThrough(ROBOT, "active"), lt.LeadThrough(ROBOT, "active")
    command = positional.step(readings["q"], readings["qd"], readings["tau"])
    stamped.step(JointState(0.004, readings["q"], readings["qd"], readings["tau"]))
    assert positional.state is stamped.state is SupervisorState.FAULT
    assert positional.supervisor.fault_reason == stamped.supervisor.fault_reason
    assert "could not convert string to float: 'abc'" in str(positional.supervisor.fault_reason)
    assert np.all(np.isfinite(command))


def test_a_clock_in_milliseconds_stops_the_calibration_before_any_kick():
    """A driver stamping milliseconds (4 per period at 250 Hz): the second sample faults.

    Before, the start-up calibration integrated 4 s of error in one period and sent the
    torque limits (30, 30, 30, 20 Nm) with nobody at the arm.
    """

    class Milliseconds(ShiftedClock):
        def read_state(self) -> JointState:
            state = self.twin.read_state()
            return JointState(1e3 * state.t, state.q, state.qd, state.tau_measured)

    robot = Milliseconds(DigitalTwin(ROBOT), 0.0)
    controller = lt.LeadThrough(ROBOT, "active", calibrate=True)
    lt.control_loop(robot, controller, duration=0.4, wall_clock=False)
    assert "time stamp jumped 4 s" in str(controller.supervisor.fault_reason)
    gravity = lt.Dynamics(ROBOT).gravity(ROBOT.home())
    assert np.max(np.abs(np.array(robot.sent) - gravity)) < 2.0  # [Nm]


@pytest.mark.parametrize(("back", "fault"), [(0.002, False), (10.0, True)])
def test_a_clock_stepping_back_further_than_the_largest_gap_stops_the_calibration(back, fault):
    """The clock steps back at 0.2 s, in the calibration: 2 ms (coarse) taken, 10 s a fault.

    Before, a step back of 10 s was taken: the calibration ran on for the time stepped
    back (the arm moving by itself for 10 s more).
    """

    class SteppingBack(ShiftedClock):
        def read_state(self) -> JointState:
            state = self.twin.read_state()
            t = state.t - (back if state.t >= 0.2 else 0.0)
            return JointState(t, state.q, state.qd, state.tau_measured)

    controller = lt.LeadThrough(ROBOT, "active", calibrate=True)
    lt.control_loop(SteppingBack(DigitalTwin(ROBOT), 0.0), controller, duration=0.4,
                    wall_clock=False, hold_at_end=False)  # fmt: skip
    assert (controller.state is SupervisorState.FAULT) is fault
    reason = str(controller.supervisor.fault_reason)
    stepped = r"time stamp stepped back 9\.99\d s, from 0\.19\d+ to -9\.8\d+ s \(more than"
    assert bool(re.match(stepped + r" max_time_gap 0\.25 s\)", reason)) is fault, reason


class Ordered(ShiftedClock):
    """A driver that notes each command sent in a shared journal."""

    def __init__(self, twin: DigitalTwin, journal: list[str]) -> None:
        super().__init__(twin, 0.0)
        self.journal = journal

    def send_torque(self, tau) -> None:
        """Note, then send."""
        self.journal.append("send")
        super().send_torque(tau)


def test_teaching_records_after_the_command_is_sent_and_warms_up_first(tmp_path, monkeypatch):
    """The recorder's writes and flushes are off the timed path; the kernels compile first.

    Before, each period was written (and every 0.1 s fsynced) inside the timed step, ahead
    of its command, and teaching skipped the warm-up: its first period compiled.
    """
    from leadthrough.runtime import recording

    journal: list[str] = []
    original = recording.SessionRecorder.record

    def noted(self, *args, **kwargs):
        journal.append("record")
        return original(self, *args, **kwargs)

    monkeypatch.setattr(recording.SessionRecorder, "record", noted)
    robot = Ordered(DigitalTwin(ROBOT), journal)
    report = teach(robot, lt.LeadThrough(ROBOT, "passive"), tmp_path / "t.mcap", duration=0.04,
                   wall_clock=False)  # fmt: skip
    hold = round(0.5 / 0.004)  # then the hold at the end (stop_time), nothing recorded
    assert journal == ["send", "record"] * 10 + ["send"] * hold
    assert report.loop.warm_up > 0.0


def test_the_estimate_a_user_reads_is_a_value_not_the_controllers_buffer():
    """ctl.tau_ext_hat and ctl.std kept over a run hold each period's values.

    Before, both returned the fusion's arrays, written in place every period: a user who
    appended them after each step got the last period's value in every row.
    """
    twin = DigitalTwin(ROBOT, operator=pulling_hand_for_a_test())
    controller = lt.LeadThrough(ROBOT, "active")
    kept, copied = [], []

    def keep(state, command) -> None:
        kept.append((controller.tau_ext_hat, controller.std))
        copied.append((controller.tau_ext_hat.copy(), controller.std.copy()))

    lt.control_loop(twin, controller, duration=1.0, after_period=keep, wall_clock=False,
                    hold_at_end=False)  # fmt: skip
    for (estimate, std), (estimate_then, std_then) in zip(kept, copied, strict=True):
        np.testing.assert_array_equal(estimate, estimate_then)
        np.testing.assert_array_equal(std, std_then)
    assert np.ptp(np.array([estimate for estimate, _ in kept]), axis=0).max() > 0.1  # [Nm]


def pulling_hand_for_a_test() -> During:
    """A hand pulling the tool 10 cm sideways in 1 s."""
    start = lt.Dynamics(ROBOT).pose(ROBOT.home())[:3, 3]
    return During(Hand(Line(start, start + np.array([0.0, 0.1, 0.0]), duration=1.0)), 0.0, 1.0)


@pytest.mark.parametrize(("dt", "period"), [(0.001, 0.004), (0.004, 0.001)])
def test_samples_at_another_rate_than_dt_are_a_fault(dt, period):
    """A controller built for 1 kHz fed 250 Hz samples (or the reverse) faults within 1 s.

    Before, step(JointState) took any spacing of stamps: a controller at dt = 1 ms fed
    samples every 4 ms read a push of 2.5 Nm as 5.9 Nm while the arm accelerated.
    """
    controller = lt.LeadThrough(ROBOT, "passive", dt=dt)
    for k in range(int(1.1 / period)):
        controller.step(JointState(1e9 + period * k, ROBOT.home(), np.zeros(N), None))
    assert controller.state is SupervisorState.FAULT
    reason = str(controller.supervisor.fault_reason)
    assert f"samples came every {1e3 * period:.3g} ms" in reason, reason
    assert f"dt = {1e3 * dt:.3g} ms" in reason, reason


def test_a_jittery_clock_with_a_gap_is_no_rate_fault():
    """Stamps that jitter by ±40 % and one gap just under max_time_gap keep the rate check quiet.

    What this prevents: a rate check that faults a real robot's jitter (34 ms at 100 Hz
    on the public UR10e logs) or one lost stretch of samples the gap check allows.
    """
    rng = np.random.default_rng(3)
    controller, t = lt.LeadThrough(ROBOT, "passive", dt=0.004), 0.0
    for k in range(1000):
        t += 0.004 * (1.0 + rng.uniform(-0.4, 0.4)) + (0.24 if k == 300 else 0.0)
        controller.step(JointState(t, ROBOT.home(), np.zeros(N), None))
    assert controller.state is not SupervisorState.FAULT, controller.supervisor.fault_reason
    # the gap is an event, the jitter is not: 60 samples were lost
    (lost,) = [e.detail for e in controller.supervisor.events if e.kind == "samples_lost"]
    assert lost.startswith("no sample for 24") and "(60 periods lost)" in lost, lost


def test_the_observer_predicts_over_the_periods_lost(monkeypatch):
    """Stamps jittering ±30 % with 60 samples lost: the observer is told 61 periods once.

    Every other sample is one period after the one before, whatever its jitter (the
    samples' ticks, :class:`~leadthrough.control.ticks.TickClock`). Before, it
    predicted over one period always (``tests/test_observer.py``: a push read into the gap).
    """
    rng = np.random.default_rng(7)
    controller = lt.LeadThrough(ROBOT, "passive", dt=0.004)
    told: list[int] = []
    update = controller.observer.update

    def counted(*args, periods: int = 1, **kwargs):
        told.append(periods)
        return update(*args, periods=periods, **kwargs)

    monkeypatch.setattr(controller.observer, "update", counted)
    for k in [*range(300), *range(360, 600)]:
        t = 0.004 * (k + rng.uniform(-0.3, 0.3))
        controller.step(JointState(t, ROBOT.home(), np.zeros(N), None))
    assert controller.state is not SupervisorState.FAULT, controller.supervisor.fault_reason
    assert told.count(61) == 1 and told.count(1) == len(told) - 1, sorted(set(told))


@pytest.mark.parametrize("calibrate", [False, True])
def test_a_measured_torque_of_the_other_sign_is_a_fault(calibrate):
    """Nobody touching the arm, its measured torque reported with the other sign.

    A fault naming a joint and its slope within 0.5 s, and the arm moves less than 0.2 rad.
    Before, active mode read twice each command as a push and followed it: the YuMi
    turned 2.1 rad in 5 s; with a calibration, it was refused as a touch and guiding
    went on with the same readings (a review).
    """

    def other_sign(state: JointState) -> JointState:
        return JointState(state.t, state.q, state.qd, -state.tau_measured)

    fault, moved = _untouched(ROBOT, other_sign, calibrate, duration=2.0)
    assert fault.t < 0.5 and "the other sign convention" in fault.detail, fault
    assert moved < 0.2  # [rad]


@pytest.mark.parametrize("robot", ["yumi", "panda"])
def test_velocities_in_degrees_per_second_fault_and_the_stop_damps_on_the_positions(robot):
    """A driver reporting degrees per second, nobody at the arm, calibrating: it stays put.

    A fault naming degrees within 0.1 s, and the safe stop damps on the positions' rate:
    the arm moves less than 20 mrad. Before, the stop damped on the readings (57× too
    strong) and drove a Panda 2.9 rad to its joint limit at full torque (a review).
    """

    def degrees(state: JointState) -> JointState:
        return JointState(state.t, state.q, np.rad2deg(state.qd), state.tau_measured)

    fault, moved = _untouched(getattr(lt.robots, robot)(), degrees, True, duration=1.5)
    assert fault.t < 0.1 and "in degrees per second?" in fault.detail, fault
    assert moved < 0.02  # [rad]


def _untouched(arm, reading, calibrate: bool, duration: float):
    """Active mode on the twin, nobody at the arm, each sample passed through ``reading``.

    Returns the supervisor's fault event and how far the arm moved [rad].
    """

    class Misreading(ShiftedClock):
        def read_state(self) -> JointState:
            return reading(self.twin.read_state())

    twin = DigitalTwin(arm)
    start = twin.truth.q.copy()
    controller = lt.LeadThrough(arm, "active", calibrate=calibrate)
    lt.control_loop(Misreading(twin, 0.0), controller, duration=duration, wall_clock=False)
    (fault,) = [e for e in controller.supervisor.events if e.kind == "fault"]
    return fault, float(np.abs(twin.truth.q - start).max())


def test_a_first_sample_with_a_bad_torque_holds_the_arm_where_it_reads():
    """A first sample whose position is sound but whose torque is NaN: the gravity hold there.

    Before, nothing was held yet, so the safe stop sent zero torque for that period.
    """
    q = ROBOT.home() + 0.3
    controller = lt.LeadThrough(ROBOT, "passive")
    command = controller.step(JointState(0.0, q, np.zeros(N), np.full(N, np.nan)))
    assert controller.state is SupervisorState.FAULT
    np.testing.assert_allclose(command, lt.Dynamics(ROBOT).gravity(q), atol=1e-9)
