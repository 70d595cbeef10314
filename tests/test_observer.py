"""Tests of the momentum Kalman observer and the classical baseline (thesis ch. 5, SPEC §5).

Synthetic data only (no simulator): a smooth YuMi trajectory, a known external torque and
the motor torque that realises it by SPEC §1, ``τ = M q̈ + C q̇ + G + mean_f(q̇) − τ_ext``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from scipy.linalg import expm

import leadthrough as lt
from leadthrough.errors import ParameterError
from leadthrough.estimation.classical import ClassicalMomentumObserver
from leadthrough.estimation.observer import (
    MomentumObserver,
    ObserverParameters,
    joint_torque_noise,
    process_noise,
    ramp_lag,
    stationary_filter,
)
from leadthrough.friction.model import FrictionModel

N = 7
DT = 0.004
R_THESIS = 1e-6  # momentum measurement noise intensity, thesis eq. (5.17)
Q_TAU_THESIS = 10.0  # external torque random-walk intensity, thesis eq. (5.18)
STEP_TIME = 1.0  # [s], on the sample grid
STEP = np.array([1.5, 0.0, 0.0, -0.8, 0.0, 0.0, 0.0])  # τ_ext after STEP_TIME [Nm]
AMPLITUDE, OMEGA = 0.3, np.pi  # 0.3 rad at 0.5 Hz on every joint
PHASE = np.linspace(0.0, 0.6, N)  # [rad], so the joints do not reverse together
DURATION = 3.0  # [s]
SUBSAMPLES = 16  # midpoints per period for the period-averaged motor torque
REVERSAL_WINDOW = 0.04  # [s] either side of a velocity reversal


# --- fixtures: model and synthetic data --------------------------------------------------


@pytest.fixture(scope="module")
def dynamics() -> lt.Dynamics:
    """The YuMi's rigid-body model."""
    return lt.Dynamics(lt.robots.yumi())


@pytest.fixture(scope="module")
def friction(dynamics) -> FrictionModel:
    """The YuMi's friction model (thesis Table 4.1)."""
    return FrictionModel.from_robot(dynamics.robot)


@dataclass(frozen=True)
class Data:
    """Samples k = 0..K−1 at t_k = k dt; tau[k] is the motor torque averaged over (t_{k−1}, t_k]."""

    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    tau_ext: np.ndarray


def trajectory(robot: lt.RobotDescription, t: np.ndarray):
    """q, q̇, q̈ of sinusoids of 0.3 rad at 0.5 Hz around the home pose, shapes (..., n)."""
    angle = OMEGA * np.asarray(t, dtype=float)[..., None] + PHASE
    q = robot.home() + AMPLITUDE * np.sin(angle)
    qd = AMPLITUDE * OMEGA * np.cos(angle)
    qdd = -AMPLITUDE * OMEGA**2 * np.sin(angle)
    return q, qd, qdd


def external_torque(t: np.ndarray) -> np.ndarray:
    """The true τ_ext(t) [Nm], SPEC §1 sign: a step at STEP_TIME on joints 1 and 4."""
    return np.where(np.asarray(t, dtype=float)[..., None] >= STEP_TIME, STEP, 0.0)


def make_data(dynamics: lt.Dynamics, friction: FrictionModel) -> Data:
    """Sampled states and the period-averaged motor torque that realises τ_ext by SPEC §1."""
    robot = dynamics.robot
    time = np.arange(round(DURATION / DT) + 1) * DT
    q, qd, _ = trajectory(robot, time)
    tau = np.zeros_like(q)
    for k in range(1, len(time)):
        ts = time[k - 1] + (np.arange(SUBSAMPLES) + 0.5) / SUBSAMPLES * DT
        qs, qds, qdds = trajectory(robot, ts)
        rigid = np.array(
            [dynamics.inverse_dynamics(*state) for state in zip(qs, qds, qdds, strict=True)]
        )
        # M q̈ + C q̇ + G + τ_f = τ + τ_ext  ⇒  τ = rigid + mean_f − τ_ext
        tau[k] = (rigid + friction.mean(qds) - external_torque(ts)).mean(axis=0)
    return Data(time, q, qd, tau, external_torque(time))


