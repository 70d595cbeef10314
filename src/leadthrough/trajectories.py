"""Time laws of reference motions: minimum jerk and the triangular velocity of §4.1.1."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.validation import FloatArray


def minimum_jerk_phase(t: ArrayLike, duration: float) -> tuple[FloatArray, FloatArray]:
    """Minimum-jerk phase and its rate, clamped outside ``[0, duration]``.

    Args:
        t: Time(s) [s].
        duration: Duration of the motion [s], > 0.

    Returns:
        The phase ``s ∈ [0, 1]`` [-] and its rate ``ṡ`` [1/s], each of the shape of ``t``.
    """
    if isinstance(t, float | int):  # the twin's hand, every period: float math
        s = min(max(t / duration, 0.0), 1.0)  # what np.clip gives, NaN included
        # the same bits as NumPy's, as NumPy scalars
        return np.float64(_phase(s)), np.float64(_rate(s, duration))  # type: ignore[return-value]
    tau = np.minimum(np.maximum(np.asarray(t, dtype=float) / duration, 0.0), 1.0)
    return _phase(tau), _rate(tau, duration)


def _phase(tau: Any) -> Any:
    """Minimum-jerk phase of the normalised time ``tau`` (float or array)."""
    return tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)


def _rate(tau: Any, duration: float) -> Any:
    """Its time derivative [1/s]."""
    return 30.0 * tau**2 * (1.0 - tau) ** 2 / duration


def minimum_jerk_acceleration(t: ArrayLike, duration: float) -> FloatArray:
    """Second derivative of the minimum-jerk phase [1/s²], zero outside ``[0, duration]``."""
    t = np.asarray(t, dtype=float)
    tau = np.clip(t / duration, 0.0, 1.0)
    inside = (t >= 0.0) & (t <= duration)
    return np.where(inside, 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / duration**2, 0.0)


def triangular_velocity(
    t: ArrayLike, peak_velocity: float, frequency: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Position, velocity and acceleration of a triangular velocity wave (thesis Fig. 4.1).

    The acceleration is a square wave of ±4 f v̂; the velocity rises from 0 to the peak
    v̂, falls to −v̂ and returns to 0 each period, so the position goes up by the stroke
    ``v̂ / (4 f)`` and back to 0.

    Args:
        t: Time(s) from the start of the wave [s].
        peak_velocity: v̂ [rad/s].
        frequency: f [Hz].

    Returns:
        Offset from the start position [rad], velocity [rad/s], acceleration [rad/s²].
    """
    quarter = 0.25 / frequency
    accel = peak_velocity / quarter
    phase = np.mod(np.asarray(t, dtype=float), 4.0 * quarter)
    k = np.minimum(np.floor(phase / quarter), 3.0)  # quarter index 0..3
    s = phase - k * quarter  # time into the quarter
    rising = np.isin(k, (0.0, 3.0))
    sign = np.where(rising, 1.0, -1.0)
    start_velocity = np.select([k == 0, k == 1, k == 2], [0.0, peak_velocity, 0.0], -peak_velocity)
    start_position = (
        np.select([k == 0, k == 1, k == 2], [0.0, 0.5, 1.0], 0.5) * peak_velocity * quarter
    )
    velocity = start_velocity + sign * accel * s
    position = start_position + start_velocity * s + 0.5 * sign * accel * s**2
    return position, velocity, sign * accel
