"""The ``"smooth_rate"`` observer: external torque with a smooth rate, and an honest std.

A human's push is a torque whose *rate* changes smoothly, not a torque that jumps. Per
joint the state is ``x = [p, τ_ext, τ̇_ext]`` with the rate a random walk (SPEC §1 signs)::

    ṗ = u + τ_ext + w_m,   τ̇_ext = r,   ṙ = w_r,   y = p + v
    w_m ~ Q_m = scale · σ_f² · dt,   w_r ~ Q_r,   v ~ R                          (1)

``σ_f`` is the friction model's *noise* (``FrictionModel.noise_std``), white at the
sample rate: independent samples of std σ held over one period ``dt`` have the
intensity σ² dt. Exact discretisation over ``dt``::

    Φ = [[1, dt, dt²/2], [0, 1, dt], [0, 0, 1]],   Γ = [dt, 0, 0]ᵀ,
    Q_d = Q_r [[dt⁵/20, dt⁴/8, dt³/6], [dt⁴/8, dt³/3, dt²/2], [dt³/6, dt²/2, dt]]
          + Q_m dt e₁e₁ᵀ,   R_d = R / dt                                        (2)

The noises are constant, so the gains are the stationary ones of the discrete algebraic
Riccati equation (computed once). The rest of the friction model's error is *not*
noise: a wrong Coulomb level (``relative_error`` × the mean friction, taken as one
standard deviation) or a friction that may hold anything up to ``v_C`` at rest (the
Coulomb uncertainty) enters ``ṗ`` exactly as ``τ_ext`` does, so no filter can tell it
from the operator and it passes into the estimate whole. It is added to the reported
variance ("consider" term), not to the process noise, where it would only slow the
filter down::

    std² = P_ττ + v_C(q̇, q)² + (relative_error · mean_f(q̇, q))²                 (3)

The filter is of type 2 in τ: a torque ramp is tracked without a steady-state lag.
"""

from __future__ import annotations

import numpy as np

from leadthrough.model.description import FloatArray


def transition(dt: float) -> FloatArray:
    """Φ of eq. (2), 3×3."""
    return np.array([[1.0, dt, 0.5 * dt * dt], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])


def process_noise(model_noise: float, rate_noise: float, dt: float) -> FloatArray:
    """Q_d of eq. (2), 3×3: ``model_noise`` Q_m [Nm² s], ``rate_noise`` Q_r [Nm²/s³]."""
    powers = np.array([[dt**5 / 20.0, dt**4 / 8.0, dt**3 / 6.0],
                       [dt**4 / 8.0, dt**3 / 3.0, dt**2 / 2.0],
                       [dt**3 / 6.0, dt**2 / 2.0, dt]])  # fmt: skip
    noise = rate_noise * powers
    noise[0, 0] += model_noise * dt
    return noise


def stationary_filter(
    model_noise: float, rate_noise: float, noise: float, dt: float
) -> tuple[FloatArray, FloatArray]:
    """Stationary gain (K_p, K_τ, K_ṙ) and posterior covariance (3×3) of one joint.

    Args:
        model_noise: Q_m [Nm² s].
        rate_noise: Q_r [Nm²/s³].
        noise: R, momentum measurement noise intensity [(kg m²/s)² s].
        dt: Period [s].
    """
    from scipy.linalg import solve_discrete_are  # at call time: keeps the import fast

    output = np.array([[1.0, 0.0, 0.0]])
    prior = solve_discrete_are(transition(dt).T, output.T,
                               process_noise(model_noise, rate_noise, dt),
                               np.array([[noise / dt]]))  # fmt: skip
    gain = prior[:, 0] / (prior[0, 0] + noise / dt)
    return gain, prior - np.outer(gain, prior[0])


class SmoothRateFilter:
    """The three-state filter of every joint, arrays over joints, stationary gains.

    Args:
        model_noise: Q_m of every joint [Nm² s], (n,).
        rate_noise: Q_r [Nm²/s³].
        noise: R [(kg m²/s)² s].
        dt: Period [s].
    """

    def __init__(self, model_noise: FloatArray, rate_noise: float, noise: float, dt: float):
        self.dt = dt
        filters = [stationary_filter(float(q), rate_noise, noise, dt) for q in model_noise]
        self.gain = np.array([gain for gain, _ in filters]).T.copy()  # (3, n)
        #: P_ττ of every joint [Nm²].
        self.torque_variance = np.array([cov[1, 1] for _, cov in filters])
        self.rate = np.zeros(len(filters))

    def reset(self) -> None:
        """Forget the torque rate."""
        self.rate[:] = 0.0

    def step(
        self,
        p: FloatArray,
        tau: FloatArray,
        u: FloatArray,
        momentum: FloatArray,
        interval: float | None = None,
    ) -> None:
        """Predict with the input ``u`` [Nm], correct with ``momentum``; p, τ in place.

        ``interval``: the time since the sample before [s] (None: ``dt``); predicted over
        it, corrected with the stationary gain (samples lost are few).
        """
        dt, rate = self.dt if interval is None else interval, self.rate
        prior_p = p + dt * (u + tau + 0.5 * dt * rate)
        innovation = momentum - prior_p
        p[:] = prior_p + self.gain[0] * innovation
        tau += dt * rate + self.gain[1] * innovation
        rate += self.gain[2] * innovation


def consider_variance(
    friction_mean: FloatArray, coulomb_variance: FloatArray, relative_error: FloatArray
) -> FloatArray:
    """The friction error no filter can separate from τ_ext, eq. (3) [Nm²].

    Args:
        friction_mean: mean_f(q̇, q) [Nm].
        coulomb_variance: v_C(q̇, q)² [Nm²].
        relative_error: The friction model's relative level error (one std) [–].
    """
    return coulomb_variance + (relative_error * friction_mean) ** 2
