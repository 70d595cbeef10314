"""Start-up calibration: payload, Coulomb levels and gravity bias, measured on the twin."""

import dataclasses
import re

import numpy as np
import pytest

import leadthrough as lt
from as_found import SIX_HERTZ, six_hertz_calibration, slow_calibration_motion, unchecked_push
from leadthrough.control.calibration import (
    Calibration,
    CalibrationParameters,
    CalibrationRun,
    calibration_gains,
    gravity_share,
    implausible_friction,
)
from leadthrough.control.calibration import run as calibration_run
from leadthrough.control.lead_through import LeadThrough
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.control.tracking import loop_damping
from leadthrough.estimation.momentum_balance import MomentumBalance, stretch_readings
from leadthrough.friction.model import FrictionModel
from leadthrough.safety.supervisor import SupervisorState
from leadthrough.twin.mjcf import Payload
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.operator import Hand
from leadthrough.twin.paths import MinimumJerk
from leadthrough.twin.plants import PlantRanges, sample_plant
from leadthrough.twin.runner import simulate
from leadthrough.twin.sensors import SensorModel
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

MASSES_OFF = ModelError(mass_error=0.05, com_error=0.005)


@pytest.fixture(scope="module")
def yumi() -> lt.RobotDescription:
    """The shipped YuMi description."""
    return lt.robots.yumi()


def calibrated(yumi, config, friction=None, seconds=1.5):
    """A controller that calibrated on a twin nobody touches, and the run."""
    twin = DigitalTwin(yumi, config)
    controller = LeadThrough(yumi, friction=friction, calibrate=True)
    return controller, twin, simulate(twin, controller, seconds)


def test_gravity_error_and_friction_levels_match_the_truth(yumi, identified_friction):
    """Friction 20 % below the identified model: both errors measured, nothing assumed."""
    config = TwinConfig(model_error=dataclasses.replace(MASSES_OFF, friction_scale=0.8), seed=7)
    controller, twin, _ = calibrated(yumi, config, identified_friction)
    result = controller.calibration
    assert result.accepted and not controller.calibrating
    truth = lt.Dynamics(yumi).gravity(result.pose) - lt.Dynamics(twin.true_robot).gravity(
        result.pose
    )
    np.testing.assert_allclose(result.gravity_error, truth, atol=0.03)
    np.testing.assert_allclose(result.friction_scale[:4], 0.8, atol=0.05)  # the heavy joints
    np.testing.assert_allclose(controller.friction.coulomb,
                               identified_friction.coulomb * result.friction_scale)  # fmt: skip


def test_unknown_payload_is_found_and_held(yumi):
    """An unmodelled 0.5 kg payload: weighed at start-up, the arm left alone stays put."""
    config = TwinConfig(model_error=dataclasses.replace(MASSES_OFF, payload=Payload(0.5)), seed=1)
    controller, _twin, sim = calibrated(yumi, config, seconds=6.0)
    assert controller.calibration.payload == pytest.approx(0.5, rel=0.1)
    logged = [e.detail for e in controller.supervisor.events if e.kind == "calibration"]
    assert len(logged) == 1 and logged[0].startswith("calibrated: payload 0.")
    settled = sim.t > 1.5
    assert np.max(np.abs(sim.q_true[settled] - sim.q_true[settled][0])) < 1e-3
    # the same arm without the calibration sags under the payload
    blind = LeadThrough(yumi)
    sagging = simulate(DigitalTwin(yumi, config), blind, 6.0)
    assert np.max(np.abs(sagging.q_true[-1] - sagging.q_true[0])) > 0.05


@pytest.mark.parametrize("name", ["yumi", "panda", "ur10e"])
def test_the_moment_regressor_is_the_gravity_of_a_payload_off_the_flange(name):
    """``m Y + Y_h m c`` equals G of the arm carrying m at c minus G without it (Pinocchio)."""
    robot = lt.robots.load(name)
    run = CalibrationRun(lt.Dynamics(robot), FrictionModel.from_robot(robot), robot.home())
    q = robot.home() + np.random.default_rng(2).uniform(-0.6, 0.6, robot.n_joints)
    mass, com = 1.3, np.array([0.04, -0.07, 0.11])
    carried = lt.Dynamics(robot.with_payload(mass, com)).gravity(q) - lt.Dynamics(robot).gravity(q)
    predicted = mass * run.payload_regressor(q) + run.moment_regressor(q) @ (mass * com)
    np.testing.assert_allclose(predicted, carried, atol=1e-9)


def test_a_payload_off_the_flange_is_weighed_with_its_moment(yumi):
    """0.5 kg 6 cm to the side of the flange: its mass, its centre across gravity, and G away.

    Before, a point mass at the flange took the moment's torques: 0.84 kg, and 0.54 Nm of
    gravity error half a radian from the pose on the joint the moment loads. The centre's
    component along gravity at the pose (here flange z, 2 cm) turns no joint there: 0.
    """
    tool = Payload(0.5, (0.06, 0.0, 0.02))
    config = TwinConfig(model_error=ModelError(payload=tool), seed=1)
    controller, _twin, _ = calibrated(yumi, config, seconds=1.5)
    result = controller.calibration
    assert result.accepted and result.payload == pytest.approx(0.5, rel=0.1)
    assert result.payload_com is not None
    np.testing.assert_allclose(result.payload_com, [0.06, 0.0, 0.0], atol=0.01)
    away = result.pose + np.array([0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0])  # the wrist turned
    model = lt.Dynamics(result.robot(yumi)).gravity(away)
    truth = lt.Dynamics(yumi.with_payload(tool.mass, tool.com)).gravity(away)
    assert np.max(np.abs(model - truth)) < 0.1  # [Nm]: m g |c_z| = 0.098 Nm at most


def test_a_heavy_tool_the_model_lacks_is_named_when_it_sinks_the_calibration(ur10e):
    """A UR10e's 5 kg tool 10 cm out, not given: refused, and the refusal names the tool.

    The wrist sinks ~64 mrad before the tracking's integral holds it. The refusal asked
    only "was the arm touched?"; the likelier cause, and its remedy, are named now.
    """
    tool = ModelError(payload=Payload(5.0, (0.0, 0.0, 0.1)))
    controller = LeadThrough(ur10e, calibrate=True)
    simulate(DigitalTwin(ur10e, TwinConfig(model_error=tool)), controller, 0.5)
    result = controller.calibration
    assert not result.accepted
    assert re.search(r"joint 4 was \d+ mrad off the calibration motion: a payload the model "
                     r"lacks \(give it with set_payload\(mass, com\)\)", result.reason)  # fmt: skip


def test_the_payload_allowed_scales_with_the_arm(yumi):
    """Half the arm's moving mass, unless ``max_payload`` says otherwise.

    A fixed 2 kg (before) was four times the YuMi's rated payload and refused a UR10e's
    calibration with a 5 kg tool; the share accepts 2.3 kg on the YuMi and refuses 3 kg.
    """
    ur10e = lt.robots.ur10e()
    assert CalibrationParameters().payload_limit(yumi) == pytest.approx(0.5 * yumi.total_mass)
    assert CalibrationParameters().payload_limit(ur10e) > 14.0
    assert CalibrationParameters(max_payload=1.0).payload_limit(ur10e) == 1.0
    tool = ModelError(mass_error=0.05, com_error=0.005, payload=Payload(5.0, (0.0, 0.0, 0.0)))
    controller, _twin, sim = calibrated(ur10e, TwinConfig(model_error=tool, seed=1), seconds=4.0)
    assert controller.calibration.accepted
    assert controller.calibration.payload == pytest.approx(5.0, rel=0.1)
    settled = sim.t > 1.5
    assert np.max(np.abs(sim.q_true[settled] - sim.q_true[settled][0])) < 1e-3
    within = dataclasses.replace(MASSES_OFF, payload=Payload(2.3, (0.0, 0.0, 0.0)))
    controller, _twin, _sim = calibrated(yumi, TwinConfig(model_error=within, seed=1))
    assert controller.calibration.accepted  # refused by the fixed 2 kg
    assert controller.calibration.payload == pytest.approx(2.3, rel=0.1)
    heavy = dataclasses.replace(MASSES_OFF, payload=Payload(3.0, (0.0, 0.0, 0.0)))
    controller, _twin, _sim = calibrated(yumi, TwinConfig(model_error=heavy, seed=1))
    assert not controller.calibration.accepted
    assert (
        "kg allowed (max_payload): was the arm touched? A tool that heavy: give it with "
        "set_payload(mass, com), or raise max_payload" in controller.calibration.reason
    )