@pytest.fixture(scope="module")
def data(dynamics, friction) -> Data:
    """Three seconds of the synthetic trajectory with the τ_ext step at 1 s."""
    return make_data(dynamics, friction)


def run(observer, q, qd, tau) -> tuple[np.ndarray, np.ndarray]:
    """Estimates and reported stds of an observer over a whole record, each (K, n)."""
    estimates, stds = [], []
    for row in zip(q, qd, tau, strict=True):
        estimates.append(observer.update(*row))
        stds.append(observer.std)
    return np.array(estimates), np.array(stds)


def _inputs(data: Data) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The observer inputs (q, q̇, τ) of a record."""
    return data.q, data.qd, data.tau


def make_observer(kind: str, dynamics, friction):
    """An observer of the given kind at DT with default tuning."""
    if kind == "classical":
        return ClassicalMomentumObserver(dynamics, friction, dt=DT)
    return MomentumObserver(dynamics, friction, dt=DT, variant=kind)


def away_from_reversals(data: Data) -> np.ndarray:
    """(K, n) mask: samples farther than REVERSAL_WINDOW from any velocity zero of that joint."""
    crossings = [data.time[np.flatnonzero(np.diff(np.sign(data.qd[:, j])) != 0)] for j in range(N)]
    mask = np.ones(data.q.shape, dtype=bool)
    for j, times in enumerate(crossings):
        for t in times:
            mask[np.abs(data.time - t) <= REVERSAL_WINDOW, j] = False
    return mask


# --- discretisation ----------------------------------------------------------------------


def van_loan(model_noise: float, torque_noise: float, dt: float) -> np.ndarray:
    """Q_d = ∫₀^dt e^{As} Q e^{Aᵀs} ds by Van Loan's matrix exponential, A = [[0,1],[0,0]]."""
    a = np.array([[0.0, 1.0], [0.0, 0.0]])
    q = np.diag([model_noise, torque_noise])
    block = np.zeros((4, 4))
    block[:2, :2], block[:2, 2:], block[2:, 2:] = -a, q, a.T
    exponential = expm(block * dt)
    transition = exponential[2:, 2:].T
    return transition @ exponential[:2, 2:]


@pytest.mark.parametrize("model_noise", [0.0, 1e-4, 0.0056, 2.25, 50.0])
def test_process_noise_equals_van_loan(model_noise):
    """process_noise gives the exact discretisation of diag(Q_m, Q_τ) (Van Loan)."""
    expected = van_loan(model_noise, Q_TAU_THESIS, DT)
    q11, q12, q22 = process_noise(np.array([model_noise, model_noise]), Q_TAU_THESIS, DT)
    np.testing.assert_allclose(q11, expected[0, 0], rtol=1e-9, atol=1e-18)
    np.testing.assert_allclose(q12, expected[0, 1], rtol=1e-9)
    np.testing.assert_allclose(q12, expected[1, 0], rtol=1e-9)
    np.testing.assert_allclose(q22, expected[1, 1], rtol=1e-9)


def test_process_noise_is_per_joint():
    """Each joint's Q₁₁ uses its own Q_m; Q₁₂ and Q₂₂ come from Q_τ only."""
    model_noise = np.array([0.0, 0.01, 1.0, 3.0])
    q11, q12, q22 = process_noise(model_noise, 4.0, 0.001)
    for j, qm in enumerate(model_noise):
        expected = van_loan(qm, 4.0, 0.001)
        np.testing.assert_allclose([q11[j], q12[j], q22[j]], expected[[0, 0, 1], [0, 1, 1]],
                                   rtol=1e-9)  # fmt: skip


def iterate_covariance(model_noise: float, torque_noise: float, noise: float, dt: float):
    """Kalman gain and posterior std of τ_ext after iterating predict/update to convergence."""
    transition = np.array([[1.0, dt], [0.0, 1.0]])
    output = np.array([[1.0, 0.0]])
    process = van_loan(model_noise, torque_noise, dt)
    covariance = np.diag([0.0, torque_noise])
    gain = np.zeros(2)
    for _ in range(200_000):
        prior = transition @ covariance @ transition.T + process
        innovation_variance = (output @ prior @ output.T)[0, 0] + noise / dt
        new_gain = (prior @ output.T)[:, 0] / innovation_variance
        covariance = (np.eye(2) - np.outer(new_gain, output)) @ prior
        if np.allclose(new_gain, gain, rtol=1e-14, atol=0.0):
            break
        gain = new_gain
    return new_gain, float(np.sqrt(covariance[1, 1]))


