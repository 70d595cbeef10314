"""Automatic identification of the Gaussian friction model from excitation logs.

The thesis tuned its sigmoids by hand (§4.1.2); here they are fitted. Per log:

1. filter q, q̇ and τ with H(z) of eq. (4.6) and differentiate q̇ for q̈;
2. the friction torque is what the motors give beyond the rigid body,
   ``τ_f = τ − (M q̈ + C q̇ + G)`` (SPEC §1, no external torque during the experiment).

Per joint, from the logs where that joint moved:

3. sliding samples (|q̇| ≥ ``sliding_velocity``) fix the Coulomb level, its position
   dependence and the viscous coefficient by *linear* least squares,
   ``τ_f = sign(q̇) τ_C (1 + k₁ u + k₂ u²) + c q̇`` with τ_C, c ≥ 0. The position terms
   are fitted only where the runs cover enough of the range; they describe the stroke
   the sliding samples cover (``u`` = ±1 at its ends), the model holds its end values
   beyond it (a quadratic fitted to 45 % of a range and extrapolated over the rest read
   a level 2.2× too high, or below zero on a single sweep of a ±2π joint), and the level
   is constrained to stay above ``MIN_LEVEL`` τ_C over the stroke, so everywhere. The
   same least squares fits what does not change sign with the motion, a torque offset and
   the first harmonic of the joint's angle where it moved alone (:func:`unsigned_basis`: a
   gravity model's error), and takes it off every sample of the joint, so that it neither
   biases the level nor counts as friction noise;
4. the noise σ is the standard deviation of the sliding residual (the thesis' "variance
   of the friction torque at high velocities");
5. the sigmoid slope A and half-width B are fitted (SciPy ``least_squares``, robust loss)
   to the slow samples with τ_C and c held, and may widen the prior's rest band but not
   narrow it (B and A B at least the prior's): an excitation passes through zero speed in
   a sample or two and never dithers, so its data cannot say how slow a joint must be to
   rest, and a band fitted to them closed at 0.2–0.5 mrad/s, where a dithered joint at
   rest twitches (the prior, the thesis' Table 4.1 for the YuMi: 2–3 mrad/s);
6. the level's relative error (``relative_error``): 3 std of τ_C plus the largest
   deviation of the level measured along the travel, up and down strokes compared at the
   same positions, the other joints still (:mod:`leadthrough.friction.along_travel`, free
   of gravity error), from the fitted ``τ_C(q)``; where too little travel was passed both
   ways with the other joints still, 2 std of the sliding residual instead, which carries
   any rigid-body model error too.

Parameter standard deviations come from the least-squares covariance.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from leadthrough.errors import LeadthroughError, ParameterError
from leadthrough.filters import low_pass_signal, pole
from leadthrough.friction.along_travel import level_along_travel, level_error
from leadthrough.friction.model import FrictionModel, level_stays_positive, sigmoid
from leadthrough.logs.log import (
    JointLog,
    as_joint_log,
    log_item,
    one_or_many,
    period_problem,
    rate_problem,
)
from leadthrough.logs.runs import log_name, refuse_repeated_logs
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics

#: Smallest relative Coulomb error an identification claims (a model is never perfect).
MIN_RELATIVE_ERROR = 0.03
#: A fitted position-dependent Coulomb level stays above this fraction of its value at the
#: stroke's middle over the stroke, and so everywhere (no joint loses its friction).
MIN_LEVEL = 0.1
#: Each direction's least share of a joint's sliding samples for the fit to separate what
#: does not change sign with the motion (:func:`unsigned_basis`) from friction [–].
BOTH_WAYS = 0.25
#: A fitted τ_C [Nm] or c [Nm s/rad] at or below this sits on its bound, 0.
ON_BOUND = 1e-9


class IdentificationError(LeadthroughError, ValueError):
    """The logs cannot identify the friction (too short, NaN, a joint that never moved)."""


@dataclass(frozen=True)
class IdentificationSettings:
    """Choices of the fit.

    Attributes:
        sliding_velocity: Samples faster than this are sliding [rad/s]; slower ones carry
            stiction and Stribeck effects that the sigmoid model does not describe.
        moving_velocity: A joint "moved" in a log when it exceeded this speed [rad/s].
        minimum_samples: Fewest sliding samples per joint for a fit [–].
        position_span: Fraction of the joint range the runs must cover to fit the
            position dependence [–].
    """

    sliding_velocity: float = 0.04
    moving_velocity: float = 0.1
    minimum_samples: int = 200
    position_span: float = 0.25


@dataclass(frozen=True, eq=False)
class FitReport:
    """Quality of an identification, per joint (arrays of n).

    Attributes:
        residual_rms: RMS of the sliding residual [Nm].
        samples: Sliding samples used [–].
        parameter_std: Standard deviation of each fitted parameter, by name.
        position_fitted: Whether the position dependence was fitted.
        joints: Joints identified (0-based); the others keep NaN in the arrays.
        level_error: Largest relative deviation of the Coulomb level measured along the
            travel (up and down strokes at the same positions) from the fitted τ_C(q) [–];
            NaN where too little travel was passed both ways.
    """

    residual_rms: FloatArray
    samples: FloatArray
    parameter_std: dict[str, FloatArray]
    position_fitted: np.ndarray
    joints: tuple[int, ...]
    level_error: FloatArray

    def not_identified(self) -> tuple[int, ...]:
        """Joints (0-based) not identified: their model values are the prior's."""
        return tuple(j for j in range(len(self.samples)) if j not in self.joints)

    def not_identified_note(self) -> str:
        """One line naming the joints not identified (1-based), or "" when every one was."""
        joints = self.not_identified()
        if not joints:
            return ""
        names = ", ".join(str(j + 1) for j in joints)
        several = len(joints) > 1
        return (f"joint{'s' if several else ''} {names} not identified (not asked for, or "
                f"never slid long enough in the logs): friction.toml keeps the robot file's "
                f"nominal friction for {'them' if several else 'it'}")  # fmt: skip

    def __str__(self) -> str:
        lines = [f"{'joint':>5}{'samples':>9}{'RMS [Nm]':>10}{'±τ_C':>9}{'±c':>9}{'position':>10}"
                 f"{'level off along travel':>24}"]  # fmt: skip
        for j in self.joints:
            std, off = self.parameter_std, self.level_error[j]
            lines.append(
                f"{j + 1:>5}{self.samples[j]:>9.0f}{self.residual_rms[j]:>10.4f}"
                f"{std['coulomb'][j]:>9.4f}{std['viscous'][j]:>9.4f}"
                f"{'yes' if self.position_fitted[j] else 'no':>10}"
                f"{f'{100 * off:.1f} %' if np.isfinite(off) else '–':>24}"
            )
        return "\n".join(lines)


