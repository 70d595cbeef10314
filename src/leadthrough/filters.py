"""The first-order low-pass of the thesis, defined by its time constant (eq. 4.6).

The thesis gives it at 250 Hz as ``H(z) = 0.4 / (1 − 0.6 z⁻¹)``: unity gain at DC and a
time constant ``τ = −dt / ln 0.6`` ≈ 7.8 ms. What it means physically is τ, so that is
what is kept: at another control period the pole follows, ``pole = exp(−dt / τ)`` (0.6 at
4 ms, 0.88 at 1 ms), and the filter smooths the same 7.8 ms of signal. The thesis uses it
on the friction compensation torque (§4.2.2) and on the velocity and torque of the
identification experiment (§4.1.1). Stateless on purpose: the caller keeps the previous
output.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import ParameterError
from leadthrough.validation import FloatArray, real

#: Pole of H(z) at the thesis' 250 Hz; the gain is 1 − POLE so that H(1) = 1.
POLE = 0.6
#: Time constant of H [s]: the pole 0.6 at 250 Hz, ``−0.004 / ln 0.6`` ≈ 7.83 ms.
TIME_CONSTANT = -0.004 / math.log(POLE)


def pole(dt: float, time_constant: float = TIME_CONSTANT) -> float:
    """The pole ``exp(−dt / τ)`` of the first-order low-pass of time constant τ at period dt.

    Args:
        dt: Sampling period [s], > 0.
        time_constant: τ [s], ≥ 0 (0: no filtering, pole 0).
    """
    dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
    time_constant = real("time_constant", time_constant, minimum=0.0, error=ParameterError)
    return math.exp(-dt / time_constant) if time_constant > 0.0 else 0.0


def low_pass(previous: ArrayLike, new: ArrayLike, pole: float = POLE) -> FloatArray:
    """One step of H(z): ``y_k = pole · y_{k−1} + (1 − pole) · x_k`` (see :func:`pole`)."""
    return pole * np.asarray(previous, dtype=float) + (1.0 - pole) * np.asarray(new, dtype=float)


def low_pass_signal(signal: ArrayLike, pole: float = POLE) -> FloatArray:
    """H(z) over a whole signal along its first axis, starting from rest at its first sample."""
    from scipy.signal import lfilter  # at call time: scipy.signal takes 0.6 s to import

    signal = np.asarray(signal, dtype=float)
    if len(signal) == 0:
        return signal.copy()
    initial = pole * signal[:1]  # state that makes y_0 = x_0
    filtered, _ = lfilter([1.0 - pole], [1.0, -pole], signal, axis=0, zi=initial)
    return filtered