@pytest.mark.parametrize("model_noise", [1e-4, 0.0056, 0.5, 2.25])
def test_stationary_filter_is_limit_of_covariance_recursion(model_noise):
    """stationary_filter's gain and std equal the converged time-varying recursion."""
    gain, std = stationary_filter(model_noise, Q_TAU_THESIS, R_THESIS, DT)
    expected_gain, expected_std = iterate_covariance(model_noise, Q_TAU_THESIS, R_THESIS, DT)
    np.testing.assert_allclose(gain, expected_gain, rtol=1e-8)
    assert std == pytest.approx(expected_std, rel=1e-8)


def test_stationary_std_grows_with_model_noise():
    """More friction uncertainty gives a less certain τ_ext estimate and a smaller gain K₂."""
    results = [stationary_filter(qm, Q_TAU_THESIS, R_THESIS, DT) for qm in (1e-4, 0.01, 1.0)]
    stds = [std for _, std in results]
    gains = [gain[1] for gain, _ in results]
    assert stds[0] < stds[1] < stds[2]
    assert gains[0] > gains[1] > gains[2] > 0.0


def simulated_ramp_lag(model_noise: float, torque_noise: float, dt: float) -> float:
    """Error over rate of the stationary discrete filter on a torque ramp, once settled [s].

    The momentum integrates the ramp exactly over each period (its mean torque), as the
    observer's trapezoidal input does for the model's terms.
    """
    (k1, k2), _ = stationary_filter(model_noise, torque_noise, R_THESIS, dt)
    rate, p, p_hat, tau_hat = 1.0, 0.0, 0.0, 0.0
    for k in range(int(3.0 / dt)):
        p += dt * rate * (k + 0.5) * dt  # ∫ τ over the period
        prior = p_hat + dt * tau_hat
        p_hat, tau_hat = prior + k1 * (p - prior), tau_hat + k2 * (p - prior)
    return (rate * (k + 1) * dt - tau_hat) / rate


@pytest.mark.parametrize("model_noise", [0.0, 0.0056, 0.25])
@pytest.mark.parametrize("torque_noise", [100.0, 1000.0])
def test_ramp_lag_is_the_filters(model_noise, torque_noise):
    """The closed form against the discrete filter on a ramp.

    Within a period at 250 Hz, within 1 % at 10 kHz (the continuous-time limit it is
    derived in).
    """
    lag = float(ramp_lag(model_noise, torque_noise, R_THESIS))
    assert simulated_ramp_lag(model_noise, torque_noise, DT) == pytest.approx(lag, abs=DT)
    assert simulated_ramp_lag(model_noise, torque_noise, 1e-4) == pytest.approx(lag, rel=0.01)


@pytest.mark.filterwarnings("ignore::leadthrough.model.robots.AssumedDriveDataWarning")
def test_max_lag_raises_the_torque_noise_of_slow_joints_only():
    """A joint that Q_τ leaves slower than max_lag gets the Q_τ that meets it exactly.

    The others, and every joint without max_lag, keep Q_τ. The UR10e's noisy shoulder and
    elbow are raised, no joint of the YuMi or the Panda (whose guiding max_lag leaves as
    it was).
    """
    parameters = ObserverParameters(torque_noise=100.0, max_lag=0.02)
    model_noise = np.array([0.0, 0.0056, 0.05, 0.25, 2.0])
    torque_noise = joint_torque_noise(parameters, model_noise)
    lag = ramp_lag(model_noise, torque_noise, parameters.measurement_noise)
    slow = ramp_lag(model_noise, 100.0, parameters.measurement_noise) > 0.02
    np.testing.assert_array_equal(slow, [False, False, True, True, True])
    np.testing.assert_allclose(lag[slow], 0.02, rtol=1e-9)
    np.testing.assert_array_equal(torque_noise[~slow], 100.0)
    unbounded = ObserverParameters(torque_noise=100.0)
    np.testing.assert_array_equal(joint_torque_noise(unbounded, model_noise), 100.0)
    for name, raised in (("yumi", 0), ("panda", 0), ("ur10e", 3)):
        noise_std = FrictionModel.from_robot(getattr(lt.robots, name)()).noise_std
        assert np.count_nonzero(joint_torque_noise(parameters, noise_std**2) > 100.0) == raised


