"""The measurement delay read from the data (``control.interface_delay``).

Against a drive simulated here (the measured torque is the command sent ``d`` periods
before, with a gain error, an offset and noise), and against the twin: the controller finds
the delay the plant has, whatever it was told, and keeps it where the commands tell nothing.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from as_found import told_measurement_delay
from leadthrough.control import interface_delay
from leadthrough.control.feedforward import DelayLine
from leadthrough.control.interface_delay import EVIDENCE, LONGEST, MEMORY, InterfaceDelay
from leadthrough.control.lead_through import LeadThrough
from leadthrough.friction.model import FrictionModel
from leadthrough.model import robots
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

N = 7
DT = 0.004


def _dither_like_commands(periods: int, rng: np.random.Generator) -> np.ndarray:
    """Gravity, a slow motion's torque and a ±0.3 Nm square wave every 8 periods [Nm]."""
    k = np.arange(periods)[:, None]
    gravity = rng.normal(0.0, 5.0, N)
    slow = 0.5 * np.sin(2.0 * np.pi * 0.5 * k * DT + rng.uniform(0, 2 * np.pi, N))
    square = 0.3 * np.where((k // 8) % 2 == 0, 1.0, -1.0) * rng.uniform(0.5, 1.5, N)
    return gravity + slow + square


def _drive(commands: np.ndarray, delay: int, rng: np.random.Generator) -> np.ndarray:
    """What a drive measures: the command ``delay`` periods late [Nm].

    The drive held the arm before the controller started; gain error ±10 %, offset ±0.2
    Nm, 5 mNm of noise.
    """
    held = np.vstack([np.repeat(commands[:1], delay, axis=0), commands[:-delay]])
    gain = rng.uniform(0.9, 1.1, N)
    return held * gain + rng.uniform(-0.2, 0.2, N) + rng.normal(0.0, 0.005, held.shape)


def _estimate(commands: np.ndarray, measured: np.ndarray, told: int) -> list[int]:
    """The estimator fed period by period as ``LeadThrough`` feeds it; its delay each period."""
    estimate = InterfaceDelay(N, told, DT)
    delays = []
    for command, tau in zip(commands, measured, strict=True):
        delays.append(estimate.update(tau))
        estimate.record(command)
    return delays


@pytest.mark.parametrize("delay", [1, 2, 3, 5, LONGEST])
@pytest.mark.parametrize("told", [1, 2, 4])
def test_the_delay_the_drive_has_is_found_within_a_fifth_of_a_second(delay, told):
    """From any delay told, the drive's within 50 periods, and kept."""
    rng = np.random.default_rng(10 * delay + told)
    commands = _dither_like_commands(250, rng)
    delays = _estimate(commands, _drive(commands, delay, rng), told)
    assert delays[50:] == [delay] * 200  # from 0.2 s on, and it never leaves it


def test_commands_that_do_not_change_leave_the_delay_as_told():
    """Noise alone tells no delay: every candidate scores alike."""
    rng = np.random.default_rng(7)
    commands = np.tile(rng.normal(0.0, 5.0, N), (2000, 1))
    delays = _estimate(commands, _drive(commands, 3, rng), 2)
    assert set(delays) == {2}


@pytest.mark.parametrize("scored", [1, None], ids=["decided-at-once", "default"])
def test_no_decision_before_enough_changes_are_scored(scored, monkeypatch):
    """The rule: :data:`SCORED` command changes before any decision.

    Over 40 drives of noise alone (commands that do not change), deciding from the first
    scored change takes a wrong delay on some; with the default, on none.
    """
    if scored is not None:  # the kernel's Python twin reads the module's constant
        monkeypatch.setattr(interface_delay, "_score", interface_delay._score.py_func)
        monkeypatch.setattr(interface_delay, "SCORED", scored)
    wrong = 0
    for seed in range(40):
        rng = np.random.default_rng(seed)
        commands = np.tile(rng.normal(0.0, 5.0, N), (60, 1))
        wrong += set(_estimate(commands, _drive(commands, 2, rng), 2)) != {2}
    assert (wrong > 0) if scored is not None else (wrong == 0)


def test_a_reading_that_is_not_a_number_is_skipped():
    """A NaN torque neither moves the delay nor poisons the scores after it."""
    rng = np.random.default_rng(3)
    commands = _dither_like_commands(500, rng)
    measured = _drive(commands, 3, rng)
    measured[[100, 101, 300], 2] = np.nan
    delays = _estimate(commands, measured, 3)
    assert set(delays) == {3}


def test_scored_on_the_latest_changes_a_candidate_not_yet_reached_looks_best():
    """The rule: every candidate is scored on the same, oldest, command change.

    Told one period on a drive of three, the first step of a motion after a long rest: one
    period after it, it has reached the candidate in use only, which loses; scored on the
    latest measured change against the command change ``L`` periods before, the candidates
    it has not reached yet all look as good, and one of them is taken (on the twin, a
    drive of three periods was taken for one of eight at the start of the calibration's
    motion, in scratch). Scored on the oldest change all have seen, the delay goes from
    one to three and nowhere else.
    """
    rng = np.random.default_rng(5)
    commands = np.tile(rng.normal(0.0, 5.0, N), (300, 1))
    commands[150:] += 0.5
    measured = _drive(commands, 3, rng)
    assert set(_estimate(commands, measured, 1)) == {1, 3}

    delay, scores, chosen = 1, np.zeros(LONGEST), set()
    lags = np.arange(1, LONGEST + 1)
    for k in range(LONGEST + 1, len(commands)):
        sent = commands[k - lags] - commands[k - lags - 1]  # Δc(k − L): unaligned
        error = (measured[k] - measured[k - 1]) - sent
        scores += DT / MEMORY * (np.einsum("ij,ij->i", error, error) - scores)
        best = int(np.argmin(scores))
        if scores[best] < EVIDENCE * scores[delay - 1]:
            delay = best + 1
        chosen.add(delay)
    assert chosen - {1, 3}


def test_the_delay_line_keeps_its_capacity_and_a_changed_delay():
    """``measured`` follows a delay changed up to the capacity."""
    line = DelayLine((2,), 2, capacity=5)
    for k in range(7):
        line.push((k, -k))
    np.testing.assert_array_equal(line.measured, [5, -5])
    line.delay = 4
    np.testing.assert_array_equal(line.measured, [3, -3])


@pytest.mark.parametrize("delay", [1, 2, 3])
def test_the_controller_finds_the_twins_delay_while_it_calibrates_and_rests(delay):
    """The twin measures a command ``delay + 1`` periods after it is sent; 2 is told.

    (A command reaches its motors ``delay`` periods late and is measured over the period
    after.)
    """
    robot = robots.yumi()
    controller = LeadThrough(robot, mode="active", dt=DT, calibrate=True)
    twin = DigitalTwin(robot, dataclasses.replace(TwinConfig(), delay_periods=delay))
    simulate(twin, controller, controller.calibration_time + 1.0, progress=False)
    assert controller.interface_delay.delay == delay + 1


def _resting_estimate(delay: int) -> np.ndarray:
    """RMS of τ̂_ext over the τ_C of each joint, the arm left alone and dithered [–].

    The default twin with ``delay`` periods of delay, calibrated, then 2 s at rest from
    1 s after the calibration (the dither on every joint).
    """
    robot = robots.yumi()
    controller = LeadThrough(robot, mode="active", dt=DT, calibrate=True)
    twin = DigitalTwin(robot, dataclasses.replace(TwinConfig(), delay_periods=delay))
    estimates = []

    class Recorder:
        dt, supervisor = DT, controller.supervisor

        def step(self, state):
            command = controller.step(state)
            estimates.append(np.array(controller.tau_ext_hat))
            return command

    simulate(twin, Recorder(), controller.calibration_time + 3.0, progress=False)
    resting = np.array(estimates)[round((controller.calibration_time + 1.0) / DT) :]
    return np.sqrt(np.mean(resting**2, axis=0)) / FrictionModel.from_robot(robot).coulomb


@pytest.mark.parametrize("told", [False, True], ids=["read", "told"])
def test_with_the_delay_read_a_dithered_arm_reads_as_on_the_delay_it_was_told(told, monkeypatch):
    """Nobody touching, the dither must not read as a push, whatever the interface's delay.

    Read from the data, the estimate of an arm left alone on plants with two and three
    periods of delay is the one of the plant whose delay the controller was told (one
    period, measured after two), within 1 % of each level; kept as told, the dither's
    edges read as pushes on the wrist (joint 5: 0.4 % → 2 % and 3.7 % of its level).
    """
    reference = _resting_estimate(1)
    if told:
        told_measurement_delay(monkeypatch)
    offs = [np.max(np.abs(_resting_estimate(delay) - reference)) for delay in (2, 3)]
    if told:
        assert max(offs) > 0.02
    else:
        assert max(offs) < 0.01


def test_periods_without_a_measured_torque_leave_the_delay():
    """Commands sent while nothing was measured shift no comparison (all by period)."""
    rng = np.random.default_rng(11)
    commands = _dither_like_commands(400, rng)
    measured = _drive(commands, 3, rng)
    estimate = InterfaceDelay(N, 3, DT)
    delays = []
    for k, (command, tau) in enumerate(zip(commands, measured, strict=True)):
        if k % 50 != 49:  # every 50th period brings no measured torque
            delays.append(estimate.update(tau))
        estimate.record(command)
    assert set(delays) == {3}


def _interpreted_score(estimate: InterfaceDelay, tau: np.ndarray) -> int:
    """The delay from :func:`interface_delay._score`'s Python twin, on ``estimate``'s state."""
    return interface_delay._score.py_func(
        estimate._changes, estimate._commands, estimate._scores, estimate._previous, tau,
        estimate._sent, estimate._rate, estimate.delay,
    )  # fmt: skip


def test_the_compiled_step_is_its_python_arithmetic():
    """The kernel and its Python twin, fed the same drive, keep the same scores."""
    rng = np.random.default_rng(2)
    commands = _dither_like_commands(200, rng)
    measured = _drive(commands, 4, rng)
    compiled, interpreted = InterfaceDelay(N, 2, DT), InterfaceDelay(N, 2, DT)
    for command, tau in zip(commands, measured, strict=True):
        compiled.update(tau)
        interpreted.delay = _interpreted_score(interpreted, tau)
        compiled.record(command)
        interpreted.record(command)
        assert compiled.delay == interpreted.delay
    np.testing.assert_allclose(compiled._scores, interpreted._scores, rtol=1e-12)
    assert compiled.delay == 4


@pytest.mark.parametrize(
    ("scale", "named"),
    [(1.0, False), (0.75, False), (1.3, False), (0.01, False), (-1.0, True), (-0.6, True)],
)
def test_a_measured_torque_of_the_other_sign_is_named(scale, named):
    """Only a measurement of the other sign is named, joint and slope, within 0.5 s.

    A drive's gain error passes (and so does a scale error: the motor side of a gear,
    1/100, is left to the calibration's readings). Before, a measured torque of the other
    sign was taken as it came: the observer read twice the command as a push, and active
    mode turned a YuMi 2.1 rad in 5 s, nobody touching it (a review).
    """
    rng = np.random.default_rng(5)
    commands = _dither_like_commands(125, rng)
    measured = _drive(commands, 2, rng)
    measured[:, 3] *= scale
    estimate, problems = InterfaceDelay(N, 2, DT), []
    for command, tau in zip(commands, measured, strict=True):
        estimate.update(tau)
        problems.append(estimate.gain_problem())
        estimate.record(command)
    assert (problems[-1] is not None) is named, problems[-1]
    np.testing.assert_allclose(estimate.gain[3], scale, rtol=0.15)  # the drive's gain error
    if named:
        gain = estimate.gain[3]
        assert problems[-1].startswith(f"joint 4's measured torque falls as its command rises "
                                       f"({gain:+.2f}×)")  # fmt: skip
    else:
        assert set(problems) == {None}


def test_a_command_that_barely_moves_is_not_judged():
    """Commands moving by less than the floor: the other sign goes unjudged, not misjudged.

    What this prevents: a judgement on a command whose variation the drives' ripple can
    rival (a loaded UR10e elbow's +2.5 slope with the right sign, a review).
    """
    rng = np.random.default_rng(6)
    commands = _dither_like_commands(125, rng)
    measured = -_drive(commands, 2, rng)
    floor = 10.0 * np.std(commands, axis=0)  # every command moves far less than this
    estimate = InterfaceDelay(N, 2, DT, floor=floor)
    for command, tau in zip(commands, measured, strict=True):
        estimate.update(tau)
        estimate.record(command)
    assert estimate.gain_problem() is None
    assert np.all(estimate.gain < -0.5)  # measured, not judged


def test_the_compiled_gain_is_its_python_arithmetic():
    """The gain's kernel and its Python twin, fed the same drive, keep the same moments."""
    rng = np.random.default_rng(3)
    commands = _dither_like_commands(200, rng)
    measured = _drive(commands, 2, rng)
    measured[:, 2] *= -1.0  # one joint the other way round: a decision to agree on
    compiled, interpreted = InterfaceDelay(N, 2, DT), InterfaceDelay(N, 2, DT)
    for command, tau in zip(commands, measured, strict=True):
        compiled.update(tau)
        interpreted.delay = _interpreted_score(interpreted, tau)
        joint = interface_delay._fit.py_func(
            interpreted._moments, interpreted._commands, tau, interpreted._sent,
            interpreted._rate, interpreted.delay, interpreted._judged, interpreted._floor,
            interface_delay.SURE, interface_delay.SLOPE,
        )  # fmt: skip
        assert joint == compiled._implausible
        compiled.record(command)
        interpreted.record(command)
    np.testing.assert_allclose(compiled._moments, interpreted._moments, rtol=1e-12)
    assert compiled._implausible == 2
