"""Tests of the safety supervisor (SPEC §7): limits, braking, walls, sensor faults, safe stop."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.errors import ParameterError
from leadthrough.safety.checks import MEASUREMENT_LAG, VELOCITY_MOVE, FrozenEncoders
from leadthrough.safety.supervisor import SafetyParameters, SafetySupervisor, SupervisorState
from realdata import REALDATA, needs_realdata

DT = 0.004
ROBOT = lt.robots.yumi()
N = ROBOT.n_joints
MID = (ROBOT.q_min + ROBOT.q_max) / 2.0
LIMIT = ROBOT.torque_limits


@pytest.fixture(scope="module")
def dyn() -> lt.Dynamics:
    """The YuMi's dynamics."""
    return lt.Dynamics(ROBOT)


@pytest.fixture
def sup(dyn) -> SafetySupervisor:
    """A fresh supervisor with default parameters."""
    return SafetySupervisor(dyn, DT)


def kinds(supervisor: SafetySupervisor, kind: str) -> list[str]:
    """Details of the logged events of one kind."""
    return [event.detail for event in supervisor.events if event.kind == kind]


def tool_velocity(dyn, q, speed: float) -> np.ndarray:
    """A joint velocity [rad/s] moving the flange at ``speed`` [m/s], joints below limits."""
    qd = np.array([0.3, -0.2, 0.4, 0.5, -0.3, 0.2, 0.1])
    qd *= speed / np.linalg.norm(dyn.jacobian(q)[:3] @ qd)
    assert np.all(np.abs(qd) < ROBOT.velocity_limits)
    return qd


def test_command_never_exceeds_the_torque_limits(sup):
    """For 1000 random huge commands, positions and velocities the output is finite and limited."""
    rng = np.random.default_rng(0)
    for _ in range(1000):
        q = rng.uniform(ROBOT.q_min - 0.3, ROBOT.q_max + 0.3)
        qd = rng.normal(0.0, 4.0, N)
        tau = rng.normal(0.0, 1e6, N) * rng.choice([1e-6, 1.0], N)
        if rng.random() < 0.5:
            sup.teach()
        sup.check(0.0, q, qd, None)
        out = sup.command(0.0, q, qd, tau)
        assert np.all(np.isfinite(out)) and np.all(np.abs(out) <= LIMIT)
        sup.reset()


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize(("reading", "kind"), [(0, "position"), (1, "velocity"), (2, "torque")])
@pytest.mark.parametrize("joint", [0, 3, 6])
def test_non_finite_reading_latches_fault_naming_the_joint(sup, value, reading, kind, joint):
    """A NaN/Inf in q, q̇ or τ_measured faults in the same call, naming the joint and the value."""
    sample = [MID.copy(), np.zeros(N), np.zeros(N)]
    sample[reading][joint] = value
    assert not sup.check(1.0, *sample)
    assert sup.state is SupervisorState.FAULT
    assert sup.fault_reason == f"joint {joint + 1} {kind} reading {value}"
    assert kinds(sup, "fault") == [sup.fault_reason]


@pytest.mark.parametrize(
    ("reading", "kind", "value"),
    [
        (0, "position", ROBOT.q_max[4] + 0.11),
        (0, "position", ROBOT.q_min[4] - 0.11),
        (1, "velocity", -2.01 * ROBOT.velocity_limits[4]),
        (2, "torque", 1.51 * LIMIT[4]),
    ],
)
def test_out_of_range_reading_latches_fault(sup, reading, kind, value):
    """A reading beyond its margin faults in the same call, naming joint 5 and the value."""
    sample = [MID.copy(), np.zeros(N), np.zeros(N)]
    sample[reading][4] = value
    assert not sup.check(1.0, *sample)
    assert sup.fault_reason.startswith(f"joint 5 {kind} reading {value:.4g}")


def test_readings_just_inside_the_margins_are_good(sup):
    """Positions, velocities and torques just inside their margins pass the check."""
    q = ROBOT.q_max + 0.099
    assert sup.check(0.0, q, 1.99 * ROBOT.velocity_limits, -1.49 * LIMIT)
    assert sup.state is SupervisorState.HOLDING


