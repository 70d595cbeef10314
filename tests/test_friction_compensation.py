"""Tests of the Coulomb friction compensation of passive lead-through (thesis §4.2.2)."""

from __future__ import annotations

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.errors import ParameterError
from leadthrough.friction.compensation import (
    CoulombCompensation,
    CoulombCompensationParameters,
    coulomb_compensation,
)
from leadthrough.friction.model import FrictionModel

N = 7
FRACTION = 0.7  # ε of the thesis
DEAD_BAND = 0.003  # q̇₀ of the thesis [rad/s]
FULL_VELOCITY = 0.01  # q̇₁ [rad/s]


@pytest.fixture(scope="module")
def model() -> FrictionModel:
    """The YuMi's friction model (thesis Table 4.1)."""
    return FrictionModel.from_robot(lt.robots.yumi())


def thesis_law(qd: float, coulomb: float, fraction: float, q0: float, q1: float) -> float:
    """The piecewise compensation torque of §4.2.2 for one joint and one velocity."""
    speed = abs(qd)
    direction = 1.0 if qd > 0 else -1.0 if qd < 0 else 0.0
    if speed < q0:
        return 0.0
    if speed < q1:
        return (speed - q0) / (q1 - q0) * direction * fraction * coulomb
    return direction * fraction * coulomb


def thesis_law_array(qd, coulomb, fraction, q0, q1) -> np.ndarray:
    """thesis_law over an (M, n) array, joint j using coulomb[j], q0[j], q1[j]."""
    qd = np.asarray(qd, dtype=float)
    coulomb, q0, q1 = (np.broadcast_to(np.asarray(v, dtype=float), (N,)) for v in (coulomb, q0, q1))
    out = np.empty_like(qd)
    for k, j in np.ndindex(*qd.shape):
        out[k, j] = thesis_law(qd[k, j], coulomb[j], fraction, q0[j], q1[j])
    return out


def straddling_grid(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """(M, n) velocities at, just below and just above both thresholds, and far away, ± each."""
    factors = [1 - 1e-9, 1.0, 1 + 1e-9]
    speeds = [np.zeros(N), 0.5 * q0, 0.5 * (q0 + q1), 0.25 * q0 + 0.75 * q1, 2.0 * q1, np.ones(N)]
    speeds += [f * q0 for f in factors] + [f * q1 for f in factors]
    speeds = np.array(speeds)
    return np.vstack([speeds, -speeds])


def test_law_matches_thesis_piecewise_on_grid(model):
    """coulomb_compensation equals the §4.2.2 law across q̇₀ and q̇₁ for every joint."""
    q0, q1 = np.full(N, DEAD_BAND), np.full(N, FULL_VELOCITY)
    qd = straddling_grid(q0, q1)
    got = coulomb_compensation(qd, model.coulomb, FRACTION, DEAD_BAND, FULL_VELOCITY)
    expected = thesis_law_array(qd, model.coulomb, FRACTION, q0, q1)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-15)
    # the three regimes are all exercised
    assert np.any(expected == 0.0) and np.any(np.abs(expected) == FRACTION * model.coulomb)
    assert np.any((np.abs(expected) > 0) & (np.abs(expected) < FRACTION * model.coulomb))


def test_law_matches_thesis_with_per_joint_thresholds(model):
    """With per-joint q̇₀, q̇₁ arrays each joint follows the law with its own thresholds."""
    rng = np.random.default_rng(11)
    q0 = rng.uniform(0.001, 0.02, N)
    q1 = q0 * rng.uniform(1.5, 4.0, N)
    qd = np.vstack([straddling_grid(q0, q1), rng.uniform(-0.1, 0.1, (300, N))])
    got = coulomb_compensation(qd, model.coulomb, 0.55, q0, q1)
    expected = thesis_law_array(qd, model.coulomb, 0.55, q0, q1)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-15)


def test_law_is_odd_in_velocity(model):
    """τ_fc(−q̇) = −τ_fc(q̇), exactly."""
    rng = np.random.default_rng(12)
    qd = np.vstack([rng.uniform(-0.015, 0.015, (400, N)), rng.uniform(-2.0, 2.0, (100, N))])
    args = (model.coulomb, FRACTION, DEAD_BAND, FULL_VELOCITY)
    negated = coulomb_compensation(-qd, *args)
    np.testing.assert_array_equal(negated, -coulomb_compensation(qd, *args))