def test_max_lag_bounds_a_noisy_sliding_joints_lag(dynamics, friction):
    """A sliding joint with 7× the YuMi's friction noise lags a push ≤ 20 ms with max_lag.

    The time-varying observer of that joint (the UR10e's shoulder's noise) follows a ramp
    about 52 ms late with Q_τ = 100 alone (the closed form, within a period).
    """
    noisy = FrictionModel(**{**friction.__dict__, "noise_std": friction.noise_std * 7.0})
    q, qd = dynamics.robot.home(), np.full(N, 0.3)
    holding = consistent_torque(dynamics, noisy, q, qd)
    lags = []
    for bound in (None, 0.02):
        observer = MomentumObserver(dynamics, noisy, dt=DT, torque_noise=100.0, max_lag=bound)
        for k in range(1000):
            push = 2.0 * k * DT  # [Nm], 2 Nm/s: the motor lets the hand's push through
            estimate = observer.update(q, qd, holding - push)
        lags.append((push - estimate[0]) / 2.0)
    unbounded = float(ramp_lag(noisy.noise_std[0] ** 2, 100.0, R_THESIS))
    assert lags[0] == pytest.approx(unbounded, abs=DT) and unbounded > 0.04
    assert lags[1] <= 0.02  # the bound (the discrete filter settles ~0.8 period earlier)


def consistent_torque(dynamics, friction, q, qd) -> np.ndarray:
    """Motor torque that keeps p = M(q) q̇ constant at a frozen (q, q̇) with τ_ext = 0."""
    return (friction.mean(qd) + dynamics.gravity(q)
            - dynamics.coriolis_transpose_times_velocity(q, qd))  # fmt: skip


@pytest.mark.parametrize("speed", [0.0, 0.5])
def test_time_varying_converges_to_stationary_gains(dynamics, friction, speed):
    """At constant q̇ the time-varying filter settles on the stationary std and gains."""
    q, qd = dynamics.robot.home(), np.full(N, speed)
    tau = consistent_torque(dynamics, friction, q, qd)
    observer = MomentumObserver(dynamics, friction, dt=DT, variant="time_varying")
    for _ in range(3000):
        observer.update(q, qd, tau)
    model_noise = friction.std(qd) ** 2
    expected = [iterate_covariance(qm, Q_TAU_THESIS, R_THESIS, DT) for qm in model_noise]
    np.testing.assert_allclose(observer.std, [std for _, std in expected], rtol=1e-6)
    np.testing.assert_allclose(observer.tau_ext_hat, 0.0, atol=1e-9)
    # a one-period torque pulse δ reveals the gains: Δτ̂₁ = −K₂ dt δ, then
    # Δτ̂₂ = K₂ (−(1 − K₁) dt δ + K₂ dt² δ) on the next, unperturbed period
    delta = 1.0
    first = observer.update(q, qd, tau + delta)
    second = observer.update(q, qd, tau)
    k2 = -first / (DT * delta)
    innovation = (second - first) / k2
    k1 = 1.0 - k2 * DT + innovation / (DT * delta)
    np.testing.assert_allclose(k2, [gain[1] for gain, _ in expected], rtol=1e-5)
    np.testing.assert_allclose(k1, [gain[0] for gain, _ in expected], rtol=1e-5)


