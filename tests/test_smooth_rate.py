"""Tests of the ``"smooth_rate"`` observer: exact discretisation, ramps, an honest std."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.linalg import expm

import leadthrough as lt
from leadthrough.errors import ParameterError
from leadthrough.estimation import smooth_rate
from leadthrough.estimation.observer import MomentumObserver, stationary_filter
from leadthrough.experiments.stability import worst_damping
from test_observer import DT, STEP, STEP_TIME, make_data, run

R = 1e-8  # momentum noise intensity the variant is measured with [(kg m²/s)² s]
Q_R = 1e3  # torque-rate noise intensity [Nm²/s³]


def van_loan(model_noise: float, rate_noise: float, dt: float) -> np.ndarray:
    """Q_d = ∫₀^dt e^{As} Q e^{Aᵀs} ds of the 3-state model (Van Loan)."""
    a = np.diag([1.0, 1.0], k=1)
    block = np.zeros((6, 6))
    block[:3, :3], block[:3, 3:], block[3:, 3:] = -a, np.diag([model_noise, 0.0, rate_noise]), a.T
    exponential = expm(block * dt)
    return exponential[3:, 3:].T @ exponential[:3, 3:]


@pytest.mark.parametrize("model_noise", [0.0, 2e-5, 0.01])
def test_discretisation_is_exact(model_noise):
    """Φ is e^{A dt} and Q_d equals Van Loan's integral."""
    np.testing.assert_allclose(smooth_rate.transition(DT), expm(np.diag([DT, DT], k=1)),
                               rtol=1e-12)  # fmt: skip
    np.testing.assert_allclose(smooth_rate.process_noise(model_noise, Q_R, DT),
                               van_loan(model_noise, Q_R, DT), rtol=1e-9, atol=1e-22)  # fmt: skip


def test_stationary_gain_is_the_limit_of_the_recursion():
    """The DARE gain equals the Kalman recursion iterated to convergence."""
    phi, process = smooth_rate.transition(DT), van_loan(2e-5, Q_R, DT)
    covariance = np.eye(3)
    for _ in range(20_000):
        prior = phi @ covariance @ phi.T + process
        gain = prior[:, 0] / (prior[0, 0] + R / DT)
        covariance = prior - np.outer(gain, prior[0])
    expected_gain, expected_covariance = smooth_rate.stationary_filter(2e-5, Q_R, R, DT)
    np.testing.assert_allclose(gain, expected_gain, rtol=1e-8)
    np.testing.assert_allclose(covariance, expected_covariance, rtol=1e-6, atol=1e-14)


def track_ramp(gain_p: float, gain_tau: float, gain_rate: float, slope: float) -> np.ndarray:
    """τ̂ − τ of a filter fed the exact momentum of a torque ramp ``slope`` [Nm/s] (u = 0)."""
    t = np.arange(1, 2001) * DT
    momentum = 0.5 * slope * t**2  # ṗ = τ = slope · t
    p, tau, rate = np.zeros(1), np.zeros(1), np.zeros(1)
    errors = []
    for k, y in enumerate(momentum):
        prior = p + DT * (tau + 0.5 * DT * rate)
        innovation = y - prior
        p, tau = prior + gain_p * innovation, tau + DT * rate + gain_tau * innovation
        rate = rate + gain_rate * innovation
        errors.append(tau[0] - slope * t[k])
    return np.array(errors)


def test_a_ramp_is_tracked_without_steady_state_lag():
    """After settling, τ̂ of a 10 Nm/s ramp has no lag; the 2-state filter's lags it."""
    gain, _ = smooth_rate.stationary_filter(2e-5, Q_R, R, DT)
    assert abs(track_ramp(*gain, slope=10.0)[-1]) < 1e-6
    two_state, _ = stationary_filter(0.0056, 100.0, 1e-6, DT)
    assert abs(track_ramp(*two_state, 0.0, slope=10.0)[-1]) > 0.1  # what the test catches