def test_a_reading_that_wraps_around_within_its_range_is_a_fault(sup):
    """Joint 5 read 2π further on within its range: a fault naming the jump, that sample.

    Before, it was taken (a review: recorded, and the replay planned a full turn).
    """
    q = MID.copy()
    q[4] = 1.5  # [rad]: 2π less is within its ±5.06 rad
    assert sup.check(0.0, q, np.zeros(N))
    wrapped = q.copy()
    wrapped[4] -= 2.0 * np.pi
    assert ROBOT.q_min[4] < wrapped[4]  # still within its range
    assert not sup.check(DT, wrapped, np.zeros(N))
    assert sup.fault_reason.startswith("joint 5's reading jumped -6.283 rad in 4 ms")


def test_steps_a_joint_can_take_are_no_jump(sup):
    """Twice the speed limit for a period, and the speed limit across a 0.24 s gap, pass."""
    q = MID.copy()
    assert sup.check(0.0, q, np.zeros(N))
    q = q + 1.99 * ROBOT.velocity_limits * DT
    assert sup.check(DT, q, np.zeros(N))
    q = q - ROBOT.velocity_limits * 0.24
    assert sup.check(DT + 0.24, q, np.zeros(N))
    assert sup.state is SupervisorState.HOLDING


def test_velocities_of_the_other_sign_are_a_fault_once_a_joint_has_moved(sup):
    """Joint 2 moving at 0.5 rad/s, its velocity read with the other sign: a fault naming it.

    Before, nothing compared the velocity with the position's change (a review).
    """
    q, qd = MID.copy(), np.zeros(N)
    qd[1] = 0.5  # [rad/s]
    for k in range(60):  # 0.12 rad in 0.24 s
        if not sup.check(k * DT, q + qd * k * DT, -qd):
            break
    assert sup.fault_reason.startswith("joint 2's velocity reading integrates to -1×")
    assert VELOCITY_MOVE <= k * DT * 0.5 < VELOCITY_MOVE + 0.01  # [rad]: once it has moved


def test_velocities_that_lag_their_position_are_no_fault(sup):
    """A velocity 50 ms late on a 1.5 rad/s sinusoid: its integral lags, within the ratio."""
    t = np.arange(500) * DT
    for k, time in enumerate(t):
        q, qd = MID.copy(), np.zeros(N)
        q[0] += 0.3 * np.sin(5.0 * time)
        qd[0] = 1.5 * np.cos(5.0 * (time - 0.05))
        assert sup.check(time, q, qd), (k, sup.fault_reason)


def test_degrees_for_radians_are_named(sup):
    """A velocity in degrees per second beyond the range: the fault says degrees."""
    qd = np.zeros(N)
    qd[2] = np.rad2deg(4.0)  # 4 rad/s in degrees per second
    assert not sup.check(0.0, MID, qd)
    hint = "(in degrees per second? converted, every joint's reading fits)"
    assert sup.fault_reason.endswith(hint)


def test_the_safe_stop_holds_the_sound_joints_where_they_read(sup, dyn):
    """Joint 1 reads 2π off (out of range) while a hand moves joint 2: the hold follows joint 2.

    Before, the whole pose of the last good sample was held: a Panda pulled on after such a
    fault fell 2.3 rad at up to 17 rad/s under a gravity hold for a pose it had left.
    """
    q = MID.copy()
    assert sup.check(0.0, q, np.zeros(N))
    moved = q.copy()
    moved[1] += 0.4  # the shoulder, pulled on
    wrapped = moved.copy()
    wrapped[0] += 2.0 * np.pi  # beyond its range
    assert not sup.check(DT, wrapped, np.zeros(N))
    periods = round(sup.parameters.safe_stop_damping_time / DT)
    stop = [sup.command(DT * (2 + k), wrapped, np.zeros(N), np.zeros(N))
            for k in range(periods + 1)]  # fmt: skip
    np.testing.assert_allclose(stop[-1], dyn.gravity(moved), atol=1e-9)


def test_frozen_encoder_faults_after_exactly_stale_periods(dyn):
    """Joint 4 bit-identical for stale_periods samples faults on that sample, not before."""
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=10))
    rng = np.random.default_rng(1)
    for k in range(10):
        q, qd = MID.copy(), rng.normal(0.0, 1e-4, N)
        qd[3] = 0.0123
        assert sup.check(k * DT, q, qd) == (k < 9)
    assert sup.fault_reason == (
        "joint 4 encoder frozen: q and qd identical for 10 samples, qd above 0.01 rad/s"
    )


def test_noisy_samples_at_rest_never_look_frozen(sup):
    """A still arm (same quantised q) with noisy velocity readings never faults."""
    rng = np.random.default_rng(2)
    q = np.round(MID / 1e-4) * 1e-4
    for k in range(1000):
        assert sup.check(k * DT, q, rng.normal(0.0, 1e-4, N), np.zeros(N))