@dataclass(frozen=True, eq=False)
class FrictionSamples:
    """Friction torque samples of all logs, after filtering and model removal, (N, n).

    Attributes:
        q: Filtered joint positions [rad].
        qd: Filtered joint velocities [rad/s].
        tau_friction: Friction torque τ − (M q̈ + C q̇ + G) [Nm].
        moved: Whether each sample's log moved each joint (N, n) booleans.
    """

    q: FloatArray
    qd: FloatArray
    tau_friction: FloatArray
    moved: np.ndarray


def identify_friction(
    logs: Any,
    robot: Dynamics | RobotDescription | None = None,
    joints: Sequence[int] | None = None,
    settings: IdentificationSettings | None = None,
    prior: FrictionModel | None = None,
    *,
    dynamics: Dynamics | RobotDescription | None = None,
) -> tuple[FrictionModel, FitReport]:
    """Fit the Gaussian friction model to excitation logs.

    Args:
        logs: One log or a list of logs (mappings or objects with arrays ``t`` (N,),
            ``q``, ``qd``, ``tau`` (N, n)); ``tau`` is the measured motor torque, arm side.
            A :class:`~leadthrough.logs.log.JointLog` of motor currents (``lt.read_log``
            of a UR CSV without the robot) takes ``K · i`` with the robot's torque
            constants, as ``identify_dynamics`` does.
        robot: The robot description (its model is built here), or its model
            (:class:`Dynamics`), used to remove gravity and inertia torques.
        dynamics: The same, by its former name (``dynamics=`` still works).
        joints: Joints to identify, 0-based (default: every joint that moved in some log and
            slid for at least ``settings.minimum_samples`` samples; a joint that only
            twitched is left at the prior rather than failing the whole fit).
        settings: Thresholds of the fit.
        prior: Values kept for joints not identified (default: the description's);
            ``report.joints`` names the joints identified, :meth:`FitReport.not_identified`
            the others.

    Returns:
        The identified model and its fit report.

    Raises:
        IdentificationError: A log is malformed, no joint moved, or a requested joint
            never moved.
        ParameterError: A log is given twice: the same object, or one run read twice
            (:func:`~leadthrough.logs.runs.refuse_repeated_logs`); a joint is no index
            0 … n − 1.

    Warns:
        UserWarning: Per joint whose τ_C sits on its bound 0: a current or torque of the
            wrong sign, a wrong torque constant or a poor rigid-body model is the likely
            cause.
    """
    settings = settings or IdentificationSettings()
    model = robot if robot is not None else dynamics
    if model is None:
        raise ParameterError("robot", "the robot (or its Dynamics) is needed to remove gravity "
                             "and inertia")  # fmt: skip
    if isinstance(model, RobotDescription):
        model = Dynamics(model)
    samples = friction_samples(logs, model, settings)
    return fit_friction(samples, model, joints, settings, prior)


