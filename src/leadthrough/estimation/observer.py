"""Sensorless external torque: the generalized-momentum Kalman observer (thesis ch. 5, SPEC §5).

The momentum ``p = M(q) q̇`` obeys (SPEC §1 signs; the thesis' τ_ext has the other sign)::

    ṗ = u + τ_ext + w_m,    u = τ + Cᵀ(q, q̇) q̇ − G(q) − mean_f(q̇)          (5.8)–(5.10)

with ``w_m`` the friction model's uncertainty. Each joint is a 2-state system,
state ``x = [p_i, τ_ext,i]``, external torque a random walk, momentum measured::

    ẋ = [[0, 1], [0, 0]] x + [1, 0]ᵀ u + w,    w ~ (Q_m, Q_τ),    y = p + v,  v ~ R   (5.11)

Q and R are continuous-time intensities (thesis §5.2.1: R = 1e−6, Q_τ = 10) and the
filter runs in discrete time with the *exact* discretisation over ``dt``::

    Φ = [[1, dt], [0, 1]],  Γ = [dt, 0]ᵀ,
    Q_d = [[Q_m dt + Q_τ dt³/3, Q_τ dt²/2], [Q_τ dt²/2, Q_τ dt]],   R_d = R / dt

With diagonal Q and R the joints decouple, so every joint is its own 2×2 filter and
all joints are updated together as arrays. Three variants:

- ``"two_level"`` (the thesis): Q_m takes a stand-still or a moving value per joint,
  from the friction std at rest and at speed; the two stationary gains come from the
  discrete algebraic Riccati equation, precomputed.
- ``"time_varying"`` (beyond the thesis, which found it too costly): Q_m = std_f(q̇)²
  of the Gaussian friction model every step, with the full covariance recursion.
- ``"smooth_rate"`` (beyond the thesis): three states ``[p, τ_ext, τ̇_ext]``, the torque's
  rate a random walk, only the friction *noise* as process noise and the rest of the
  friction model's error added to the std (:mod:`leadthrough.estimation.smooth_rate`).

Either way :attr:`std` is the standard deviation of the estimate from the filter's
covariance: the observer reports its own uncertainty.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.compiled import kernel
from leadthrough.errors import InputShapeError, InputValueError, ParameterError
from leadthrough.estimation import smooth_rate
from leadthrough.estimation.smooth_rate import SmoothRateFilter, consider_variance
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics
from leadthrough.model.snapshot import ModelSnapshot
from leadthrough.validation import real

Variant = Literal["two_level", "time_varying", "smooth_rate"]
VARIANTS = ("two_level", "time_varying", "smooth_rate")


@dataclass(frozen=True)
class ObserverParameters:
    """Tuning of the Kalman observer (defaults: thesis §5.2.1).

    Attributes:
        measurement_noise: R, intensity of the momentum measurement noise [(kg m²/s)² s].
        torque_noise: Q_τ, intensity of the external torque random walk [Nm²/s]: larger is
            faster and noisier. With ``max_lag``, the least of each joint's.
        variant: ``"two_level"``, ``"time_varying"`` or ``"smooth_rate"`` (see the module
            docstring).
        moving_velocity: Two-level variant: a joint is moving above this speed [rad/s];
            None takes B + 5/A of each joint's friction model (where its sigmoids settle).
        friction_noise_scale: Multiplies the friction variance to form Q_m [1/s]: Q_m =
            scale · std_f(q̇)² (1: the thesis' choice of Q_m equal to the uncertainty);
            smooth-rate variant: Q_m = scale · σ_f² dt (the friction noise, white).
        torque_rate_noise: Smooth-rate variant: Q_r, intensity of the random walk of the
            external torque's rate [Nm²/s³]: larger is faster and noisier. 1e3 with
            R = 1e-8 gives ≈ 18 Hz while moving (the default observer's ≈ 15 Hz); with the
            thesis' R = 1e-6 it gives ≈ 9 Hz, too slow for the start-up calibration's
            strokes of a few mrad (take 3e4 there: ≈ 15 Hz, std ≈ 0.7 Nm).
        max_lag: Two-state variants: the most a sliding joint's estimate may lag a torque
            ramp [s] (:func:`ramp_lag`); None: no bound. A joint whose friction noise is so
            large that ``torque_noise`` would leave it slower (Q_m = scale · σ² against
            Q_τ sets the bandwidth) gets the Q_τ that meets the bound
            (:func:`joint_torque_noise`): how fast an operator's torque changes does not
            depend on how noisy the arm's friction is, and the lag is what the admittance's
            coupled stability needs (:mod:`leadthrough.experiments.stability`).
    """

    measurement_noise: float = 1e-6
    torque_noise: float = 10.0
    variant: Variant = "time_varying"
    moving_velocity: float | None = None
    friction_noise_scale: float = 1.0
    torque_rate_noise: float = 1000.0
    max_lag: float | None = None

    def __post_init__(self) -> None:
        real(
            "measurement_noise",
            self.measurement_noise,
            minimum=0,
            strict=True,
            error=ParameterError,
        )
        real("torque_noise", self.torque_noise, minimum=0, strict=True, error=ParameterError)
        real("friction_noise_scale", self.friction_noise_scale, minimum=0, error=ParameterError)
        real("torque_rate_noise", self.torque_rate_noise, minimum=0, strict=True,
             error=ParameterError)  # fmt: skip
        if self.max_lag is not None:
            real("max_lag", self.max_lag, minimum=0, strict=True, error=ParameterError)
        if self.variant not in VARIANTS:
            raise ParameterError("variant", f"one of {VARIANTS}, got {self.variant!r}")
        if self.moving_velocity is not None:
            real(
                "moving_velocity",
                self.moving_velocity,
                minimum=0,
                strict=True,
                error=ParameterError,
            )


def process_noise(
    model_noise: FloatArray, torque_noise: float | FloatArray, dt: float
) -> tuple[FloatArray, ...]:
    """Entries (Q₁₁, Q₁₂, Q₂₂) of the exactly discretised process noise Q_d, per joint."""
    return (model_noise * dt + torque_noise * dt**3 / 3.0,
            np.ones_like(model_noise) * (torque_noise * dt**2 / 2.0),
            np.ones_like(model_noise) * (torque_noise * dt))  # fmt: skip


def ramp_lag(
    model_noise: ArrayLike, torque_noise: ArrayLike, measurement_noise: float
) -> FloatArray:
    """How far a two-state filter's estimate lags a torque ramp [s]: error / ramp rate.

    The stationary continuous-time filter (Q_m, Q_τ, R as in the module docstring) has
    P₁₂ = √(R Q_τ), P₁₁ = √(R (Q_m + 2 P₁₂)) and gains L = P₁·/R; a ramp leaves the
    error ``L₁ / L₂`` times its rate::

        T = √(Q_m / Q_τ + 2 √(R / Q_τ))

    The discrete filter's lag on a ramp is within a period of it (``tests/test_observer.py``).
    """
    q_m, q_tau = np.asarray(model_noise, dtype=float), np.asarray(torque_noise, dtype=float)
    return np.sqrt(q_m / q_tau + 2.0 * np.sqrt(measurement_noise / q_tau))


def joint_torque_noise(parameters: ObserverParameters, model_noise: ArrayLike) -> FloatArray:
    """Q_τ of each joint whose sliding model noise is ``model_noise`` (Q_m) [Nm²/s].

    ``parameters.torque_noise``, raised where the joint would lag a ramp by more than
    ``parameters.max_lag`` (:func:`ramp_lag` solved for Q_τ: with x = 1/√Q_τ,
    Q_m x² + 2√R x = T², x = T² / (√R + √(R + Q_m T²))). The smooth-rate variant
    (Q_r, not Q_τ) and ``max_lag=None`` leave it as given.
    """
    q_m = np.asarray(model_noise, dtype=float)
    least = np.full(q_m.shape, parameters.torque_noise)
    lag = parameters.max_lag
    if lag is None or parameters.variant == "smooth_rate":
        return least
    root_r = math.sqrt(parameters.measurement_noise)
    x = lag**2 / (root_r + np.sqrt(parameters.measurement_noise + q_m * lag**2))
    return np.maximum(least, 1.0 / x**2)


def stationary_filter(
    model_noise: float, torque_noise: float, noise: float, dt: float
) -> tuple[FloatArray, float]:
    """Stationary gain (K₁, K₂) and posterior std of τ_ext of one joint (discrete ARE)."""
    from scipy.linalg import solve_discrete_are  # at call time: keeps the import fast

    transition = np.array([[1.0, dt], [0.0, 1.0]])
    output = np.array([[1.0, 0.0]])
    q11, q12, q22 = (float(v) for v in process_noise(np.array(model_noise), torque_noise, dt))
    prior = solve_discrete_are(transition.T, output.T, np.array([[q11, q12], [q12, q22]]),
                               np.array([[noise / dt]]))  # fmt: skip
    gain = prior[:, 0] / (prior[0, 0] + noise / dt)
    posterior_22 = prior[1, 1] - gain[1] * prior[0, 1]
    return gain, float(np.sqrt(posterior_22))


def sliding_gains(parameters: ObserverParameters, friction_std: float, dt: float) -> FloatArray:
    """Stationary Kalman gains of a sliding joint whose friction std is ``friction_std`` [Nm].

    (K_p, K_τ) of the 2-state filters with Q_m = scale · std² (``"time_varying"``, and
    ``"two_level"`` while moving); (K_p, K_τ, K_ṙ) of ``"smooth_rate"``, whose Q_m is
    the friction noise, white (scale · std² dt).
    """
    scale = parameters.friction_noise_scale * friction_std**2
    if parameters.variant == "smooth_rate":
        return smooth_rate.stationary_filter(scale * dt, parameters.torque_rate_noise,
                                             parameters.measurement_noise, dt)[0]  # fmt: skip
    torque_noise = float(joint_torque_noise(parameters, scale))
    return stationary_filter(scale, torque_noise, parameters.measurement_noise, dt)[0]


class MomentumObserver:
    """Kalman filter on the generalized momentum: external joint torques and their std.

    Args:
        dynamics: Model of the arm.
        friction: Gaussian friction model (mean subtracted, std drives Q_m).
        dt: Update period [s].
        parameters: Tuning; keyword arguments override single fields
            (e.g. ``variant="two_level"``).
    """

    #: Run the time-varying step compiled (:func:`_time_varying_step`); False runs the
    #: readable NumPy reference (:meth:`_covariance_step`), which the tests compare it to.
    compiled = True

    def __init__(
        self,
        dynamics: Dynamics,
        friction: FrictionModel | None = None,
        dt: float = 0.004,
        parameters: ObserverParameters | None = None,
        **overrides: object,
    ) -> None:
        self.dynamics = dynamics
        self.friction = friction or FrictionModel.from_robot(dynamics.robot)
        if self.friction.n_joints != dynamics.n:
            raise ParameterError("friction", f"has {self.friction.n_joints} joints, the robot "
                                 f"{dynamics.robot.name} has {dynamics.n}")  # fmt: skip
        self.dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
        parameters = parameters or ObserverParameters()
        unknown = sorted(set(overrides) - set(parameters.__dict__))
        if unknown:
            raise ParameterError(unknown[0], "unknown observer parameter")
        if overrides:
            parameters = ObserverParameters(**{**parameters.__dict__, **overrides})
        self.parameters = parameters
        n = dynamics.n
        #: Q_τ of each joint [Nm²/s] (:func:`joint_torque_noise`, at its sliding Q_m = scale · σ²)
        self.torque_noise = joint_torque_noise(
            parameters, parameters.friction_noise_scale * np.asarray(self.friction.noise_std) ** 2
        )
        self._levels = self._two_level_gains() if parameters.variant == "two_level" else None
        self._smooth = None
        if parameters.variant == "smooth_rate":
            white = parameters.friction_noise_scale * self.friction.noise_std**2 * self.dt
            self._smooth = SmoothRateFilter(white, parameters.torque_rate_noise,
                                            parameters.measurement_noise, self.dt)  # fmt: skip
        # the filter's state, one array (one argument of the compiled step), rows: p, τ̂_ext,
        # the previous drift, the covariances P11, P12, P22, the std of τ̂_ext and the
        # friction model's error std at the sample (error_std, when the compiled step ran)
        self._filter = np.zeros((8, n))
        self._p, self._tau, self._previous_drift = self._filter[0], self._filter[1], self._filter[2]
        self._cov_rows, self._std = self._filter[3:6], self._filter[6]
        self._error_std = self._filter[7]
        self._relative_error = np.array(self.friction.relative_error, dtype=float)
        self._level_std = np.ascontiguousarray(self.friction.level_std, dtype=float)
        # the entries of Q_d that do not depend on Q_m (Q_m enters Q₁₁ as Q_m dt), per joint
        self._torque_rows = np.array(process_noise(np.zeros(n), self.torque_noise, self.dt))
        self._gaps: dict[int, tuple[FloatArray, FloatArray]] = {}  # _over's, per gap
        self._noise_d = parameters.measurement_noise / self.dt
        # (dt, friction_noise_scale, R_d) for the compiled step
        self._constants = np.array([self.dt, parameters.friction_noise_scale, self._noise_d])
        self._terms = np.zeros((4, n))  # the friction terms of a period, when not given
        self._no_mean = np.zeros(n)  # the compiled step's ``credited`` when none is given
        self.reset()

    # --- public state ------------------------------------------------------------------

    @property
    def tau_ext_hat(self) -> FloatArray:
        """Estimated external joint torque [Nm], arm side, SPEC §1 sign."""
        return self._tau.copy()

    @property
    def std(self) -> FloatArray:
        """Standard deviation of :attr:`tau_ext_hat` from the filter's covariance [Nm]."""
        return self._std.copy()

    @property
    def error_std(self) -> FloatArray:
        """How far :attr:`tau_ext_hat` may be off [Nm]: what no filter separates from τ_ext.

        The friction model's error at the latest sample, eq. (3) of
        :mod:`~leadthrough.estimation.smooth_rate` without the filter's own term: the
        Coulomb uncertainty v_C(q̇, q) (≈ τ_C at rest, where friction holds a push below
        breakaway unseen, → 0 moving) and the level error ``level_std · mean_f`` (the
        std of a level known to within ±``relative_error``).
        :attr:`std` is the filter's covariance; for the time-varying and two-level
        variants the tuning Q_τ sets it (the torque may jump 0.6 Nm within a period at
        Q_τ = 100), so it covers the error many times over. The smooth-rate variant's
        :attr:`std` is this plus its own P_ττ, and is returned as it is. Computed when
        read (not in :meth:`update`); :attr:`std` before the first update.
        """
        if self._smooth is not None or self._sample is None:
            return self.std
        if self._error_in_filter:  # the compiled step computed it
            return self._error_std.copy()
        q, qd = self._sample
        mean, std = self.friction.mean_and_std(qd, q)
        coulomb_variance = np.maximum(std**2 - self.friction.noise_std**2, 0.0)
        return np.sqrt(consider_variance(mean, coulomb_variance, self._level_std))

    def set_level_error(self, relative: FloatArray) -> None:
        """This period's relative error of each Coulomb level [–] (the model's until set).

        The level error of :attr:`error_std` (and the smooth-rate variant's std): where a
        level was read at one pose, it grows with the travel from it
        (:mod:`~leadthrough.friction.measured_level`).
        """
        self._relative_error[:] = relative
        np.multiply(relative, 1.0 / np.sqrt(3.0), out=self._level_std)

    def reset(self) -> None:
        """Forget the estimate; the next update starts from the measured momentum."""
        self._initialised = False
        self._sample: tuple[FloatArray, FloatArray] | None = None
        self._error_in_filter = False  # whether the latest step wrote error_std's row
        self._tau[:] = 0.0
        variance = self.torque_noise  # 1 s of random walk
        self._cov_rows[:2] = 0.0
        self._cov_rows[2] = variance
        self._std[:] = np.sqrt(variance)
        if self._smooth is not None:
            self._smooth.reset()

    # --- the filter --------------------------------------------------------------------

    def update(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        tau: ArrayLike,
        model: ModelSnapshot | None = None,
        terms: FloatArray | None = None,
        friction_mean: FloatArray | None = None,
        periods: int = 1,
    ) -> FloatArray:
        """One filter step with the state now and the motor torque of the last period.

        Args:
            q: Joint positions [rad].
            qd: Joint velocities [rad/s].
            tau: Motor torque applied over the last period, arm side [Nm] (dither excluded).
            model: The model at (q, q̇) computed this period (M, G, Cᵀq̇), if the caller
                has it; else computed here.
            terms: The friction model's terms at (q̇, q) of this period, (4, n)
                (:meth:`~leadthrough.friction.model.FrictionModel.terms_into`), if the
                caller has them; else computed here.
            friction_mean: The friction torque the filter takes as applied [Nm], if not
                the model's mean at q̇ (its std, and with it the gains and
                :attr:`error_std`, stay the model's at q̇): a caller that knows better
                whether the joint slides passes its own (e.g. none below a rest
                velocity: docs/active_mode_log.md, *Friction credited to a creep*).
            periods: Control periods since the sample before: more than one where samples
                were lost (the drive held its command, ``tau``, over all of them); the
                filter predicts over all of them, with the drift terms' trapezoid across
                the gap (over one, the momentum a 100 ms gap built was read as a push).

        Returns:
            The estimated external torque [Nm].

        Raises:
            InputValueError: ``tau`` is None, or ``tau`` (or, without ``model``, ``q`` or
                ``qd``) is not finite: the filter's state is left as it was.
            InputShapeError: An input is not one value per joint (``tau`` may be a scalar).
        """
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        tau = self._input(tau)
        if model is None:  # a caller with its own snapshot has checked its sample
            model = self.dynamics.snapshot(q, qd)
            _require_finite(("q", q), ("qd", qd))
        if friction_mean is not None:
            friction_mean = np.ascontiguousarray(np.broadcast_to(friction_mean, qd.shape),
                                                 dtype=float)  # fmt: skip
        self._sample = (q, qd)  # for error_std, computed when read (or by the compiled step)
        self._error_in_filter = False
        compiled = self.compiled and self._levels is None and self._smooth is None
        torque_rows, constants = self._over(periods)
        if compiled and self._initialised and qd.shape == q.shape:  # time-varying: one pass
            if terms is None:
                terms = self.friction.terms_into(qd, q, self._terms)
            credited = self._no_mean if friction_mean is None else friction_mean
            _time_varying_step(self._filter, tau, model.mass, qd, model.coriolis_drift,
                               model.gravity, terms, credited, friction_mean is not None,
                               self.friction.noise_std, self._level_std,
                               torque_rows, constants)  # fmt: skip
            self._error_in_filter = True
            return self._tau.copy()
        momentum = model.mass @ qd
        if self._smooth is not None:
            return self._smooth_rate_update(q, qd, tau, model, momentum, friction_mean,
                                            periods * self.dt)  # fmt: skip
        if self._levels is None:
            model_mean, friction_std = self.friction.mean_and_std(qd, q)
        else:  # the two-level gains need no friction std
            model_mean, friction_std = self.friction.mean(qd, q), None
        if friction_mean is None:
            friction_mean = model_mean
        if not self._initialised:
            self._p[:] = momentum
            self._previous_drift[:] = model.coriolis_drift - model.gravity - friction_mean
            self._initialised = True
            return self.tau_ext_hat
        drift = model.coriolis_drift - model.gravity - friction_mean
        # input over the last period: measured torque plus the drift terms (trapezoid)
        u = tau + 0.5 * (drift + self._previous_drift)
        self._previous_drift[:] = drift
        dt = float(constants[0])  # over every period since the sample before
        prior_p = self._p + dt * (u + self._tau)
        innovation = momentum - prior_p
        gain_p, gain_tau = self._gains(qd, friction_std, torque_rows, dt)
        self._p[:] = prior_p + gain_p * innovation
        self._tau[:] = self._tau + gain_tau * innovation
        return self.tau_ext_hat

    def _smooth_rate_update(
        self, q: FloatArray, qd: FloatArray, tau: ArrayLike, model: ModelSnapshot,
        momentum: FloatArray, applied_friction: FloatArray | None = None,
        interval: float | None = None,
    ) -> FloatArray:  # fmt: skip
        """One step of the smooth-rate variant (same input, eqs. (1)–(3) of its module).

        ``applied_friction``: the caller's ``friction_mean`` of :meth:`update`, if any;
        ``interval``: the time since the sample before [s] (None: one period).
        """
        assert self._smooth is not None
        friction_mean, friction_std = self.friction.mean_and_std(qd, q)
        credited = friction_mean if applied_friction is None else applied_friction
        drift = model.coriolis_drift - model.gravity - credited
        if self._initialised:
            u = np.asarray(tau, dtype=float)
            self._smooth.step(self._p, self._tau, u + 0.5 * (drift + self._previous_drift),
                              momentum, interval)  # fmt: skip
        else:
            self._p[:] = momentum
            self._initialised = True
        self._previous_drift[:] = drift
        # v_C² from std_f² = v_C² + σ_f² (one evaluation of the friction model)
        coulomb_variance = np.maximum(friction_std**2 - self.friction.noise_std**2, 0.0)
        considered = consider_variance(friction_mean, coulomb_variance,
                                       self._relative_error)  # fmt: skip
        self._std[:] = np.sqrt(self._smooth.torque_variance + considered)
        return self.tau_ext_hat

    def _input(self, tau: ArrayLike | None) -> FloatArray:
        """The motor torque [Nm] as (n,) floats: a scalar broadcasts, anything else raises.

        Checked before the filter moves, so that a bad sample leaves its state as it was
        (a NaN taken in would stay in the estimate for good).

        Raises:
            InputValueError: ``tau`` is None or not finite.
            InputShapeError: ``tau`` is neither a scalar nor one value per joint.
        """
        if tau is None:
            raise InputValueError("tau", "the motor torque of the last period is missing (None)")
        tau = np.asarray(tau, dtype=float)
        if tau.shape != self._p.shape:
            if tau.ndim:
                raise InputShapeError("tau", self._p.shape, tau.shape)
            tau = np.full(self._p.shape, float(tau))
        _require_finite(("tau", tau))
        return tau

    def _over(self, periods: int) -> tuple[FloatArray, FloatArray]:
        """Q_d's entries without Q_m, and (dt, scale, R_d), over ``periods`` periods.

        Over one period, the filter's own; over more (samples lost), computed for the
        gap and kept: a robot that loses samples loses them again, mostly as many.
        """
        if periods == 1:
            return self._torque_rows, self._constants
        if periods not in self._gaps:
            interval = periods * self.dt
            rows = np.array(process_noise(np.zeros_like(self._p), self.torque_noise, interval))
            self._gaps[periods] = (rows, np.array([interval, *self._constants[1:]]))
        return self._gaps[periods]

    def _gains(
        self,
        qd: FloatArray,
        friction_std: FloatArray | None,
        torque_rows: FloatArray,
        dt: float,
    ) -> tuple[FloatArray, FloatArray]:
        if self._levels is not None:
            moving = np.abs(qd) > self._levels["threshold"]
            levels = self._levels
            self._std[:] = np.where(moving, levels["std_moving"], levels["std_still"])
            return (np.where(moving, levels["k1_moving"], levels["k1_still"]),
                    np.where(moving, levels["k2_moving"], levels["k2_still"]))  # fmt: skip
        assert friction_std is not None  # computed whenever the gains are not two-level
        return self._covariance_step(self.parameters.friction_noise_scale * friction_std**2,
                                     torque_rows, dt)  # fmt: skip

    def _covariance_step(
        self, model_noise: FloatArray, torque_rows: FloatArray, dt: float
    ) -> tuple[FloatArray, FloatArray]:
        """Predict (Φ P Φᵀ + Q_d) and update the 2×2 covariances of all joints; the gains.

        ``model_noise`` is Q_m [Nm²/s]; ``torque_rows`` the other entries of Q_d over
        ``dt`` [s], the time since the sample before (:meth:`_over`).
        """
        p11, p12, p22 = self._cov_rows
        q11_torque, q12, q22 = torque_rows
        prior12 = p12 + dt * p22 + q12
        prior22 = p22 + q22
        prior11 = p11 + dt * (2.0 * p12 + dt * p22) + dt * model_noise + q11_torque
        k1 = prior11 / (prior11 + self._noise_d)
        k2 = prior12 / (prior11 + self._noise_d)
        keep = 1.0 - k1
        self._cov_rows[:] = np.array([keep * prior11, keep * prior12, prior22 - k2 * prior12])
        self._std[:] = np.sqrt(self._cov_rows[2])
        return k1, k2

    def _two_level_gains(self) -> dict[str, FloatArray]:
        """Stationary gains and stds at stand-still and moving, per joint (offline)."""
        friction = self.friction
        threshold = (friction.half_width + 5.0 / friction.slope
                     if self.parameters.moving_velocity is None
                     else np.full(friction.n_joints, self.parameters.moving_velocity))  # fmt: skip
        # moving: past the sigmoids and past the Stribeck range (4 v_s: its band's share
        # below 1e-7), where the friction model's std is its noise σ
        moving = 2.0 * threshold + np.maximum(0.05, 4.0 * friction.stribeck_velocity)
        levels: dict[str, list[float]] = {}
        for name, speed in (("still", np.zeros_like(threshold)), ("moving", moving)):
            noises = self.parameters.friction_noise_scale * self.friction.std(speed) ** 2
            for noise, torque_noise in zip(noises, self.torque_noise, strict=True):
                p = self.parameters
                gain, std = stationary_filter(noise, torque_noise, p.measurement_noise, self.dt)
                for key, value in (("k1", gain[0]), ("k2", gain[1]), ("std", std)):
                    levels.setdefault(f"{key}_{name}", []).append(value)
        return {key: np.array(values) for key, values in levels.items()} | {"threshold": threshold}


def _require_finite(*inputs: tuple[str, FloatArray]) -> None:
    """Raise :class:`InputValueError` naming the first (name, array) with a NaN or Inf."""
    for name, value in inputs:
        if not _finite(value):
            bad = np.flatnonzero(~np.isfinite(value)).tolist()
            raise InputValueError(name, f"not finite (NaN or Inf) on joints {bad}")


@kernel
def _finite(values):
    """Whether every entry of the vector ``values`` is finite (compiled: no NumPy reduction)."""
    for value in values:  # noqa: SIM110 (a loop numba compiles)
        if not math.isfinite(value):
            return False
    return True


@kernel
def _time_varying_step(state, tau, mass, qd, coriolis_drift, gravity, terms, credited, given,
                       noise_std, level_std, torque_rows, constants):  # fmt: skip
    """One step of the time-varying filter, all joints, in place (compiled, ~1 µs).

    The same arithmetic, in the same order, as :meth:`MomentumObserver.update` with
    :meth:`MomentumObserver._covariance_step` (the readable reference, which the tests
    hold this to): the momentum M q̇, the friction mean and std from the terms of
    :meth:`~leadthrough.friction.model.FrictionModel.sigmoid_terms` (as
    ``mean_and_std``), predict with the trapezoidal input, predict and update the 2×2
    covariance with Q_m = scale · std_f², correct the state with the gains. ``state``
    is ``MomentumObserver._filter`` (rows p, τ̂_ext, previous drift, P11, P12, P22, std,
    and :attr:`~MomentumObserver.error_std`, written here), ``terms`` are the friction
    terms, rows as :meth:`~leadthrough.friction.model.FrictionModel.terms_into`;
    ``credited`` is the friction the filter takes as applied when ``given`` (the caller's
    ``friction_mean``), else the mean of ``terms``; ``torque_rows`` are each joint's
    entries of Q_d without Q_m (``MomentumObserver._torque_rows``), ``constants`` are
    (dt, friction_noise_scale, R_d).
    """
    dt, scale, noise_d = constants
    p, tau_hat, previous_drift, cov, std = state[0], state[1], state[2], state[3:6], state[6]
    error_std = state[7]
    n = p.shape[0]
    for i in range(n):
        momentum = 0.0
        for j in range(n):
            momentum += mass[i, j] * qd[j]
        half_level, upper, lower = 0.5 * terms[0, i], terms[2, i], terms[3, i]
        coulomb_std = half_level * (upper - lower)
        friction_std = math.hypot(coulomb_std, noise_std[i])
        friction_mean = half_level * (upper + lower) + terms[1, i]
        error_std[i] = math.hypot(coulomb_std, level_std[i] * friction_mean)
        if given:
            friction_mean = credited[i]
        drift = coriolis_drift[i] - gravity[i] - friction_mean
        u = tau[i] + 0.5 * (drift + previous_drift[i])
        previous_drift[i] = drift
        prior_p = p[i] + dt * (u + tau_hat[i])
        innovation = momentum - prior_p
        p11, p12, p22 = cov[0, i], cov[1, i], cov[2, i]
        model_noise = scale * (friction_std * friction_std)
        prior12 = p12 + dt * p22 + torque_rows[1, i]
        prior22 = p22 + torque_rows[2, i]
        prior11 = p11 + dt * (2.0 * p12 + dt * p22) + dt * model_noise + torque_rows[0, i]
        k1 = prior11 / (prior11 + noise_d)
        k2 = prior12 / (prior11 + noise_d)
        keep = 1.0 - k1
        cov[0, i], cov[1, i], cov[2, i] = keep * prior11, keep * prior12, prior22 - k2 * prior12
        std[i] = math.sqrt(cov[2, i])
        p[i] = prior_p + k1 * innovation
        tau_hat[i] = tau_hat[i] + k2 * innovation