def test_frozen_counter_restarts_on_reset(dyn):
    """After reset() a frozen encoder needs stale_periods new samples to fault again."""
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=5))
    moving = np.full(N, 0.02)  # the velocity readings say every joint moves
    results = [sup.check(k * DT, MID, moving) for k in range(5)]
    sup.reset()
    results += [sup.check(k * DT, MID, moving) for k in range(5)]
    assert results == [True] * 4 + [False] + [True] * 4 + [False]


def test_an_arm_at_rest_repeating_its_readings_exactly_never_faults(dyn):
    """A real arm at rest repeats q and q̇ bit for bit; its torque readings stay noisy.

    What the check prevents (before, (q, q̇) of one joint repeated 25 times faulted): a
    UR10e standing still faults within 0.25 s (the real logs, below).
    """
    sup = SafetySupervisor(dyn, DT)
    rng = np.random.default_rng(3)
    still = np.full(N, 1e-4)  # a resting joint's velocity reading, repeated
    for k in range(1000):
        assert sup.check(k * DT, MID, still, rng.normal(0.0, 0.01, N))
    for k in range(1000, 2000):  # and without a torque measurement
        assert sup.check(k * DT, MID, still)


def test_a_stale_sample_faults_after_exactly_stale_periods(dyn):
    """q, q̇ and τ of every joint repeated stale_periods times: stale data, safe stop."""
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=10))
    tau = np.random.default_rng(4).normal(0.0, 0.01, N)
    for k in range(10):
        assert sup.check(k * DT, MID, np.zeros(N), tau) == (k < 9)
    assert sup.fault_reason == ("sensor data stale: q, qd and torque of every joint identical "
                                "for 10 samples")  # fmt: skip


def test_a_whole_sample_counts_only_with_torques_each_time(dyn):
    """τ given, then none, then given again: the count restarts; without τ it never counts.

    A sample without a torque measurement cannot be stale as a whole, so a repeated τ
    around it is compared with nothing; reset() restarts the whole-sample count too.
    """
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=3))
    tau, still = np.full(N, 0.1), np.zeros(N)
    pattern = [tau, tau, None, tau, tau, None, None, None, None]
    assert all(sup.check(k * DT, MID, still, t) for k, t in enumerate(pattern))
    assert [sup.check(t, MID, still, tau) for t in (0.1, 0.2, 0.3)] == [True, True, False]
    sup.reset()  # the whole-sample count restarts too
    assert [sup.check(t, MID, still, tau) for t in (0.4, 0.5, 0.6)] == [True, True, False]


def _live_then_frozen(sup: SafetySupervisor, periods: int) -> tuple[np.ndarray, int]:
    """Live torque readings for ``periods``, each the command sent the period before.

    Returns the last reading (to be repeated from now on) and the next period's number.
    """
    tau, zeros = np.zeros(N), np.zeros(N)
    for k in range(periods):
        assert sup.check(k * DT, MID, zeros, tau)
        tau = sup.command(k * DT, MID, zeros, np.full(N, 0.01 * k))
    return tau, periods


def test_a_noise_free_torque_at_rest_repeats_with_its_command_and_is_not_stale(dyn):
    """A reading that holds the command sent, both steady: the sample repeats bit for bit.

    What it prevents: a passive arm at rest whose torque reading has no noise (a
    simulator's, a driver that reports the torque it was sent) faulted "sensor data
    stale" 2.1 s into its rest, once its dither parked and its command stopped changing.
    """
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=10))
    tau, zeros = np.zeros(N), np.zeros(N)
    for k in range(500):
        assert sup.check(k * DT, MID, zeros, tau), sup.fault_reason
        tau = sup.command(k * DT, MID, zeros, np.full(N, 0.5))


def test_a_repeated_sample_while_the_commands_change_is_stale_after_stale_periods(dyn):
    """Live readings, then the same one repeated while every command differs: stale."""
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=12))
    frozen, start = _live_then_frozen(sup, 20)
    results = []
    for k in range(start, start + 12):
        results.append(sup.check(k * DT, MID, np.zeros(N), frozen))
        sup.command(k * DT, MID, np.zeros(N), np.full(N, 0.1 * (k % 2)))
    assert results == [True] * 11 + [False]
    assert sup.fault_reason.startswith("sensor data stale")