def fit_friction(
    samples: FrictionSamples,
    dynamics: Dynamics,
    joints: Sequence[int] | None = None,
    settings: IdentificationSettings | None = None,
    prior: FrictionModel | None = None,
) -> tuple[FrictionModel, FitReport]:
    """The fit of :func:`identify_friction`, on samples from :func:`friction_samples`."""
    settings = settings or IdentificationSettings()
    moved = np.flatnonzero(samples.moved.any(axis=0))
    if moved.size == 0:  # nothing to fit: the prior must not come back as a result
        raise IdentificationError(f"no joint moved faster than {settings.moving_velocity:g} "
                                  f"rad/s in any log: nothing to identify")  # fmt: skip
    if joints is None:
        joints = tuple(int(j) for j in moved if _sliding_count(samples, int(j), settings)
                       >= settings.minimum_samples)  # fmt: skip
        if not joints:
            raise IdentificationError(f"no joint slid faster than {settings.sliding_velocity:g}"
                                      f" rad/s for {settings.minimum_samples} samples")  # fmt: skip
    joints = _valid_joints(joints, dynamics.n)
    for j in joints:
        if j not in moved:
            raise IdentificationError(f"joint {j + 1} never moved faster than "
                                      f"{settings.moving_velocity:g} rad/s in any log")  # fmt: skip
    prior = prior or FrictionModel.from_robot(dynamics.robot)
    values = {name: getattr(prior, name).copy() for name in prior.to_dict()} | {
        "relative_error": prior.relative_error.copy(),
        "position_mid": prior.position_mid.copy(),
        "position_half_range": prior.position_half_range.copy(),
        "position_linear": prior.position_linear.copy(),
        "position_quadratic": prior.position_quadratic.copy(),
    }
    n = dynamics.n
    report = _empty_report(n, joints)
    for j in joints:
        _fit_joint(j, samples, dynamics, settings, values, report)
    values["identified"] = np.isin(np.arange(n), joints)
    return FrictionModel(**values), report


