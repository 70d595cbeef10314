"""The first-order low-pass of the thesis, ``H(z) = 0.4 / (1 − 0.6 z⁻¹)`` (eq. 4.6).

Unity gain at DC; at 250 Hz its time constant is ``−dt / ln 0.6`` ≈ 7.8 ms. The thesis
uses it on the friction compensation torque (§4.2.2) and on the velocity and torque
of the identification experiment (§4.1.1). Stateless on purpose: the caller keeps
the previous output.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.validation import FloatArray

#: Pole of H(z); the gain is 1 − POLE so that H(1) = 1.
POLE = 0.6


def low_pass(previous: ArrayLike, new: ArrayLike, pole: float = POLE) -> FloatArray:
    """One step of H(z): ``y_k = pole · y_{k−1} + (1 − pole) · x_k``."""
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