def test_two_level_uses_stationary_values(dynamics, friction):
    """Two-level std at rest and at speed equal the stationary std of std_f(0)², σ²."""
    q = dynamics.robot.home()
    observer = MomentumObserver(dynamics, friction, dt=DT, variant="two_level")
    still = np.zeros(N)
    observer.update(q, still, consistent_torque(dynamics, friction, q, still))
    observer.update(q, still, consistent_torque(dynamics, friction, q, still))
    expected_still = [iterate_covariance(qm, Q_TAU_THESIS, R_THESIS, DT)[1]
                      for qm in friction.std(still) ** 2]  # fmt: skip
    np.testing.assert_allclose(observer.std, expected_still, rtol=1e-6)
    moving = np.full(N, 0.5)
    observer.update(q, moving, consistent_torque(dynamics, friction, q, moving))
    expected_moving = [iterate_covariance(s**2, Q_TAU_THESIS, R_THESIS, DT)[1]
                       for s in friction.noise_std]  # fmt: skip
    np.testing.assert_allclose(observer.std, expected_moving, rtol=1e-4)


# --- consistency and sign on the synthetic trajectory ------------------------------------


def test_synthetic_data_moves_and_obeys_momentum_law(data, dynamics, friction):
    """Data sanity: joints move ≥ 85 % of the time and ṗ = τ + Cᵀq̇ − G − τ_f + τ_ext holds."""
    assert np.all(np.mean(np.abs(data.qd) > 0.1, axis=0) > 0.85)
    momentum = np.array([dynamics.momentum(*state) for state in zip(data.q, data.qd, strict=True)])
    coriolis = np.array([dynamics.coriolis_transpose_times_velocity(*state)
                         for state in zip(data.q, data.qd, strict=True)])  # fmt: skip
    gravity = np.array([dynamics.gravity(q) for q in data.q])
    drift = coriolis - gravity - friction.mean(data.qd)
    rate = np.diff(momentum, axis=0) / DT
    # τ_ext averaged over (t_{k−1}, t_k]: the step starts on the grid, so its value at t_{k−1}
    law = data.tau[1:] + 0.5 * (drift[1:] + drift[:-1]) + data.tau_ext[:-1]
    clean = away_from_reversals(data)[1:]
    np.testing.assert_allclose(rate[clean], law[clean], atol=5e-3)
    # with the SPEC §1 sign, τ_ext enters the motor torque negatively: a +1.5 Nm push on
    # joint 1 lowers the torque the motor must give across the step by about 1.5 Nm
    k = round(STEP_TIME / DT)
    assert data.tau[k + 1, 0] - data.tau[k, 0] == pytest.approx(-1.5, abs=0.05)


@pytest.mark.parametrize("kind", ["time_varying", "two_level"])
def test_kalman_estimate_tracks_step_with_sign(data, dynamics, friction, kind):
    """Kalman τ̂_ext: ≈ 0 before the step, within 0.1 Nm of +1.5 / −0.8 Nm after it settles."""
    estimate, _ = run(make_observer(kind, dynamics, friction), data.q, data.qd, data.tau)
    before = (data.time > 0.0) & (data.time < STEP_TIME)
    after = data.time > STEP_TIME + 0.3
    np.testing.assert_allclose(estimate[before], 0.0, atol=0.05)
    np.testing.assert_allclose(estimate[after], data.tau_ext[after], atol=0.1)
    assert np.all(estimate[after, 0] > 1.4) and np.all(estimate[after, 3] < -0.7)


@pytest.mark.parametrize("kind", ["time_varying", "numpy", "two_level", "smooth_rate"])
def test_samples_lost_are_predicted_over(data, dynamics, friction, kind):
    """25 samples lost (100 ms) while the arm accelerates: no push read into the gap.

    The sample after the gap brings the torque averaged over it (a drive holding its
    command) and ``periods=26``. Within 0.1 Nm of the estimate with every sample, from the
    gap on (0.04 measured); predicted over one period, the momentum the gap built read as a
    push 1.2–1.5 Nm off on the base.
    """
    observer = make_observer("time_varying" if kind == "numpy" else kind, dynamics, friction)
    observer.compiled = kind != "numpy"
    whole, _ = run(observer, *_inputs(data))
    first, last = round(1.6 / DT), round(1.7 / DT)  # lost: first … last − 1
    observer.reset()
    estimates, periods = [], 1
    for k in range(len(data.time)):
        if first <= k < last:
            continue
        tau = data.tau[first : last + 1].mean(axis=0) if k == last else data.tau[k]
        estimates.append(observer.update(data.q[k], data.qd[k], tau, periods=periods))
        periods = 1 + (last - first) * (k == first - 1)
    kept = np.r_[0:first, last : len(data.time)]
    after = kept >= last
    off = np.abs(np.array(estimates)[after] - whole[kept[after]]).max()
    assert off < 0.1, off