def _valid_joints(joints: Sequence[Any], n: int) -> tuple[int, ...]:
    """``joints`` as indices, each an integer 0 … n − 1.

    Raises:
        ParameterError: One is not (7 of a 6-joint arm read "joint 7 never moved", −1
            "joint 0", 1.5 was truncated to 1), or there are none (the prior came back as
            the result).
    """
    if not joints:  # the prior would come back as a result
        raise ParameterError("joints", "is empty: give the joints to identify, or None for "
                             "every joint that slid")  # fmt: skip
    if not all(isinstance(j, int | np.integer) and not isinstance(j, bool) and 0 <= j < n
               for j in joints):  # fmt: skip
        raise ParameterError(
            "joints",
            f"joints are numbered 0 to {n - 1} here (0-based; the "
            f"command line's --joints counts 1 to {n}), got {list(joints)}",
        )
    return tuple(int(j) for j in joints)


def _sliding_count(samples: FrictionSamples, j: int, settings: IdentificationSettings) -> int:
    """Sliding samples of joint ``j`` in the logs where it moved."""
    return int(
        np.sum(samples.moved[:, j] & (np.abs(samples.qd[:, j]) >= settings.sliding_velocity))
    )


def friction_samples(
    logs: Any, dynamics: Dynamics, settings: IdentificationSettings | None = None
) -> FrictionSamples:
    """Filtered samples and friction torques of every log, stacked.

    Raises:
        IdentificationError: No log, or a log is malformed.
        ParameterError: A log is given twice (:func:`~leadthrough.logs.runs.refuse_repeated_logs`).
    """
    settings = settings or IdentificationSettings()
    logs = one_or_many(logs)
    if not logs:
        raise IdentificationError("no logs given")
    paths = [log for log in logs if isinstance(log, str | os.PathLike)]
    if paths:  # a path given as a log (its characters were taken for logs)
        raise IdentificationError(f"logs: {paths[0]} is a path: read it first, "
                                  "lt.read_log(path)")  # fmt: skip
    refuse_repeated_logs(logs)
    parts = [_log_samples(i, log, dynamics, settings) for i, log in enumerate(logs)]
    return FrictionSamples(*(np.concatenate(arrays) for arrays in zip(*parts, strict=True)))


def log_field(log: Any, name: str, index: int = 0) -> FloatArray:
    """Array ``name`` of a log given as a mapping or an object."""
    try:
        value = log[name] if isinstance(log, Mapping) else getattr(log, name)
    except (KeyError, AttributeError):
        raise IdentificationError(f"{log_name(log, index)}: missing '{name}'") from None
    return np.asarray(value, dtype=float)


def _measured_torque(log: Any, index: int, robot: RobotDescription) -> FloatArray:
    """The log's arm-side torque [Nm]: ``tau``, or ``K · i`` of a log of currents."""
    if not isinstance(log, JointLog):
        if log_item(log, "tau") is not None or log_item(log, "current") is None:
            return log_field(log, "tau", index)  # or the line saying it is missing
        log = as_joint_log(log, index)  # currents, as a mapping or an object
    if isinstance(log, JointLog):
        torque = log.joint_torque(robot.torque_constants)
        if torque is None:
            has = "no motor currents" if log.current is None else "currents"
            raise IdentificationError(f"{log_name(log, index)}: no measured torque, and {has} "
                                      f"without {robot.name}'s torque constants")  # fmt: skip
        return torque
    return log_field(log, "tau", index)