def test_friction_far_above_the_model_is_measured_not_refused(yumi, monkeypatch):
    """A sampled plant whose joint 3 reads 1.6× the model (level, position, drive gain).

    Measured and accepted: refused (as with a ±50 % band), the arm was guided
    uncalibrated, and released on the guiding benchmark it ran away 112 mrad. With the 6
    Hz loop it was found with: under the 4 Hz one the joint sticks too often to count as
    measured and keeps the model's level, which understates it (heavier, never unsafe).
    """
    plant = sample_plant(yumi, 11, "dry")

    def calibrated() -> Calibration:
        controller = LeadThrough(yumi, calibrate=True)
        twin = DigitalTwin(yumi, plant.config)
        simulate(twin, controller, controller.calibration_time + 0.05)
        assert controller.calibration is not None
        return controller.calibration

    default = calibrated()  # 4 Hz: accepted, joint 3 keeps the model's (lower) level
    assert default.accepted and not default.measured[2] and default.friction_scale[2] == 1.0
    six_hertz_calibration(monkeypatch)
    result = calibrated()
    assert result.accepted, result.reason
    assert result.friction_scale[2] > 1.5
    change = CalibrationParameters().max_friction_change
    assert not implausible_friction(result.friction_scale, change).any()


@pytest.mark.parametrize("slow", [False, True], ids=["sliding", "stick-slip"])
def test_the_motion_slides_above_the_stribeck_range_and_reads_the_level(yumi, slow, monkeypatch):
    """Lugre #29's joint 4 (Stribeck velocity 0.021 rad/s, stiction 1.42× Coulomb).

    At 15 mrad and 0.1 rad/s it slides, and its level comes out within 10 % of the plant's
    at the pose (half the 20 % the controller then assumes). At 5 mrad and 0.05 rad/s
    (before) it sticks and jumps at 3× the pace: read through the robot's filtered
    velocity, the edges of its jumps passed through the pace band and the level came out
    16 % high; read from the encoders' central difference, the jumps are seen as jumps,
    too few samples slide at pace, and the joint keeps its model's level.
    """
    if slow:
        slow_calibration_motion(monkeypatch)
    plant = sample_plant(yumi, 29, "lugre")
    controller = LeadThrough(yumi, calibrate=True)
    simulate(DigitalTwin(yumi, plant.config), controller, controller.calibration_time + 0.05)
    result = controller.calibration
    gain = plant.config.sensors.torque_gain[3]  # the level in commanded torque
    true = plant.config.friction.coulomb_level(result.pose)[3] / gain
    error = controller.friction.coulomb_level(result.pose)[3] / true - 1.0
    assert result.accepted
    if slow:
        assert not result.measured[3] and result.friction_scale[3] == 1.0
    else:
        assert result.measured[3] and abs(error) < 0.1


def test_a_level_nothing_measured_carries_the_unit_spread(yumi):
    """Uncalibrated every joint's friction error is ≥ 0.35; calibrated, a measured one's 0.2.

    A joint the calibration could not slide keeps 0.35; a measured one carries at most 0.2,
    less near the pose it was read at (``level_error``, tests/test_measured_level.py); the
    Coulomb compensation's ceiling uses the same errors; ``unmeasured_friction_error = 0``
    trusts the model's own, and a model given to the controller (identified on this arm)
    keeps its own. The friction margin takes each whole error.
    """
    plant = sample_plant(yumi, 1, "dry")  # stiction holds joint 3 in its calibration
    controller = LeadThrough(yumi, calibrate=True)
    np.testing.assert_allclose(controller.law.friction_error, 0.35)
    simulate(DigitalTwin(yumi, plant.config), controller, controller.calibration_time + 0.05)
    measured = controller.calibration.measured
    assert controller.calibration.accepted and not measured.all() and measured.any()
    np.testing.assert_allclose(controller.level_error.far, np.where(measured, 0.2, 0.35))
    error = controller.law.friction_error
    assert np.all(error[measured] <= 0.2) and np.all(error[~measured] == 0.35)
    np.testing.assert_array_equal(
        controller.feed_forward.friction_error, controller.law.friction_error
    )
    np.testing.assert_array_equal(controller.law.margin_error, controller.law.friction_error)
    controller.set_payload(0.1)  # a new model, the same knowledge of the friction
    np.testing.assert_allclose(controller.law.friction_error, np.where(measured, 0.2, 0.35))
    np.testing.assert_allclose(controller.level_error.far, np.where(measured, 0.2, 0.35))
    trusting = LeadThroughParameters(unmeasured_friction_error=0.0)
    np.testing.assert_allclose(LeadThrough(yumi, parameters=trusting).law.friction_error, 0.2)
    identified = dataclasses.replace(FrictionModel.from_robot(yumi), relative_error=np.full(7, 0.1))
    identified_law = LeadThrough(yumi, friction=identified).law
    np.testing.assert_allclose(identified_law.friction_error, 0.1)
    np.testing.assert_allclose(identified_law.margin_error, 0.1)


def test_a_payload_is_taken_only_where_it_stands_out_of_the_models_gravity_error(yumi):
    """Drive gains 10 % off are not a payload; a real 0.5 kg is.

    Near the YuMi's home pose a payload loads joints 1–4 much as their own gravity does:
    a plain least-squares fit reads drive gains 10 % off as a payload (on lugre #32 a
    spurious 0.20 kg put 0.57 Nm of error on joint 4 away from the pose, and the released
    arm ran 1.3 rad). Weighed by what the model may be off anyway, it is not one.
    """
    run = CalibrationRun(lt.Dynamics(yumi), FrictionModel.from_robot(yumi), yumi.home())
    per_kilogram = run.payload_regressor(run.pose)
    gravity = lt.Dynamics(yumi).gravity(run.pose)
    everywhere = np.ones(yumi.n_joints, bool)
    gains_off = -0.1 * gravity  # G_model − G_true with every drive 10 % weak
    plain = float(-per_kilogram @ gains_off) / float(per_kilogram @ per_kilogram)
    assert plain > 0.1  # what a plain fit would have put into the model
    assert run.payload(gains_off, per_kilogram, everywhere) == 0.0
    assert run.payload(-0.5 * per_kilogram, per_kilogram, everywhere) == pytest.approx(0.5)
    assert run.payload(-0.5 * per_kilogram, per_kilogram, ~everywhere) == 0.0  # none slid


def test_a_joint_read_at_pace_only_a_few_times_keeps_its_models_level(yumi):
    """A level is measured only if the joint slid at pace an eighth of the time it was driven.

    Over the whole motion joint 6 slides at pace in 4 samples each way only (between them
    it sticks): its readings are a sample of its stick-slip, whose level and gravity came
    out +20 % and 0.16 Nm off on lugre #28 (the released arm ran 0.9 rad in passive mode).
    It slid (the calibration is accepted, its gravity error read) but keeps the model's
    level and counts as not measured; joint 7, at pace a quarter of the time, is measured.
    """
    run = CalibrationRun(lt.Dynamics(yumi), FrictionModel.from_robot(yumi), yumi.home())
    p, n = run.parameters, yumi.n_joints
    times = np.arange(p.settle_time, p.duration, 0.004)
    velocity = np.zeros((len(times), n))
    seen = np.zeros((2, n))  # paced samples each way so far
    for k, t in enumerate(times):
        way = np.sign(np.sin(2 * np.pi * p.frequency * (t - p.settle_time)))  # the wave's
        qd = run._direction * way * p.speed
        if seen[int(qd[5] < 0), 5] >= 4:
            qd[5] = 0.0  # sticks
        if k % 4:
            qd[6] = 0.0
        seen += [qd > 0, qd < 0]
        velocity[k] = qd
    readings = np.where(velocity != 0.0, 0.1 + 0.05 * np.sign(velocity), np.nan)
    result = run.judge(times, velocity, readings)
    assert result.accepted, result.reason
    np.testing.assert_array_equal(result.measured, np.arange(n) != 5)
    assert result.coulomb_error[5] == 0.0 and result.friction_scale[5] == 1.0
    np.testing.assert_allclose(result.coulomb_error[result.measured], 0.05)
    np.testing.assert_allclose(result.gravity_error, 0.1)


