r"""Variants of active lead-through for ``guiding_quality.py --factory`` (issue 13 diagnosis).

Each factory builds the default controller with one thing changed, so that the README's
"why active mode is not lighter" figures can be reproduced on the same 56 cases::

    PYTHONPATH=src:benchmarks python benchmarks/guiding_quality.py \
        --factory guiding_variants:no_weighting

Passive mode is always the default one (the denominator of every ratio). The variants are
experiments, not alternatives: each makes guiding lighter or a band narrower and costs
something the defaults keep (see README).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from typing import Any

import numpy as np

import leadthrough as lt
from leadthrough.control.active_law import ActiveLaw
from leadthrough.control.admittance import operator_weight
from leadthrough.control.calibration import CalibrationParameters
from leadthrough.estimation.observer import MomentumObserver, ObserverParameters
from leadthrough.estimation.tool_force import fuse
from leadthrough.friction.compensation import CoulombCompensationParameters
from observer_variants import SMOOTH_RATE

#: A calibration that slides every joint 10 mrad at 0.1 rad/s under the 6 Hz loop (the
#: default from when it was made so until the 4 Hz loop, which slides 15 mrad; 5 mrad at
#: 0.05 rad/s when the README's variant table was measured).
LONG_STROKE = {"stroke": 0.01, "speed": 0.1, "bandwidth": 6.0}


def _build(
    robot: lt.RobotDescription,
    mode: str,
    cls: type[lt.LeadThrough] = lt.LeadThrough,
    calibration: dict[str, Any] | None = None,
    dither: dict[str, Any] | None = None,
    calibrate: bool = True,
    **fields: Any,
) -> lt.LeadThrough:
    """The default controller of ``mode``; in active mode with ``fields`` changed.

    ``calibrate``: whether it starts with the start-up calibration (both modes).
    """
    parameters = lt.LeadThroughParameters()
    if mode == "active":
        changes = dict(fields)
        if calibration:
            changes["calibration"] = dataclasses.replace(CalibrationParameters(), **calibration)
        if dither:
            changes["dither"] = dataclasses.replace(parameters.dither, **dither)  # type: ignore[arg-type]
        parameters = dataclasses.replace(parameters, **changes)
        return cls(robot, mode=mode, dt=0.004, parameters=parameters, calibrate=calibrate)
    return lt.LeadThrough(robot, mode=mode, dt=0.004, parameters=parameters, calibrate=calibrate)


def joint_estimates(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """``tool_force = None``: each joint's own estimate drives, not the joints read together."""
    return _build(robot, mode, tool_force=None)