def test_classical_residual_tracks_step_with_sign(data, dynamics, friction):
    """Classical residual within 0.1 Nm of τ_ext after the step, away from velocity reversals."""
    estimate, std = run(make_observer("classical", dynamics, friction), *_inputs(data))
    clean = away_from_reversals(data)
    before = ((data.time > 0.0) & (data.time < STEP_TIME))[:, None] & clean
    after = (data.time > STEP_TIME + 0.3)[:, None] & clean
    assert np.all(np.abs(estimate[before]) < 0.05)
    assert np.all(np.abs(estimate - data.tau_ext)[after] < 0.1)
    assert np.all(estimate[data.time > STEP_TIME + 0.3, 0] > 1.2)
    assert np.all(estimate[data.time > STEP_TIME + 0.3, 3] < -0.5)
    assert np.all(np.isnan(std))


def test_estimate_flips_with_the_external_torque(data, dynamics, friction):
    """Data realising −τ_ext give an estimate of −τ_ext: the sign follows the push."""
    pushed = np.vstack([np.zeros((1, N)), data.tau_ext[:-1]])  # τ_ext over (t_{k−1}, t_k]
    flipped_tau = data.tau + 2.0 * pushed  # τ realising −τ_ext
    plain, _ = run(make_observer("time_varying", dynamics, friction), *_inputs(data))
    flipped, _ = run(make_observer("time_varying", dynamics, friction),
                     data.q, data.qd, flipped_tau)  # fmt: skip
    after = data.time > STEP_TIME + 0.3
    np.testing.assert_allclose(flipped[after], -data.tau_ext[after], atol=0.1)
    np.testing.assert_allclose(plain[after], data.tau_ext[after], atol=0.1)


def test_a_given_friction_mean_moves_the_estimate_only(dynamics, friction):
    """A creep at 3 mrad/s, the motor holding gravity and Coriolis, no friction applied.

    From ṗ = 0 the filter settles at τ̂ = G + mean_f − τ − (the Coriolis drift term): the
    model's friction at 3 mrad/s (≈ τ_C) read as a push, or nothing when told a friction of
    0. Its std and error_std stay those of the measured velocity.
    """
    q, qd = dynamics.robot.home(), np.full(N, 0.003)
    model = dynamics.snapshot(q, qd)
    tau = model.gravity - model.coriolis_drift
    credited, sliding = (MomentumObserver(dynamics, friction, DT) for _ in range(2))
    for _ in range(500):
        credited.update(q, qd, tau, model)
        sliding.update(q, qd, tau, model, friction_mean=np.zeros(N))
    np.testing.assert_allclose(credited.tau_ext_hat, friction.mean(qd, q), atol=1e-6)
    assert np.all(credited.tau_ext_hat > 0.5 * friction.coulomb)
    np.testing.assert_allclose(sliding.tau_ext_hat, 0.0, atol=1e-6)
    np.testing.assert_array_equal(sliding.std, credited.std)
    np.testing.assert_array_equal(sliding.error_std, credited.error_std)


@pytest.mark.parametrize(
    ("tau", "error", "message"),
    [
        (None, lt.InputValueError, "tau: the motor torque of the last period is missing"),
        (np.full(N, np.nan), lt.InputValueError, r"tau: not finite \(NaN or Inf\) on joints"),
        (np.zeros((N, 1)), lt.InputShapeError, r"tau: expected shape \(7,\), got \(7, 1\)"),
        (np.zeros(N - 1), lt.InputShapeError, r"tau: expected shape \(7,\), got \(6,\)"),
    ],
    ids=["none", "nan", "column", "short"],
)
def test_a_bad_torque_is_refused_and_the_filter_keeps_its_state(dynamics, friction, tau, error,
                                                                message):  # fmt: skip
    """A missing, NaN or misshapen τ raises a one-line error before the filter moves.

    Taken in, a NaN stayed in the estimate for good (every later update read NaN).
    """
    q, qd = dynamics.robot.home(), np.full(N, 0.05)
    good = dynamics.gravity(q) + 0.3
    refused, untouched = (MomentumObserver(dynamics, friction, DT) for _ in range(2))
    for observer in (refused, untouched):
        for _ in range(3):
            observer.update(q, qd, good)
    with pytest.raises(error, match=message):
        refused.update(q, qd, tau)
    for _ in range(3):
        np.testing.assert_array_equal(refused.update(q, qd, good), untouched.update(q, qd, good))