def test_a_changed_command_that_the_repeated_reading_never_shows_is_stale(dyn):
    """Steady for 100 periods, then one new command: stale once it is MEASUREMENT_LAG old.

    A reading may hold a command up to :data:`MEASUREMENT_LAG` periods late; one that
    has not followed it after that is not a live reading.
    """
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=10))
    frozen, start = _live_then_frozen(sup, 20)
    steady = np.full(N, 0.19)
    for k in range(start, start + 100):
        assert sup.check(k * DT, MID, np.zeros(N), frozen)
        sup.command(k * DT, MID, np.zeros(N), steady)
    results = []
    for k in range(start + 100, start + 102 + MEASUREMENT_LAG):  # the new command from here
        results.append(sup.check(k * DT, MID, np.zeros(N), frozen))
        sup.command(k * DT, MID, np.zeros(N), steady + 0.05)
    assert results == [True] * (MEASUREMENT_LAG + 1) + [False]


def test_a_reading_that_follows_a_changed_command_within_the_lag_is_live(dyn):
    """The same, but the reading follows the new command two periods late: no fault."""
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=10))
    frozen, start = _live_then_frozen(sup, 20)
    for k in range(start, start + 100):
        assert sup.check(k * DT, MID, np.zeros(N), frozen)
        sup.command(k * DT, MID, np.zeros(N), np.full(N, 0.19))
    new = np.full(N, 0.3)
    sent = []  # the commands sent from now on, each read back two periods late
    for k in range(start + 100, start + 200):
        reading = frozen if len(sent) < 2 else sent[-2]
        assert sup.check(k * DT, MID, np.zeros(N), reading), sup.fault_reason
        sent.append(sup.command(k * DT, MID, np.zeros(N), new))


def test_the_measurement_lag_is_the_longest_delay_the_controller_looks_for():
    """The safety layer states the bound itself (it imports nothing from control)."""
    from leadthrough.control.interface_delay import LONGEST

    assert MEASUREMENT_LAG == LONGEST


@pytest.mark.parametrize("compiled", [True, False])
def test_the_compiled_check_and_the_numpy_reference_agree_on_stale_samples(dyn, compiled,
                                                                          monkeypatch):  # fmt: skip
    """A whole sample repeated faults on the same sample through either path, torques read."""
    monkeypatch.setattr(SafetySupervisor, "compiled", compiled)
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=4))
    tau = np.full(N, 0.2)
    assert [sup.check(k * DT, MID, np.zeros(N), tau) for k in range(4)] == [True] * 3 + [False]
    assert sup.fault_reason.startswith("sensor data stale")


@needs_realdata
@pytest.mark.parametrize("name", ["validation/ur-20_01_17-p1.csv",
                                  "jointwise/ur-20_01_22-joint_1.csv"])  # fmt: skip
def test_a_real_ur10e_at_rest_and_moving_one_joint_never_faults(name):
    """Its logs streamed through the controller: no fault (per joint (q, q̇) faulted at 0.25 s).

    A static hold, and a run that moves joint 1 while the others rest for seconds with
    their readings repeated exactly (joint 2 for up to 5.6 s).
    """
    import warnings

    robot = lt.robots.ur10e()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the log reader's notes on this run: not tested here
        log = lt.read_log(REALDATA / "ur10e" / name, robot)
    controller = lt.LeadThrough(robot, mode="passive", dt=log.median_period)
    old_rule = FrozenEncoders(robot.n_joints, 25, speed=-1.0)  # every repeat counted
    faulted_before = None
    for k in range(log.n_samples):
        controller.step(lt.JointState(float(log.t[k]), log.q[k], log.qd[k], log.tau[k]))
        assert controller.state is not SupervisorState.FAULT, controller.supervisor.fault_reason
        if faulted_before is None and old_rule.update(log.q[k], log.qd[k]) is not None:
            faulted_before = log.t[k] - log.t[0]
    assert faulted_before is not None and faulted_before < 0.3


def test_stale_periods_zero_turns_the_check_off(dyn):
    """With stale_periods = 0, identical samples (a noiseless mock) never fault."""
    sup = SafetySupervisor(dyn, DT, SafetyParameters(stale_periods=0))
    assert all(sup.check(k * DT, MID, np.zeros(N)) for k in range(100))