def test_stretches_that_disagree_state_their_disagreement(yumi):
    """A level read from stretches that disagree carries their standard deviation.

    Joint 2's readings are 0.03 Nm high on three blocks of samples in five and 0.03 Nm low
    on two (the Panda's shoulder, whose tracking rings, disagrees by ±25 % of its level
    from one stretch to the next): its spread is their scatter. A median absolute deviation
    (before) put it at 0, more than half the samples sharing one value, and a level read
    10–14 % off the Panda's was stated known to the 5 % floor.
    """
    run = CalibrationRun(lt.Dynamics(yumi), FrictionModel.from_robot(yumi), yumi.home())
    p, n = run.parameters, yumi.n_joints
    times = np.arange(p.settle_time, p.duration, 0.004)
    way = np.sign(np.sin(2 * np.pi * p.frequency * (times - p.settle_time)))
    velocity = run._direction * way[:, None] * p.speed * np.ones(n)
    readings = 0.1 + 0.05 * np.sign(velocity)
    low = (np.arange(len(times)) // 10) % 5 < 2
    readings[:, 1] += np.where(low, -0.03, 0.03)
    result = run.judge(times, velocity, readings)
    assert result.accepted, result.reason
    shares = [low[velocity[:, 1] > 0].mean(), low[velocity[:, 1] < 0].mean()]
    scatter = [0.06 * np.sqrt(share * (1.0 - share)) for share in shares]
    assert result.coulomb_spread[1] == pytest.approx(0.5 * np.hypot(*scatter), rel=1e-9)
    assert result.coulomb_spread[1] > 0.02
    np.testing.assert_allclose(np.delete(result.coulomb_spread, 1), 0.0, atol=1e-12)
    up = readings[velocity[:, 1] > 0, 1]
    assert np.median(np.abs(up - np.median(up))) == 0.0  # what the MAD saw


def _calibration_motion(robot, speeds, error, dt=0.004):
    """Samples of a smooth back-and-forth motion and the torque that drives it [Nm].

    Each joint ``q_i = q₀ + a_i sin(2π f t)`` peaks at ``speeds[i]`` [rad/s] (f the
    calibration's frequency). The torque is the inverse dynamics (Pinocchio's RNEA: an
    independent route from the momentum ``M(q) q̇`` the readings use) plus the model's
    friction, less ``error(q̇)`` (what the model misses), averaged over each period as a
    drive applies it.
    """
    dynamics, friction = lt.Dynamics(robot), FrictionModel.from_robot(robot)
    frequency = CalibrationParameters().frequency
    omega = 2.0 * np.pi * frequency
    amplitude = np.asarray(speeds) / omega
    start = robot.home()

    def torque(t):
        q = start + amplitude * np.sin(omega * t)
        qd = amplitude * omega * np.cos(omega * t)
        qdd = -amplitude * omega**2 * np.sin(omega * t)
        return dynamics.inverse_dynamics(q, qd, qdd) + friction.mean(qd, q) - error(qd)

    t = np.arange(0.0, 2.0 / frequency, dt)
    q = start + amplitude * np.sin(omega * t)[:, None]
    fine = [np.mean([torque(s) for s in np.linspace(k - dt, k, 9)], axis=0) for k in t]
    return dynamics, friction, t, q, np.array(fine)


def _kept_sample_by_sample(dynamics, friction, t, q, tau):
    """Times, velocities and ``u`` of a :class:`MomentumBalance` fed the samples one by one."""
    balance = MomentumBalance(dynamics, friction)
    for sample in zip(t, q, tau, strict=True):
        balance.add(*sample)
    return balance.arrays()


def test_the_readings_are_the_torque_the_model_misses_where_a_joint_slides_at_pace(yumi):
    """The momentum balance over each stretch at pace gives back what the model misses.

    A motion driven by the inverse dynamics with a known gravity error (0.1 Nm) and Coulomb
    error (0.05 Nm): every reading recovers ``0.1 ± 0.05`` to 3 mNm, with no lag (the
    velocity is the positions' central difference). Joint 5 moves 30× faster than the pace
    (a jump out of stiction: its friction is on the Stribeck curve) and joint 6 not at all
    (stiction holds it): neither has a reading.
    """
    speeds = np.full(yumi.n_joints, 0.1)
    speeds[4], speeds[5] = 3.0, 0.0
    dynamics, friction, t, q, tau = _calibration_motion(
        yumi, speeds, lambda qd: 0.1 + 0.05 * np.sign(qd))  # fmt: skip
    pace = (0.025, 0.2)
    times, velocity, unexplained = _kept_sample_by_sample(dynamics, friction, t, q, tau)
    readings = stretch_readings(times, velocity, unexplained, pace)
    read = np.isfinite(readings)
    assert not read[:, 4].any() and not read[:, 5].any()
    for joint in (0, 1, 2, 3, 6):
        assert read[:, joint].mean() > 0.6  # most of the motion is at pace
        expected = 0.1 + 0.05 * np.sign(velocity[read[:, joint], joint])
        np.testing.assert_allclose(readings[read[:, joint], joint], expected, atol=3e-3)
    assert np.all((np.abs(velocity[read]) > pace[0]) & (np.abs(velocity[read]) <= pace[1]))


def test_one_encoder_too_coarse_for_the_pace_refuses_the_calibration(yumi):
    """An encoder that steps more than the motion moves in two periods refuses the run.

    The same motion as above, with what the model misses 0.1 ± 0.05 Nm, its angles read
    through encoders: 1 µrad on every joint but joint 2, whose 1 mrad step is more than the
    0.8 mrad the 0.1 rad/s pace moves in two 4 ms periods. Refused, naming joint 2. Left
    unchecked (no step known), the readings are accepted and off: joint 2's velocity, in
    steps of a count, enters the other joints' momentum through the arm's inertia, and
    their gravity errors read more than 5 mNm off the 0.1 Nm the 1 µrad encoders alone read
    to 1 mNm.
    """
    speeds = np.full(yumi.n_joints, 0.1)
    dynamics, friction, t, q, tau = _calibration_motion(
        yumi, speeds, lambda qd: 0.1 + 0.05 * np.sign(qd))  # fmt: skip
    start = CalibrationParameters().settle_time

    def judged(quantum, checked=True):
        run = CalibrationRun(dynamics, friction, q[0])
        for sample, angles, torque in zip(t, np.round(q / quantum) * quantum, tau, strict=True):
            run.record(start + sample, angles, torque)
        if not checked:
            run._moves.clear()  # no count known
        return run, run.result()

    fine = np.full(yumi.n_joints, 1e-6)
    run, result = judged(fine)
    assert result.accepted and np.all(np.isinf(run.encoder_step))  # moves finer than a count
    np.testing.assert_allclose(result.gravity_error, 0.1, atol=1e-3)
    coarse = fine.copy()
    coarse[1] = 1e-3
    run, result = judged(coarse)
    assert run.encoder_step[1] == pytest.approx(1e-3)
    assert not result.accepted and "joint(s) 2 step up to 1 mrad" in result.reason
    _, unchecked = judged(coarse, checked=False)
    others = np.arange(yumi.n_joints) != 1
    assert unchecked.accepted, unchecked.reason
    assert np.max(np.abs(unchecked.gravity_error[others] - 0.1)) > 5e-3


def test_an_encoders_count_is_read_from_moves_that_are_whole_counts_of_it(yumi):
    """A joint's count: its smallest move, where every move is a whole number of it.

    Joint 1 sticks and jumps (0.43, 2.1, 3.7, 1.2 mrad a period, a fine encoder): its
    moves are no count's multiples, so no count is read (inf), and a jump's first move is
    not taken for a coarse encoder. Joint 2 moves by 0 or 1 of 1 mrad counts, joint 3 by
    1–3 counts of 3.8 µrad, joint 4 once only (too few moves to tell), joint 5 never. Only
    joint 2's count is more than the 0.8 mrad the motion moves in two periods.
    """
    dynamics = lt.Dynamics(yumi)
    run = CalibrationRun(dynamics, FrictionModel.from_robot(yumi), yumi.home())
    jump = np.cumsum([0, 0, 0, 0.43e-3, 2.1e-3, 3.7e-3, 1.2e-3, 0, 0, 0, 0, 0])
    coarse = 1e-3 * np.array([0, 0, 1, 1, 1, 2, 2, 3, 3, 3, 4, 4])
    fine = 2.0 * np.pi / 2**14 / 100 * np.array([0, 1, 3, 4, 6, 7, 9, 12, 13, 15, 16, 18])
    once = np.where(np.arange(12) < 6, 0.0, 0.7e-3)
    for k in range(12):
        q = yumi.home() + np.array([jump[k], coarse[k], fine[k], once[k], 0, 0, 0])
        run.record(0.004 * k, q, np.zeros(7))
    step = run.encoder_step
    assert np.isinf(step[0]) and step[1] == pytest.approx(1e-3)
    assert step[2] == pytest.approx(2.0 * np.pi / 2**14 / 100, rel=1e-3)
    assert np.all(np.isinf(step[3:]))
    t = 0.004 * np.arange(12)
    np.testing.assert_array_equal(run.unresolved(t), np.arange(7) == 1)


def test_encoders_too_coarse_for_the_calibration_refuse_it_with_the_reason(yumi):
    """Dry #1 with 64 counts per motor turn (0.98 mrad at a joint): refused, and why.

    Unchecked, the same run's readings are accepted with joint 4's gravity error 0.2 Nm off
    what 2¹⁴ counts read (there the released arm ran 238 mrad); checked, the controller
    guides with its model. 128 counts (0.49 mrad, less than the 0.8 mrad the motion moves
    in two periods) are read. At 1 kHz the line is 0.2 mrad: 165 counts (0.38 mrad, a
    14-bit encoder on the joint's side), which unchecked left dry #3's joint 3 with a gravity
    error 1.67 Nm off (docs), are refused, and the family's encoders are read.
    """

    def run(counts, dt=0.004):
        plant = sample_plant(yumi, 1, "dry", PlantRanges(encoder_counts=counts))
        controller = LeadThrough(yumi, dt=dt, calibrate=True)
        twin = DigitalTwin(yumi, dataclasses.replace(plant.config, control_dt=dt))
        simulate(twin, controller, controller.calibration_time + 0.05)
        return controller

    coarse = run(64)
    assert not coarse.calibration.accepted
    assert "too coarse" in coarse.calibration.reason and not coarse.calibrating
    np.testing.assert_array_equal(coarse.friction.coulomb, FrictionModel.from_robot(yumi).coulomb)
    readings = coarse._calibration_run
    readings._moves.clear()  # no count known
    unchecked, fine = readings.result(), run(2**14).calibration
    assert unchecked.accepted and fine.accepted
    assert abs(unchecked.gravity_error[3] - fine.gravity_error[3]) > 0.1
    assert run(128).calibration.accepted
    at_1khz = run(165, dt=0.001).calibration
    assert not at_1khz.accepted and "two periods (0.2 mrad)" in at_1khz.reason
    assert run(2**14, dt=0.001).calibration.accepted


def test_the_plausible_friction_band_is_symmetric_in_the_ratio():
    """1 + c above the model and 1 / (1 + c) below it are the edges; a pushing friction never."""
    scale = np.array([1.74, 1.76, 1.0 / 1.74, 1.0 / 1.76, 0.42, 1.0, 0.0, -0.2])
    flagged = implausible_friction(scale, 0.75)
    np.testing.assert_array_equal(flagged, [False, True, False, True, True, False, True, True])


def test_touching_the_arm_during_calibration_refuses_it_and_never_faults(yumi):
    """A push during the calibration: refused at once with a one-line reason, guiding goes on."""
    start = lt.Dynamics(yumi).pose(yumi.home())[:3, 3]
    hand = Hand(MinimumJerk(start, start + np.array([0.0, 0.1, 0.0]), duration=0.5))
    controller = LeadThrough(yumi, calibrate=True)
    simulate(DigitalTwin(yumi, operator=hand), controller, 1.5)
    result = controller.calibration
    assert not result.accepted and "touched" in result.reason and "\n" not in result.reason
    assert result.payload == 0.0 and np.all(result.bias == 0.0)
    nominal = FrictionModel.from_robot(yumi)
    np.testing.assert_array_equal(controller.friction.coulomb, nominal.coulomb)  # as given
    assert np.all(controller.friction.relative_error >= nominal.relative_error)
    assert controller.state is SupervisorState.TEACHING
    assert any(e.kind == "calibration" for e in controller.supervisor.events)


#: The lines a stiff hand pulls the tool along from the home pose, 20 cm in 4 s [m, world]
#: (those of ``benchmarks/guiding_quality.py``).
PULLS = {"upwards": (0.0, 0.0, 0.2), "sideways": (0.0, 0.2, 0.0),
         "down-in": (-0.2 / np.sqrt(2.0), 0.0, -0.2 / np.sqrt(2.0))}  # fmt: skip
#: How soon the arm must be let go once a hand's torque on some joint exceeds what the
#: model may be off there [s]: about a person's reaction, so the hand is not held longer
#: than it takes them to notice the arm resisting.
LET_GO_WITHIN = 0.15


def _pulled_while_calibrating(yumi, line):
    """Latency [s] from the hand's torque exceeding the push bound to the run's end, reason."""
    start = lt.Dynamics(yumi).pose(yumi.home())[:3, 3]
    path = MinimumJerk(start, start + np.array(PULLS[line]), duration=4.0)
    controller = LeadThrough(yumi, calibrate=True)
    twin = DigitalTwin(yumi, operator=Hand(path, stiffness=3000.0, damping=100.0))
    calibrating = []

    class Watch:
        dt, supervisor = controller.dt, controller.supervisor

        def step(self, state):
            command = controller.step(state)
            calibrating.append(controller.calibrating)
            return command

    sim = simulate(twin, Watch(), 1.5)
    bound = controller._calibration_run.push_bound
    over = np.any(np.abs(sim.tau_operator) > bound, axis=1)
    assert over.any() and not all(calibrating)
    return sim.t[calibrating.index(False)] - sim.t[np.argmax(over)], controller.calibration.reason


@pytest.mark.parametrize("line", PULLS)
def test_a_hand_that_pulls_while_the_arm_calibrates_is_let_go_at_once(yumi, line, monkeypatch):
    """The run ends once the observer reads more than any model error it accepts (check_push).

    A stiff hand grabs the tool at once and pulls it along a line: the calibration's
    tracking, with its integral, held the arm within four strokes of its motion against
    up to 53 N, and let go 0.19–0.46 s after the hand's torque on some joint exceeded
    every model error the calibration accepts (:attr:`CalibrationRun.push_bound`); with
    the check, within the observer's lag.
    """
    latency, reason = _pulled_while_calibrating(yumi, line)
    assert latency <= LET_GO_WITHIN and "pushed" in reason and "touched" in reason
    monkeypatch.setattr(CalibrationRun, "check_push", lambda run, estimate: None)
    latency, reason = _pulled_while_calibrating(yumi, line)
    assert latency > LET_GO_WITHIN and "off the calibration motion" in reason


def test_the_push_bound_is_every_model_error_the_calibration_accepts(yumi):
    """Offset, gravity and payload, and friction, each at the bound the judge allows."""
    p, dynamics = CalibrationParameters(), lt.Dynamics(yumi)
    friction = FrictionModel.from_robot(yumi)
    pose = yumi.home()
    run = CalibrationRun(dynamics, friction, pose, p, gravity_uncertainty=0.15)
    payload = -dynamics.jacobian(pose)[:3].T @ yumi.gravity * p.payload_limit(yumi)
    expected = (
        p.max_torque_offset * yumi.torque_limits
        + 0.15 * np.abs(dynamics.gravity(pose))
        + np.abs(payload)
        + (1.0 + p.max_friction_change) * friction.coulomb_level(pose)
    )
    np.testing.assert_allclose(run.push_bound, expected)
    run.check_push(0.99 * run.push_bound)
    assert run.disturbance is None
    pushed = 0.5 * run.push_bound
    pushed[1] = -1.01 * run.push_bound[1]
    run.check_push(pushed)
    assert "joint 2 was pushed with -" in run.disturbance


#: Offsets of the torque measurement, ±0.2 Nm per joint: the twin's drive applies what it
#: is commanded, but measures it this far off (a torque sensor's zero).
OFFSETS = (0.2, -0.2, 0.2, -0.2, 0.2, -0.2, 0.2)


def _measured_with(config: TwinConfig, offsets) -> TwinConfig:
    """``config`` whose drives measure the torque ``offsets`` [Nm] off what they apply."""
    return dataclasses.replace(
        config, sensors=dataclasses.replace(config.sensors, torque_offset=offsets)
    )


def test_an_offset_of_the_torque_measurement_is_read_and_never_commanded(yumi, monkeypatch):
    """The drives measure 0.2 Nm off what they apply; the arm never feels that offset.

    The calibration's readings carry it as if gravity were off by it. It reads the offset
    as ``τ_measured − τ_commanded`` (to 0.05 Nm, a fifth of the YuMi's smallest Coulomb
    level), adds it back to the gravity error, which is then the arm's (as read on the
    same plant measuring without an offset), and takes it off every later measurement:
    the calibrated passive arm left alone stays put. Without it (the readings' gravity
    error alone, as before), the feed-forward commands the offset onto the arm, which
    runs away by several radians within 5 s.
    """
    plant = sample_plant(yumi, 1, "lugre")
    config = _measured_with(plant.config, OFFSETS)
    controller = LeadThrough(yumi, "passive", calibrate=True)
    sim = simulate(DigitalTwin(yumi, config), controller, 6.0)
    assert controller.calibration.accepted
    np.testing.assert_allclose(controller.torque_offset, OFFSETS, atol=0.05)
    assert "measured torque offset up to 0.2" in controller.calibration.summary()
    exact = LeadThrough(yumi, "passive", calibrate=True)
    simulate(DigitalTwin(yumi, _measured_with(plant.config, None)), exact,
             exact.calibration_time + 0.1)  # fmt: skip
    np.testing.assert_allclose(controller.calibration.gravity_error,
                               exact.calibration.gravity_error, atol=0.05)  # fmt: skip
    rest = sim.t > controller.calibration_time + 0.1
    assert np.max(np.abs(sim.q_true[rest] - sim.q_true[rest][0])) < 1e-3
    monkeypatch.setattr(CalibrationRun, "torque_offset", lambda self: None)  # as before
    before = LeadThrough(yumi, "passive", calibrate=True)
    ran = simulate(DigitalTwin(yumi, config), before, 6.0)
    assert np.max(np.abs(ran.q_true[rest] - ran.q_true[rest][0])) > 0.1


def test_a_measured_torque_far_off_its_command_refuses_the_calibration(yumi):
    """3 Nm on joint 2 (10 % of its limit): not the motor torque the model expects.

    Refused with a one-line reason naming the joint; nothing of it is used.
    """
    config = _measured_with(TwinConfig(seed=1), (0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0))
    controller = LeadThrough(yumi, calibrate=True)
    simulate(DigitalTwin(yumi, config), controller, 1.5)
    result = controller.calibration
    assert not result.accepted and "\n" not in result.reason
    read = re.search(r"joint 2's measured torque is ([+-][0-9.]+) Nm off", result.reason)
    assert read and abs(float(read.group(1)) - 3.0) < 0.1
    assert "Nm off its command: is it the motor torque?" in result.reason
    assert result.torque_offset is None and np.all(controller.torque_offset == 0.0)
    assert controller.state is SupervisorState.TEACHING


def test_the_offset_is_read_only_once_a_command_has_reached_the_drive(yumi):
    """No settle time: the first measurements answer no command of the calibration yet.

    Before ``measurement_delay`` periods have passed, the command "sent then" is the delay
    line's zeros, and the whole measured torque would count as offset (0.036 Nm off on the
    shoulder over the run). A drive without ripple or noise: the offset read exactly.
    """
    sensors = SensorModel(torque_ripple=0.0, torque_noise_std=0.0, torque_offset=OFFSETS)
    parameters = LeadThroughParameters(calibration=CalibrationParameters(settle_time=0.0))
    controller = LeadThrough(yumi, parameters=parameters, calibrate=True)
    simulate(DigitalTwin(yumi, TwinConfig(seed=1, sensors=sensors)), controller,
             controller.calibration_time + 0.05)  # fmt: skip
    np.testing.assert_allclose(controller.torque_offset, OFFSETS, atol=1e-3)


def test_without_a_measured_torque_no_offset_is_read(yumi):
    """A robot that measures no torque: the command stands for it, no offset to read."""
    run = CalibrationRun(lt.Dynamics(yumi), FrictionModel.from_robot(yumi), yumi.home())
    for k in range(100):
        run.record(0.2 + 0.004 * k, yumi.home(), np.zeros(7))
    assert run.torque_offset() is None and run.result().torque_offset is None


def test_a_refused_calibration_widens_the_friction_error_of_levels_it_read_low(yumi):
    """Refused: not its readings, but how far below the model's it read a level, is used.

    The error that runs a released arm on is a level the model overstates: one read at
    ``r`` < 1 times the model's makes ``1 − r`` that joint's friction error.
    """
    nominal, zeros = FrictionModel.from_robot(yumi), np.zeros(7)
    read = np.array([0.52, 1.3, 0.9, -0.1, 0.3, 1.0, 0.7])
    measured = np.array([True, True, True, True, False, True, True])
    refused = Calibration(zeros, zeros, zeros, 0.0, zeros, read, False,
                          "calibration refused: joint 1 …", measured)  # fmt: skip
    friction = refused.friction(nominal)
    np.testing.assert_array_equal(friction.coulomb, nominal.coulomb)
    np.testing.assert_allclose(friction.relative_error, [0.48, 0.2, 0.2, 1.0, 0.2, 0.2, 0.3])
    assert refused.summary().endswith("(joint 1 0.52×, joint 3 0.90×, joint 4 0.00×, "
                                      "joint 7 0.70×)")  # fmt: skip
    nothing_read = dataclasses.replace(refused, friction_scale=np.ones(7))
    assert nothing_read.friction(nominal) is nominal
    assert nothing_read.summary() == "calibration refused: joint 1 …"


def test_a_rescaled_level_carries_the_models_error_plus_the_readings(yumi):
    """A model's level along the travel, rescaled by one reading, is off by all three.

    The model's own error, the readings' scatter, and how far the reading disagrees with
    the model at the pose: one reading cannot tell a level that changed everywhere (the
    rescale is right elsewhere) from a model whose shape is off at the pose (the rescale is
    as wrong elsewhere as it moved the level). An identified model (error 5 %) read with a
    2 % scatter at 1.04 of its level carries 11 %; a nominal one (20 %) the calibration's
    20 %, never more; an unmeasured joint keeps the model's level and error.
    """
    zeros = np.zeros(7)
    read = np.array([1.0, 1.04, 0.97, 1.25, 0.75, 1.3, 1.0])
    measured = np.array([True, True, True, True, True, True, False])
    pose = yumi.home()
    identified = np.minimum(0.05 + 0.02 + np.abs(read - 1.0), 0.2)  # 0.07, 0.11, 0.10, 0.2…
    for error, expected in ((0.05, identified), (0.2, np.full(7, 0.2))):
        model = dataclasses.replace(FrictionModel.from_robot(yumi),
                                    relative_error=np.full(7, error))  # fmt: skip
        spread = 0.02 * model.coulomb_level(pose) * read
        accepted = Calibration(pose, zeros, zeros, 0.0, zeros, read, True, "", measured, spread)
        friction = accepted.friction(model, 0.2)
        np.testing.assert_allclose(friction.coulomb, model.coulomb * read)
        np.testing.assert_allclose(friction.relative_error, np.where(measured, expected, error))
    np.testing.assert_allclose(identified[:3], [0.07, 0.11, 0.10])


def test_the_balance_kept_one_sample_late_is_the_whole_runs(yumi):
    """Sample by sample, ``u`` is what the whole run gives at once (to 1e-12).

    The central difference of uneven steps (``np.gradient``), the balance integrated by
    ``np.cumsum``; each period costs a few model evaluations instead of all of them at
    the end of the run (12 ms at 1 kHz: a dozen missed periods).
    """
    speeds = np.linspace(0.05, 0.15, yumi.n_joints)
    dynamics, friction, t, q, tau = _calibration_motion(yumi, speeds, lambda qd: 0.0 * qd)
    t = t + 1e-9 * np.sin(np.arange(len(t)))  # uneven steps, as a clock's
    times, velocity, unexplained = _kept_sample_by_sample(dynamics, friction, t, q, tau)
    whole = np.gradient(q, t, axis=0)
    explained = np.cumsum(
        [
            (
                tau[k]
                - dynamics.gravity(q[k])
                - friction.mean(whole[k], q[k])
                + dynamics.coriolis_transpose_times_velocity(q[k], whole[k])
            )
            * (t[k] - t[k - 1] if k else 0.0)
            for k in range(len(t))
        ],
        axis=0,
    )
    momentum = np.array([dynamics.momentum(q[k], whole[k]) for k in range(len(t))])
    np.testing.assert_array_equal(times, t)
    np.testing.assert_allclose(velocity, whole, rtol=0, atol=1e-12)
    np.testing.assert_allclose(unexplained, momentum - explained, rtol=0, atol=1e-12)


def test_a_sample_delivered_twice_adds_nothing_to_the_balance(yumi):
    """A repeated sample (a driver's, or 500 Hz data in a 1 kHz loop) is left out.

    Before, its zero interval stopped a Panda's calibration at 1 kHz with a fault naming a
    ZeroDivisionError; now the balance is what it is without the repeats.
    """
    speeds = np.linspace(0.05, 0.15, yumi.n_joints)
    dynamics, friction, t, q, tau = _calibration_motion(yumi, speeds, lambda qd: 0.0 * qd)
    repeated = np.repeat(np.arange(len(t)), np.where(np.arange(len(t)) % 7 == 3, 2, 1))
    sound = _kept_sample_by_sample(dynamics, friction, t, q, tau)
    twice = _kept_sample_by_sample(dynamics, friction, t[repeated], q[repeated], tau[repeated])
    for kept, expected in zip(twice, sound, strict=True):
        np.testing.assert_array_equal(kept, expected)


class _JitteredStamps(DigitalTwin):
    """The twin behind a driver that stamps each sample on receipt: ±30 % of a period off."""

    def __init__(self, *args, jitter: float, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._jitter, self._rng = jitter, np.random.default_rng(11)

    def read_state(self) -> lt.JointState:
        state = super().read_state()
        t = state.t + self.dt * self._rng.uniform(-self._jitter, self._jitter)
        return lt.JointState(t, state.q, state.qd, state.tau_measured)


def test_stamps_that_jitter_read_the_same_calibration(yumi):
    """Stamps ±30 % of a period off their ticks: the calibration the exact stamps give.

    Before, its motion and momentum balance ran on the stamps: a YuMi's levels came out
    1.5–3.5 % off those read with exact stamps, and half the calibrations of a Panda at 1 kHz
    were refused, each naming a touch that was the stamps' error.
    """
    plant = sample_plant(yumi, 1, "dry")
    results = []
    for jitter in (0.0, 0.3):
        controller = LeadThrough(yumi, mode="active", calibrate=True)
        twin = _JitteredStamps(yumi, plant.config, jitter=jitter)
        simulate(twin, controller, controller.calibration_time + 0.05, progress=False)
        results.append(controller.calibration)
    exact, jittered = results
    assert exact.accepted and jittered.accepted
    np.testing.assert_array_equal(jittered.friction_scale, exact.friction_scale)
    np.testing.assert_array_equal(jittered.gravity_error, exact.gravity_error)
    np.testing.assert_array_equal(jittered.coulomb_error, exact.coulomb_error)


def test_the_error_stated_at_the_pose_bounds_how_far_a_level_read_is_off(yumi):
    """Every level read is within the error the controller states for it at the pose.

    On a dry plant whose wrist sticks and jumps (dry #4), each measured level lies within
    ``level_error`` at the calibration pose (its readings' spread, at least the stiction
    margin's 5 %) of the plant's true one, and that error is far below the calibration's own
    20 % (``friction_accuracy``).
    """
    plant = sample_plant(yumi, 4, "dry")
    controller = LeadThrough(yumi, mode="active", calibrate=True)
    simulate(DigitalTwin(yumi, plant.config), controller, controller.calibration_time + 0.05,
             progress=False)  # fmt: skip
    result = controller.calibration
    assert result.accepted and result.measured.sum() >= 5
    true = plant.config.friction.coulomb_level(result.pose) / np.asarray(
        plant.config.sensors.torque_gain)  # fmt: skip
    read = FrictionModel.from_robot(yumi).coulomb_level(result.pose) * result.friction_scale
    off = (np.abs(read - true) / read)[result.measured]
    stated = controller.level_error.at(result.pose)[result.measured]
    assert np.all(off <= stated), (off, stated)
    assert np.all(stated < 0.1)


def test_a_level_read_far_below_the_model_refuses_the_calibration_and_widens_its_error(
    yumi, monkeypatch
):
    """Dry #11 with every level 0.45–0.5 of the model's: joint 1 reads a third of it.

    Refused (outside the plausible band), the controller guides with the model as given,
    joint 1 with a friction error as large as the reading shows (a refused calibration's
    released arm: ``tests/test_released_arm.py``). With the 6 Hz loop it was found with:
    under the 4 Hz one, the model's friction fed forward runs joint 5 four strokes off
    first, which refuses the run and leaves that joint none of its friction.
    """
    plant = sample_plant(yumi, 11, "dry", PlantRanges(friction_scale=(0.45, 0.5)))
    default = LeadThrough(yumi, calibrate=True)  # 4 Hz: joint 5 runs off first
    simulate(DigitalTwin(yumi, plant.config), default, default.calibration_time + 0.05)
    assert "joint 5 was" in default.calibration.reason
    assert "off the calibration motion" in default.calibration.reason
    assert default.law.friction_error[4] == 1.0
    six_hertz_calibration(monkeypatch)
    controller = LeadThrough(yumi, calibrate=True)
    simulate(DigitalTwin(yumi, plant.config), controller, controller.calibration_time + 0.05)
    result = controller.calibration
    assert not result.accepted and "joint 1's friction seems" in result.reason
    read = result.friction_scale[0]
    assert read < 1.0 / (1.0 + CalibrationParameters().max_friction_change)
    np.testing.assert_array_equal(controller.friction.coulomb,
                                  FrictionModel.from_robot(yumi).coulomb)  # fmt: skip
    assert controller.law.friction_error[0] == pytest.approx(1.0 - read)
    assert f"joint 1 {read:.2f}×" in controller.supervisor.events[-1].detail


def test_calibration_motion_is_small_and_returns(yumi):
    """Each joint moves about one stroke and comes back to within a stroke of where it was."""
    _controller, _, sim = calibrated(yumi, TwinConfig(model_error=MASSES_OFF, seed=3))
    stroke = CalibrationParameters().stroke
    excursion = np.max(np.abs(sim.q_true - sim.q_true[0]), axis=0)
    assert np.all(excursion < 2.5 * stroke)
    assert np.all(excursion > 0.5 * stroke)  # every joint really moved
    assert np.max(np.abs(sim.q_true[-1] - sim.q_true[0])) < stroke


def test_without_calibration_guiding_starts_at_once(yumi, tmp_path):
    """``calibration = false`` in TOML (or None): no calibration motion."""
    path = tmp_path / "lead_through.toml"
    path.write_text("calibration = false\n[dither]\nfrequency = 12.0\n", encoding="utf-8")
    parameters = LeadThroughParameters.from_toml(path)
    controller = LeadThrough(yumi, parameters=parameters)
    assert parameters.calibration is None and not controller.calibrating


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("stroke", 0.0),
        ("speed", -1.0),
        ("cycles", 0),
        ("cycles", 1.5),
        ("max_payload", 0.0),
        ("max_speed", 0.05),
        ("max_torque_offset", 0.0),
    ],
)
def test_bad_calibration_parameters_are_one_line_errors(field, value):
    """Each bad setting names itself."""
    with pytest.raises(lt.errors.ParameterError, match=field):
        CalibrationParameters(**{field: value})


