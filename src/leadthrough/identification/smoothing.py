"""Zero-phase smoothing and differentiation of irregularly sampled signals.

A local linear regression with a Gaussian kernel in *time* (not in samples): at each
sample t_k, the line ``x ≈ a + b (t − t_k)`` is fitted to the neighbours with weights
``exp(−½ ((t − t_k)/h)²)``; ``a`` is the smoothed value and ``b`` the derivative. The
kernel is symmetric, so there is no phase lag; it works at the log's own time stamps,
so jitter and gaps need no resampling; near the ends the window is one-sided but the
line stays unbiased.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.model.description import FloatArray

#: Neighbours farther than this many bandwidths carry no weight.
_REACH = 3.0


def smooth_derivative(
    t: ArrayLike, x: ArrayLike, bandwidth: float
) -> tuple[FloatArray, FloatArray]:
    """Smoothed signal and its time derivative, zero phase, at irregular times.

    Args:
        t: Sample times [s], (N,), strictly increasing.
        x: Signal, (N,) or (N, n), in any unit [u].
        bandwidth: Standard deviation h of the Gaussian time kernel [s] (−3 dB near
            0.13 / h Hz for the value).

    Returns:
        (smoothed x [u], dx/dt [u/s]), each shaped like ``x``.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    flat = x.reshape(len(t), -1)
    reach = np.searchsorted(t, t + _REACH * bandwidth) - np.arange(len(t))
    width = int(max(reach.max(), 1))
    sums = [np.zeros(len(t)) for _ in range(3)]
    moments = [np.zeros(flat.shape) for _ in range(2)]
    for offset in range(-width, width + 1):
        index = np.arange(len(t)) + offset
        valid = (index >= 0) & (index < len(t))
        index = np.clip(index, 0, len(t) - 1)
        dt = t[index] - t
        weight = np.where(valid & (np.abs(dt) <= _REACH * bandwidth),
                          np.exp(-0.5 * (dt / bandwidth) ** 2), 0.0)  # fmt: skip
        for power in range(3):
            sums[power] += weight * dt**power
        moments[0] += weight[:, None] * flat[index]
        moments[1] += (weight * dt)[:, None] * flat[index]
    s0, s1, s2 = (s[:, None] for s in sums)
    slope = (s0 * moments[1] - s1 * moments[0]) / (s0 * s2 - s1 * s1)
    value = (moments[0] - slope * s1) / s0
    return value.reshape(x.shape), slope.reshape(x.shape)