def test_std_covers_the_monte_carlo_error_and_is_not_wider():
    """±2 std covers 90–99 % of the error of 400 simulated runs, std ≤ 1.2 × the RMS error.

    The truth is the variant's own model: a torque with a random-walk rate (Q_r), white
    friction noise (σ = 0.07 Nm), a momentum noise R, and a friction level off by a
    Gaussian of std 0.2 × 1.4 Nm per run, which the std takes as the consider term.
    """
    rng = np.random.default_rng(13)
    runs, steps, sigma, level_std = 400, 1500, 0.07, 0.2 * 1.4
    model_noise = np.full(runs, sigma**2 * DT)
    observer = smooth_rate.SmoothRateFilter(model_noise, Q_R, R, DT)
    std = np.sqrt(observer.torque_variance + level_std**2)
    level_error = rng.normal(0.0, level_std, runs)
    phi = smooth_rate.transition(DT)
    root = np.linalg.cholesky(smooth_rate.process_noise(sigma**2 * DT, Q_R, DT))
    state = np.zeros((3, runs))  # true p, τ, ṙ: sampled exactly, x ← Φ x + w
    p_hat, tau_hat = np.zeros(runs), level_error.copy()  # started where it settles
    errors = []
    for _ in range(steps):
        state = phi @ state + root @ rng.standard_normal((3, runs))
        state[0] += DT * level_error  # the wrong friction level: a constant torque
        measured = state[0] + rng.normal(0.0, np.sqrt(R / DT), runs)
        observer.step(p_hat, tau_hat, np.zeros(runs), measured)
        errors.append(tau_hat - state[1])
    error = np.array(errors)[500:]  # after the transient
    coverage = np.mean(np.abs(error) <= 2.0 * std)
    assert 0.90 <= coverage <= 0.99
    assert np.median(std) <= 1.2 * np.sqrt(np.mean(error**2))


@pytest.fixture(scope="module")
def yumi_data():
    """The synthetic YuMi record of test_observer (τ_ext step at 1 s), its model."""
    dynamics = lt.Dynamics(lt.robots.yumi())
    friction = lt.FrictionModel.from_robot(dynamics.robot)
    return dynamics, friction, make_data(dynamics, friction)


def test_the_variant_tracks_a_step_and_reports_its_std(yumi_data):
    """On the synthetic YuMi record: the step is read, and std² = P_ττ + v_C² + (0.2 mean_f)²."""
    dynamics, friction, data = yumi_data
    observer = MomentumObserver(dynamics, friction, DT, variant="smooth_rate",
                                measurement_noise=R, torque_rate_noise=Q_R)  # fmt: skip
    estimates, stds = run(observer, data.q, data.qd, data.tau)
    late = data.time > STEP_TIME + 0.3
    np.testing.assert_allclose(np.median(estimates[late], axis=0), STEP, atol=0.05)
    last_qd, last_q = data.qd[-1], data.q[-1]
    expected = np.sqrt(observer._smooth.torque_variance
                       + friction.coulomb_uncertainty(last_qd, last_q) ** 2
                       + (0.2 * friction.mean(last_qd, last_q)) ** 2)  # fmt: skip
    np.testing.assert_allclose(stds[-1], expected, rtol=1e-12)


def test_the_variant_keeps_the_coupled_loop_damped():
    """With the variant (R = 1e-8, Q_r = 1e3), every hand up to 3000 N/m keeps ζ ≥ 0.15."""
    defaults = lt.LeadThroughParameters()
    observer = dataclasses.replace(defaults.observer, variant="smooth_rate",
                                   measurement_noise=R, torque_rate_noise=Q_R)  # fmt: skip
    parameters = dataclasses.replace(defaults, observer=observer)
    robot = lt.robots.yumi()
    for stiffness in (300.0, 3000.0):
        for delay in (1, 2):
            damping = worst_damping(robot, parameters, stiffness, 1.8 * np.sqrt(stiffness),
                                    DT, delay)  # fmt: skip
            assert damping >= 0.15


@pytest.mark.parametrize("overrides", [{"torque_rate_noise": 0.0}, {"variant": "smooth"}])
def test_invalid_smooth_rate_parameters_raise(overrides):
    """A non-positive Q_r or an unknown variant is a ParameterError naming the field."""
    dynamics = lt.Dynamics(lt.robots.yumi())
    with pytest.raises(ParameterError, match=next(iter(overrides))):
        MomentumObserver(dynamics, dt=DT, **overrides)