@pytest.mark.parametrize(("name", "length"), [("q", 6), ("qd", 8), ("tau_measured", 1)])
def test_wrong_shape_is_a_fault_with_a_clear_reason(sup, name, length):
    """A reading of the wrong length faults, saying the shape expected."""
    sample = {"q": MID, "qd": np.zeros(N), "tau_measured": np.zeros(N), name: np.zeros(length)}
    assert not sup.check(0.0, **sample)
    assert f"has shape ({length},), expected ({N},)" in sup.fault_reason


def test_garbage_and_internal_errors_never_escape(sup, dyn, monkeypatch):
    """Unconvertible input or a failing model is a fault and a finite torque, not an exception."""
    assert not sup.check(0.0, "not a position", None, None)
    assert sup.fault_reason.startswith("sensor check failed: ValueError")
    sup.reset()
    monkeypatch.setattr(dyn, "snapshot", lambda q, qd: 1 / 0)
    out = sup.command(0.0, MID, np.zeros(N), np.zeros(N))
    assert sup.fault_reason.startswith("command failed: ZeroDivisionError: division by zero")
    assert "(at safety/supervisor.py:" in sup.fault_reason  # where, inside the package
    assert np.all(np.isfinite(out)) and np.all(np.abs(out) <= LIMIT)


def test_nan_command_faults_and_output_is_the_safe_stop(sup, dyn):
    """A NaN in the desired torque faults in the same period, with a finite damped gravity hold."""
    qd = np.full(N, 0.1)
    assert sup.check(2.0, MID, qd, None)
    tau = np.zeros(N)
    tau[2] = np.nan
    out = sup.command(2.0, MID, qd, tau)
    assert sup.fault_reason == "non-finite command on joint 3"
    expected = dyn.gravity(MID) - np.diag(dyn.mass(MID)) / 0.05 * qd
    np.testing.assert_allclose(out, np.clip(expected, -LIMIT, LIMIT))


def test_safe_stop_is_damped_then_pure_gravity(sup, dyn):
    """The safe stop is G(q_good) − D q̇ for safe_stop_damping_time, then G(q_good) alone."""
    q_good, qd = MID + 0.05, np.array([0.2, -0.1, 0.3, 0.0, -0.2, 0.1, 0.05])
    assert sup.check(0.0, q_good, qd)
    assert not sup.check(DT, q_good, np.full(N, np.nan))
    damping = np.diag(dyn.mass(q_good)) / sup.parameters.braking_time
    tau = np.full(N, 1.0)
    periods = round(sup.parameters.safe_stop_damping_time / DT)  # of the stop, 0.5 s
    stop = [sup.command(DT * (2 + k), MID, qd, tau) for k in range(periods + 1)]
    damped = np.clip(dyn.gravity(q_good) - damping * qd, -LIMIT, LIMIT)
    np.testing.assert_allclose(stop[:periods], np.tile(damped, (periods, 1)))
    np.testing.assert_allclose(stop[periods], dyn.gravity(q_good))
    sup.reset()
    sup.check(0.0, q_good, qd)
    sup.command(0.0, q_good, qd, np.full(N, np.inf))
    np.testing.assert_allclose(
        sup.command(0.0, q_good, np.full(N, np.nan), tau), dyn.gravity(q_good)
    )


@pytest.mark.parametrize("when", ["a stamp from the past", "before the first sample"])
def test_the_damped_stop_counts_its_own_periods_not_a_faulty_clock(sup, dyn, when):
    """A fault on a stamp 10 s back, or latched before any sample on a Unix clock: damped.

    Before, the damped phase counted from the fault's stamp: a stamp 10 s back left the
    stop undamped from its second period (the arm moving at 0.3 rad/s travelled 36 mrad,
    22 with the damping), and a stop before the first sample (Ctrl-C in the warm-up)
    counted from t = 0, undamped at once on a robot whose clock reads 1.7e9 s.
    """
    qd, start = np.full(N, 0.3), 1.7e9
    if when == "a stamp from the past":
        for k in range(3):
            assert sup.check(start + k * DT, MID, qd)
        assert not sup.check(start - 10.0, MID, qd)
    else:
        sup.stop("interrupted by the operator (Ctrl-C)")
    damping = np.diag(dyn.mass(MID)) / sup.parameters.braking_time
    damped = np.clip(dyn.gravity(MID) - damping * qd, -LIMIT, LIMIT)
    for k in range(3, 10):  # the robot's clock goes on as before
        sup.check(start + k * DT, MID, qd)
        np.testing.assert_allclose(sup.command(start + k * DT, MID, qd, np.zeros(N)), damped)


