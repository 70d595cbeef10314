"""Compiled kernels equal their NumPy references; the whole stack runs at 1 kHz."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.admittance import dead_zone
from leadthrough.estimation.observer import MomentumObserver
from leadthrough.friction.model import FrictionModel
from leadthrough.safety.checks import FrozenEncoders, in_range, within_bounds
from leadthrough.safety.supervisor import SupervisorState
from leadthrough.trajectories import minimum_jerk_phase
from leadthrough.twin.operator import During
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.runner import simulate
from leadthrough.twin.scenarios import scenario
from leadthrough.twin.simulator import DigitalTwin
from test_speed_reference import CASES


@pytest.fixture(scope="module")
def yumi() -> lt.RobotDescription:
    """The shipped YuMi description."""
    return lt.robots.yumi()


def _observer_run(
    yumi, friction: FrictionModel, compiled: bool, sliding: bool, **parameters: float
) -> np.ndarray:
    """τ̂_ext, std and error_std over 5000 seeded random periods, with a reset every 1000.

    ``sliding``: the friction taken as applied is the mean at the law's sliding velocity.
    """
    rng = np.random.default_rng(3)
    dynamics = lt.Dynamics(yumi)
    observer = MomentumObserver(dynamics, friction, 0.004, **parameters)
    observer.compiled = compiled
    rows = []
    for k in range(5000):
        if k % 1000 == 999:
            observer.reset()
        q = rng.uniform(yumi.q_min, yumi.q_max)
        qd = rng.normal(0.0, (1e-3, 0.05, 1.0)[k % 3], yumi.n_joints)
        mean = friction.mean(dead_zone(qd, 0.01), q) if sliding else None
        estimate = observer.update(q, qd, rng.normal(0.0, 5.0, yumi.n_joints),
                                   friction_mean=mean)  # fmt: skip
        rows.append(np.concatenate([estimate, observer.std, observer.error_std]))
    return np.array(rows)


@pytest.mark.parametrize("sliding", [False, True], ids=["measured", "sliding mean"])
def test_compiled_observer_step_equals_the_numpy_reference(yumi, sliding):
    """Time-varying filter, with a position-dependent friction too: equal to 1e-12."""
    nominal = FrictionModel.from_robot(yumi)
    cable = replace(nominal, position_linear=np.full(7, 0.1), position_quadratic=np.full(7, 0.05))
    for friction in (nominal, cable):
        compiled = _observer_run(yumi, friction, compiled=True, sliding=sliding)
        reference = _observer_run(yumi, friction, compiled=False, sliding=sliding)
        np.testing.assert_allclose(compiled, reference, rtol=1e-12, atol=1e-12)


def test_compiled_observer_step_takes_each_joints_torque_noise(yumi):
    """Joints with their own Q_τ (``max_lag`` raises two noisy ones): equal to 1e-12."""
    nominal = FrictionModel.from_robot(yumi)
    noisy = replace(nominal, noise_std=nominal.noise_std * np.array([1, 8, 1, 5, 1, 1, 1]))
    runs = [_observer_run(yumi, noisy, compiled, False, torque_noise=100.0, max_lag=0.02)
            for compiled in (True, False)]  # fmt: skip
    np.testing.assert_allclose(runs[0], runs[1], rtol=1e-12, atol=1e-12)
    torque_noise = MomentumObserver(lt.Dynamics(yumi), noisy, 0.004, torque_noise=100.0,
                                    max_lag=0.02).torque_noise  # fmt: skip
    assert np.count_nonzero(torque_noise > 100.0) == 2  # the two noisy joints


@pytest.mark.parametrize(
    "case", ["active", "passive, constraints", "active, sensor fault", "active, calibration"]
)
def test_step_with_the_numpy_observer_equals_the_compiled_one(case, monkeypatch):
    """Whole steps (modes, constraints, a fault, calibration): equal to 1e-12."""
    compiled = CASES[case]()
    monkeypatch.setattr(MomentumObserver, "compiled", False)
    np.testing.assert_allclose(compiled, CASES[case](), rtol=1e-12, atol=1e-12)


def test_range_check_agrees_with_numpy_comparisons():
    """Random readings with NaN, ±inf, values on the bounds and wrong shapes."""
    rng = np.random.default_rng(5)
    low, high = -np.arange(1.0, 22.0), np.arange(1.0, 22.0)
    for _ in range(3000):
        readings = [rng.uniform(-1.2, 1.2, 7) * high[:7] for _ in range(rng.integers(1, 4))]
        for reading in readings:
            if rng.random() < 0.2:
                reading[rng.integers(7)] = rng.choice([np.nan, np.inf, -np.inf, 1.0, -1.0])
        values = np.concatenate(readings)
        expected = bool(np.all((values >= low[: values.size]) & (values <= high[: values.size])))
        assert in_range(tuple(readings), low, high, 7) is expected
        assert within_bounds(readings[0], low, high, 0) is bool(
            np.all((readings[0] >= low[:7]) & (readings[0] <= high[:7]))
        )
    assert not in_range((np.zeros(6),), low, high, 7)


def test_frozen_encoder_count_equals_the_numpy_formula():
    """Bit-identical repeats (−0.0 differs from 0.0) counted as the array formula does.

    A joint is frozen once its (q, q̇) repeated ``periods`` times with |q̇| above the
    speed; the sample is stale once q, q̇ and τ of every joint repeated so (never without τ).
    """
    rng = np.random.default_rng(6)
    n, periods, speed = 4, 5, 0.01
    encoders = FrozenEncoders(n, periods, speed)
    runs, whole, previous = np.ones(n, dtype=int), 1, None
    for k in range(3000):
        if previous is None or rng.random() < 0.3:
            q, qd = rng.choice([0.0, -0.0, 1.0], n), rng.choice([0.0, -0.0, 0.005, 2.0], n)
            tau = None if rng.random() < 0.2 else rng.choice([0.0, -0.0, 3.0], n)
        reason = encoders.update(q.copy(), qd.copy(), None if tau is None else tau.copy())
        bits = np.concatenate((q, qd, np.zeros(n) if tau is None else tau)).view(np.uint64)
        if previous is not None:
            same = bits == previous[0]
            runs = runs * (same[:n] & same[n : 2 * n]) + 1
            whole = whole + 1 if tau is not None and previous[1] and same.all() else 1
        previous = bits, tau is not None
        frozen = np.flatnonzero((runs >= periods) & (np.abs(qd) > speed))
        np.testing.assert_array_equal(encoders.frozen(), (runs >= periods) | (whole >= periods))
        assert (reason is None) == (frozen.size == 0 and whole < periods), k
        if frozen.size:
            assert reason.startswith(f"joint {frozen[0] + 1} encoder frozen"), reason
        elif reason is not None:
            assert reason.startswith("sensor data stale"), reason


def test_minimum_jerk_phase_of_one_time_equals_numpy_scalar_math():
    """Float math for one time gives the bits of NumPy's 0-d arithmetic, outside too."""
    for t in np.random.default_rng(7).uniform(-0.5, 3.0, 20000):
        assert minimum_jerk_phase(float(t), 2.5) == minimum_jerk_phase(np.asarray(t), 2.5)
    assert np.isnan(minimum_jerk_phase(float("nan"), 2.5)[0])