def test_a_non_finite_position_is_refused_without_a_snapshot(dynamics, friction):
    """Without the caller's model snapshot, the observer checks q and q̇ itself."""
    observer = MomentumObserver(dynamics, friction, DT)
    q = dynamics.robot.home()
    with pytest.raises(lt.InputValueError, match=r"qd: not finite \(NaN or Inf\) on joints \[2\]"):
        observer.update(q, np.where(np.arange(N) == 2, np.inf, 0.0), np.zeros(N))


def test_time_varying_std_smaller_moving_than_still(data, dynamics, friction):
    """The time-varying filter is more certain while moving than at stand-still."""
    _, moving_std = run(make_observer("time_varying", dynamics, friction), *_inputs(data))
    q = dynamics.robot.home()
    still = MomentumObserver(dynamics, friction, dt=DT, variant="time_varying")
    zero = np.zeros(N)
    for _ in range(500):
        still.update(q, zero, dynamics.gravity(q))
    moving = (np.abs(data.qd) > 0.1) & (data.time > 0.5)[:, None]
    for j in range(N):
        assert moving_std[moving[:, j], j].max() < 0.75 * still.std[j]
    np.testing.assert_allclose(still.tau_ext_hat, 0.0, atol=1e-12)


def test_noisy_velocity_error_and_coverage(data, dynamics, friction):
    """With q̇ noise of 1e-4 the Kalman error RMS < 0.15 Nm and |error| ≤ 2σ ≥ 90 % moving."""
    rng = np.random.default_rng(20240605)
    qd_noisy = data.qd + rng.normal(0.0, 1e-4, data.qd.shape)
    for kind in ("time_varying", "two_level"):
        estimate, std = run(make_observer(kind, dynamics, friction), data.q, qd_noisy, data.tau)
        error = estimate - data.tau_ext
        settled = (data.time > 0.1) & ~((data.time >= STEP_TIME) & (data.time < STEP_TIME + 0.3))
        rms = np.sqrt(np.mean(error[settled] ** 2, axis=0))
        assert np.all(rms < 0.15), (kind, rms)
        moving = (np.abs(data.qd) > 0.05) & (data.time > 0.1)[:, None]
        inside = np.abs(error) <= 2.0 * std
        for j in range(N):
            assert inside[moving[:, j], j].mean() >= 0.9, (kind, j)


# --- the classical baseline's first-order lag --------------------------------------------


@pytest.mark.parametrize("gain", [10.0, 50.0])
def test_classical_residual_is_first_order_lag(data, dynamics, friction, gain):
    """After the step the residual error decays like exp(−K_O t): ≈ 63 % reached at 1/K_O."""
    observer = ClassicalMomentumObserver(dynamics, friction, dt=DT, gain=gain)
    estimate, _ = run(observer, *_inputs(data))
    k_step = round(STEP_TIME / DT)  # first period with τ_ext ends at k_step + 1
    baseline = estimate[k_step]
    joints = [0, 3]
    k = np.arange(1, round(0.2 / DT))
    reached = (estimate[k_step + k][:, joints] - baseline[joints]) / STEP[joints]
    at_time_constant = reached[round(1.0 / (gain * DT)) - 1]
    np.testing.assert_allclose(at_time_constant, 1.0 - np.exp(-1.0), atol=0.05)
    # exactly: the Euler recursion r_k = r_{k−1} + K_O dt (τ_ext − r_{k−1})
    expected = 1.0 - (1.0 - gain * DT) ** k
    np.testing.assert_allclose(reached, np.column_stack([expected, expected]), atol=0.02)
    assert np.all(np.diff(reached[: round(3.0 / (gain * DT))], axis=0) > 0.0)