@pytest.mark.parametrize("rate", [0.0, -1.0])
def test_a_clock_that_stops_or_runs_backwards_is_a_fault(sup, rate):
    """Stamps that repeat, or go back 4 ms a period: a fault once max_time_gap has passed.

    Each stamp compared with the one before passed: a controller fed a stopped clock
    calibrated for good, the arm held by the calibration's first reference, no event.
    """
    gap = sup.parameters.max_time_gap
    periods = round(gap / DT)
    for k in range(periods + 2):
        good = sup.check(5.0 + rate * k * DT, MID, np.zeros(N))
        if not good:
            break
    assert periods - 2 <= k <= periods + 1
    assert sup.state is SupervisorState.FAULT
    reason = sup.fault_reason
    assert "the robot's clock stopped or runs backwards" in reason or "stepped back" in reason


def test_a_coarse_clock_that_repeats_stamps_is_no_fault(sup):
    """A clock with 10 ms resolution at 250 Hz repeats stamps 2–3 times: taken as it is."""
    for k in range(200):
        assert sup.check(0.01 * math.floor(k * DT / 0.01), MID, np.zeros(N))


def test_the_safe_stop_holds_with_the_gravity_the_calibration_measured(sup, dyn):
    """correct_gravity(scale, offset): the hold is scale · G(q) + offset, as the controller's."""
    scale, offset = np.full(N, 0.9), np.linspace(-0.2, 0.2, N)
    sup.correct_gravity(scale, offset)
    assert sup.check(0.0, MID, np.zeros(N))
    sup.stop("test")
    held = [sup.command(DT * (1 + k), MID, np.zeros(N), np.zeros(N)) for k in range(200)]
    expected = np.clip(scale * dyn.gravity(MID) + offset, -LIMIT, LIMIT)
    np.testing.assert_allclose(held[0], expected)
    np.testing.assert_allclose(held[-1], expected)


def test_fault_stays_latched_until_reset(sup):
    """After a fault, good samples, mode changes and commands keep FAULT until reset()."""
    sup.check(0.0, MID, np.full(N, np.nan))
    reason = sup.fault_reason
    sup.teach()
    for k in range(50):
        assert not sup.check(k * DT, MID, np.zeros(N) + k * 1e-5)
        assert not np.allclose(sup.command(k * DT, MID, np.zeros(N), np.ones(N)), np.ones(N))
    sup.check(1.0, MID, np.full(N, np.inf))
    assert sup.state is SupervisorState.FAULT and sup.fault_reason == reason
    assert len(kinds(sup, "fault")) == 1 and not kinds(sup, "mode")
    sup.reset()
    assert sup.state is SupervisorState.HOLDING and sup.fault_reason is None
    assert sup.check(2.0, MID, np.full(N, 1e-3))
    np.testing.assert_allclose(sup.command(2.0, MID, np.full(N, 1e-3), np.ones(N)), np.ones(N))
    assert [event.kind for event in sup.events] == ["fault", "reset"]


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_joint_braking_opposes_velocity_above_the_limit_only(sup, dyn, sign):
    """Above its limit a joint gets G − M_ii(|q̇|−limit)/T sign(q̇), not the command."""
    tau = np.array([1.0, -2.0, 0.5, 0.0, 0.3, -0.1, 0.2])
    below = sign * 0.99 * ROBOT.velocity_limits
    np.testing.assert_allclose(sup.command(0.0, MID, below, tau), tau)
    qd = below.copy()
    qd[5] = sign * 1.02 * ROBOT.velocity_limits[5]
    out = sup.command(0.0, MID, qd, tau)
    brake = dyn.mass(MID)[5, 5] * 0.02 * ROBOT.velocity_limits[5] / 0.05
    gravity = dyn.gravity(MID)[5]
    assert np.sign(out[5] - gravity) == -sign
    expected = tau.copy()
    expected[5] = gravity - sign * brake
    np.testing.assert_allclose(out, expected, atol=1e-12)


def test_tool_speed_braking_only_while_teaching(sup, dyn):
    """A 0.5 m/s tool is braked by −(1 − v_lim/‖v‖) M q̇ / T while teaching, not while holding."""
    qd = tool_velocity(dyn, MID, 0.5)
    tau = np.zeros(N)
    np.testing.assert_allclose(sup.command(0.0, MID, qd, tau), tau)
    sup.teach()
    expected = dyn.gravity(MID) - (1.0 - 0.25 / 0.5) * dyn.mass(MID) @ qd / 0.05
    np.testing.assert_allclose(sup.command(0.0, MID, qd, tau), np.clip(expected, -LIMIT, LIMIT))
    assert sup.max_tool_speed == pytest.approx(0.5)
    np.testing.assert_allclose(sup.command(0.0, MID, tool_velocity(dyn, MID, 0.24), tau), tau)


