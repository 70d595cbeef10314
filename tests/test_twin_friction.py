"""Tests of the twin's true joint friction (LuGre + Stribeck + viscous + cable twist)."""

from __future__ import annotations

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.errors import InputShapeError
from leadthrough.twin.errors import FrictionParameterError
from leadthrough.twin.friction import (
    LuGreFriction,
    TwinFrictionParameters,
    stable_bristle_damping,
    stable_bristle_stiffness,
)

DT = 0.0005  # plant physics step [s], 2 kHz
TABLE_4_1_COULOMB = [1.5, 1.4, 0.85, 0.7, 0.25, 0.4, 0.24]
TABLE_4_1_VISCOUS = [1.1, 0.9, 0.7, 0.7, 0.05, 0.1, 0.03]
# (inertia [kg m²], τ_C [Nm], c [Nm s/rad]): a wrist joint (YuMi 4–6) and a base joint.
JOINTS = [(0.0052, 0.7, 0.7), (0.09, 1.5, 1.1)]


def one_joint(inertia: float, coulomb: float, viscous: float, **overrides) -> LuGreFriction:
    """LuGre friction of one joint with σ0, σ1 at the 2 kHz stability bounds."""
    stiffness = stable_bristle_stiffness([inertia], DT)
    values = {
        "coulomb": coulomb,
        "static": 1.3 * coulomb,
        "stribeck_velocity": 0.01,
        "viscous": viscous,
        "bristle_stiffness": stiffness,
        "bristle_damping": stable_bristle_damping(stiffness, [inertia], DT),
        "cable_amplitude": 0.15,
        "cable_neutral": 0.0,
        "cable_width": 1.0,
    }
    values.update(overrides)
    return LuGreFriction(TwinFrictionParameters(**values), DT)


def simulate(friction: LuGreFriction, inertia: float, load, duration: float):
    """Semi-implicit Euler of I q̈ = load(t) + friction, as the plant does; returns q, q̇."""
    steps = round(duration / DT)
    q, qd = np.zeros(1), np.zeros(1)
    positions, velocities = np.empty(steps), np.empty(steps)
    for k in range(steps):
        qd = qd + DT / inertia * (load(k * DT) + friction.torque(q, qd))
        q = q + DT * qd
        positions[k], velocities[k] = q[0], qd[0]
    return positions, velocities


def random_params(rng: np.random.Generator, n: int, **overrides) -> TwinFrictionParameters:
    """Random but plausible parameters for n joints."""
    coulomb = rng.uniform(0.2, 1.5, n)
    values = {
        "coulomb": coulomb,
        "static": coulomb * rng.uniform(1.0, 1.5, n),
        "stribeck_velocity": rng.uniform(0.005, 0.05, n),
        "viscous": rng.uniform(0.0, 1.0, n),
        "bristle_stiffness": rng.uniform(5e3, 1e5, n),
        "bristle_damping": rng.uniform(0.0, 50.0, n),
        "cable_amplitude": rng.uniform(0.0, 0.3, n),
        "cable_neutral": rng.uniform(-1.0, 1.0, n),
        "cable_width": rng.uniform(0.5, 2.0, n),
    }
    values.update(overrides)
    return TwinFrictionParameters(**values)


@pytest.mark.parametrize(("inertia", "coulomb", "viscous"), JOINTS)
def test_sticks_without_drift_below_breakaway(inertia, coulomb, viscous):
    """A load of 0.8 τ_S deflects the joint by −(τ_S/σ0) ln(0.2), then it never drifts."""
    friction = one_joint(inertia, coulomb, viscous)
    static, stiffness = 1.3 * coulomb, friction.params.bristle_stiffness[0]
    ramp = 0.3  # [s]: a hand loads a joint in tenths of a second, not in one 0.5 ms step

    def load(t):
        return 0.8 * static * min(t / ramp, 1.0)

    q, qd = simulate(friction, inertia, load, duration=10.0)
    after = q[round(0.5 / DT) :]
    assert np.ptp(after) < 1e-6
    assert abs(qd[-1]) < 1e-9
    # Stuck bristles: dz/dq = 1 − σ0 z / τ_S, so q = −(τ_S / σ0) ln(1 − F / τ_S).
    expected = -static / stiffness * np.log(1.0 - 0.8)
    assert q.max() < 1.1 * expected
    assert q[-1] == pytest.approx(expected, rel=0.05)
    assert friction.bristle_state[0] == pytest.approx(0.8 * static / stiffness, rel=1e-6)