def test_law_never_exceeds_fraction_of_coulomb(model):
    """|τ_fc| ≤ ε τ_C and has the sign of q̇ (or is zero)."""
    rng = np.random.default_rng(13)
    qd = rng.uniform(-0.05, 0.05, (1000, N))
    torque = coulomb_compensation(qd, model.coulomb, FRACTION, DEAD_BAND, FULL_VELOCITY)
    assert np.all(np.abs(torque) <= FRACTION * model.coulomb * (1 + 1e-15))
    assert np.all(torque * qd >= 0.0)


def test_step_filters_a_step_as_one_minus_pole_power(model):
    """A constant full-compensation input gives ε τ_C (1 − 0.6^k) at step k = 1, 2, …."""
    compensation = CoulombCompensation(model)
    qd = np.array([0.5, -0.5, 0.2, -0.02, 1.0, -1.0, 0.011])
    target = FRACTION * model.coulomb * np.sign(qd)
    outputs = np.array([compensation.step(qd) for _ in range(120)])
    np.testing.assert_allclose(outputs[0], 0.4 * target, rtol=1e-15)
    np.testing.assert_allclose(outputs[1], 0.64 * target, rtol=1e-15)
    np.testing.assert_allclose(outputs[2], 0.784 * target, rtol=1e-15)
    k = np.arange(1, 121)[:, None]
    np.testing.assert_allclose(outputs, target * (1.0 - 0.6**k), rtol=1e-13)
    np.testing.assert_allclose(outputs[-1], target, rtol=1e-14)


def test_step_filters_the_law_not_just_its_saturation(model):
    """On a random velocity sequence, step is H(z) applied to the unfiltered law."""
    rng = np.random.default_rng(14)
    qd = rng.uniform(-0.015, 0.015, (200, N))
    compensation = CoulombCompensation(model)
    state = np.zeros(N)
    for row in qd:
        raw = thesis_law_array(row[None], model.coulomb, FRACTION, DEAD_BAND, FULL_VELOCITY)[0]
        state = 0.6 * state + 0.4 * raw
        np.testing.assert_allclose(compensation.step(row), state, rtol=1e-12, atol=1e-15)


def test_step_output_is_a_copy(model):
    """Mutating a returned torque does not change the filter state."""
    compensation = CoulombCompensation(model)
    first = compensation.step(np.full(N, 0.5))
    first[:] = 1e6
    second = compensation.step(np.full(N, 0.5))
    np.testing.assert_allclose(second, 0.64 * FRACTION * model.coulomb, rtol=1e-15)


def test_step_uses_position_dependent_coulomb_level():
    """With q given, the compensation converges to ε τ_C(q)."""
    rng = np.random.default_rng(15)
    model = FrictionModel(
        coulomb=rng.uniform(0.2, 1.5, N),
        slope=np.full(N, 5e3),
        half_width=np.full(N, 2e-3),
        viscous=rng.uniform(0.0, 1.0, N),
        noise_std=np.full(N, 0.05),
        position_linear=rng.uniform(-0.3, 0.3, N),
        position_quadratic=rng.uniform(-0.3, 0.3, N),
        position_half_range=np.full(N, 2.0),
    )
    q = rng.uniform(-2.0, 2.0, N)
    u = q / 2.0
    level = model.coulomb * (1.0 + model.position_linear * u + model.position_quadratic * u**2)
    compensation = CoulombCompensation(model)
    first = compensation.step(np.full(N, 0.3), q)
    np.testing.assert_allclose(first, 0.4 * FRACTION * level, rtol=1e-14)


def test_dead_band_override_widens_zero_band(model):
    """Per-joint dead_band: zero below it, where the default band already compensates."""
    band = np.array([0.003, 0.005, 0.008, 0.01, 0.02, 0.004, 0.006])
    qd = 0.95 * band  # inside each widened band
    default = CoulombCompensation(model).step(qd)
    widened = CoulombCompensation(model).step(qd, dead_band=band)
    np.testing.assert_array_equal(widened, np.zeros(N))
    assert np.all(np.abs(default[1:]) > 0.0)  # joints whose band was actually widened


