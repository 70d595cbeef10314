"""The admittance rule of active lead-through (thesis §6.2, SPEC §6): a small pure core.

The virtual system the operator feels is ``M̃(q) q̈_ref + D̃ q̇_ref = τ_in`` with
``M̃ = k_M M(q)`` and ``D̃`` diagonal (eq. 6.5, written on the reference velocity so
that the virtual system is self-contained), integrated with implicit Euler in the
damping so that it is stable for any D̃::

    (M̃ + dt D̃) q̇_ref⁺ = M̃ q̇_ref + dt τ_in,     q_ref⁺ = q_ref + dt q̇_ref⁺

and tracked with ``τ_fb = K_P (q_ref − q) + K_D (q̇_ref − q̇)`` (eq. 6.4); ``K_P = 0`` is
damping control (§6.3.1). References never wind up: they are kept within the soft
joint limits and re-anchored to the measured state when tracking is lost (an end-stop,
a collision) or when the operator lets go.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
        damping: Diagonal of D̃ [Nm s/rad], (n,).
        dt: Control period [s].
    """
    virtual_mass = inertia_scale * mass
    lhs = virtual_mass + dt * np.diag(damping)
    qd_ref = np.linalg.solve(lhs, virtual_mass @ state.qd_ref + dt * tau_in)
    return AdmittanceState(state.q_ref + dt * qd_ref, qd_ref)


def tracking_torque(
    state: AdmittanceState, q: FloatArray, qd: FloatArray, kp: FloatArray, kd: FloatArray
) -> FloatArray:
    """PD tracking of the references, eq. (6.4) [Nm]."""
    return kp * (state.q_ref - q) + kd * (state.qd_ref - qd)


def dead_zone(value: FloatArray, width: FloatArray, offset: FloatArray | float = 0.0) -> FloatArray:
    """What is left of ``value`` outside [min(0, offset) − width, max(0, offset) + width].

    With ``offset = 0`` this is ``sign(x) · max(|x| − w, 0)``. A non-zero offset (a learned
    bias) only widens the band towards itself: it can silence a reading, never create one.
    """
    upper = np.maximum(offset, 0.0) + width
    lower = np.minimum(offset, 0.0) - width
    return np.where(value > upper, value - upper, np.where(value < lower, value - lower, 0.0))


def operator_started(drive: FloatArray, qd: FloatArray, rest_velocity: float) -> FloatArray:
    """What of the operator torque ``drive`` [Nm] the admittance may act on.

    A joint moving the way its torque pushes is assisted; one moving against it is not
    (the operator brakes it, or the reading is model error); a joint at rest (|q̇| ≤
    ``rest_velocity`` [rad/s], where the observer is nearly blind) only while another
    joint moves with the operator: a push that has not broken its stiction yet. With
    nothing moving nothing is assisted, so model error read at rest cannot start a motion.
    """
    moving = np.abs(qd) > rest_velocity
    started = moving & (np.sign(qd) * drive > 0.0)
    return np.where(started | (~moving & started.any()), drive, 0.0)


def keep_within(state: AdmittanceState, low: FloatArray, high: FloatArray) -> AdmittanceState:
    """Clamp the position reference into [low, high]; stop its velocity at the bound."""
    clamped = np.clip(state.q_ref, low, high)
    at_bound = ((clamped <= low) & (state.qd_ref < 0)) | ((clamped >= high) & (state.qd_ref > 0))
    return AdmittanceState(clamped, np.where(at_bound, 0.0, state.qd_ref))