@pytest.mark.parametrize(("inertia", "coulomb", "viscous"), JOINTS)
def test_a_step_below_coulomb_sticks(inertia, coulomb, viscous):
    """Even applied as a step, a load below τ_C(1 − β) leaves the joint stuck within µrad."""
    friction = one_joint(inertia, coulomb, viscous)
    q, qd = simulate(friction, inertia, lambda t: 0.8 * coulomb, duration=2.0)
    assert np.ptp(q[round(0.5 / DT) :]) < 1e-6
    assert abs(qd[-1]) < 1e-9
    assert q.max() < 5.0 * 1.3 * coulomb / friction.params.bristle_stiffness[0]


@pytest.mark.parametrize(("inertia", "coulomb", "viscous"), JOINTS)
def test_slides_above_breakaway(inertia, coulomb, viscous):
    """A load of 1.2 τ_S breaks away and drives the joint to (F − τ_C(q)) / c."""
    friction = one_joint(inertia, coulomb, viscous)
    force = 1.2 * 1.3 * coulomb
    q, qd = simulate(friction, inertia, lambda t: force, duration=2.0)
    assert q[-1] > 0.5
    assert np.all(np.diff(q[100:]) > 0.0)
    terminal = (force - friction.params.coulomb_level(q[-1:])[0]) / viscous
    assert qd[-1] == pytest.approx(terminal, rel=0.02)


def test_undamped_bristles_do_not_inject_energy_at_2khz():
    """With σ1 = c = 0 the stuck joint's bristle oscillation decays: the coupling is symplectic."""
    inertia, coulomb = 0.0052, 0.7
    friction = one_joint(inertia, coulomb, 0.0, bristle_damping=0.0)
    _, qd = simulate(friction, inertia, lambda t: 0.3 * coulomb, duration=2.0)
    assert np.all(np.isfinite(qd))
    envelope = np.abs(qd).reshape(-1, 200).max(axis=1)  # per 0.1 s
    assert np.all(np.diff(envelope) < 0.0)
    assert envelope[-1] < 0.05 * envelope[0]