def test_tool_braking_decelerates_the_tool(sup, dyn):
    """With M q̈ = τ_brake alone, d‖v‖/dt < 0: v·(J M⁻¹ τ_brake) < 0 at random states."""
    rng = np.random.default_rng(3)
    sup.teach()
    for _ in range(50):
        q = rng.uniform(ROBOT.q_min + 0.2, ROBOT.q_max - 0.2)
        qd = rng.normal(0.0, 1.0, N)
        jv = dyn.jacobian(q)[:3]
        qd *= rng.uniform(0.3, 0.6) / np.linalg.norm(jv @ qd)
        qd = np.clip(qd, -0.99 * ROBOT.velocity_limits, 0.99 * ROBOT.velocity_limits)
        brake = sup.command(0.0, q, qd, np.zeros(N)) - dyn.gravity(q)  # gravity held
        v = jv @ qd
        assert np.linalg.norm(v) <= 0.25 or v @ (jv @ np.linalg.solve(dyn.mass(q), brake)) < 0.0


@pytest.mark.parametrize("side", ["lower", "upper"])
def test_wall_pushes_away_and_grows_with_penetration(sup, dyn, side):
    """Inside the margin the wall pushes away from the limit, growing to fraction×limit at it."""
    away = 1.0 if side == "lower" else -1.0
    hard = ROBOT.q_min[3] if side == "lower" else ROBOT.q_max[3]
    torques = []
    for depth in [0.0, 0.02, 0.05, 0.1]:
        q = MID.copy()
        q[3] = hard + away * (0.1 - depth)
        torques.append(sup.command(0.0, q, np.zeros(N), np.zeros(N))[3] * away)
    assert torques[0] == 0.0 and np.all(np.diff(torques) > 0.0)
    assert torques[-1] == pytest.approx(0.5 * LIMIT[3])
    qd_out, qd_in = np.zeros(N), np.zeros(N)
    qd_out[3], qd_in[3] = 0.5 * away, -0.5 * away
    pushing = sup.command(0.0, q, qd_out, np.zeros(N))[3] * away
    damped = sup.command(0.0, q, qd_in, np.zeros(N))[3] * away
    assert pushing == pytest.approx(torques[-1])
    assert damped == pytest.approx(torques[-1] + dyn.mass(q)[3, 3] / 0.05 * 0.5)


def test_record_cycle_counts_overruns(sup):
    """Every cycle longer than dt is counted; one event per run of consecutive overruns."""
    for k, duration in enumerate([0.003, 0.005, 0.006, 0.001, 0.0041, np.nan, 0.004]):
        sup.record_cycle(k * DT, duration)
    assert sup.overruns == 4
    assert len(kinds(sup, "overrun")) == 2
    sup.record_cycle(8 * DT, 5.2 * DT)  # five ticks pass before its command: five missed
    assert sup.overruns == 9 and len(kinds(sup, "overrun")) == 3


def test_events_are_logged_once_per_episode(sup, dyn):
    """Walls, joint and tool braking and mode changes log when they start, not every period."""
    in_wall = MID.copy()
    in_wall[1] = ROBOT.q_max[1] - 0.05
    fast = np.zeros(N)
    fast[0] = 1.1 * ROBOT.velocity_limits[0]
    sup.teach()
    sup.teach()
    for _ in range(2):
        for k in range(20):
            sup.command(k * DT, in_wall, fast, np.zeros(N))
        for k in range(20):
            sup.command(k * DT, MID, tool_velocity(dyn, MID, 0.4), np.zeros(N))
        sup.command(1.0, MID, np.zeros(N), np.zeros(N))
    assert len(kinds(sup, "soft_limit")) == 2
    assert any("joint 2 entered the upper" in event.detail for event in sup.events)
    assert len(kinds(sup, "joint_speed")) == 2 and len(kinds(sup, "tool_speed")) == 2
    assert kinds(sup, "mode") == ["mode teaching"]
    sup.hold()
    sup.hold()
    assert kinds(sup, "mode") == ["mode teaching", "mode holding"]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("tool_speed_limit", 0.0),
        ("joint_speed_fraction", 1.5),
        ("braking_time", -0.1),
        ("soft_limit_margin", np.nan),
        ("wall_torque_fraction", 0.0),
        ("wall_damping_time", 0.0),
        ("stale_periods", 1),
        ("stale_periods", 2.5),
        ("stale_periods", True),
        ("stale_speed", -0.01),
        ("stale_speed", 0.0),
        ("stale_speed", np.nan),
        ("torque_reading_margin", 0.9),
        ("velocity_reading_margin", 0.5),
        ("position_reading_margin", -0.01),
        ("safe_stop_damping_time", "long"),
    ],
)
def test_invalid_parameters_are_rejected(field, value):
    """Each invalid setting raises a ParameterError naming the field."""
    with pytest.raises(ParameterError) as error:
        SafetyParameters(**{field: value})
    assert error.value.parameter == field


