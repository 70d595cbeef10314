"""The admittance rule of active lead-through (thesis §6.2, SPEC §6): a small pure core.

The virtual system the operator feels is ``M̃(q) q̈_ref + D̃ q̇_ref = τ_in`` with
``M̃ = k_M M(q)`` and ``D̃ = S M(q) S / T`` shaped like the arm's inertia too (eq. 6.5,
written on the reference velocity so that the virtual system is self-contained; ``S``
diagonal, near the identity while every joint is pushed: :func:`virtual_damping`), integrated
with implicit Euler in the damping so that it is stable for any D̃::

    (M̃ + dt D̃) q̇_ref⁺ = M̃ q̇_ref + dt τ_in,     q_ref⁺ = q_ref + dt q̇_ref⁺

and tracked with ``τ_fb = K_P (q_ref − q) + K_D (q̇_ref − q̇)`` (eq. 6.4); ``K_P = 0`` is
damping control (§6.3.1). References never wind up: they are kept within the soft
joint limits, re-anchored when tracking is lost (an end-stop, a collision, a joint
that runs ahead: :func:`reanchored`) and relaxed towards a joint that lags behind them
(:func:`unwound`).

Which part of the estimate is the operator's is weighed smoothly by how far it stands
out of the model's own uncertainty (:func:`operator_weight`), and the virtual damping
rises smoothly once nobody pushes a joint on (:func:`damping_weight`,
:func:`virtual_damping`). The virtual inertia is
*heavier* than the arm (k_M > 1): the estimate lags the operator's torque (the
observer's bandwidth, the command delay), and an admittance lighter than the arm it
moves turns that lag into a negative damping that a stiff hand makes unstable
(:mod:`leadthrough.experiments.stability` computes the stable region).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import NDArray

from leadthrough.model.description import FloatArray


@dataclass
class AdmittanceState:
    """References of the virtual system.

    Attributes:
        q_ref: Position reference [rad].
        qd_ref: Velocity reference [rad/s].
    """

    q_ref: FloatArray
    qd_ref: FloatArray


def admittance_step(
    state: AdmittanceState,
    tau_in: FloatArray,
    mass: FloatArray,
    inertia_scale: float,
    damping: FloatArray,
    dt: float,
) -> AdmittanceState:
    """Advance the virtual system by ``dt`` under the input torque ``tau_in`` [Nm].

    Args:
        state: References now.
        tau_in: Torque driving the virtual system (estimated operator torque, constraints).
        mass: M(q) [kg m²], (n, n).
        inertia_scale: k_M [–].
        damping: D̃ [Nm s/rad], (n, n) (:func:`virtual_damping`).
        dt: Control period [s].
    """
    virtual_mass = inertia_scale * mass
    lhs = virtual_mass + dt * damping
    qd_ref = cast(FloatArray, np.linalg.solve(lhs, virtual_mass @ state.qd_ref + dt * tau_in))
    return AdmittanceState(state.q_ref + dt * qd_ref, qd_ref)


def tracking_torque(
    state: AdmittanceState, q: FloatArray, qd: FloatArray, kp: FloatArray, kd: FloatArray
) -> FloatArray:
    """PD tracking of the references, eq. (6.4) [Nm]."""
    return kp * (state.q_ref - q) + kd * (state.qd_ref - qd)


def dead_zone(
    value: FloatArray, width: FloatArray | float, offset: FloatArray | float = 0.0
) -> FloatArray:
    """What is left of ``value`` outside [min(0, offset) − width, max(0, offset) + width].

    With ``offset = 0`` this is ``sign(x) · max(|x| − w, 0)``. A non-zero offset (a learned
    bias) only widens the band towards itself: it can silence a reading, never create one.
    """
    upper = np.maximum(offset, 0.0) + width
    lower = np.minimum(offset, 0.0) - width
    return np.where(value > upper, value - upper, np.where(value < lower, value - lower, 0.0))


def relieved_margin(residual: FloatArray, margin: FloatArray) -> FloatArray:
    """The friction margin, kept whole up to its size and relieved beyond it [Nm].

    ``margin · |margin| / a`` where ``a > |margin|``, else the whole margin, with ``a =
    residual · sign(margin)`` the reading along the motion (the margin's sign): a reading
    no larger than the margin, or against the motion, loses all of it, so friction the
    model overstates by up to the margin still reads as drag (a released arm stops); a
    larger reading loses ``margin² / a`` in size, continuously, and a push far above the
    margin passes almost whole (``a − margin² / a``, the shape of
    :func:`operator_weight`'s). The slope of ``a − kept`` is 2 just above the margin.
    Relief is only as safe as the margin is a bound: friction overstated by more than
    the margin reads as a larger push than with the whole margin removed (design log,
    *A friction margin relieved above its size*). An experiment, off by default
    (``ActiveLaw.margin_relief``).

    Args:
        residual: The estimate with the learned bias removed [Nm].
        margin: The friction margin, signed along the motion [Nm].
    """
    size = np.abs(margin)
    along = np.where(margin > 0.0, residual, -residual)
    above = along > size
    return margin * np.where(above, size / np.where(above, along, 1.0), 1.0)


def operator_weight(residual: FloatArray, uncertainty: FloatArray, knee: float) -> FloatArray:
    """How much of each joint's residual torque is the operator's, smoothly, in [0, 1).

    ``w = z² / (1 + z²)`` with ``z = residual / (knee · uncertainty)``: a residual well
    inside the model's own uncertainty (friction and gravity error, the observer's std)
    passes as ``residual³ / (knee σ)²``, almost nothing; one well outside passes almost
    whole (``residual − (knee σ)² / residual``). There is no threshold to switch on and
    off, so the assist cannot chatter, and ``d(w r)/dr`` stays within [0, 1.3]: the
    weighting never amplifies the estimate. ``knee = 0`` passes everything (the thesis).

    Args:
        residual: Estimated operator torque, bias removed [Nm].
        uncertainty: Standard deviation of what the model may read without an operator [Nm].
        knee: Residual, in uncertainties, of which half passes [–].
    """
    if knee == 0.0:
        return np.ones_like(residual)
    z2 = (residual / (knee * np.maximum(uncertainty, 1e-12))) ** 2
    return z2 / (1.0 + z2)


def signed_push_weight(push: FloatArray, uncertainty: FloatArray, knee: float) -> FloatArray:
    """How surely, and which way, a push drives each joint, in (−1, 1) [–].

    :func:`operator_weight` of the push with the push's sign. With ``follow_push`` the
    Coulomb compensation of a joint below its velocity ramp follows it, averaged over
    ``push_time`` (:attr:`~leadthrough.control.active_law.ActiveLaw.signed_weight`): a
    joint the operator pushes is compensated as surely as the law reads the push, in its
    direction.

    Args:
        push: The residual plus the constraints' torque [Nm].
        uncertainty: As for :func:`operator_weight` [Nm].
        knee: As for :func:`operator_weight` [–].
    """
    return np.sign(push) * operator_weight(push, uncertainty, knee)


def motion_sign(qd_ref: FloatArray, rest_velocity: float) -> FloatArray:
    """Smooth sign of each joint's motion, in (−1, 1) [–]: ``q̇ / √(q̇² + v_rest²)``.

    ±1 for a joint that clearly moves, 0 at rest, with no step in between.
    """
    return qd_ref / np.sqrt(qd_ref**2 + rest_velocity**2)


def damping_weight(
    residual: FloatArray,
    sustained: FloatArray,
    moving: FloatArray,
    uncertainty: FloatArray,
    knee: float,
) -> FloatArray:
    """Weight that sets the virtual damping: of the push that starts or sustains a motion.

    The push (the operator's residual before its weight, plus the virtual constraints'
    torque) counts whole when it starts a joint from rest; on a moving joint only its
    part *along* the motion, averaged over ``push_time`` (``sustained``, the low-passed
    ``push · s``), counts. A push against the motion is the operator braking, or the
    friction the model may overstate, which the law reads as drag by design once nobody
    holds the arm: either way nothing sustains the motion, so the damping rises and the
    joint stops instead of coasting on its virtual inertia. The average keeps a stiff
    hand's oscillation, whose sign alternates within 0.1–0.2 s, from modulating the
    damping. ``√((push (1 − |s|))² + max(sustained, 0)²)`` is weighed as
    :func:`operator_weight` weighs the residual.

    Args:
        residual: The push: residual plus the constraints' torque [Nm].
        sustained: The push along the motion, averaged over ``push_time`` [Nm].
        moving: :func:`motion_sign` of the reference velocity [–].
        uncertainty: As for :func:`operator_weight` [Nm].
        knee: As for :func:`operator_weight` [–].
    """
    idle, along = residual * (1.0 - np.abs(moving)), np.maximum(sustained, 0.0)
    push = np.sqrt(idle * idle + along * along)
    return operator_weight(push, uncertainty, knee)


def reanchored(
    references: AdmittanceState, q: FloatArray, qd: FloatArray, lost: NDArray[np.bool_]
) -> AdmittanceState:
    """The references where tracking is lost (``lost``), re-anchored to the joint.

    The position reference goes to where the joint is, so nothing winds up. The velocity
    reference slows to a joint that lags behind it (an end-stop, a collision, stiction:
    ``0 ≤ q̇ / q̇_ref < 1``) and is never sped up or turned by one: a joint that runs
    ahead of it, or against it, keeps the admittance's velocity and so the PD's damping,
    the one thing that brakes a joint nobody pushes. Taking the joint's velocity there
    (before) made the reference follow a released wrist joint that the feed-forward's
    errors drove: it ran 1.3 rad into its end-stop (held-out plant dry #20).

    Args:
        references: Position [rad] and velocity [rad/s] references.
        q: Joint positions [rad].
        qd: Joint velocities [rad/s].
        lost: Where the tracking is lost.
    """
    v = references.qd_ref
    return AdmittanceState(np.where(lost, q, references.q_ref),
                           np.where(lost & lagging(v, qd), qd, v))  # fmt: skip


def lagging(qd_ref: FloatArray, qd: FloatArray) -> NDArray[np.bool_]:
    """Where a joint lags behind its velocity reference: ``0 ≤ q̇ / q̇_ref < 1``."""
    return np.where(qd_ref > 0.0, (qd >= 0.0) & (qd < qd_ref), (qd <= 0.0) & (qd > qd_ref))


def unwound(qd_ref: FloatArray, qd: FloatArray, rate: float) -> FloatArray:
    """Velocity reference of the joints that lag behind it, relaxed towards theirs [rad/s].

    A joint that stiction holds (or a contact, or the end-stop) while the operator pushes
    does not follow its admittance: the reference would run on at the speed the push
    asks for, and the PD's damper store the difference as a push of its own. When the
    joint breaks away the stored push adds to the operator's, it slips, the estimate
    reads the slip's drag, the reference brakes and the joint sticks again: stick-slip at
    a few hertz (held-out LuGre #24, a stiff hand: the reference 34 mrad ahead at 0.15
    rad/s). Relaxing a lagging joint's reference towards its velocity every period,
    ``q̇_ref += rate (q̇ − q̇_ref)`` (the anti-windup of a saturated integrator), keeps
    that store to what the joint's own lag builds within ``unwind_time``; like
    :func:`reanchored`, it never speeds a reference up nor turns it, so a joint that runs
    ahead keeps the PD's damping.

    Args:
        qd_ref: Velocity reference [rad/s].
        qd: Joint velocities [rad/s].
        rate: Share of the lag removed per period, ``dt / (unwind_time + dt)`` [–].
    """
    return cast(FloatArray, np.where(lagging(qd_ref, qd), qd_ref + rate * (qd - qd_ref), qd_ref))


def settled_reference(
    q_ref: FloatArray,
    q: FloatArray,
    moving: FloatArray,
    weight: FloatArray,
    rate: float,
    joint_moving: FloatArray | float = 0.0,
) -> FloatArray:
    """Position reference of the joints that rest with no push, drawn to where they are [rad].

    The PD's position error is a spring between the admittance's reference and the arm.
    A joint that friction stopped short of its reference (the operator let go, or stopped
    pushing) would stay loaded by that spring against stiction: under the dither it
    creeps, and it jumps when the stiction gives. Where nobody starts or sustains a motion
    (``weight`` → 0), the admittance has come to rest (``moving``, the
    :func:`motion_sign` of the reference velocity, → 0) and so has the joint
    (``joint_moving``, the same sign of its own velocity, → 0), the reference follows the
    joint, ``q_ref += rate (1 − |s|) (1 − |s_q|) (1 − w) (q − q_ref)``: the spring keeps
    what an operator put in, and what holds the joint where it stopped against a slow
    creep, not the push that was left when the motion ended. A joint that moves on its
    own while nothing drives it (a gravity error its friction cannot hold) is not
    followed: a reference drawn after it would turn a steady error into a steady drift,
    where the spring, left to build, holds it. No threshold: the large errors of a lost
    tracking are re-anchored at once instead.

    Args:
        q_ref: Position reference [rad].
        q: Joint positions [rad].
        moving: :func:`motion_sign` of the reference velocity [–].
        weight: :func:`damping_weight` of every joint [–].
        rate: Share of the error removed per period, ``dt / (settle_time + dt)`` [–].
        joint_moving: :func:`motion_sign` of the joint's own velocity [–].
    """
    resting = (1.0 - np.abs(moving)) * (1.0 - np.abs(joint_moving))
    return q_ref + rate * (resting * (1.0 - weight)) * (q - q_ref)


def virtual_damping(
    mass: FloatArray, damping_time: float, rest_scale: float, weight: FloatArray
) -> FloatArray:
    """D̃ = S M(q) S / damping_time [Nm s/rad], (n, n): the arm's inertia, heavier where unpushed.

    ``S = diag(√((1 + B) / (1 + B w_i)))`` with ``w_i`` the joint's
    :func:`damping_weight` and ``B = rest_scale``: a joint's damping (``D̃_ii = m_ii /
    damping_time · (1 + B) / (1 + B w_i)``) rises smoothly to ``1 + B`` times its
    guiding value as its weight falls to 0 (the operator lets go, does not push that
    joint, or holds it back). A released joint then stops within about ``k_M ·
    damping_time / (1 + B)``, and a model error ``e`` that leaks through the weight
    moves it at about ``e w (1 + B w) / ((1 + B) D̃_guide)`` (exactly so for a diagonal
    D̃), quadratically slower as the weight fades, instead of coasting at ``e / D̃``.

    Shaped like M(q), not only its diagonal: while every joint is pushed (S → I) the arm settles
    at ``q̇ = damping_time · M⁻¹ τ``, every motion of the arm on the same time constant
    ``k_M · damping_time``, and a force ``F`` at the tool (``τ = Jᵀ F``) moves the tool at
    ``damping_time · J M⁻¹ Jᵀ F``, the arm's own mobility there. A diagonal ``m_ii /
    damping_time`` answers each joint's share of the torque on its own, the lightest
    joints (a wrist) fastest whatever the rest of the arm does (design log, *Damping
    shaped like the arm*).

    Args:
        mass: M(q) [kg m²], (n, n).
        damping_time: Time constant m_ii / D̃_ii while guiding [s].
        rest_scale: Extra damping, in multiples, once nobody pushes [–].
        weight: :func:`damping_weight` of every joint.
    """
    scale = np.sqrt((1.0 + rest_scale) / (1.0 + rest_scale * weight))
    return scale[:, None] * mass * scale[None, :] / damping_time


def braking_cap(
    q_ref: FloatArray, qd_ref: FloatArray, low: FloatArray, high: FloatArray,
    cap: FloatArray, zone: float,
) -> FloatArray:  # fmt: skip
    """Velocity reference within its speed cap and a braking curve to its bounds [rad/s].

    Towards a bound at distance ``d`` the reference may move at most ``cap · √(d / zone)``:
    the speed from which a constant deceleration ``cap² / (2 zone)`` stops it at the bound.
    A joint guided into its limit zone slows down smoothly instead of being stopped at once
    by the bound (and thrown by the PD into the supervisor's wall); away from a bound, or
    farther than ``zone`` from it, only the cap applies.

    Args:
        q_ref: Position reference now [rad].
        qd_ref: The admittance's new velocity reference [rad/s].
        low: Lower bound of the position reference [rad].
        high: Upper bound [rad].
        cap: Speed cap [rad/s].
        zone: Braking distance from the cap to rest [rad].
    """
    ahead = np.where(qd_ref > 0.0, high - q_ref, q_ref - low)
    braking = cap * np.sqrt(np.clip(ahead / zone, 0.0, 1.0))
    return cast(FloatArray, np.clip(qd_ref, -braking, braking))


def keep_within(state: AdmittanceState, low: FloatArray, high: FloatArray) -> AdmittanceState:
    """Clamp the position reference into [low, high]; stop its velocity at the bound."""
    clamped = np.clip(state.q_ref, low, high)
    at_bound = ((clamped <= low) & (state.qd_ref < 0)) | ((clamped >= high) & (state.qd_ref > 0))
    return AdmittanceState(clamped, np.where(at_bound, 0.0, state.qd_ref))
