"""The plant family: dry friction physics, the seeded sampler, interface errors, release safety."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.errors import ParameterError
from leadthrough.experiments.guiding import (
    Case,
    release_figures,
    run_case,
    tool_vibration,
    vibration_within,
)
from leadthrough.model.dynamics import Dynamics
from leadthrough.twin.dry_friction import DryFrictionParameters
from leadthrough.twin.operator import TorqueProfile, step
from leadthrough.twin.plants import PlantRanges, sample_plant
from leadthrough.twin.sensors import SensorModel
from leadthrough.twin.simulator import DigitalTwin, TwinConfig


@pytest.fixture(scope="module")
def robot():
    """The nominal YuMi."""
    return lt.robots.yumi()


def _pushed_travel(robot, joint: int, fraction: float, periods: int = 150) -> float:
    """Travel [rad] of ``joint`` under a torque ``fraction`` × its dry level at rest."""
    twin = DigitalTwin(robot, TwinConfig(friction_physics="dry", delay_periods=0))
    dynamics = Dynamics(twin.true_robot)
    q0 = twin.truth.q.copy()
    level = twin.friction.params.level(q0, np.zeros(robot.n_joints))[joint]
    twin.operator = TorqueProfile(joint, (step(0.0, fraction * level),))
    for _ in range(periods):
        twin.send_torque(dynamics.gravity(twin.truth.q))  # the true gravity, held
    return float(abs(twin.truth.q[joint] - q0[joint]))


@pytest.mark.parametrize("joint", [1, 6])
def test_dry_friction_sticks_below_and_slides_above_its_level(robot, joint):
    """A torque at 90 % of the stiction level leaves the joint put; 110 % moves it."""
    assert _pushed_travel(robot, joint, 0.9) < 1e-4
    assert _pushed_travel(robot, joint, 1.1) > 0.02


def test_dry_friction_level_stribeck_and_position():
    """The level is τ_S at rest, → τ_C when sliding, and varies ±a with the position."""
    p = DryFrictionParameters(coulomb=[1.0], static=[1.3], stribeck_velocity=[0.01],
                              viscous=[0.0], position_amplitude=[0.15],
                              position_wavenumber=[2.0], position_phase=[0.0])  # fmt: skip
    assert p.level([0.0], [0.0])[0] == pytest.approx(1.3)
    assert p.level([0.0], [0.1])[0] == pytest.approx(1.0, abs=1e-9)
    assert p.level([np.pi / 4], [0.0])[0] == pytest.approx(1.3 * 1.15)
    assert p.level([-np.pi / 4], [0.0])[0] == pytest.approx(1.3 * 0.85)
    q = np.array([[0.3], [-1.1]])
    np.testing.assert_allclose(p.coulomb_level(q), p.level(q, [[10.0], [10.0]]), rtol=1e-12)


def test_a_plant_identified_first_guides_with_its_identified_friction(robot):
    """IdentifiedFirst identifies the plant's friction once and builds both modes with it.

    The excitation of `leadthrough identify` runs on a twin of the plant (dry, with its
    drives' gains): each level comes out within 10 % of the plant's own, read through the
    drive, at the middle of the stroke it saw.
    """
    from leadthrough.experiments.guiding import IdentifiedFirst

    built = []

    def factory(robot, mode, dt, friction):
        built.append(friction)
        return SimpleNamespace(dt=dt)

    plant = sample_plant(robot, 3, "dry")
    first = IdentifiedFirst(factory, dt=0.004)
    first.controller(robot, "active", plant.config)
    first.controller(robot, "passive", plant.config)
    model = built[0]
    assert built[1] is model and np.all(np.isfinite(model.relative_error))
    # the drive reports applied / gain: a level read through it is the true one / gain
    gain = np.asarray(plant.config.sensors.torque_gain or 1.0)
    truth = plant.config.friction.coulomb_level(model.position_mid) / gain
    np.testing.assert_allclose(model.coulomb, truth, rtol=0.1)


def test_sampler_is_seeded_and_within_its_ranges(robot):
    """The same seed gives the same plant; every draw lies in the stated ranges."""
    r = PlantRanges()
    assert repr(sample_plant(robot, 5, "dry")) == repr(sample_plant(robot, 5, "dry"))
    for seed in range(6):
        for physics in ("dry", "lugre"):
            config = sample_plant(robot, seed, physics).config
            s = config.sensors
            assert r.delay_periods[0] <= config.delay_periods <= r.delay_periods[1]
            assert np.all((np.array(s.torque_gain) >= 0.9) & (np.array(s.torque_gain) <= 1.1))
            assert np.all(np.abs(s.torque_offset) <= 0.05)
            assert r.velocity_cutoff[0] <= s.velocity_cutoff <= r.velocity_cutoff[1]
            f = config.friction
            ratio = f.static / np.maximum(f.coulomb, 1e-12)
            assert np.all((ratio >= 1.1 - 1e-9) & (ratio <= 1.5 + 1e-9))
            nominal = np.array([j.friction.coulomb for j in robot.joints])
            assert np.all(np.abs(f.coulomb / nominal - 1.0) <= 0.2 + 1e-9)
    assert repr(sample_plant(robot, 1, "dry")) != repr(sample_plant(robot, 2, "dry"))


def test_a_start_spread_moves_only_where_the_arm_starts(robot):
    """``start_spread``: each joint within ±spread of home and 0.4 rad inside its limits.

    The start is drawn from a stream of its own: the plant is otherwise the one without a
    spread, and the twin built with it rests there.
    """
    from leadthrough.twin.plants import START_MARGIN

    assert sample_plant(robot, 3, "lugre").start is None
    for seed in range(1, 9):
        plant = sample_plant(robot, seed, "dry", PlantRanges(start_spread=0.5))
        assert repr(plant.config) == repr(sample_plant(robot, seed, "dry").config)
        offset = plant.start - robot.home()
        assert np.all(np.abs(offset) <= 0.5) and np.any(np.abs(offset) > 0.1)
        assert np.all(plant.start >= robot.q_min + START_MARGIN - 1e-12)
        assert np.all(plant.start <= robot.q_max - START_MARGIN + 1e-12)
    twin = DigitalTwin(robot, plant.config, q0=plant.start)
    np.testing.assert_allclose(twin.read_state().q, plant.start, atol=1e-3)


def test_differenced_velocity_lags_the_truth(robot):
    """A low-passed difference of the encoder reports a ramp late, by ~dt/2 + 1/(2π f_c)."""
    sensors = SensorModel(velocity_noise_std=0.0, velocity_cutoff=20.0)
    twin = DigitalTwin(robot, TwinConfig(sensors=sensors))
    dt, n = twin.dt, robot.n_joints
    accel = 0.5  # [rad/s²] on every joint
    reported = []
    for k in range(100):
        t = k * dt
        reported.append(twin.sensors.joint_velocity(np.full(n, accel * t),
                                                    np.full(n, 0.5 * accel * t * t)))  # fmt: skip
    lag = accel * 99 * dt - reported[-1][0]
    expected = accel * (dt / 2.0 + 1.0 / (2.0 * np.pi * 20.0))
    assert lag == pytest.approx(expected, rel=0.1)


def test_torque_constant_error_scales_applied_against_measured(robot):
    """The drive applies gain × command and reports applied / gain + offset."""
    gain = np.linspace(0.9, 1.1, robot.n_joints)
    offset = np.full(robot.n_joints, 0.02)
    sensors = SensorModel(torque_noise_std=0.0, torque_ripple=0.0, torque_gain=tuple(gain),
                          torque_offset=tuple(offset))  # fmt: skip
    twin = DigitalTwin(robot, TwinConfig(sensors=sensors, delay_periods=0))
    command = Dynamics(robot).gravity(robot.home()) + 0.1
    twin.send_torque(command)
    np.testing.assert_allclose(twin.truth.tau_motor, gain * command, rtol=1e-12)
    measured = twin.read_state().tau_measured
    np.testing.assert_allclose(measured, command + offset, rtol=1e-12)


def test_dry_truth_excludes_friction_from_the_external_torque(robot):
    """On the dry plant at rest, nobody touching, the true external torque is zero."""
    twin = DigitalTwin(robot, dataclasses.replace(TwinConfig(friction_physics="dry")))
    for _ in range(50):
        twin.send_torque(Dynamics(twin.true_robot).gravity(twin.truth.q) + 0.05)
    np.testing.assert_allclose(twin.truth.tau_ext, 0.0, atol=1e-9)


@pytest.mark.parametrize("case", [Case("lugre", 2, "relaxed", "upwards")])
def test_active_release_stops_without_runaway(robot, case):
    """Released at speed on a sampled plant, the active arm stops within 0.5 s, drifts < 1 mrad."""
    result = run_case(case, "active", robot=robot)
    assert result.stop_time <= 0.5
    assert result.drift < 1e-3
    assert result.max_joint_speed < 1.0


def test_vibration_keeps_what_is_above_4_hz():
    """A 12 Hz tool velocity of amplitude A reads A/√2; a 0.5 Hz one reads almost nothing."""
    dt = 0.004
    t = np.arange(0.0, 6.0, dt)[:, None]
    fast = 0.01 * np.sin(2 * np.pi * 12.0 * t) * np.array([[1.0, 0.0, 0.0]])
    slow = 0.1 * np.sin(2 * np.pi * 0.5 * t) * np.array([[0.0, 1.0, 0.0]])
    assert tool_vibration(fast, dt) == pytest.approx(0.01 / np.sqrt(2.0), rel=0.03)
    assert tool_vibration(slow, dt) < 0.02 * 0.1


def test_vibration_within_windows_reads_each_windows_shaking():
    """A 12 Hz shake in the second half only: that window reads A/√2, the first nearly 0.

    One window over the whole run reads what :func:`tool_vibration` reads.
    """
    dt = 0.004
    t = np.arange(0.0, 6.0, dt)
    second = t >= 3.0
    slow = 0.1 * np.sin(2 * np.pi * 0.5 * t)[:, None] * np.array([[0.0, 1.0, 0.0]])
    shake = np.where(second, 0.01 * np.sin(2 * np.pi * 12.0 * t), 0.0)
    velocity = slow + shake[:, None] * np.array([[1.0, 0.0, 0.0]])
    first_half, second_half = vibration_within(velocity, dt, [~second, second])
    assert second_half == pytest.approx(0.01 / np.sqrt(2.0), rel=0.05)
    assert first_half < 0.1 * second_half
    whole = vibration_within(velocity, dt, [np.ones_like(second)])
    assert whole[0] == pytest.approx(tool_vibration(velocity, dt), rel=1e-12)
    assert np.isnan(vibration_within(velocity, dt, [np.zeros_like(second)])[0])


def test_stop_time_counts_motion_not_the_dither_twitch():
    """A joint that rocks at 15 Hz (±0.012 rad/s, ±0.2 mrad) once it stopped has stopped.

    The same joint still coasting at 0.02 rad/s for 1 s after the release has not, and
    its drift is its travel from 0.5 s after the release on (10 mrad).
    """
    dt, release = 0.004, 1.0
    t = np.arange(0.0, 6.0, dt)
    braking = np.clip(0.1 * (release + 0.1 - t) / 0.1, 0.0, 0.1)  # stops 0.1 s after
    twitch = 0.012 * np.sign(np.sin(2 * np.pi * 15.0 * t)) * (t > release + 0.2)
    coasting = 0.02 * ((t > release) & (t < release + 1.0))

    def figures(qd):
        sim = SimpleNamespace(t=t, qd_true=qd[:, None], q_true=np.cumsum(qd)[:, None] * dt)
        return release_figures(sim, release)

    stop_time, drift = figures(braking + twitch)
    assert stop_time == pytest.approx(0.1, abs=0.06) and drift < 1e-3
    stop_time, drift = figures(braking + coasting)
    assert stop_time == pytest.approx(1.0, abs=0.06) and drift == pytest.approx(0.01, abs=1e-3)


def test_benchmark_seeds_and_uncalibrated_factory(robot):
    """``--seeds`` picks the plants of the full set; ``--uncalibrated`` never calibrates."""
    from leadthrough.experiments.guiding import cases, uncalibrated_factory

    held_out = cases("full", (5, 6))
    assert len(held_out) == 28 and {c.seed for c in held_out} == {5, 6}
    assert len(cases("full")) == 56 and {c.seed for c in cases("full")} == {1, 2, 3, 4}
    for mode in ("passive", "active"):
        controller = uncalibrated_factory(robot, mode)
        assert not controller.calibrating and controller.mode == mode


def test_coarser_encoders_report_coarser_angles(robot):
    """``encoder_counts``: the twin's angles fall on the joint quantum 2π / (counts · gear).

    The plant is otherwise the one the default count draws; the measured angle is the true
    one rounded to the quantum, so it errs by at most half of it, and by more than the
    default's quantum once the encoder is 64× coarser.
    """
    fine = sample_plant(robot, 3, "dry")
    coarse = sample_plant(robot, 3, "dry", PlantRanges(encoder_counts=256))
    assert coarse.config.sensors.encoder_counts == 256
    same_count = dataclasses.replace(
        coarse.config.sensors, encoder_counts=SensorModel.encoder_counts
    )
    assert same_count == fine.config.sensors
    q0 = robot.home() + 0.0123
    errors = {}
    for name, plant in (("fine", fine), ("coarse", coarse)):
        twin = DigitalTwin(robot, plant.config, q0=q0)
        quantum = plant.config.sensors.quantum(robot)
        error = np.abs(twin.read_state().q - twin.truth.q)
        assert np.all(error <= 0.5 * quantum + 1e-12)
        errors[name] = error
    assert np.max(errors["coarse"]) > np.max(fine.config.sensors.quantum(robot))


@pytest.mark.parametrize("field, value, says", [
    ("position_amplitude", 1.0, "position_amplitude: must be in [0, 1), got 1.0"),
    ("friction_scale", (1.3, 0.7), "friction_scale: must be > 0, LOW ≤ HIGH, got (1.3, 0.7)"),
    ("static_ratio", (0.9, 1.2), "static_ratio: must be ≥ 1"),
    ("delay_periods", (1, 2.5), "delay_periods: must be whole periods ≥ 0"),
    ("torque_offset", (-0.1, float("nan")), "torque_offset: must be finite"),
    ("start_spread", -0.1, "start_spread: must be ≥ 0, got -0.1"),
    ("encoder_counts", 0, "encoder_counts: must be a whole number ≥ 1, got 0"),
])  # fmt: skip
def test_a_plant_range_outside_what_it_allows_is_a_one_line_error(field, value, says):
    """A family is checked where it is made, not when a plant of it is drawn mid-run."""
    with pytest.raises(ParameterError) as error:
        PlantRanges(**{field: value})
    assert says in str(error.value) and "\n" not in str(error.value)


def test_the_friction_study_runs_on_a_dry_twin_and_knows_its_truth(robot):
    """run_friction_study reads a dry twin's true level (its Stribeck-free τ_C(q))."""
    from leadthrough.experiments.friction_study import run_friction_study

    study = run_friction_study(robot, twin_config=TwinConfig(friction_physics="dry"), joints=[6])
    coulomb_error, _ = study.errors()
    assert abs(coulomb_error[6]) < 0.1