def _log_samples(
    index: int, log: Any, dynamics: Dynamics, settings: IdentificationSettings
) -> tuple[FloatArray, ...]:
    """(q, q̇, τ_f, moved) of one validated log."""
    t, q, qd = (log_field(log, name, index) for name in ("t", "q", "qd"))
    tau = _measured_torque(log, index, dynamics.robot)
    n, label = dynamics.n, log_name(log, index)
    if t.ndim != 1 or len(t) < 50:
        raise IdentificationError(f"{label}: too short ({len(t)} samples, need ≥ 50)")
    for name, array in (("q", q), ("qd", qd), ("tau", tau)):
        if array.ndim == 2 and len(array) == len(t) and array.shape[1] != n:
            raise IdentificationError(f"{label}: {array.shape[1]} joints, but "
                                      f"{dynamics.robot.name} has {n}")  # fmt: skip
        if array.shape != (len(t), n):
            raise IdentificationError(f"{label}: '{name}' has shape {array.shape}, "
                                      f"expected ({len(t)}, {n}) like 't'")  # fmt: skip
    for name, array in (("t", t), ("q", q), ("qd", qd), ("tau", tau)):
        bad = np.argwhere(~np.isfinite(array))
        if bad.size:
            where = f"sample {bad[0][0]}" + (f", joint {bad[0][1] + 1}" if array.ndim > 1 else "")
            raise IdentificationError(f"{label}: '{name}' is not finite at {where}")
    if np.any(np.diff(t) <= 0):
        raise IdentificationError(f"{label}: 't' must increase strictly")
    period = float(np.median(np.diff(t)))
    problem = period_problem(period) or rate_problem(t, q, qd)
    if problem is not None:
        raise IdentificationError(f"{label}: {problem}")
    smoothing = pole(period)  # the thesis' 7.8 ms at the log's rate
    q_f, qd_f, tau_f = (low_pass_signal(x, smoothing) for x in (q, qd, tau))
    qdd = np.gradient(qd_f, t, axis=0)
    rigid = np.array([dynamics.inverse_dynamics(*row) for row in zip(q_f, qd_f, qdd, strict=True)])
    moved = np.abs(qd_f).max(axis=0) > settings.moving_velocity
    return q_f, qd_f, tau_f - rigid, np.broadcast_to(moved, q.shape)


def _empty_report(n: int, joints: tuple[int, ...]) -> FitReport:
    names = ("coulomb", "viscous", "slope", "half_width", "position_linear", "position_quadratic")
    return FitReport(
        residual_rms=np.full(n, np.nan),
        samples=np.zeros(n),
        parameter_std={name: np.full(n, np.nan) for name in names},
        position_fitted=np.zeros(n, dtype=bool),
        joints=joints,
        level_error=np.full(n, np.nan),
    )