def test_with_payload_matches_the_twin_carrying_it(yumi):
    """A payload lumped into the last link: gravity as MuJoCo computes it for the twin."""
    import mujoco

    payload = Payload(0.5, (0.0, 0.0, 0.05))
    twin = DigitalTwin(yumi, TwinConfig(model_error=ModelError(payload=payload)))
    model = lt.Dynamics(yumi.with_payload(payload.mass, payload.com))
    for q in np.random.default_rng(0).uniform(yumi.q_min, yumi.q_max, (3, yumi.n_joints)):
        twin.data.qpos[:], twin.data.qvel[:] = q, 0.0
        mujoco.mj_forward(twin.model, twin.data)
        np.testing.assert_allclose(model.gravity(q), twin.data.qfrc_bias, atol=1e-9)
    assert yumi.with_payload(0.0) is yumi


def test_every_plant_calibrates_and_its_released_arm_stays(yumi, identified_friction):
    """The defaults on every plant of PLANTS: calibration close to the truth, arm stays put."""
    from leadthrough.experiments.lead_through import calibration_checks, plants_table, robustness

    checks = calibration_checks(yumi, identified_friction)
    releases = robustness(yumi, identified_friction)
    for check in checks:
        result = check.calibration
        assert result.accepted, check.plant
        assert result.payload == pytest.approx(check.true_payload, abs=0.1), check.plant
        error = np.abs(result.gravity_error - check.true_gravity_error)[result.measured]
        assert np.all(error < 0.05), check.plant
        assert releases[check.plant].stop_time <= 0.5 and releases[check.plant].drift < 1e-3
    assert plants_table(checks, releases).count("\n") == len(checks) + 1


