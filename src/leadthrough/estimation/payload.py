"""Payload mass and centre of mass from the joint torque a payload adds.

A rigid payload of mass m with centre of mass c in the flange frame adds, at every
sample, a torque linear in θ = (m, m c) [kg, kg m]::

    τ − τ_model(q, q̇, q̈) − τ_f(q̇) = Y_p(q, q̇, q̈) θ + Y_n(q̇) β + e

``Y_p`` is Pinocchio's joint-torque regressor of the last body, restricted to its mass
and first moment and moved to the flange frame (gravity and the translational
dynamics of the payload; its own rotational inertia, small for a compact tool, is
taken as that of a point mass and refined once). ``τ_model`` is the **unloaded** arm's
rigid-body torque and ``τ_f`` its friction model's mean.

Assumptions (the estimate is only as good as they are):

- The robot description is the arm *without* payload, and it is right up to what the
  nuisance terms ``Y_n β`` absorb: a constant offset per joint and a correction of each
  joint's Coulomb and viscous friction (friction grows with the load a drive carries).
  Any other error of the unloaded model that resembles a payload's torque reads as a
  payload: an identified model (``lt.identify_dynamics``) is much better here than a
  nominal URDF. When logs of the same arm *without* the payload are given
  (``unloaded=``, ideally the same motions), their apparent payload is estimated in the
  same way and subtracted: the unloaded model's error then cancels.
- Measured torque is K·i with the robot's torque constants: a gain error of x % scales
  the mass by x % (unloaded runs do not cancel it). ``gain_error`` (5 %) puts that into
  the std; the UR10e's published K and its controller's own ratio differ by 11–14 % on
  joints 2–3, so identify K (``lt.identify_dynamics``) or weigh a known mass once.
- Samples are weighted by the model's torque uncertainty: a floor, a relative error of
  the rigid-body torque and the friction model's std (at rest the friction may hold
  anything up to its Coulomb level, so static samples say little on joints with large
  friction). The weights are refined once from the residual RMS per joint.
- The std comes from the residuals, which are correlated in time: the covariance is
  the cluster-robust ("sandwich") one over blocks of ``block_time`` seconds, so it is
  honest for slowly varying model errors, not only for white noise.
- A model error does not average out over samples: each joint's rigid-body model
  torque is taken as wrong by a systematic relative ``model_error`` (3 %: a nominal
  URDF; the UR10e's reads 0.2–0.45 kg of phantom payload on unloaded runs) and its
  effect on θ is added to the covariance. With ``unloaded`` runs the same error shifts
  both fits, so only the difference of the two effects remains (≈ 0 for the same
  motions). Unloaded runs of another *kind* of motion cancel less than that says: on
  the real UR10e, point-to-point motion against ten static holds read 0.16 ± 0.04 kg
  for no payload (friction at rest is not friction in motion); use the same motions.
- Scope: a payload rigidly fixed to the flange, the same in every loaded log; logs of
  one pose only cannot separate m from m c (an error). Excitation that moves joints
  2–6 over a wide range (±0.4 rad or more) gives mass std < 0.1 kg.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from leadthrough.errors import LeadthroughError, ParameterError
from leadthrough.estimation.log_observer import measured_torque, resample
from leadthrough.friction.model import FrictionModel
from leadthrough.logs.log import JointLog, joint_logs
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.model.pinocchio_model import FLANGE_FRAME
from leadthrough.validation import real


class PayloadError(LeadthroughError, ValueError):
    """The logs cannot tell a payload (no logs, too short, nothing excites it)."""


#: Logs whose every joint stays within this of one value hold one pose [rad]: there the
#: per-joint offsets take up any payload torque, and the component of m c along gravity
#: turns no joint, so m and c are not separable (a static hold reads 91 m off the flange).
ONE_POSE = 0.01


@dataclass(frozen=True)
class PayloadParameters:
    """Settings of the payload regression.

    Attributes:
        smoothing_time: Window of the Savitzky–Golay filter that gives q̈ and smooths τ
            [s].
        sample_period: The smoothed samples are used every this long [s].
        rigid_body_error: Relative error of the unloaded rigid-body torque, for the
            weights [–].
        torque_floor: Smallest torque std of a sample [Nm].
        block_time: Length of the blocks of the cluster-robust covariance [s].
        prior_offset: Prior std of the per-joint torque offset [Nm].
        prior_friction: Prior std of the friction corrections, as a fraction of each
            joint's Coulomb level [–].
        model_error: Relative systematic error of each joint's rigid-body model torque,
            propagated into the covariance (it does not average out over samples) [–].
            With ``unloaded`` runs of the same motions it cancels.
        gain_error: Relative error of each joint's drive gain (K of τ = K·i, or a
            torque sensor's scale) [–]; it scales the payload's torque, so unloaded runs
            do not cancel it. 0 when the torque is known exactly (a simulation).
    """

    smoothing_time: float = 0.15
    sample_period: float = 0.02
    rigid_body_error: float = 0.05
    torque_floor: float = 0.5
    block_time: float = 1.0
    prior_offset: float = 10.0
    prior_friction: float = 0.5
    model_error: float = 0.03
    gain_error: float = 0.05

    def __post_init__(self) -> None:
        for name in ("smoothing_time", "sample_period", "block_time", "torque_floor"):
            real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)
        for name in ("rigid_body_error", "prior_offset", "prior_friction", "model_error",
                     "gain_error"):  # fmt: skip
            real(name, getattr(self, name), minimum=0.0, error=ParameterError)


@dataclass(frozen=True, eq=False)
class PayloadEstimate:
    """An estimated payload.

    Attributes:
        mass: Payload mass [kg].
        com: Its centre of mass in the flange frame [m], shape (3,).
        mass_std: Standard deviation of ``mass`` [kg].
        com_std: Standard deviation of each coordinate of ``com`` [m], shape (3,).
        covariance: Covariance of θ = (m, m c_x, m c_y, m c_z) [kg², kg² m, kg² m²].
        residual_rms: RMS of the weighted fit's torque residual per joint [Nm], (n,).
        n_samples: Samples used.
    """

    mass: float
    com: FloatArray
    mass_std: float
    com_std: FloatArray
    covariance: FloatArray = field(repr=False)
    residual_rms: FloatArray = field(repr=False)
    n_samples: int = 0

    @property
    def first_moment(self) -> FloatArray:
        """The first moment m c [kg m], shape (3,)."""
        return self.mass * self.com


@dataclass(frozen=True, eq=False)
class _Rows:
    """Stacked regression rows of some logs (samples × joints flattened)."""

    payload: FloatArray  # (N n, 4): columns of θ = (m, m c)
    inertia: FloatArray  # (N n, 6): the last body's rotational-inertia columns (flange)
    nuisance: FloatArray  # (N n, 3 n)
    residual: FloatArray  # (N n,)
    model: FloatArray  # (N n,)  the unloaded model's rigid-body torque
    measured: FloatArray  # (N n,)  the measured (smoothed) torque
    std: FloatArray  # (N n,)  prior torque std per row
    block: FloatArray  # (N n,)  cluster label
    joint: FloatArray  # (N n,)  joint index


def estimate_payload(
    logs: Sequence[JointLog] | JointLog,
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    unloaded: Sequence[JointLog] | JointLog | None = None,
    parameters: PayloadParameters | None = None,
) -> PayloadEstimate:
    """Estimate the payload carried in ``logs`` (module docstring: model and assumptions).

    Args:
        logs: Runs of the loaded arm (``tau``, or ``current`` and the robot's torque
            constants); several poses and motions make the estimate well-posed.
        robot: The arm's model *without* the payload (nominal or identified).
        friction: Its friction model; None takes the robot's.
        unloaded: Runs of the same arm without the payload (best the same motions):
            their apparent payload is subtracted.
        parameters: Regression settings.

    Returns:
        Mass [kg] and centre of mass in the flange frame [m] with their std.

    Raises:
        PayloadError: No logs, logs of one pose (:data:`ONE_POSE`), or data that cannot
            separate mass and centre of mass.
        LogInputError: A log without torque or current, or with another joint count.
    """
    logs = joint_logs(logs)
    if not logs:
        raise PayloadError("estimate_payload: no logs given")
    parameters = parameters or PayloadParameters()
    friction = friction or FrictionModel.from_robot(robot)
    regressor = _PayloadRegressor(robot)
    coulomb = np.asarray(friction.coulomb, dtype=float)

    def fit(runs: list[JointLog]) -> _Fit:
        rows = _rows(runs, regressor, friction, parameters)
        _require_poses(runs)
        return _fit(rows, parameters, coulomb, regressor.point_inertia_parameters)

    loaded = fit(logs)
    theta, covariance = loaded.theta, loaded.covariance
    bias, gain = loaded.bias, loaded.gain_bias
    if unloaded is not None:
        empty = fit(joint_logs(unloaded))
        theta, covariance = theta - empty.theta, covariance + empty.covariance
        bias, gain = bias - empty.bias, gain - empty.gain_bias  # shifted alike in both fits
    systematic = (parameters.model_error**2 * (bias @ bias.T)
                  + parameters.gain_error**2 * (gain @ gain.T))  # fmt: skip
    return _estimate(theta, covariance + systematic, loaded.rms, loaded.count)


def _require_poses(runs: list[JointLog]) -> None:
    """Raise :class:`PayloadError` if ``runs`` together hold one pose (:data:`ONE_POSE`)."""
    q = np.concatenate([np.asarray(run.q, dtype=float) for run in runs])
    span = float(np.max(np.ptp(q, axis=0))) if q.size else 0.0
    if span < ONE_POSE:
        names = ", ".join(str(run.source or "log") for run in runs[:3])
        raise PayloadError(f"{names}: the logs hold one pose (no joint moved more than "
                           f"{span * 1e3:.1f} mrad): a payload's mass and centre of mass "
                           "need several poses or a motion")  # fmt: skip


@dataclass(frozen=True, eq=False)
class _Fit:
    """One regression of θ = (m, m c).

    ``bias`` (4, n) is the shift of θ if joint j's rigid-body model torque were 100 %
    too large: a systematic error that more samples do not average away; ``gain_bias``
    (4, n) the shift if joint j's measured torque were 100 % too large (its drive gain).
    """

    theta: FloatArray
    covariance: FloatArray
    rms: FloatArray
    count: int
    bias: FloatArray
    gain_bias: FloatArray


class _PayloadRegressor:
    """Torque columns of a payload's (m, m c) and point-mass inertia, flange frame."""

    def __init__(self, robot: RobotDescription) -> None:
        self.dynamics = Dynamics(robot)
        model = self.dynamics.model
        self.data = model.createData()
        flange = model.frames[model.getFrameId(FLANGE_FRAME)].placement
        self.rotation, self.translation = flange.rotation.copy(), flange.translation.copy()
        self.n = robot.n_joints

    def columns(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> tuple[FloatArray, ...]:
        """(payload (n, 4), inertia (n, 6)) regressor columns at one sample."""
        model = self.dynamics.model
        last = pin.computeJointTorqueRegressor(model, self.data, q, qd, qdd)[:, -10:]
        mass = last[:, 0] + last[:, 1:4] @ self.translation
        moment = last[:, 1:4] @ self.rotation
        return np.column_stack([mass, moment]), last[:, 4:10]

    def point_inertia_parameters(self, theta: FloatArray) -> FloatArray:
        """The 6 inertia parameters (about the last joint's origin) of a point payload θ.

        θ = (m, m c) with c in the flange frame; zero while the mass is not positive.
        """
        mass = float(theta[0])
        if mass <= 1e-3:
            return np.zeros(6)
        at = self.translation + self.rotation @ (theta[1:] / mass)
        return pin.Inertia(mass, at, np.zeros((3, 3))).toDynamicParameters()[4:10]


def _rows(
    logs: list[JointLog],
    regressor: _PayloadRegressor,
    friction: FrictionModel,
    parameters: PayloadParameters,
) -> _Rows:
    from scipy.signal import savgol_filter  # at call time: keeps the import fast

    parts: list[tuple[FloatArray, ...]] = []
    n = regressor.n
    blocks = 0.0
    for log in logs:
        t, q, qd, tau = resample(log, measured_torque(log, regressor.dynamics.robot))
        dt = float(t[1] - t[0])
        window = max(5, round(parameters.smoothing_time / dt) | 1)
        if t.size < 2 * window:
            raise PayloadError(f"{log.source or 'log'}: too short for a payload estimate "
                               f"({log.duration:.2f} s)")  # fmt: skip
        qdd = savgol_filter(qd, window, 2, deriv=1, delta=dt, axis=0)
        qd_s = savgol_filter(qd, window, 2, axis=0)
        tau_s = savgol_filter(tau, window, 2, axis=0)
        step = max(1, round(parameters.sample_period / dt))
        keep = np.arange(window, t.size - window, step)  # away from the filter's edges
        for k in keep:
            payload, inertia = regressor.columns(q[k], qd_s[k], qdd[k])
            model = regressor.dynamics.inverse_dynamics(q[k], qd_s[k], qdd[k])
            mean, std = friction.mean_and_std(qd_s[k], q[k])
            sigma = np.sqrt(parameters.torque_floor**2 + std**2
                            + (parameters.rigid_body_error * model) ** 2)  # fmt: skip
            block = blocks + np.floor((t[k] - t[0]) / parameters.block_time)
            parts.append((payload, inertia, _nuisance(qd_s[k], friction),
                          tau_s[k] - model - mean, model, tau_s[k], sigma, np.full(n, block),
                          np.arange(n, dtype=float)))  # fmt: skip
        blocks += np.floor(log.duration / parameters.block_time) + 1.0
    stacked = [np.concatenate(column) for column in zip(*parts, strict=True)]
    return _Rows(*stacked)


def _nuisance(qd: FloatArray, friction: FrictionModel) -> FloatArray:
    """Per-joint offset, Coulomb and viscous columns (n, 3 n), scaled to the friction."""
    n = qd.size
    sign = np.tanh(0.5 * friction.slope * qd)
    columns = np.zeros((n, 3 * n))
    rows = np.arange(n)
    columns[rows, 3 * rows] = 1.0
    columns[rows, 3 * rows + 1] = sign
    columns[rows, 3 * rows + 2] = qd
    return columns


def _fit(
    rows: _Rows,
    parameters: PayloadParameters,
    coulomb: FloatArray,
    point_inertia: Callable[[FloatArray], FloatArray],
) -> _Fit:
    """Weighted least squares with priors on the nuisance; cluster-robust covariance.

    Three passes: the payload's point-mass inertia is put in from the last θ and the
    weights of each joint are rescaled so that its weighted residual is of unit RMS.
    """
    n = coulomb.size
    design = np.column_stack([rows.payload, rows.nuisance])
    prior = np.zeros(design.shape[1])
    prior[4::3] = parameters.prior_offset
    prior[5::3] = parameters.prior_friction * np.maximum(coulomb, 0.1)
    prior[6::3] = parameters.prior_friction * np.maximum(coulomb, 0.1)
    joint = rows.joint.astype(int)
    std = rows.std.copy()
    theta = np.zeros(4)
    for _ in range(3):
        target = rows.residual - rows.inertia @ point_inertia(theta)
        solution, covariance, gain = _weighted_solve(design, target, 1.0 / std, prior,
                                                     rows.block)  # fmt: skip
        theta = solution[:4]
        error = target - design @ solution
        rms = np.sqrt(np.bincount(joint, error**2, n) / np.bincount(joint, None, n))
        ratio = np.sqrt(np.bincount(joint, (error / std) ** 2, n) / np.bincount(joint, None, n))
        std = std * np.maximum(ratio, 1e-3)[joint]
    # a model torque too large by 100 % on joint j lowers every residual of joint j by it
    bias = np.column_stack([-gain[:4, joint == j] @ rows.model[joint == j] for j in range(n)])
    scaled = np.column_stack([gain[:4, joint == j] @ rows.measured[joint == j] for j in range(n)])
    return _Fit(theta, covariance[:4, :4], rms, rows.residual.size // n, bias, scaled)


def _weighted_solve(
    design: FloatArray,
    target: FloatArray,
    weights: FloatArray,
    prior: FloatArray,
    block: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Solution and cluster-robust covariance of min Σ (w (y − A x))² + Σ (x_i / prior_i)²."""
    weighted = design * weights[:, None]
    regular = np.diag(np.where(prior > 0, 1.0 / np.maximum(prior, 1e-12) ** 2, 0.0))
    normal = weighted.T @ weighted + regular
    if np.linalg.cond(normal[:4, :4]) > 1e12:
        raise PayloadError("estimate_payload: the logs do not excite the payload's torque")
    inverse = np.linalg.inv(normal)
    solution = inverse @ (weighted.T @ (target * weights))
    error = (target - design @ solution) * weights
    labels = np.unique(block, return_inverse=True)[1]
    scores = np.zeros((labels.max() + 1, design.shape[1]))
    np.add.at(scores, labels, weighted * error[:, None])
    gain = inverse @ (weighted * weights[:, None]).T  # d solution / d target
    return solution, inverse @ (scores.T @ scores) @ inverse, gain


def _estimate(
    theta: FloatArray, covariance: FloatArray, rms: FloatArray, count: int
) -> PayloadEstimate:
    mass = float(theta[0])
    safe = mass if abs(mass) > 1e-9 else 1e-9
    com = theta[1:] / safe
    jacobian = np.column_stack([-theta[1:] / safe**2, np.eye(3) / safe])  # d c / d θ
    com_covariance = jacobian @ covariance @ jacobian.T
    return PayloadEstimate(mass, com, float(np.sqrt(covariance[0, 0])),
                           np.sqrt(np.diag(com_covariance)), covariance, rms, count)  # fmt: skip