def test_invalid_period_is_rejected(dyn):
    """A non-positive control period raises a ParameterError naming dt."""
    with pytest.raises(ParameterError, match="dt"):
        SafetySupervisor(dyn, dt=0.0)


def test_a_period_longer_than_the_largest_time_gap_is_refused_at_construction(dyn):
    """A 0.5 s period > max_time_gap 0.25 s: refused naming both; with no max_time_gap, taken."""
    with pytest.raises(ParameterError, match=r"dt: 0\.5 s is longer than .*max_time_gap 0\.25 s"):
        lt.LeadThrough(ROBOT, dt=0.5)
    assert SafetySupervisor(dyn, 0.5, SafetyParameters(max_time_gap=None)).dt == 0.5


def test_use_model_keeps_robot_dynamics_and_bounds_together(sup):
    """After a payload the supervisor's robot is its model's; the safe stop holds the payload."""
    loaded = lt.Dynamics(ROBOT.with_payload(1.5))
    sup.use_model(loaded)
    assert sup.robot is sup.dynamics.robot is loaded.robot
    assert sup.check(0.0, MID, np.zeros(N))
    sup.stop("test")
    hold = sup.command(1.0, MID, np.zeros(N), np.zeros(N))  # past the damped phase
    np.testing.assert_allclose(hold, np.clip(loaded.gravity(MID), -LIMIT, LIMIT), atol=1e-12)
    with pytest.raises(ParameterError, match="joints"):
        six = dataclasses.replace(ROBOT, joints=ROBOT.joints[:6], home_position=None)
        sup.use_model(lt.Dynamics(six))


def test_a_failed_safe_stop_is_an_event(sup, dyn, monkeypatch):
    """A safe stop that cannot be computed sends zero torque and logs it once."""
    assert sup.check(0.0, MID, np.zeros(N))
    sup.stop("test")
    monkeypatch.setattr(dyn, "gravity", lambda q: 1 / 0)
    for k in range(3):
        out = sup.command(k * DT, MID, np.zeros(N), np.zeros(N))
        np.testing.assert_array_equal(out, 0.0)
    (detail,) = kinds(sup, "safe_stop_failed")
    assert "ZeroDivisionError" in detail


def test_the_tool_speed_limit_holds_at_the_tool_centre_point():
    """A 15 cm tool turning at 2.5 rad/s about a still flange: its tip (0.375 m/s) is braked."""
    tool = dataclasses.replace(ROBOT, tcp=lt.Placement([0.0, 0.0, 0.15]))
    q = ROBOT.home()
    flange = lt.Dynamics(ROBOT)
    axis = np.cross(flange.pose(q)[:3, 2], [0.0, 0.0, 1.0])
    twist = np.concatenate([np.zeros(3), 2.5 * axis / np.linalg.norm(axis)])
    qd = np.linalg.pinv(flange.jacobian(q)) @ twist  # flange origin still, flange turning
    assert np.linalg.norm(flange.jacobian(q)[:3] @ qd) < 1e-9
    assert np.all(np.abs(qd) < ROBOT.velocity_limits)
    bare, tipped = SafetySupervisor(flange, DT), SafetySupervisor(lt.Dynamics(tool), DT)
    for supervisor in (bare, tipped):
        supervisor.teach()
        assert supervisor.check(0.0, q, qd)
        supervisor.command(0.0, q, qd, flange.gravity(q))
    assert bare.max_tool_speed < 1e-9 and not kinds(bare, "tool_speed")
    assert tipped.max_tool_speed == pytest.approx(0.375, rel=1e-9)
    assert kinds(tipped, "tool_speed") and not kinds(tipped, "joint_speed")
