"""Zero-phase smoothing and differentiation of irregularly sampled signals.

A local quadratic regression with a Gaussian kernel in *time* (not in samples): at each
sample t_k, ``x ≈ a + b (t − t_k) + c (t − t_k)²`` is fitted to the neighbours with
weights ``exp(−½ ((t − t_k)/h)²)``; ``a`` is the smoothed value and ``b`` the derivative.
The kernel is symmetric, so there is no phase lag; it works at the log's own time
stamps, so jitter and gaps need no resampling; the quadratic keeps the derivative free
of the curvature bias where the window is lopsided (gaps, the ends of the run).
"""

from __future__ import annotations

from typing import cast

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.model.description import FloatArray

#: Neighbours farther than this many bandwidths carry no weight.
_REACH = 3.0
#: Ridge on the local slope and curvature, relative to the window's weight [–].
_RIDGE = 1e-6


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
    sums = np.zeros((len(t), 5))  # Σ w dtᵖ, p = 0…4
    moments = np.zeros((3, *flat.shape))  # Σ w dtᵖ x, p = 0…2
    for offset in range(-width, width + 1):
        index = np.arange(len(t)) + offset
        valid = (index >= 0) & (index < len(t))
        index = np.clip(index, 0, len(t) - 1)
        dt = t[index] - t
        weight = np.where(valid & (np.abs(dt) <= _REACH * bandwidth),
                          np.exp(-0.5 * (dt / bandwidth) ** 2), 0.0)  # fmt: skip
        powers = weight[:, None] * dt[:, None] ** np.arange(5)
        sums += powers
        moments += powers[:, :3].T[:, :, None] * flat[index][None]
    normal = sums[:, [[0, 1, 2], [1, 2, 3], [2, 3, 4]]]  # (N, 3, 3) normal equations
    # a sample with fewer than three neighbours in its window (rows dropped as corrupted
    # around it, a dropout) cannot fix a quadratic: a ridge of 1e-6 of its weight on the
    # slope and the curvature leaves it its value, with no slope when it stands alone
    # (singular before), and moves a well-sampled fit by ~1e-6 of itself
    ridge = _RIDGE * sums[:, 0]
    normal[:, 1, 1] += ridge * bandwidth**2
    normal[:, 2, 2] += ridge * bandwidth**4
    coefficients = np.linalg.solve(normal, moments.transpose(1, 0, 2))  # (N, 3, m)
    value, rate = coefficients[:, 0].reshape(x.shape), coefficients[:, 1].reshape(x.shape)
    return cast(FloatArray, value), cast(FloatArray, rate)