def _fit_joint(
    j: int,
    samples: FrictionSamples,
    dynamics: Dynamics,
    settings: IdentificationSettings,
    values: dict[str, FloatArray],
    report: FitReport,
) -> None:
    """Fit joint ``j`` in place into ``values`` and ``report``."""
    robot = dynamics.robot
    mine = samples.moved[:, j]
    q, qd, tau = samples.q[mine, j], samples.qd[mine, j], samples.tau_friction[mine, j]
    sliding = np.abs(qd) >= settings.sliding_velocity
    if sliding.sum() < settings.minimum_samples:
        raise IdentificationError(f"joint {j + 1}: only {sliding.sum()} samples faster than "
                                  f"{settings.sliding_velocity:g} rad/s")  # fmt: skip
    half = 0.5 * (robot.q_max[j] - robot.q_min[j])
    with_position = bool(np.ptp(q[sliding]) >= settings.position_span * 2.0 * half)
    # the position dependence describes the stroke the sliding samples cover, and the model
    # holds its end values beyond it: a quadratic is not extrapolated where no data were
    span = q[sliding] if with_position else np.array([robot.q_min[j], robot.q_max[j]])
    low, high = span.min(), span.max()
    mid, half = 0.5 * (low + high), 0.5 * (high - low)
    u = (q - mid) / half
    # only a joint that slid both ways tells what changes sign with the motion from what
    # does not; one that turned one way keeps it all as friction, as before
    both_ways = min(np.mean(qd[sliding] > 0.0), np.mean(qd[sliding] < 0.0)) >= BOTH_WAYS
    unsigned = unsigned_basis(q, samples.moved[mine].sum(axis=1) == 1)
    if not both_ways:
        unsigned = unsigned[:, :0]  # no column: all of it stays friction
    theta, std, residual, offset = _fit_sliding(qd[sliding], u[sliding], tau[sliding],
                                                with_position, unsigned[sliding])  # fmt: skip
    if with_position and not theta[0] > 3.0 * std[0]:  # no level the data resolve to scale by
        with_position = False
        theta, std, residual, offset = _fit_sliding(qd[sliding], u[sliding], tau[sliding],
                                                    False, unsigned[sliding])  # fmt: skip
    tau = tau - unsigned @ offset  # what does not change sign with the motion is not friction
    coulomb, viscous = theta[0], theta[-1]
    _warn_on_bound(j, coulomb, viscous)
    values["coulomb"][j], values["viscous"][j] = coulomb, max(viscous, 0.0)
    values["noise_std"][j] = float(np.std(residual))
    values["position_mid"][j], values["position_half_range"][j] = mid, half
    values["position_linear"][j] = theta[1] / coulomb if with_position else 0.0
    values["position_quadratic"][j] = theta[2] / coulomb if with_position else 0.0
    if with_position:
        report.parameter_std["position_linear"][j] = std[1] / coulomb
        report.parameter_std["position_quadratic"][j] = std[2] / coulomb
    report.parameter_std["coulomb"][j], report.parameter_std["viscous"][j] = std[0], std[-1]
    others = np.delete(samples.q[mine], j, axis=1)[sliding]
    centres, levels = level_along_travel(q[sliding], qd[sliding], tau[sliding], viscous, others)
    off = level_error(levels, _level(values, j, (centres - mid) / half))
    report.level_error[j] = off
    # what the level may be off: 3 std of τ_C plus what it mis-states along the travel, or
    # (too little travel passed both ways to measure that) the sliding residual's spread
    unexplained = off * coulomb if np.isfinite(off) else 2.0 * np.std(residual)
    values["relative_error"][j] = np.clip((3.0 * std[0] + unexplained) / max(coulomb, 1e-12),
                                          MIN_RELATIVE_ERROR, 0.5)  # fmt: skip
    report.residual_rms[j] = float(np.sqrt(np.mean(residual**2)))
    report.samples[j] = sliding.sum()
    report.position_fitted[j] = with_position
    slow = np.abs(qd) < 2.0 * settings.sliding_velocity
    if slow.sum() >= 20:
        level = _level(values, j, u[slow])
        prior = (values["slope"][j], values["half_width"][j])  # the rest band's floor
        params, std = _fit_sigmoids(qd[slow], level, values["viscous"][j],
                                    values["noise_std"][j], tau[slow], prior)  # fmt: skip
        (values["slope"][j], values["half_width"][j]) = params
        report.parameter_std["slope"][j], report.parameter_std["half_width"][j] = std


def _warn_on_bound(j: int, coulomb: float, viscous: float) -> None:
    """A warning if joint ``j``'s τ_C sits on its bound 0 (the data pull it negative).

    A c alone at 0 is not warned about: a small one the data cannot tell from 0 (the
    Panda's joints 2, 5 and 6; its published c of joint 6 is negative).
    """
    if coulomb > ON_BOUND:
        return
    what = "Coulomb level" + (" and viscous coefficient" if viscous <= ON_BOUND else "")
    warnings.warn(f"identify_friction: joint {j + 1}: fitted {what} held at 0 (the data pull "
                  "it negative): is its current or torque sign flipped, its torque constant "
                  "wrong, or the rigid-body model far off?", stacklevel=5)  # fmt: skip


