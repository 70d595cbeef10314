"""The classical first-order momentum observer (De Luca et al.), as a baseline.

    r = K_O (p − p(0) − ∫₀ᵗ (u + r) ds),   u = τ + Cᵀ q̇ − G − mean_f(q̇)

so that ``ṙ = K_O (τ_ext − r)``: each residual follows the external torque through a
first-order lag of time constant 1/K_O. Same interface as the Kalman observer, but it
has no notion of its own uncertainty (:attr:`std` is NaN).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import ParameterError
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics
from leadthrough.validation import real


class ClassicalMomentumObserver:
    """First-order momentum residual.

    Args:
        dynamics: Model of the arm.
        friction: Friction model whose mean is subtracted.
        dt: Update period [s].
        gain: K_O [1/s] (50: a 20 ms time constant, like the Kalman observer while moving).
    """

    def __init__(
        self,
        dynamics: Dynamics,
        friction: FrictionModel | None = None,
        dt: float = 0.004,
        gain: float = 50.0,
    ) -> None:
        self.dynamics = dynamics
        self.friction = friction or FrictionModel.from_robot(dynamics.robot)
        self.dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
        self.gain = real("gain", gain, minimum=0.0, strict=True, error=ParameterError)
        self.reset()

    @property
    def tau_ext_hat(self) -> FloatArray:
        """Residual = estimated external joint torque [Nm]."""
        return self._residual.copy()

    @property
    def std(self) -> FloatArray:
        """Not available for this observer: NaN per joint."""
        return np.full(self.dynamics.n, np.nan)

    def reset(self) -> None:
        """Restart the integral at the next update."""
        self._residual = np.zeros(self.dynamics.n)
        self._integral = np.zeros(self.dynamics.n)
        self._initial: FloatArray | None = None

    def update(self, q: ArrayLike, qd: ArrayLike, tau: ArrayLike) -> FloatArray:
        """One step with the state now and the motor torque of the last period [Nm]."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        dynamics = self.dynamics
        momentum = dynamics.mass(q) @ qd
        drift = dynamics.coriolis_transpose_times_velocity(q, qd) - dynamics.gravity(q)
        drift -= self.friction.mean(qd, q)
        if self._initial is None:
            self._initial, self._previous_drift = momentum, drift
            return self.tau_ext_hat
        # input over the last period, drift terms averaged over its ends as in the Kalman filter
        u = np.asarray(tau, dtype=float) + 0.5 * (drift + self._previous_drift)
        self._previous_drift = drift
        self._integral += self.dt * (u + self._residual)
        self._residual = self.gain * (momentum - self._initial - self._integral)
        return self.tau_ext_hat