def no_unwinding(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """References that wind up against a joint stiction holds (the previous default)."""
    return _build(robot, mode, unwind_time=None)


def no_weighting(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """``assist_knee = 0``: the whole residual drives, and the damping never rises."""
    return _build(robot, mode, assist_knee=0.0)


class _FullResidualLaw(ActiveLaw):
    """The weight sets the virtual damping only; the whole residual drives the admittance."""

    compiled = False

    def _update_drive(self, estimate: Any, q: Any, qd: Any, gravity: Any) -> None:
        super()._update_drive(estimate, q, qd, gravity)
        self.drive = _unweighted(self.drive, self.weight)


class _FullResidual(lt.LeadThrough):
    law_class = _FullResidualLaw


def _unweighted(drive: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """The residual a weighted drive came from [Nm] (0 where the weight is 0)."""
    weighted = weight > 0.0
    return np.where(weighted, drive / np.where(weighted, weight, 1.0), 0.0)


def full_residual(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The residual not attenuated by its weight (the damping still follows the weight)."""
    return _build(robot, mode, cls=_FullResidual)


def long_stroke(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The start-up calibration with :data:`LONG_STROKE`."""
    return _build(robot, mode, calibration=LONG_STROKE)


def long_stroke_trusted(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """:func:`long_stroke`, its Coulomb levels trusted to 10 % (default 20 %)."""
    return _build(robot, mode, calibration={**LONG_STROKE, "friction_accuracy": 0.1})


class _OwnRestBandLaw(ActiveLaw):
    """Keeps each joint's whole Coulomb band: the fused std narrows nothing."""

    def narrow(self, fused_std: Any, own_std: Any) -> None:
        """Leave :attr:`narrowing` at ones."""


class _OwnRestBand(lt.LeadThrough):
    law_class = _OwnRestBandLaw


def own_rest_uncertainty(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """Each joint's whole Coulomb band in the law's uncertainty (before: not narrowed)."""
    return _build(robot, mode, cls=_OwnRestBand)


def strong_dither(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """A dither of 0.6 τ_C on resting joints in active mode (the default since it was kept)."""
    return _build(robot, mode, dither={"amplitude": 0.6})


class _OwnCalibrationObserver(lt.LeadThrough):
    """Guides with its own observer; the calibration reads the default observer."""

    def _build(self, robot: lt.RobotDescription, friction: lt.FrictionModel) -> None:
        super()._build(robot, friction)
        self._calibration_observer = MomentumObserver(self.dynamics, friction, self.dt,
                                                      ObserverParameters())  # fmt: skip

    def _calibrate(self, t: float, model: Any, tau_measured: Any) -> Any:
        guiding = self.observer
        self.observer = calibration = self._calibration_observer
        try:
            return super()._calibrate(t, model, tau_measured)
        finally:
            if self.observer is calibration:  # still calibrating, or the result refused
                self.observer = guiding


def smooth_rate_guiding(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The ``"smooth_rate"`` observer while guiding; the calibration reads the default one."""
    observer = dataclasses.replace(ObserverParameters(), **SMOOTH_RATE)  # type: ignore[arg-type]
    return _build(robot, mode, cls=_OwnCalibrationObserver, observer=observer)


class _ToolWrenchPriorLaw(ActiveLaw):
    """The operator torque as a posterior under ``τ_op ~ N(0, Jᵀ Σ_F J + σ_L² I)``.

    The hand holds the tool (a wrench at the TCP, Σ_F: 30 N, 3 Nm) plus a little anywhere
    else (σ_L = 0.1 Nm per joint); every joint reads ``τ_op`` plus model error of its own
    uncertainty ``u``: a joint friction holds (large ``u``) gets its torque from the
    joints that move. The weight compares the posterior mean with its posterior std.
    """

    compiled = False
    prior = np.diag([30.0**2] * 3 + [3.0**2] * 3)
    anywhere = 0.1

    @functools.cached_property
    def _dynamics(self) -> lt.Dynamics:
        """A model of the arm for the TCP Jacobian (the law is not handed one)."""
        return lt.Dynamics(self.robot)

    def _update_drive(self, estimate: Any, q: Any, qd: Any, gravity: Any) -> None:
        super()._update_drive(estimate, q, qd, gravity)  # bias learning and the residual
        p = self.parameters
        residual = _unweighted(self.drive, self.weight)
        uncertainty = (self._rest_tolerance + self.model_error.tolerance(gravity)
                       + self.friction.coulomb_uncertainty(qd, q))  # fmt: skip
        jacobian = self._dynamics.snapshot(q, qd).tool_jacobian
        covariance = jacobian.T @ self.prior @ jacobian + self.anywhere**2 * np.eye(q.size)
        gain = np.linalg.solve(covariance + np.diag(uncertainty**2), covariance).T
        posterior = gain @ residual
        std = np.sqrt(np.maximum(np.diag(covariance - gain @ covariance), 1e-24))
        self.weight = operator_weight(posterior, std, p.assist_knee)
        self.drive = posterior * self.weight


class _ToolWrenchPrior(lt.LeadThrough):
    law_class = _ToolWrenchPriorLaw


def tool_wrench_prior(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The operator torque read as a wrench at the tool (:class:`_ToolWrenchPrior`)."""
    return _build(robot, mode, cls=_ToolWrenchPrior)


def _scaled_margin(
    scale: float, relief: bool = False
) -> Callable[[lt.RobotDescription, str], lt.LeadThrough]:
    """A factory whose law removes ``scale`` times the level's whole error (the default's).

    It sets ``ActiveLaw.margin_share`` (and ``margin_relief``: the margin relieved where the
    reading exceeds it), which the compiled law reads too.
    """

    class _ScaledMarginLaw(ActiveLaw):
        margin_share = scale
        margin_relief = relief

    class _ScaledMargin(lt.LeadThrough):
        law_class = _ScaledMarginLaw

    def factory(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
        return _build(robot, mode, cls=_ScaledMargin)

    relieved = ", relieved above its size" if relief else ""
    factory.__doc__ = f"The friction margin at {scale:g} of the level's whole error{relieved}."
    return factory


#: The friction margin the released arm needs, scaled down: how much lightness it costs.
no_friction_margin = _scaled_margin(0.0)
half_friction_margin = _scaled_margin(0.5)
three_quarter_friction_margin = _scaled_margin(0.75)
#: The margin relieved above its size (design log): lighter, but only as safe as it bounds
#: the error. 1.3 margins relieved: as light as the default, every release of the ±25 %
#: plants stopped, but farther run-ons with drive gains ±30 % and more vibration; 1.6:
#: heavier than the default (0.87).
relieved_friction_margin = _scaled_margin(1.0, relief=True)
relieved_wider_margin = _scaled_margin(1.3, relief=True)
relieved_widest_margin = _scaled_margin(1.6, relief=True)


class _TrueTorqueLaw(ActiveLaw):
    """The law fed the simulated operator torque instead of the estimate (an oracle)."""

    truth: Callable[[], np.ndarray] | None = None

    def operator_torque(self, estimate: Any, q: Any, qd: Any, gravity: Any) -> Any:
        if self.truth is not None:
            estimate = np.array(self.truth(), dtype=float)
        return super().operator_torque(estimate, q, qd, gravity)


class _TrueTorque(lt.LeadThrough):
    """Guides on the twin's true operator torque (``guiding.run_case`` hands it the twin)."""

    law_class = _TrueTorqueLaw

    def observe_truth(self, twin: Any) -> None:
        self.law.truth = lambda: twin.truth.tau_operator  # type: ignore[attr-defined]


#: The issue's "plain smooth admittance": the whole estimate drives (no weight, no friction
#: margin), the damping never rises; k_M = 2 and the PD as the defaults.
PLAIN = {"assist_knee": 0.0, "stiction_margin": 0.0, "friction_uncertainty": 0.0}


def true_torque(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The defaults fed the twin's true operator torque: what the estimate costs."""
    return _build(robot, mode, cls=_TrueTorque)


def plain_admittance(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """:data:`PLAIN`, fed the estimate: what the released arm's guarantees cost."""
    return _build(robot, mode, **PLAIN)


def true_torque_plain(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """:data:`PLAIN`, fed the twin's true operator torque: the law's own floor."""
    return _build(robot, mode, cls=_TrueTorque, **PLAIN)


class _TrueTorqueNoMarginLaw(_TrueTorqueLaw):
    margin_share = 0.0


class _TrueTorqueNoMargin(_TrueTorque):
    law_class = _TrueTorqueNoMarginLaw


def true_torque_no_margin(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The defaults without the friction margin, fed the twin's true operator torque.

    What the margin costs where the reading holds no friction error (the truth reads 0
    once the hand lets go, so no released arm needs it), and what the weight and the
    rising damping cost beyond it.
    """
    return _build(robot, mode, cls=_TrueTorqueNoMargin)


class _NoDriveGainTermLaw(ActiveLaw):
    """The law's residual without ``− drive_gain_uncertainty · τ_PD`` (the last tracking torque).

    The tracking torque enters the operator torque only there, so it is read as zero;
    ``drive_gain_uncertainty`` itself stays, as it also sets the gravity tolerance.
    """

    def operator_torque(self, estimate: Any, q: Any, qd: Any, gravity: Any) -> Any:
        feedback, self.feedback = self.feedback, np.zeros_like(self.feedback)
        try:
            return super().operator_torque(estimate, q, qd, gravity)
        finally:
            self.feedback = feedback


class _NoDriveGainTerm(lt.LeadThrough):
    law_class = _NoDriveGainTermLaw


def no_drive_gain_margin(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The law without its drive-gain term (:class:`_NoDriveGainTermLaw`).

    The default removes 10 % of the last tracking torque from the residual
    (``LeadThroughParameters.drive_gain_uncertainty``); run on the family and with
    ``--plants torque_gain=0.7,1.3`` (design log, *The drive-gain term*).
    """
    return _build(robot, mode, cls=_NoDriveGainTerm)


class _NoCreditAtRest(lt.LeadThrough):
    """The law reads a second filter that credits no friction to a joint it calls at rest.

    The same filter as the reported one (``observer``), the friction it takes as applied
    the model's at the law's sliding velocity (``ActiveLaw.sliding_velocity``, zero below
    ``rest_velocity``) instead of at the measured one; read together as the reported one
    is, with the same stds. The reported estimate is unchanged.
    """

    def _build(self, robot: lt.RobotDescription, friction: lt.FrictionModel,
               measured: Any = None) -> None:  # fmt: skip
        super()._build(robot, friction, measured)
        reported = self.observer
        reading = MomentumObserver(self.dynamics, reported.friction, self.dt,
                                   self.parameters.observer)  # fmt: skip
        # the class's methods: _build runs again after a calibration and on reset
        update = reported.update
        operator_torque = functools.partial(type(self.law).operator_torque, self.law)

        def both(q: Any, qd: Any, tau: Any, model: Any = None, periods: int = 1) -> Any:
            credited = reported.friction.mean(self.law.sliding_velocity(qd), q)
            reading.update(q, qd, tau, model, friction_mean=credited, periods=periods)
            return update(q, qd, tau, model, periods=periods)

        def from_reading(estimate: Any, q: Any, qd: Any, gravity: Any) -> Any:
            own = reading.tau_ext_hat
            if self.fusion is not None and self.model is not None:
                fusion, std = self.fusion, self.joint_std
                own, _ = fuse(own, std, self.model.tool_jacobian, fusion.other_std,
                              fusion.parameters.force_std, np.empty(own.size),
                              np.empty(own.size))  # fmt: skip
            return operator_torque(own, q, qd, gravity)

        reported.update = both  # type: ignore[method-assign]
        self.law.operator_torque = from_reading  # type: ignore[method-assign]


def no_credit_at_rest(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """:class:`_NoCreditAtRest` (docs/active_mode_log.md, *Friction credited to a creep*)."""
    return _build(robot, mode, cls=_NoCreditAtRest)


def no_credit_at_rest_uncalibrated(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """:func:`no_credit_at_rest` without the start-up calibration (passive: the same)."""
    return _build(robot, mode, cls=_NoCreditAtRest, calibrate=False)


def thesis_compensation(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """Active mode's compensation never follows the push: the thesis' law.

    The default before it followed the push once a start-up calibration is accepted.
    """
    return _build(robot, mode,
                  compensation=CoulombCompensationParameters(follow_push="never"))  # fmt: skip


def follow_push_uncalibrated(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """Active mode's compensation follows the push without the start-up calibration.

    Run with ``--uncalibrated``; the default there is the thesis' law.
    """
    return _build(robot, mode, calibrate=False,
                  compensation=CoulombCompensationParameters(follow_push="always"))  # fmt: skip


#: The stiction excess the plant family's band needs (stiction up to 1.5× Coulomb).
STIFF_STICTION = 0.5


class _StribeckBand(lt.LeadThrough):
    """The nominal friction model with a band that holds the Stribeck range (not identified)."""

    def __init__(self, robot: lt.RobotDescription, **options: Any) -> None:
        super().__init__(robot, **options)
        excess = np.full(robot.n_joints, STIFF_STICTION)
        self.nominal_friction = dataclasses.replace(self.nominal_friction, stiction_excess=excess)
        self.reset()


def stribeck_band(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """Active mode's friction band holds a stiction excess of 0.5 τ_C below 0.03 rad/s.

    ``FrictionModel.stiction_excess`` (the default is the thesis' band, 0): the observer's
    std and the joints read together see it, the active law does not.
    """
    return _build(robot, mode, cls=_StribeckBand)


def stribeck_band_uncalibrated(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """:func:`stribeck_band` without the start-up calibration (run with ``--uncalibrated``)."""
    return _build(robot, mode, cls=_StribeckBand, calibrate=False)