def test_dead_band_override_follows_law_with_ramp_to_max(model):
    """With a per-joint q̇₀ override the ramp ends at max(q̇₁, 2 q̇₀)."""
    band = np.array([0.001, 0.003, 0.004, 0.005, 0.008, 0.02, 0.0])
    full = np.array([max(FULL_VELOCITY, 2.0 * b) for b in band])
    np.testing.assert_array_equal(full[[0, 1, 2, 3, 6]], FULL_VELOCITY)
    qd_grid = straddling_grid(band, full)
    for qd in qd_grid:
        torque = CoulombCompensation(model).step(qd, dead_band=band)  # fresh: output = 0.4 raw
        expected = thesis_law_array(qd[None], model.coulomb, FRACTION, band, full)[0]
        np.testing.assert_allclose(torque, 0.4 * expected, rtol=1e-12, atol=1e-15)
    # just below 2 q̇₀ a wide-band joint is still on the ramp, above it at full compensation
    wide = 5
    below, above = np.zeros(N), np.zeros(N)
    below[wide], above[wide] = 0.039, 0.0401
    ramp = CoulombCompensation(model).step(below, dead_band=band)[wide]
    saturated = CoulombCompensation(model).step(above, dead_band=band)[wide]
    np.testing.assert_allclose(ramp, 0.4 * 0.95 * FRACTION * model.coulomb[wide], rtol=1e-12)
    np.testing.assert_allclose(saturated, 0.4 * FRACTION * model.coulomb[wide], rtol=1e-15)


def test_reset_clears_filter_state(model):
    """After reset, the next output is that of a fresh compensator."""
    rng = np.random.default_rng(16)
    compensation = CoulombCompensation(model)
    for _ in range(25):
        compensation.step(rng.uniform(-0.05, 0.05, N))
    qd = rng.uniform(-0.05, 0.05, N)
    compensation.reset()
    after_reset = compensation.step(qd)
    np.testing.assert_array_equal(after_reset, CoulombCompensation(model).step(qd))
    compensation.reset()
    np.testing.assert_array_equal(compensation.step(np.zeros(N)), np.zeros(N))


def test_default_parameters_are_the_thesis_values():
    """Defaults: ε = 0.7, q̇₀ = 0.003 rad/s, q̇₁ = 0.01 rad/s."""
    parameters = CoulombCompensationParameters()
    assert (parameters.fraction, parameters.dead_band, parameters.full_velocity) == (
        FRACTION,
        DEAD_BAND,
        FULL_VELOCITY,
    )


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        pytest.param({"fraction": 1.2}, "fraction", id="fraction-above-1"),
        pytest.param({"fraction": -0.1}, "fraction", id="fraction-negative"),
        pytest.param({"fraction": float("nan")}, "fraction", id="fraction-nan"),
        pytest.param({"dead_band": -0.001}, "dead_band", id="dead-band-negative"),
        pytest.param({"full_velocity": 0.003}, "full_velocity", id="full-equals-dead-band"),
        pytest.param({"full_velocity": 0.002}, "full_velocity", id="full-below-dead-band"),
        pytest.param({"dead_band": 0.02}, "full_velocity", id="dead-band-above-default-full"),
        pytest.param({"full_velocity": float("inf")}, "full_velocity", id="full-inf"),
    ],
)
def test_parameters_reject_invalid_values(overrides, field):
    """Invalid ε, q̇₀ or q̇₁ raise ParameterError naming the parameter."""
    with pytest.raises(ParameterError) as info:
        CoulombCompensationParameters(**overrides)
    assert info.value.parameter == field
    assert str(info.value).startswith(f"{field}: ")


@pytest.mark.parametrize(
    "values", [{"fraction": 1.0}, {"fraction": 0.0}, {"dead_band": 0.0, "full_velocity": 1e-6}]
)
def test_parameters_accept_boundary_values(values):
    """ε = 0 or 1 and q̇₀ = 0 are valid."""
    parameters = CoulombCompensationParameters(**values)
    for name, value in values.items():
        assert getattr(parameters, name) == value