def test_the_column_medians_are_numpys_nanmedian():
    """Bit for bit, every column: any length, NaNs anywhere, a column of NaNs only (NaN)."""
    rng = np.random.default_rng(7)
    for rows in (1, 2, 5, 200, 601, 900):
        values = np.round(rng.normal(size=(rows, 7)), 2)  # ties too
        values[rng.random((rows, 7)) < 0.4] = np.nan
        values[:, 3] = np.nan
        with pytest.warns(RuntimeWarning):  # NumPy's, for the column of NaNs
            expected = np.nanmedian(values, axis=0)
        np.testing.assert_array_equal(calibration_run._column_medians(values), expected)


def test_the_settings_follow_a_slower_control_period():
    """At 125 Hz the loop's bandwidth drops to what its delay allows, the stroke grows alike."""
    defaults = CalibrationParameters()
    assert defaults.at_period(0.004) is defaults and defaults.at_period(0.001) is defaults
    slow = defaults.at_period(0.008)
    assert slow.bandwidth == pytest.approx(3.95, abs=0.01)  # 4 Hz keeping 0.14 at 125 Hz
    assert slow.stroke * slow.bandwidth == pytest.approx(defaults.stroke * defaults.bandwidth)
    assert slow.frequency / slow.bandwidth == pytest.approx(defaults.frequency / defaults.bandwidth)
    controller = LeadThrough(lt.robots.yumi(), dt=0.008, calibrate=True)
    assert controller.calibration_parameters == slow
    assert controller.calibration_time == pytest.approx(slow.duration)
    assert LeadThrough(lt.robots.yumi(), dt=0.008).calibration_time == 0.0