def test_steady_sliding_matches_stribeck_curve():
    """At constant velocity the torque converges to −(g(q̇, q) sign q̇ + c q̇)."""
    rng = np.random.default_rng(1)
    n = 40
    params = random_params(rng, n)
    velocity = rng.choice([-1.0, 1.0], n) * np.geomspace(1e-3, 2.0, n)
    position = rng.uniform(-3.0, 3.0, n)
    friction = LuGreFriction(params, DT)
    for _ in range(round(20.0 / DT)):
        torque = friction.torque(position, velocity)
    p = params
    coulomb = p.coulomb * (
        1.0 + p.cable_amplitude * np.tanh((position - p.cable_neutral) / p.cable_width)
    )
    level = coulomb + (p.static - p.coulomb) * np.exp(-((velocity / p.stribeck_velocity) ** 2))
    expected = -(np.sign(velocity) * level + p.viscous * velocity)
    np.testing.assert_allclose(torque, expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(friction.steady_state(velocity, position), expected, rtol=1e-12)


def test_steady_state_curve_shape():
    """The steady curve is odd in q̇, peaks at τ_S near q̇ = 0+ and tends to τ_C + c q̇."""
    params = TwinFrictionParameters.from_robot(lt.robots.yumi())
    friction = LuGreFriction(params, DT)
    q = params.cable_neutral
    slow = friction.steady_state(np.full(7, 1e-9), q)
    fast = friction.steady_state(np.full(7, 1.0), q)
    np.testing.assert_allclose(slow, -params.static, rtol=1e-9)
    np.testing.assert_allclose(fast, -(params.coulomb + params.viscous), rtol=1e-9)
    np.testing.assert_allclose(
        friction.steady_state(-np.full(7, 0.3), q), -friction.steady_state(np.full(7, 0.3), q)
    )
    grid = np.linspace(-0.5, 0.5, 101)[:, None] * np.ones(7)
    assert friction.steady_state(grid, q).shape == (101, 7)
    assert np.all(friction.steady_state(np.zeros(7), q) == 0.0)


def test_friction_dissipates_over_a_period():
    """On sinusoidal motions, from sticking to sliding, friction never does positive work."""
    rng = np.random.default_rng(2)
    n = 30
    params = random_params(rng, n)
    amplitude = np.geomspace(1e-6, 1.0, n)
    frequency = rng.uniform(0.5, 20.0, n)
    friction = LuGreFriction(params, DT)
    periods = 3
    steps = round(periods / frequency.min() / DT)
    work = np.zeros(n)
    done = np.zeros(n)
    omega = 2.0 * np.pi * frequency
    for k in range(steps):
        t = k * DT
        q = amplitude * np.sin(omega * t)
        qd = amplitude * omega * np.cos(omega * t)
        power = friction.torque(q, qd) * qd
        active = t < periods / frequency  # whole periods only
        work += np.where(active, power * DT, 0.0)
        done = np.where(active, work, done)
        assert np.all(work <= 1e-15 * amplitude)
    assert np.all(done < 0.0)


def test_bristle_update_is_exact_and_bounded_for_any_dt():
    """The z step is the exact frozen-v flow: stable and bounded for dt up to 1 s."""
    rng = np.random.default_rng(3)
    n = 25
    params = random_params(rng, n, bristle_stiffness=rng.uniform(1e3, 1e7, n))
    q = rng.uniform(-3.0, 3.0, n)
    level_max = params.coulomb * (1.0 + params.cable_amplitude) + params.static - params.coulomb
    for dt in (0.01, 1.0):
        friction = LuGreFriction(params, dt)
        rate_gain = params.bristle_damping / (params.bristle_stiffness * dt)
        for _ in range(500):
            qd = rng.normal(0.0, 1.0, n) * rng.choice([1e-4, 1e-2, 1.0, 10.0], n)
            torque = friction.torque(q, qd)
            assert np.all(np.isfinite(torque))
            assert np.all(
                np.abs(friction.bristle_state) <= level_max / params.bristle_stiffness * (1 + 1e-12)
            )
            bound = level_max * (1.0 + 2.0 * rate_gain) + params.viscous * np.abs(qd)
            assert np.all(np.abs(torque) <= bound * (1 + 1e-12))
    qd = rng.normal(0.0, 0.05, n)
    coarse, fine = LuGreFriction(params, 0.01), LuGreFriction(params, 0.0001)
    coarse.torque(q, qd)
    for _ in range(100):
        fine.torque(q, qd)
    np.testing.assert_allclose(coarse.bristle_state, fine.bristle_state, rtol=1e-9, atol=1e-15)


def test_cable_term_differs_between_range_ends():
    """Sliding at q_max and q_min, the Coulomb levels differ by 2 tanh(2) β τ_C, bounded."""
    robot = lt.robots.yumi()
    params = TwinFrictionParameters.from_robot(robot)
    speed = np.full(7, 0.5)  # 50 v_s: the Stribeck term is exp(−2500) = 0
    levels = []
    for q in (robot.q_min, robot.q_max):
        friction = LuGreFriction(params, DT)
        for _ in range(2000):
            torque = friction.torque(q, speed)
        levels.append(-torque - params.viscous * speed)
    difference = levels[1] - levels[0]
    np.testing.assert_allclose(difference, 2.0 * np.tanh(2.0) * 0.15 * params.coulomb, rtol=1e-9)
    rng = np.random.default_rng(4)
    q = rng.uniform(-100.0, 100.0, (1000, 7))
    level = params.coulomb_level(q)
    assert np.all(np.abs(level - params.coulomb) <= 0.15 * params.coulomb * (1 + 1e-12))
    np.testing.assert_allclose(params.coulomb_level(params.cable_neutral), params.coulomb)


def test_from_robot_carries_table_4_1():
    """from_robot takes τ_C and c from Table 4.1, τ_S = 1.3 τ_C, and ``scale`` scales all three."""
    robot = lt.robots.yumi()
    params = TwinFrictionParameters.from_robot(robot)
    np.testing.assert_allclose(params.coulomb, TABLE_4_1_COULOMB)
    np.testing.assert_allclose(params.viscous, TABLE_4_1_VISCOUS)
    np.testing.assert_allclose(params.static, 1.3 * np.array(TABLE_4_1_COULOMB))
    np.testing.assert_allclose(params.cable_neutral, (robot.q_min + robot.q_max) / 2)
    np.testing.assert_allclose(params.cable_width, (robot.q_max - robot.q_min) / 4)
    scaled = TwinFrictionParameters.from_robot(robot, scale=0.8, static_ratio=1.5)
    np.testing.assert_allclose(scaled.coulomb, 0.8 * np.array(TABLE_4_1_COULOMB))
    np.testing.assert_allclose(scaled.static, 1.2 * np.array(TABLE_4_1_COULOMB))
    np.testing.assert_allclose(scaled.viscous, 0.8 * np.array(TABLE_4_1_VISCOUS))
    assert not params.coulomb.flags.writeable


def test_from_robot_defaults_are_stable_at_2khz():
    """Default σ0, σ1 meet a + 2b < 4 on the rotor inertia, and pre-slide ≥ 1e-5 rad."""
    robot = lt.robots.yumi()
    params = TwinFrictionParameters.from_robot(robot)
    inertia = robot.reflected_rotor_inertias
    a = params.bristle_stiffness * DT**2 / inertia
    b = (params.bristle_damping + params.viscous) * DT / inertia
    assert np.all(a <= 0.25 + 1e-12)
    assert np.all(a + 2 * b < 2.0)
    assert np.all(params.static / params.bristle_stiffness >= 1e-5 * (1 - 1e-12))
    loose = TwinFrictionParameters.from_robot(robot, dt=None)
    np.testing.assert_allclose(loose.static / loose.bristle_stiffness, 1e-5)
    given = TwinFrictionParameters.from_robot(robot, bristle_stiffness=1e4, bristle_damping=3.0)
    np.testing.assert_allclose(given.bristle_stiffness, 1e4)
    np.testing.assert_allclose(given.bristle_damping, 3.0)


def test_decoupled_yumi_joints_stay_bounded_under_random_pushes():
    """Seven joints on their rotor inertias, pushed at random at 2 kHz, stay finite and slow."""
    robot = lt.robots.yumi()
    params = TwinFrictionParameters.from_robot(robot)
    friction = LuGreFriction(params, DT)
    inertia = robot.reflected_rotor_inertias
    rng = np.random.default_rng(5)
    q, qd = robot.home(), np.zeros(7)
    push = np.zeros(7)
    for k in range(4000):
        if k % 100 == 0:
            push = rng.uniform(-2.0, 2.0, 7) * params.static
        qd = qd + DT / inertia * (push + friction.torque(q, qd))
        q = q + DT * qd
        assert np.all(np.isfinite(qd))
    # Terminal speed bound: |push| ≤ 2 τ_S, so |q̇| ≤ (2 τ_S − τ_C(1 − β)) / c.
    assert np.all(np.abs(qd) <= (2.0 * params.static - 0.85 * params.coulomb) / params.viscous)


def test_state_reset_and_read_only():
    """reset() relaxes the bristles and bristle_state cannot be written."""
    friction = LuGreFriction(TwinFrictionParameters.from_robot(lt.robots.yumi()), DT)
    friction.torque(np.zeros(7), np.full(7, 0.1))
    assert np.all(friction.bristle_state > 0.0)
    with pytest.raises(ValueError, match="read-only"):
        friction.bristle_state[0] = 1.0
    friction.reset()
    assert np.all(friction.bristle_state == 0.0)


@pytest.mark.parametrize(
    ("override", "match"),
    [
        ({"static": [1.0, 0.5]}, r"^static\[1\]: must be ≥ coulomb \(0\.7\), got 0\.5$"),
        ({"viscous": [0.1, -1.0]}, r"^viscous\[1\]: must be ≥ 0"),
        ({"stribeck_velocity": 0.0}, r"^stribeck_velocity\[0\]: must be > 0"),
        ({"bristle_stiffness": [1e4, -1.0]}, r"^bristle_stiffness\[1\]: must be > 0"),
        ({"cable_amplitude": 1.0}, r"^cable_amplitude\[0\]: must be < 1"),
        ({"cable_width": [1.0, np.nan]}, r"^cable_width\[1\]: must be finite$"),
        ({"coulomb": [0.7, 0.7, 0.7]}, r"^coulomb: shapes do not match"),
        ({"cable_neutral": [[0.0]]}, r"^cable_neutral: expected shape \(n,\)"),
    ],
)
def test_invalid_parameters_raise_one_line_errors(override, match):
    """Each invalid field raises a one-line FrictionParameterError naming field and joint."""
    values = {
        "coulomb": [0.7, 0.7],
        "static": [0.9, 0.9],
        "stribeck_velocity": 0.01,
        "viscous": 0.5,
        "bristle_stiffness": 1e4,
        "bristle_damping": 5.0,
        "cable_amplitude": 0.15,
        "cable_neutral": 0.0,
        "cable_width": 1.0,
    }
    values.update(override)
    with pytest.raises(FrictionParameterError, match=match) as error:
        TwinFrictionParameters(**values)
    assert "\n" not in str(error.value)


def test_invalid_arguments_raise():
    """Bad from_robot arguments, dt and input shapes raise clear errors."""
    robot = lt.robots.yumi()
    with pytest.raises(FrictionParameterError, match=r"^scale: must be >= 0"):
        TwinFrictionParameters.from_robot(robot, scale=-1.0)
    with pytest.raises(FrictionParameterError, match=r"^static_ratio: must be >= 1"):
        TwinFrictionParameters.from_robot(robot, static_ratio=0.9)
    with pytest.raises(FrictionParameterError, match=r"^inertia\[2\]: must be finite and > 0"):
        TwinFrictionParameters.from_robot(robot, inertia=[0.1, 0.1, 0.0, 0.1, 0.1, 0.1, 0.1])
    params = TwinFrictionParameters.from_robot(robot)
    with pytest.raises(FrictionParameterError, match=r"^dt: must be > 0"):
        LuGreFriction(params, dt=0.0)
    with pytest.raises(InputShapeError, match=r"^qd: expected shape \(7,\), got \(6,\)$"):
        LuGreFriction(params, DT).torque(np.zeros(7), np.zeros(6))