def test_friction_terms_follow_the_values_not_the_array(yumi):
    """A q̇ changed in place between calls gets its own mean and std (nothing stale)."""
    friction = FrictionModel.from_robot(yumi)
    qd = np.full(7, 0.01)
    first = friction.mean(qd)
    qd[:] = -0.5
    np.testing.assert_array_equal(friction.mean(qd), FrictionModel.from_robot(yumi).mean(qd))
    assert not np.array_equal(friction.mean(qd), first)


def test_one_kilohertz_stack_guides_and_the_released_arm_stops(yumi):
    """LeadThrough at dt = 1 ms on the twin controlled at 1 kHz: a hand pulls, lets go.

    The calibration is accepted, the supervisor never faults, the tool follows the hand,
    commands stay within the limits; after the release the arm stops: from 0.5 s on its
    50 ms mean joint speeds stay below 0.01 rad/s and it moves less than 1 mrad. (The
    15 Hz dither shakes the wrist at up to ~0.014 rad/s peak at 1 kHz, zero mean.)
    """
    dt, grab, release = 0.001, 1.0, 3.25
    config = replace(REALISTIC_TWIN, control_dt=dt)
    chosen = scenario("line", yumi, config)
    twin = DigitalTwin(yumi, config, During(chosen.operator, grab, release), chosen.q0)
    controller = lt.LeadThrough(yumi, "active", dt=dt, calibrate=True)
    sim = simulate(twin, controller, release + 2.5, progress=False)
    assert controller.state is SupervisorState.TEACHING, controller.supervisor.fault_reason
    assert controller.calibration is not None and controller.calibration.accepted
    assert np.all(np.abs(sim.tau_command) <= yumi.torque_limits + 1e-9)
    at_release = np.searchsorted(sim.t, release)
    assert np.linalg.norm(sim.flange_position[at_release] - sim.flange_position[0]) > 0.1
    settled = sim.t >= release + 0.5
    window = round(0.05 / dt)
    speeds = sim.qd_true[settled]
    mean_speed = np.array([np.convolve(s, np.ones(window) / window, "valid") for s in speeds.T])
    assert np.max(np.abs(mean_speed)) < 0.01
    assert np.max(np.abs(sim.q_true[settled] - sim.q_true[settled][0])) < 1e-3