@pytest.mark.parametrize("physics, seed", [("dry", 1), ("dry", 4), ("lugre", 3)])
def test_at_125_hz_the_calibration_is_accepted_where_the_250_hz_settings_were_not(
    yumi, physics, seed, monkeypatch
):
    """Plants of the guiding benchmark at 125 Hz (delays 1–2 periods, 8–16 ms).

    With the 250 Hz settings of the release that found it (6 Hz, 10 mrad) the wrist jumped
    42–48 mrad off the motion (refused: touched?) or the shoulder ran at 2.1 rad/s
    (refused: stopped, held).
    """
    plant = sample_plant(yumi, seed, physics)
    config = dataclasses.replace(plant.config, control_dt=0.008)

    def calibrate() -> Calibration:
        controller = LeadThrough(yumi, dt=0.008, calibrate=True)
        simulate(DigitalTwin(yumi, config), controller, controller.calibration_time + 0.1)
        assert controller.calibration is not None
        return controller.calibration

    assert calibrate().accepted
    monkeypatch.setattr(CalibrationParameters, "at_period", lambda self, dt: self)
    six_hertz_calibration(monkeypatch)
    unchecked_push(monkeypatch)
    refused = calibrate()
    assert not refused.accepted and ("off the calibration motion" in refused.reason
                                     or "faster than" in refused.reason)  # fmt: skip