# --- reset, initialisation, parameters ---------------------------------------------------


@pytest.mark.parametrize("kind", ["time_varying", "two_level", "classical"])
def test_first_update_returns_zeros(data, dynamics, friction, kind):
    """The first update initialises from the measured momentum and returns zeros."""
    observer = make_observer(kind, dynamics, friction)
    k = round(1.5 / DT)  # while τ_ext is on
    first = observer.update(data.q[k], data.qd[k], data.tau[k] + 5.0)
    np.testing.assert_array_equal(first, np.zeros(N))
    np.testing.assert_array_equal(observer.tau_ext_hat, np.zeros(N))


@pytest.mark.parametrize("kind", ["time_varying", "two_level", "classical"])
def test_reset_forgets_the_estimate(data, dynamics, friction, kind):
    """After reset the observer behaves exactly like a new one started at the same sample."""
    observer = make_observer(kind, dynamics, friction)
    k0 = round(1.6 / DT)
    run(observer, data.q[:k0], data.qd[:k0], data.tau[:k0])
    assert abs(observer.tau_ext_hat[0]) > 1.0
    observer.reset()
    np.testing.assert_array_equal(observer.tau_ext_hat, np.zeros(N))
    resumed, resumed_std = run(observer, data.q[k0:], data.qd[k0:], data.tau[k0:])
    fresh, fresh_std = run(make_observer(kind, dynamics, friction),
                           data.q[k0:], data.qd[k0:], data.tau[k0:])  # fmt: skip
    np.testing.assert_array_equal(resumed[0], np.zeros(N))
    np.testing.assert_allclose(resumed, fresh, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(resumed_std, fresh_std, rtol=0.0, atol=1e-12)


def test_reset_restores_initial_std(dynamics, friction, data):
    """reset() puts the reported std back to √Q_τ (one second of random walk)."""
    observer = MomentumObserver(dynamics, friction, dt=DT)
    np.testing.assert_allclose(observer.std, np.sqrt(Q_TAU_THESIS))
    run(observer, data.q[:100], data.qd[:100], data.tau[:100])
    assert np.all(observer.std < 1.0)
    observer.reset()
    np.testing.assert_allclose(observer.std, np.sqrt(Q_TAU_THESIS))


@pytest.mark.parametrize(
    "overrides",
    [
        {"variant": "steady"},
        {"variant": "Two_Level"},
        {"measurement_noise": -1e-6},
        {"measurement_noise": 0.0},
        {"torque_noise": -10.0},
        {"torque_noise": 0.0},
        {"friction_noise_scale": -1.0},
        {"moving_velocity": -0.01},
        {"measurement_noise": float("nan")},
        {"max_lag": 0.0},
        {"max_lag": float("nan")},
    ],
)
def test_invalid_parameters_raise(dynamics, friction, overrides):
    """Unknown variants and negative (or zero) noise intensities raise ParameterError."""
    with pytest.raises(ParameterError):
        ObserverParameters(**overrides)
    with pytest.raises(ParameterError):
        MomentumObserver(dynamics, friction, dt=DT, **overrides)


@pytest.mark.parametrize("dt", [0.0, -0.004])
def test_invalid_dt_raises(dynamics, friction, dt):
    """A non-positive period raises ParameterError in both observers."""
    with pytest.raises(ParameterError):
        MomentumObserver(dynamics, friction, dt=dt)
    with pytest.raises(ParameterError):
        ClassicalMomentumObserver(dynamics, friction, dt=dt)


def test_classical_invalid_gain_raises(dynamics, friction):
    """A non-positive K_O raises ParameterError."""
    with pytest.raises(ParameterError):
        ClassicalMomentumObserver(dynamics, friction, dt=DT, gain=0.0)


def test_a_friction_model_of_another_arm_is_refused_by_name():
    """An observer given a friction model with another joint count says so in one line.

    Before, NumPy's broadcasting ValueError came out of the constructor.
    """
    ur5 = lt.robots.ur5()
    with pytest.raises(ParameterError, match=r"friction.*has 7 joints, the robot .* has 6"):
        lt.MomentumObserver(lt.Dynamics(ur5), FrictionModel.from_robot(lt.robots.yumi()))