def _level(values: dict[str, FloatArray], j: int, u: FloatArray) -> FloatArray:
    """Joint ``j``'s fitted level τ_C(q) [Nm] at ``u``, held at its ends as the model is."""
    u = np.clip(u, -1.0, 1.0)
    return values["coulomb"][j] * (1.0 + values["position_linear"][j] * u
                                   + values["position_quadratic"][j] * u**2)  # fmt: skip


def unsigned_basis(q: FloatArray, alone: NDArray[np.bool_]) -> FloatArray:
    """What a joint's torque holds besides friction, not changing sign with it, (N, 3).

    ``1, sin q, cos q``: a torque offset is a constant, and where the joint moved alone
    (``alone``: in a log where no other joint moved, as the project's excitation does,
    ``runtime/excitation.py``) the gravity torque about its axis is a first harmonic of its
    angle (the distal links' centre of mass turns on a circle about the axis), so a
    model's error in it is too. Where other joints moved as well that form does not hold,
    and only the constant stands.
    """
    return np.column_stack([np.ones_like(q), np.sin(q) * alone, np.cos(q) * alone])


def _fit_sliding(
    qd: FloatArray, u: FloatArray, tau: FloatArray, with_position: bool, unsigned: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Least squares of ``τ = sign(q̇) (a₀ + a₁ u + a₂ u²) + c q̇ + unsigned · b``.

    Friction has the sign of the motion; what does not change sign with it is not
    friction: the rigid-body model's error along the stroke (a gravity term off by the
    masses' few per cent, newton-metres on a loaded shoulder) and an offset of the torque
    measurement. ``unsigned`` (N, k) holds its basis (:func:`unsigned_basis`), so that it
    neither biases the level nor counts as friction noise (σ, which the controller's bands
    are made of).

    Friction dissipates, so the Coulomb level and the viscous coefficient are bounded
    below by 0 (where the rigid-body model is poor, a nominal URDF, an unconstrained fit
    returns a negative level). The position-dependent level must stay above
    ``MIN_LEVEL`` of its value at the stroke's middle over u ∈ [−1, 1], the stroke the
    samples cover; the model holds its end values beyond it, so the level is positive at
    every position.

    Returns:
        θ (``a₀[, a₁, a₂], c``), std(θ), the residual, and ``b``.
    """
    from scipy import optimize  # at call time: keeps `import leadthrough` fast

    sign = np.sign(qd)
    columns = [sign, sign * u, sign * u * u, qd] if with_position else [sign, qd]
    k = len(columns)  # the friction's columns; the offset's follow
    design = np.column_stack([*columns, unsigned])
    lower = np.full(design.shape[1], -np.inf)
    lower[[0, k - 1]] = 0.0
    theta = optimize.lsq_linear(design, tau, bounds=(lower, np.inf)).x
    if with_position:
        # a₀ + a₁u + a₂u² > MIN_LEVEL a₀  ⇔  1 + k₁'u + k₂'u² > 0 with k' = a / ((1 − MIN_LEVEL) a₀)
        relative = theta[1:3] / ((1.0 - MIN_LEVEL) * max(theta[0], 1e-12))
        if not level_stays_positive(*relative):
            theta = _level_bounded_fit(design, tau, theta)
    residual = tau - design @ theta
    dof = max(len(tau) - len(theta), 1)
    covariance = np.linalg.pinv(design.T @ design) * (residual @ residual) / dof
    return theta[:k], np.sqrt(np.diag(covariance))[:k], residual, theta[k:]


def _level_bounded_fit(design: FloatArray, tau: FloatArray, start: FloatArray) -> FloatArray:
    """Least squares with ``a₀ + a₁ u + a₂ u² ≥ MIN_LEVEL a₀`` on a fine grid of u ∈ [−1, 1].

    ``design``'s columns: the level's three, the viscous one, then the offset's.
    """
    from scipy import optimize

    grid = np.linspace(-1.0, 1.0, 81)
    rows = np.zeros((grid.size, design.shape[1]))
    rows[:, :3] = np.column_stack([np.full_like(grid, 1.0 - MIN_LEVEL), grid, grid**2])
    hessian, gradient = design.T @ design, design.T @ tau
    scale = float(np.trace(hessian)) or 1.0
    initial = np.array(start, dtype=float)  # the level alone, and the offset as fitted
    initial[0], initial[1:3] = max(float(start[0]), 1e-9), 0.0
    initial[3] = max(float(start[3]), 0.0)
    bounds = [(0.0, None), (None, None), (None, None), (0.0, None)]
    bounds += [(None, None)] * (design.shape[1] - 4)
    fit = optimize.minimize(
        lambda x: (x @ hessian @ x - 2.0 * gradient @ x) / scale,
        initial,
        jac=lambda x: 2.0 * (hessian @ x - gradient) / scale,
        bounds=bounds,
        constraints=[{"type": "ineq", "fun": lambda x: rows @ x, "jac": lambda x: rows}],
        method="SLSQP",
        options={"maxiter": 200, "ftol": 1e-12},
    )
    return fit.x


def _fit_sigmoids(
    qd: FloatArray,
    level: FloatArray,
    viscous: float,
    noise_std: float,
    tau: FloatArray,
    prior: tuple[float, float],
) -> tuple[FloatArray, FloatArray]:
    """Fit A and B so that the Gaussian model describes the slow samples.

    Both moments are fitted at once, τ_C(q), c and σ held: the mean (4.4) to the
    friction torque, and the variance v_C² + σ² (4.5) to the squared deviation from that
    mean, so that near zero velocity, where stiction and Stribeck effects make the
    friction anything between −τ_S and +τ_S, the model's standard deviation is honest.

    The rest band is the prior's ``(A, B)`` at its narrowest: the fit runs over the
    band's half-point B and its opening at rest A B (``v_C(0) = τ_C tanh(A B / 2)``),
    each bounded below by the prior's (module docstring, step 5).

    Returns:
        (A, B) and their standard deviations.
    """
    scale = max(float(np.max(level)), noise_std, 1e-9)  # a zero level (τ_C bounded at 0)

    def residual(log_params: FloatArray) -> FloatArray:
        opening, half_width = np.exp(log_params)
        slope = opening / half_width
        upper = sigmoid(slope * (qd + half_width))
        lower = sigmoid(slope * (qd - half_width))
        deviation = tau - (level * (upper + lower - 1.0) + viscous * qd)
        variance = (level * (upper - lower)) ** 2 + noise_std**2
        return np.concatenate([deviation, (deviation**2 - variance) / scale])

    from scipy import optimize  # at call time: scipy.optimize takes 0.15 s to import

    prior_slope, prior_width = prior
    # log (A B) and log B: A B within [50 · 1e-5, 1e5 · 0.05] and B within [1e-5, 0.05]
    # rad/s (the ranges of A [s/rad] and B before the floor), each at least the prior's
    low = np.log([max(prior_slope * prior_width, 50.0 * 1e-5), max(prior_width, 1e-5)])
    high = np.maximum(np.log([1e5 * 0.05, 0.05]), low + 1e-6)
    start = np.clip(np.log([prior_slope * prior_width, prior_width]), low + 1e-9, high - 1e-9)
    fit = optimize.least_squares(residual, start, bounds=(low, high), loss="soft_l1",
                                 f_scale=0.05)  # fmt: skip
    opening, half_width = np.exp(fit.x)
    dof = max(2 * len(qd) - 2, 1)
    # the covariance of (log A B, log B), carried to (A, B): log A = log A B − log B
    covariance = np.linalg.pinv(fit.jac.T @ fit.jac) * 2.0 * fit.cost / dof
    to_log_slope = np.array([[1.0, -1.0], [0.0, 1.0]])
    log_std = np.sqrt(np.diag(to_log_slope @ covariance @ to_log_slope.T))
    params = np.array([opening / half_width, half_width])
    return params, params * log_std