def test_at_125_hz_a_wrist_its_own_friction_damps_tracks_its_samples(yumi):
    """Dry #1 at 125 Hz: what predicting only the joints that need it prevents.

    The prediction takes the command's acceleration for the arm's; a stick-slip jump of the
    light wrist (joint 6, up to 1.8 rad/s either way) is then braked later. Predicted on
    every joint (``predict = "always"``) it carries the wrist four strokes off the motion:
    refused (the arm held, nothing faster than ``max_speed``, at rest after). By default the
    wrist, whose loop its own viscous friction damps, tracks its samples, and the
    calibration is accepted.
    """
    plant = sample_plant(yumi, 1, "dry")
    config = dataclasses.replace(plant.config, control_dt=0.008)

    def run(predict: str) -> tuple[LeadThrough, np.ndarray]:
        calibration = CalibrationParameters(predict=predict)
        parameters = dataclasses.replace(lt.LeadThroughParameters(), calibration=calibration)
        controller = LeadThrough(yumi, dt=0.008, parameters=parameters, calibrate=True)
        sim = simulate(DigitalTwin(yumi, config), controller, controller.calibration_time + 0.5)
        return controller, sim

    controller, _ = run("needed")
    result = controller.calibration
    assert result.accepted
    assert np.flatnonzero(result.predicted).tolist() == [0, 1, 2, 6]  # the wrist's own friction
    assert "joint(s) 1, 2, 3, 7 tracked one period ahead" in result.summary()
    controller, sim = run("always")
    result = controller.calibration
    assert not result.accepted and "joint 6" in result.reason
    assert "off the calibration motion" in result.reason
    assert np.abs(sim.qd_true).max() < CalibrationParameters().max_speed
    assert np.abs(sim.qd_true[sim.t > controller.calibration_time + 0.2]).max() < 0.01


@pytest.mark.filterwarnings("ignore::leadthrough.model.robots.drive.AssumedDriveDataWarning")
def test_at_every_rate_each_joints_loop_decays_with_two_periods_of_delay():
    """Linearised with the plant family's longest delay, two periods, every joint's loop decays.

    The 6 Hz of before grew there at 250 Hz (ζ −0.02; the loop simulated in time grows
    where the model says so, ``test_tracking``); 4 Hz keeps 0.20 and no joint predicts.
    Slower, the bandwidth keeps ``slow_rate_damping`` with one period of delay (its
    docstring says why), which tracking the samples grows with two (ζ −0.07 and −0.08 at
    125 and 100 Hz) unless the joint's own viscous friction damps it: the joints that predict
    (at the home pose) are every one of the Panda's (``b / m_ii`` 0–0.7 1/s), the YuMi's 1–3
    and 7 (its others 6–14 1/s), and the UR10e's 1–3 (and 6 at 100 Hz).
    """
    expected = {"yumi": [0, 1, 2, 6], "panda": list(range(7)), "ur10e": [0, 1, 2]}
    for name, joints in expected.items():
        robot = getattr(lt.robots, name)()
        friction, dynamics = FrictionModel.from_robot(robot), lt.Dynamics(robot)
        own = friction.viscous / np.diag(dynamics.mass(robot.home()))  # [1/s]
        for dt in (0.001, 0.002, 0.004, 0.008, 0.01):
            settings = CalibrationParameters().at_period(dt)
            run = CalibrationRun(dynamics, friction, robot.home(), settings, dt=dt)
            gains = calibration_gains(2.0 * np.pi * settings.bandwidth)
            # required: decays with room for what the linear model lacks (measured 0.20 at
            # 250 Hz; 0.10 and 0.11 predicted at 125 and 100 Hz)
            least = 0.15 if dt <= 0.004 else 0.05
            for predicted, viscous in zip(run.predicted, own, strict=True):
                if predicted:
                    assert loop_damping(gains, dt, 2, viscous=viscous) < 0.0
                assert loop_damping(gains, dt, 2, predicted=predicted, viscous=viscous) > (
                    least if predicted or dt <= 0.004 else 0.0
                )
            if dt <= 0.004:
                assert not run.predicted.any()
            elif dt == 0.008:
                assert np.flatnonzero(run.predicted).tolist() == joints
    assert loop_damping(calibration_gains(2.0 * np.pi * SIX_HERTZ["bandwidth"]), 0.004, 2) < 0.0
    yumi = lt.robots.yumi()
    dynamics, friction = lt.Dynamics(yumi), FrictionModel.from_robot(yumi)
    never = CalibrationParameters(predict="never")
    assert not CalibrationRun(dynamics, friction, yumi.home(), never, dt=0.01).predicted.any()
    always = CalibrationParameters(predict="always")
    assert CalibrationRun(dynamics, friction, yumi.home(), always).predicted.all()
    with pytest.raises(lt.errors.ParameterError, match="predict"):
        CalibrationParameters(predict=True)


def test_at_250_hz_predicting_where_needed_commands_as_tracking_the_samples(yumi):
    """No joint needs it at 250 Hz: the commands equal, bit for bit, those of ``"never"``."""
    dynamics, friction = lt.Dynamics(yumi), FrictionModel.from_robot(yumi)
    rng = np.random.default_rng(3)
    runs = [CalibrationRun(dynamics, friction, yumi.home(), CalibrationParameters(predict=p))
            for p in ("needed", "never")]  # fmt: skip
    for k in range(300):
        t = 0.004 * k
        q = yumi.home() + rng.normal(scale=1e-3, size=7)
        qd = rng.normal(scale=0.05, size=7)
        needed, never = (run.command(t, q, qd) for run in runs)
        np.testing.assert_array_equal(needed, never)


def test_a_panda_with_two_periods_of_delay_reads_its_levels_and_then_rests(monkeypatch):
    """Panda dry #4 of the guiding family, its delay two periods (8 ms at 250 Hz).

    Its levels (0.13–0.33 Nm at the pose) are small beside its inertia, so friction damps its
    calibration loop little. With the 6 Hz loop of before joint 3 rang up to 2.6× the
    motion's speed, read its level 1.7× the truth, and the arm it left guiding kept moving
    0.2–0.5 s after (0.056 rad/s): the 4 Hz loop slides every joint at the motion's pace.
    """
    panda = lt.robots.panda()
    plant = sample_plant(panda, 4, "dry", PlantRanges(delay_periods=(2, 2)))

    def run() -> tuple[np.ndarray, float, float]:
        """Measured over true level of each joint measured, fastest joint during, after."""
        controller = LeadThrough(panda, calibrate=True)
        twin = DigitalTwin(panda, plant.config)
        sim = simulate(twin, controller, controller.calibration_time + 0.5)
        result = controller.calibration
        assert result is not None and result.accepted and result.measured is not None
        true = plant.config.friction.level(result.pose, np.full(7, 1e3))
        gain = plant.config.sensors.torque_gain  # the level in commanded torque
        ratio = controller.friction.coulomb_level(result.pose) * gain / true
        during = sim.t < controller.calibration_time
        after = sim.t > controller.calibration_time + 0.2
        return (ratio[result.measured], np.abs(sim.qd_true[during]).max(),
                np.abs(sim.qd_true[after]).max())  # fmt: skip

    levels, fastest, resting = run()
    speed = CalibrationParameters().speed
    assert np.all(np.abs(levels - 1.0) < 0.1) and len(levels) == 7
    assert fastest < 2.0 * speed and resting < 0.01
    six_hertz_calibration(monkeypatch)
    unchecked_push(monkeypatch)
    levels, fastest, resting = run()
    assert levels.max() > 1.4 and fastest > 2.0 * speed and resting > 0.03


