"""Tests of the first-order low-pass H(z) = 0.4 / (1 − 0.6 z⁻¹) (thesis eqs. 4.1, 4.6)."""

from __future__ import annotations

import numpy as np
import pytest

from leadthrough.filters import POLE, low_pass, low_pass_signal


def loop_filter(signal: np.ndarray, pole: float = POLE) -> np.ndarray:
    """low_pass applied sample by sample, from rest at the first sample."""
    out = np.empty_like(signal, dtype=float)
    previous = signal[0]
    for k, sample in enumerate(signal):
        previous = low_pass(previous, sample, pole)
        out[k] = previous
    return out


def test_pole_is_the_thesis_value():
    """The pole is 0.6 so that the gain 1 − pole is the thesis' 0.4."""
    assert POLE == 0.6
    np.testing.assert_allclose(low_pass(0.0, 1.0), 0.4, rtol=1e-15)


@pytest.mark.parametrize("pole", [POLE, 0.0, 0.3, 0.95])
@pytest.mark.parametrize("shape", [(300,), (300, 7)])
def test_signal_equals_loop_of_steps(pole, shape):
    """low_pass_signal equals low_pass applied in a loop, started at the first sample."""
    signal = np.random.default_rng(21).normal(size=shape)
    np.testing.assert_allclose(
        low_pass_signal(signal, pole), loop_filter(signal, pole), rtol=1e-12, atol=1e-14
    )


def test_step_is_the_recurrence():
    """low_pass(y, x) = 0.6 y + 0.4 x, elementwise on arrays."""
    rng = np.random.default_rng(22)
    previous, new = rng.normal(size=(2, 5, 7))
    np.testing.assert_allclose(low_pass(previous, new), 0.6 * previous + 0.4 * new, rtol=1e-15)


@pytest.mark.parametrize("value", [0.0, 1.0, -3.7, 1e6])
def test_dc_gain_is_one(value):
    """A constant input stays constant from the first sample on (H(1) = 1, start at rest)."""
    signal = np.full((50, 3), value)
    np.testing.assert_allclose(low_pass_signal(signal), signal, rtol=1e-15, atol=0)
    np.testing.assert_allclose(low_pass(value, value), value, rtol=1e-15, atol=0)


def test_impulse_response_is_geometric():
    """From zero state, a unit impulse gives 0.4 · 0.6^k."""
    k = np.arange(40)
    expected = 0.4 * 0.6**k
    impulse = np.zeros(40)
    impulse[0] = 1.0
    stepped = loop_filter_from_zero(impulse)
    np.testing.assert_allclose(stepped, expected, rtol=1e-13)
    # low_pass_signal starts at rest at its first sample: lead with one zero sample
    delayed = low_pass_signal(np.concatenate([[0.0], impulse]))
    np.testing.assert_allclose(delayed, np.concatenate([[0.0], expected]), rtol=1e-13)


def loop_filter_from_zero(signal: np.ndarray) -> np.ndarray:
    """low_pass applied sample by sample from a zero state."""
    out, previous = np.empty_like(signal), np.zeros_like(signal[0])
    for k, sample in enumerate(signal):
        previous = low_pass(previous, sample)
        out[k] = previous
    return out


def test_step_response_time_constant():
    """A unit step from rest reaches 1 − 0.6^(k+1) at sample k (≈ 63 % after −1/ln 0.6)."""
    signal = np.concatenate([[0.0], np.ones(30)])
    response = low_pass_signal(signal)
    k = np.arange(30)
    np.testing.assert_allclose(response[1:], 1.0 - 0.6 ** (k + 1), rtol=1e-13)
    assert response[0] == 0.0


def test_filters_each_column_independently_along_axis_0():
    """On an (N, n) array each column is filtered alone, along the first axis."""
    rng = np.random.default_rng(23)
    signal = rng.normal(size=(200, 5))
    filtered = low_pass_signal(signal)
    assert filtered.shape == signal.shape
    for j in range(signal.shape[1]):
        np.testing.assert_allclose(filtered[:, j], low_pass_signal(signal[:, j]), rtol=1e-14)
    np.testing.assert_allclose(low_pass_signal(signal.T).T, loop_filter(signal.T).T, atol=1e-14)
    # a change in one column leaves the others untouched
    changed = signal.copy()
    changed[50:, 2] += 10.0
    other = [0, 1, 3, 4]
    np.testing.assert_array_equal(low_pass_signal(changed)[:, other], filtered[:, other])


def test_signal_does_not_modify_its_input():
    """The input array is left unchanged."""
    signal = np.random.default_rng(24).normal(size=(20, 3))
    copy = signal.copy()
    low_pass_signal(signal)
    np.testing.assert_array_equal(signal, copy)


def test_empty_signal_gives_empty_output():
    """A signal with no samples filters to an empty array of the same shape."""
    assert low_pass_signal(np.zeros((0, 3))).shape == (0, 3)


@pytest.mark.parametrize("dt", [0.004, 0.001, 0.0005])
def test_the_time_constant_holds_at_any_rate(dt):
    """Pole 0.6 at 250 Hz is τ = 7.8 ms; at 1 kHz the pole follows so a step still takes τ."""
    from leadthrough.filters import TIME_CONSTANT, pole

    assert abs(TIME_CONSTANT - 0.00783) < 1e-5
    step = low_pass_signal(np.concatenate([[0.0], np.ones(round(0.1 / dt))]), pole(dt))
    t = np.arange(len(step)) * dt
    np.testing.assert_allclose(step, 1.0 - np.exp(-t / TIME_CONSTANT), atol=1e-12)


def test_the_thesis_pole_and_invalid_periods():
    """pole(4 ms) is the thesis' 0.6 exactly; a zero period is refused, τ = 0 filters nothing."""
    from leadthrough.errors import ParameterError
    from leadthrough.filters import pole

    assert pole(0.004) == POLE
    assert pole(0.004, 0.0) == 0.0
    with pytest.raises(ParameterError, match="dt"):
        pole(0.0)
