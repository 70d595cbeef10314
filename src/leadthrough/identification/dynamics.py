"""``identify_dynamics``: rigid body, rotor inertias, friction and drive gains from logs.

The torque model of :mod:`leadthrough.identification.regressor` is linear in its unknowns
``x``, so the fit is a Bayesian linear regression: the prior is the description itself
(URDF inertials, rotor inertias, the friction given, gains as stated, no offsets) with a
standard deviation per parameter, and the data pull each parameter as far as they can
tell it. A parameter the runs do not excite keeps its nominal value (ridge toward the
URDF rather than base parameters: the result is a full description that Dynamics and
the observer use as is); the posterior standard deviation says which were identified.

Velocities are smoothed and differentiated at the log's own, irregular time stamps
(:func:`~leadthrough.identification.smoothing.smooth_derivative`, zero phase); torques
are used raw. Rows of
a joint moving slower than ``min_velocity`` are left out (at rest the friction is
anything within ±τ_C: not a model the regression can use). The noise of each joint is
its residual RMS, estimated in a first pass and used as its weight in the second.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from leadthrough.errors import LeadthroughError
from leadthrough.friction.model import FrictionModel
from leadthrough.identification.prediction import log_torque
from leadthrough.identification.regressor import (
    BLOCKS,
    described,
    inertial_parameters,
    parameters_of,
    regressor_rows,
)
from leadthrough.identification.smoothing import smooth_derivative
from leadthrough.logs.log import joint_logs
from leadthrough.logs.runs import log_name, refuse_repeated_logs
from leadthrough.model.description import FloatArray, RobotDescription

#: Alternations of the linear fit (weights from the last residual) and of the gains.
_PASSES = 4


class DynamicsIdentificationError(LeadthroughError, ValueError):
    """The logs cannot identify the dynamics (no torque, too short, wrong joint count)."""


@dataclass(frozen=True)
class DynamicsSettings:
    """Choices of the dynamics fit.

    Attributes:
        bandwidth: Time kernel of the smoothing derivative [s].
        max_samples: Samples used at most (the runs are subsampled evenly beyond) [–].
        min_velocity: Rows of a joint slower than this are left out [rad/s].
        prior_scale: Multiplies every prior standard deviation (larger: trust the data
            more) [–].
        gain_std: Prior standard deviation of the drive-gain scale g [–]; 0 holds g = 1.
    """

    bandwidth: float = 0.03
    max_samples: int = 6000
    min_velocity: float = 0.05
    prior_scale: float = 1.0
    gain_std: float = 0.15

    def __post_init__(self) -> None:
        for name in ("bandwidth", "prior_scale"):
            if not getattr(self, name) > 0.0:
                raise DynamicsIdentificationError(f"settings.{name} must be > 0")
        if self.max_samples < 100 or self.min_velocity < 0.0 or self.gain_std < 0.0:
            raise DynamicsIdentificationError(
                "settings: max_samples ≥ 100, min_velocity ≥ 0 and gain_std ≥ 0 required"
            )


@dataclass(frozen=True, eq=False)
class DynamicsReport:
    """What the fit found, per joint (arrays of n).

    Attributes:
        residual_rms: Torque residual RMS on the fitted rows [Nm], of the description
            returned (a negative τ_C or c held at 0 there), not of the unconstrained fit.
        nominal_rms: The same rows' residual with the prior parameters [Nm]: the
            description's inertials with the ``friction`` the fit was given (in
            ``leadthrough identify``, the friction fitted first), not the description's own
            friction, which the held-out tables' "nominal" rows use.
        samples: Rows used per joint [–].
        gain_scale: Drive-gain scale g (identified K = g K_nominal) [–].
        gain_std: Its posterior standard deviation [–], the model's parameters free too:
            the overall scale of (π, g) is flat in the data and held by the priors (on
            the UR10e's excitation runs 5–13 %; g is then the nominal K unless the data
            single out a joint).
        offset: Torque offset o [Nm] (a sensor bias, not carried by the description).
        parameter_std: Posterior standard deviation of each per-joint block, by name
            (armature [kg m²], coulomb [Nm], viscous [Nm s/rad], offset [Nm]).
        identified_fraction: Per inertial parameter, 1 − posterior/prior std (0: the
            data said nothing, stays nominal; 1: fully determined by the data), (10 n,).
    """

    residual_rms: FloatArray
    nominal_rms: FloatArray
    samples: FloatArray
    gain_scale: FloatArray
    gain_std: FloatArray
    offset: FloatArray
    parameter_std: dict[str, FloatArray]
    identified_fraction: FloatArray

    def __str__(self) -> str:
        lines = [f"{'joint':>5}{'rows':>7}{'RMS nominal':>13}{'RMS ours':>10}{'g':>8}{'±g':>7}"
                 f"{'offset':>8}"]  # fmt: skip
        for j in range(len(self.residual_rms)):
            if self.samples[j] == 0:  # no row of this joint: its values are the prior's
                lines.append(f"{j + 1:>5}{0:>7}{'–':>13}{'–':>10}{'–':>8}{'–':>7}{'–':>8}"
                             "   (never moved fast enough: nominal)")  # fmt: skip
                continue
            lines.append(f"{j + 1:>5}{self.samples[j]:>7.0f}{self.nominal_rms[j]:>13.3f}"
                         f"{self.residual_rms[j]:>10.3f}{self.gain_scale[j]:>8.3f}"
                         f"{self.gain_std[j]:>7.3f}{self.offset[j]:>8.3f}")  # fmt: skip
        return "\n".join(lines)


def identify_dynamics(
    logs: Any,
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    *,
    settings: DynamicsSettings | None = None,
) -> tuple[RobotDescription, DynamicsReport]:
    """Identify inertials, rotor inertias, friction and drive gains from runs of ``robot``.

    Args:
        logs: One :class:`~leadthrough.logs.log.JointLog` or a list (``t``, ``q``,
            ``qd``, ``tau`` [Nm] arm side; ``tau`` = K i for current-logging drives).
        robot: The nominal description: the prior, and what the result is built on.
        friction: Prior friction (e.g. identified from single-joint runs); default the
            description's. Its sigmoid shape is kept, its τ_C and c are re-fitted.
        settings: Choices of the fit.

    Returns:
        The description carrying the identified parameters (torque constants scaled by
        the gain when the description has them) and the fit report.

    Warns:
        UserWarning: Per joint whose fitted τ_C is negative (held at 0): a current or
            torque of the wrong sign, or a wrong torque constant, is the likely cause.

    Raises:
        DynamicsIdentificationError: A log has no torque, the wrong joint count, or
            fewer than 20 samples.
        ParameterError: A log is given twice: the same object, or one run read twice
            (:func:`~leadthrough.logs.runs.refuse_repeated_logs`).
    """
    settings = settings or DynamicsSettings()
    friction = friction or FrictionModel.from_robot(robot)
    q, qd, qdd, tau = _stacked_samples(logs, robot, settings)
    n = robot.n_joints
    rows = regressor_rows(robot, friction, q, qd, qdd)
    measured = tau.reshape(-1)
    keep = np.abs(qd.reshape(-1)) >= settings.min_velocity
    joint = np.tile(np.arange(n), len(q))[keep]
    rows, measured = rows[keep], measured[keep]
    prior, prior_std = _prior(robot, friction, settings)
    nominal_residual = measured - rows @ prior
    gain_std = settings.gain_std * settings.prior_scale if robot.torque_constants is not None else 0
    noise, gain, gain_sd = np.ones(n), np.ones(n), np.zeros(n)
    for _ in range(_PASSES):
        x, std = _posterior(rows, gain[joint] * measured, gain[joint] * noise[joint], prior,
                            prior_std)  # fmt: skip
        predicted = rows @ x
        if gain_std > 0.0:
            gain = _gains(predicted, measured, noise[joint], joint, n, gain_std)
        noise = _per_joint_rms(measured - predicted / gain[joint], joint, n)
    if gain_std > 0.0:
        gain_sd = _gain_std(rows, measured, noise[joint], joint, x, gain, (prior_std, gain_std))
    _warn_negative_friction(x, n)
    offset, block_std = _blocks(x, std, n)
    # the residual of the model saved (friction held at 0, inertials made physical), not x's
    saved = parameters_of(described(robot, x, friction, noise, gain), offset)
    residual_rms = _per_joint_rms(measured - rows @ saved / gain[joint], joint, n)
    samples = np.bincount(joint, minlength=n).astype(float)
    # a joint without rows keeps the prior's noise, as it keeps its other values
    identified = described(robot, x, friction, np.where(samples > 0, residual_rms,
                                                        friction.noise_std), gain)  # fmt: skip
    fraction = 1.0 - std[: 10 * n] / prior_std[: 10 * n]
    rms = _per_joint_rms(nominal_residual, joint, n)
    report = DynamicsReport(residual_rms, rms, samples, gain, gain_sd, offset, block_std,
                            fraction)  # fmt: skip
    return identified, report


def _warn_negative_friction(x: FloatArray, n: int) -> None:
    """One warning per joint whose fitted τ_C is negative (the description holds 0).

    A c alone below 0 is not warned about: a small one the data cannot tell from 0.
    """
    first = 10 * n + BLOCKS.index("coulomb") * n
    coulomb, viscous = x[first : first + n], x[first + n : first + 2 * n]
    for j in np.flatnonzero(coulomb < 0.0):
        what = "Coulomb level" + (" and viscous coefficient" if viscous[j] < 0.0 else "")
        warnings.warn(f"identify_dynamics: joint {j + 1}: fitted {what} negative, saved as 0: "
                      "is its current or torque sign flipped, or its torque constant wrong?",
                      stacklevel=3)  # fmt: skip


def smoothed_signals(
    log: Any, bandwidth: float, tau: FloatArray | None = None
) -> tuple[FloatArray, ...]:
    """(q, q̇, q̈, τ) of a log: q̇ smoothed and q̈ its zero-phase derivative [SI].

    τ (default ``log.tau``) stays raw: its noise is white and averages out in the
    regression, while smoothing would smear the Coulomb step at each reversal that the
    friction model keeps sharp.
    """
    t = np.asarray(log.t, dtype=float)
    qd, qdd = smooth_derivative(t, log.qd, bandwidth)
    torque = np.asarray(log.tau if tau is None else tau, dtype=float)
    return np.asarray(log.q, dtype=float), qd, qdd, torque


def _stacked_samples(
    logs: Any, robot: RobotDescription, settings: DynamicsSettings
) -> tuple[FloatArray, ...]:
    logs = joint_logs(logs)
    if not logs:
        raise DynamicsIdentificationError("no logs given")
    refuse_repeated_logs(logs)
    n, parts = robot.n_joints, []
    for index, log in enumerate(logs):
        where = log_name(log, index)
        if log.q.shape[1] != n or len(log.t) < 20:
            shape = f"{log.q.shape[1]} joints and {len(log.t)} samples"
            raise DynamicsIdentificationError(f"{where}: {shape}, expected {n} and ≥ 20")
        tau = log_torque(log, robot)
        if tau is None:
            raise DynamicsIdentificationError(f"{where}: no joint torque, and no motor "
                                              f"currents with {robot.name}'s torque "
                                              "constants (Joint.torque_constant)")  # fmt: skip
        parts.append(smoothed_signals(log, settings.bandwidth, tau))
    stacked = [np.concatenate(arrays) for arrays in zip(*parts, strict=True)]
    stride = max(1, int(np.ceil(len(stacked[0]) / settings.max_samples)))
    return tuple(array[::stride] for array in stacked)


def _prior(
    robot: RobotDescription, friction: FrictionModel, settings: DynamicsSettings
) -> tuple[FloatArray, FloatArray]:
    """Prior mean and standard deviation of ``x``.

    Inertial parameters: 25 % of the nominal (mass +0.1 kg, first moments with a 5 cm
    lever floor, inertias 30 % of the link's largest plus 5e-3 kg m²); armature 50 % or
    0.1 kg m²; friction 30 % + 0.5; offsets 2 Nm.
    """
    n = robot.n_joints
    pi = inertial_parameters(robot)
    std = np.empty_like(pi)
    for i in range(n):
        p = pi[10 * i : 10 * i + 10]
        mass = abs(p[0])
        lever = np.linalg.norm(p[1:4]) / max(mass, 1e-9)
        std[10 * i] = 0.25 * mass + 0.1
        std[10 * i + 1 : 10 * i + 4] = 0.25 * mass * (lever + 0.05) + 0.01
        std[10 * i + 4 : 10 * i + 10] = 0.3 * np.max(np.abs(p[[4, 6, 9]])) + 5e-3
    armature = robot.reflected_rotor_inertias
    mean = np.concatenate([pi, armature, friction.coulomb, friction.viscous, np.zeros(n)])
    spread = np.concatenate([std, np.maximum(0.5 * armature, 0.1),
                             0.3 * friction.coulomb + 0.5, 0.3 * friction.viscous + 0.5,
                             np.full(n, 2.0)])  # fmt: skip
    return mean, spread * settings.prior_scale


def _posterior(
    rows: FloatArray, target: FloatArray, noise: FloatArray, prior: FloatArray, std: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Posterior mean and standard deviation of the Gaussian linear model."""
    from scipy import linalg  # at call time: keeps `import leadthrough` fast

    weighted = rows / noise[:, None]
    precision = weighted.T @ weighted + np.diag(1.0 / std**2)
    rhs = weighted.T @ (target / noise) + prior / std**2
    factor = linalg.cho_factor(precision)
    x = linalg.cho_solve(factor, rhs)
    covariance = linalg.cho_solve(factor, np.eye(len(x)))
    return x, np.sqrt(np.diag(covariance))


def _gains(
    predicted: FloatArray,
    measured: FloatArray,
    noise: FloatArray,
    joint: np.ndarray,
    n: int,
    prior_std: float,
) -> FloatArray:
    """Drive-gain scales g minimising Σ (τ − p / g)² / σ² + (1/g − 1)² / σ_g², π held.

    Linear in u = 1/g: the measured torque τ is the model's torque p over g. The overall
    scale of (π, g) is flat in the data; the priors on both hold it (their std:
    :func:`_gain_std`).
    """
    u = np.ones(n)
    for j in range(n):
        mine = joint == j
        p, tau, w = predicted[mine], measured[mine], 1.0 / noise[mine] ** 2
        information = np.sum(w * p * p) + 1.0 / prior_std**2
        u[j] = (np.sum(w * p * tau) + 1.0 / prior_std**2) / information
    return 1.0 / u


def _gain_std(
    rows: FloatArray,
    measured: FloatArray,
    noise: FloatArray,
    joint: np.ndarray,
    x: FloatArray,
    gain: FloatArray,
    priors: tuple[FloatArray, float],
) -> FloatArray:
    """Posterior std of each drive-gain scale g_j with π free too (Laplace, at (π, g)) [–].

    :func:`_gains` fits g with π held, and its std is that of g *given* π: 0.1 %,
    however the currents are scaled. But ``τ = Y π / g_j`` is unchanged by (s π, s g):
    the data do not see the overall scale of π and g, which only their priors hold.
    The std of the joint posterior, linearised at the fit, says so: on the UR10e's ten
    excitation runs 5–13 % instead of 0.1 %.
    """
    from scipy import linalg  # at call time: keeps `import leadthrough` fast

    prior_std, gain_std = priors
    n, count = len(gain), len(measured)
    g = gain[joint]
    jacobian = np.zeros((count, len(x) + n))
    jacobian[:, : len(x)] = -rows / g[:, None]
    jacobian[np.arange(count), len(x) + joint] = (rows @ x) / g**2
    jacobian /= noise[:, None]
    precision_prior = 1.0 / np.concatenate([prior_std, np.full(n, gain_std)]) ** 2
    precision = jacobian.T @ jacobian + np.diag(precision_prior)
    covariance = linalg.cho_solve(linalg.cho_factor(precision), np.eye(len(x) + n))
    return np.sqrt(np.diag(covariance)[-n:])


def _per_joint_rms(residual: FloatArray, joint: np.ndarray, n: int) -> FloatArray:
    return np.array([np.sqrt(np.mean(residual[joint == j] ** 2)) if np.any(joint == j)
                     else 1.0 for j in range(n)])  # fmt: skip


def _blocks(x: FloatArray, std: FloatArray, n: int) -> tuple[FloatArray, dict[str, FloatArray]]:
    """(offsets, posterior std of each per-joint block by name)."""
    blocks = {name: slice(10 * n + b * n, 10 * n + (b + 1) * n) for b, name in enumerate(BLOCKS)}
    return x[blocks["offset"]], {name: std[part] for name, part in blocks.items()}