# the Panda's assumed gear ratio: not what is tested
@pytest.mark.filterwarnings("ignore::leadthrough.model.robots.drive.AssumedDriveDataWarning")
def test_a_panda_at_125_hz_with_two_periods_of_delay_calibrates_with_the_prediction(monkeypatch):
    """Panda dry #1 of the guiding family at 125 Hz, its delay two periods (16 ms).

    Tracking the samples, the calibration's loop grows there (ζ −0.07): joints ring up to
    1.7 rad/s, the calibration is refused, and the arm is still moving 0.2–0.5 s after.
    Tracking the state predicted for when each command acts, it reads every level within
    15 % of the truth and leaves the arm at rest.
    """
    panda, dt = lt.robots.panda(), 0.008
    plant = sample_plant(panda, 1, "dry", PlantRanges(delay_periods=(2, 2)))
    config = dataclasses.replace(plant.config, control_dt=dt)

    def run(predict: str) -> tuple[LeadThrough, float, float]:
        """The controller, its fastest joint during the calibration and after it [rad/s]."""
        calibration = CalibrationParameters(predict=predict)
        parameters = dataclasses.replace(lt.LeadThroughParameters(), calibration=calibration)
        controller = LeadThrough(panda, dt=dt, parameters=parameters, calibrate=True)
        sim = simulate(DigitalTwin(panda, config), controller, controller.calibration_time + 0.5)
        during = sim.t < controller.calibration_time
        after = sim.t > controller.calibration_time + 0.2
        return controller, np.abs(sim.qd_true[during]).max(), np.abs(sim.qd_true[after]).max()

    controller, fastest, resting = run(predict="needed")  # the default: predicted at 125 Hz
    result = controller.calibration
    assert result is not None and result.accepted and result.measured.all()
    assert result.predicted.all() and "joint(s) 1, 2, 3, 4, 5, 6, 7 tracked one period ahead" in (
        result.summary()
    )
    true = plant.config.friction.level(result.pose, np.full(7, 1e3))
    ratio = controller.friction.coulomb_level(result.pose) * plant.config.sensors.torque_gain / true
    assert np.all(np.abs(ratio - 1.0) < 0.15)
    assert fastest < 3.0 * CalibrationParameters().speed and resting < 0.01
    unchecked_push(monkeypatch)  # as found: the ringing read as a push stops it sooner now
    controller, fastest, resting = run(predict="never")
    assert not controller.calibration.accepted and fastest > 1.0 and resting > 0.1


def test_a_gravity_error_is_a_relative_error_of_g_up_to_the_models_tolerance():
    """The share is bias / G within ±limit; beyond it the rest stays constant; no G, none.

    A bias of more than a gain can make fades the share, to 0 at twice the gain's reach:
    its sign is then the other error's (what this prevents: a shoulder balanced at the
    pose, read 0.13 Nm off by its masses, held with 0.83 of its gravity elsewhere).
    """
    bias = np.array([0.4, -0.4, 0.4, 0.1, 0.0, 0.15, 0.45])
    gravity = np.array([5.0, 5.0, 2.0, 0.0, 3.0, 1.0, 2.0])
    share = gravity_share(bias, gravity, 0.15)
    np.testing.assert_allclose(share, [0.08, -0.08, 0.15 * 0.6667, 0.0, 0.0, 0.15, 0.075],
                               rtol=1e-3)  # fmt: skip
    constant = bias - share * gravity  # what stays constant: 0 where k explains it all
    np.testing.assert_allclose(constant[[0, 1, 3, 4, 5]], [0.0, 0.0, 0.1, 0.0, 0.0], atol=1e-15)
    upright = gravity_share(np.array([-0.129]), np.array([-0.229]), 0.1)  # 5.6 gains' worth
    assert upright[0] == 0.0
    np.testing.assert_array_equal(gravity_share(bias, gravity, 0.0), 0.0)  # no gain: no NaN


def test_the_scripted_sessions_take_the_arm_once_the_calibration_is_over(yumi):
    """A hand on the arm during the calibration refuses it: the sessions wait for its end."""
    from leadthrough.experiments.demo import teaching_actions
    from leadthrough.twin.session_operator import teaching_session_operator

    ends = LeadThrough(yumi, calibrate=True).calibration_time
    assert teaching_session_operator.actions(yumi)[0].start > ends
    assert teaching_actions(yumi)[0].start > ends


def _readings_with_a_growing_push(run, change):
    """Synthetic readings of ``run`` with a push on joint 2 growing by ``change`` [Nm].

    Every joint reads a gravity error of 0.1 Nm and a level error of 0.05 Nm; joint 2's
    push grows evenly over the motion.
    """
    p, n = run.parameters, run.pose.size
    times = np.arange(p.settle_time, p.duration, 0.004)
    way = np.sign(np.sin(2 * np.pi * p.frequency * (times - p.settle_time)))
    velocity = run._direction * way[:, None] * p.speed * np.ones(n)
    readings = 0.1 + 0.05 * np.sign(velocity)
    readings[:, 1] += change * (times - p.settle_time) / (p.duration - p.settle_time)
    return times, velocity, readings


def test_a_push_that_changes_between_the_cycles_refuses_the_calibration(yumi):
    """At one pose the model's errors stay as they are: readings that move are a hand.

    A push on joint 2 that grows evenly while the arm calibrates moves its readings from
    the first cycle to the last by half its change. Above ``max_drift`` (0.25) of what the
    joint carries (its level plus the gravity error read) the run is refused; with the
    check off (as found) it was accepted and the push's mean read as a gravity error,
    which drives the arm once the hand lets go.
    """
    friction = FrictionModel.from_robot(yumi)
    run = CalibrationRun(lt.Dynamics(yumi), friction, yumi.home())
    level = friction.coulomb_level(yumi.home())[1]
    small = run.judge(*_readings_with_a_growing_push(run, 0.2 * level))
    assert small.accepted, small.reason
    readings = _readings_with_a_growing_push(run, 2.0 * level)
    drift = run.drift(readings[0], *(np.where(s * readings[1] > 0, readings[2], np.nan)
                                     for s in (1, -1)))  # fmt: skip
    assert drift[1] == pytest.approx(level, rel=0.05)
    np.testing.assert_allclose(np.delete(drift, 1), 0.0, atol=1e-12)
    assert drift[1] > 0.25 * (level + 0.1 + level)  # the level, the gravity error read
    large = run.judge(*readings)
    assert not large.accepted and "joint 2's readings moved" in large.reason
    assert "touched" in large.reason and np.all(large.bias == 0.0)
    # the levels it read go with the refusal: one read low widens that joint's error
    others = np.arange(yumi.n_joints) != 1
    np.testing.assert_allclose(large.friction_scale[others], small.friction_scale[others])
    assert np.all(large.lowered()[others] < 1.0)
    unchecked = dataclasses.replace(run.parameters, max_drift=1e9)
    as_found = CalibrationRun(lt.Dynamics(yumi), friction, yumi.home(), unchecked)
    accepted = as_found.judge(*readings)
    assert accepted.accepted and accepted.gravity_error[1] - 0.1 > 0.9 * level


@pytest.mark.parametrize("path", ["sideways", "circle"])
def test_a_relaxed_hand_that_grabs_as_the_arm_calibrates_refuses_it(yumi, path):
    """A relaxed hand grabs at once and pulls: too gently for the push bound, not for the drift.

    On dry #9 of ``benchmarks/guiding_quality.py``, the hand (300 N/m) loads the arm as its
    path goes on; below every model error the run accepts at any one time
    (:meth:`CalibrationRun.check_push`), its push changes from one cycle to the next. With
    the drift unchecked, the calibration was accepted with a gravity error 0.3–0.6 Nm off
    the one it reads untouched, and the released arm ran 1.5 rad.
    """
    from leadthrough.experiments.guiding import HANDS, case_path

    config = sample_plant(yumi, 9, "dry").config

    def calibration(parameters):
        hand = Hand.from_parameters(case_path(yumi, path), HANDS["relaxed"])
        controller = LeadThrough(yumi, calibrate=True, parameters=parameters)
        simulate(DigitalTwin(yumi, config, operator=hand), controller, 1.5)
        return controller.calibration

    result = calibration(LeadThroughParameters())
    assert not result.accepted and "readings moved" in result.reason, result.reason
    defaults = LeadThroughParameters()
    unchecked = dataclasses.replace(defaults, calibration=dataclasses.replace(
        defaults.calibration, max_drift=1e9))  # fmt: skip
    as_found = calibration(unchecked)
    if path == "sideways":  # another check caught this hand, later in the judge
        assert not as_found.accepted and "friction seems" in as_found.reason
        return
    assert as_found.accepted, as_found.reason
    untouched = calibrated(yumi, config)[0].calibration
    assert np.max(np.abs(as_found.bias - untouched.bias)) > 0.3
