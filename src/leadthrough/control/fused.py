"""The active law (:class:`~leadthrough.control.active_law.ActiveLaw`), compiled.

Four kernels do, per joint and in one pass, what the readable NumPy code of the controller
does in some forty vector operations and a 7×7 solve (the reference, which the tests hold
these to at 1e-9: one-ulp differences of the friction terms carried through the damping's
average over 20 000 random periods):

* :func:`sliding_velocity` is ``ActiveLaw.sliding_velocity``: the speed the law's
  friction sees, zero below ``rest_velocity``;
* :func:`rest_narrowing` is ``ActiveLaw.narrow``: what the joints read together leave of
  each joint's Coulomb uncertainty;
* :func:`operator_drive` is ``ActiveLaw._update_drive``: learn the model-error bias
  (:class:`~leadthrough.control.bias.ModelErrorBias`), remove it through the dead-zone,
  remove the friction the model may overstate, weigh the residual by the model's own
  uncertainty (:func:`~leadthrough.control.admittance.operator_weight`);
* :func:`admittance_law` is ``ActiveLaw._admittance``: ignore an end-stop's reaction,
  re-anchor lost references (:func:`~leadthrough.control.admittance.reanchored`), relax
  a lagging joint's velocity reference (:func:`~leadthrough.control.admittance.unwound`), weigh
  the push that starts or sustains each motion
  (:func:`~leadthrough.control.admittance.damping_weight`), integrate the admittance
  (:func:`~leadthrough.control.admittance.admittance_step`, the (k_M M + dt D̃) system
  solved by Gaussian elimination with partial pivoting), cap and bound the references,
  and the PD that tracks them.

They work in place on the law's state (arrays preallocated once) and take its
constants packed in one (7, n) array of per-joint rows and one array of scalars (see
:data:`JOINT_ROWS`, :data:`DRIVE_SCALARS`, :data:`ADMITTANCE_SCALARS`): a call costs
~1 µs of dispatch, not one per argument.
"""

from __future__ import annotations

import math

from leadthrough.compiled import kernel

#: Rows of the per-joint constants: the friction tolerance 2σ + relative τ_C, the low and
#: high reference limits, the relative error the friction margin removes of the Coulomb
#: part (``ActiveLaw.margin_error``), the tolerance at rest, the speed cap of the
#: references, and the relative error the margin removes of the viscous part
#: (``ActiveLaw.viscous_margin_error``).
JOINT_ROWS = ("friction_tolerance", "reference_low", "reference_high", "margin_error",
              "rest_tolerance", "speed_cap", "viscous_margin_error")  # fmt: skip
#: Scalars of :func:`operator_drive`, in order.
DRIVE_SCALARS = ("gravity_uncertainty", "dt", "bias_time", "drive_gain_uncertainty",
                 "assist_knee", "margin_relief")  # fmt: skip
#: Scalars of :func:`admittance_law`, in order (``limit_aware`` as 0/1, ``position_gain``
#: is (2π f)² [1/s²]).
ADMITTANCE_SCALARS = ("limit_aware", "reanchor_error", "damping_time", "rest_damping",
                      "inertia_scale", "dt", "position_gain", "velocity_time", "assist_knee",
                      "rest_velocity", "push_average", "settle_rate", "limit_zone",
                      "unwind_rate")  # fmt: skip


@kernel
def operator_drive(estimate, q, gravity, level, viscous, upper, lower, joint, scalars,
                   narrowing, bias, gravity_learned, confidence, weight, drive, feedback,
                   residuals, uncertainty):  # fmt: skip
    """One period of the operator torque, in place (the bias' confidence included).

    Args:
        estimate: Observer estimate τ̂_ext [Nm].
        q: Joint positions [rad].
        gravity: G(q) [Nm].
        level: τ_C(q) [Nm] (the friction model's terms at (q̇, q),
            ``FrictionModel.sigmoid_terms``, as are the next three).
        viscous: c q̇ [Nm].
        upper: tanh(A (q̇ + B) / 2) [–].
        lower: tanh(A (q̇ − B) / 2) [–].
        joint: Per-joint constants, rows :data:`JOINT_ROWS`.
        scalars: :data:`DRIVE_SCALARS`.
        narrowing: What the joints read together leave of each joint's Coulomb
            uncertainty [–] (``ActiveLaw.narrowing``).
        bias: The learned bias [Nm] (``ModelErrorBias.bias``), updated.
        gravity_learned: ``ModelErrorBias.gravity_learned`` [Nm], updated.
        confidence: The bias' confidence per joint [–], updated (as fast as the joint
            slides, ``1 − (upper − lower) / 2``: ``ModelErrorBias.update``).
        weight: Operator weights [–], updated.
        drive: Operator drive [Nm], written.
        feedback: The admittance's last tracking torque [Nm].
        residuals: The residual before its weight [Nm], written.
        uncertainty: What the model may read without an operator [Nm], written.
    """
    gravity_uncertainty, dt, bias_time, gain_uncertainty, knee, relief = scalars
    n = q.shape[0]
    clear_of_limits, top, undefined = True, -math.inf, False
    for i in range(n):
        clear_of_limits = clear_of_limits and q[i] > joint[1, i] and q[i] < joint[2, i]
        undefined = undefined or weight[i] != weight[i]
        top = weight[i] if weight[i] > top else top
    top = math.nan if undefined else top  # np.max: NaN wins
    unguided = (1.0 - top) ** 2 if clear_of_limits else 0.0
    if unguided > 0.0:  # NaN learns nothing, as in ModelErrorBias.update
        rate = unguided * dt / bias_time
        for i in range(n):
            bound = 2.0 * (joint[0, i] + gravity_uncertainty * abs(gravity[i]))
            learned = bias[i] + rate * (estimate[i] - bias[i])
            learned = learned if learned > -bound or learned != learned else -bound
            bias[i] = learned if learned < bound or learned != learned else bound
            gravity_learned[i] = gravity_learned[i] + rate * (gravity[i] - gravity_learned[i])
            sliding = 1.0 - 0.5 * (upper[i] - lower[i])
            confidence[i] = confidence[i] + rate * sliding * (1.0 - confidence[i])
    for i in range(n):
        b = bias[i]
        band_high = (b if b > 0.0 or b != b else 0.0) + 0.0
        band_low = (b if b < 0.0 or b != b else 0.0) - 0.0
        value = estimate[i]
        if value > band_high:
            residual = value - band_high
        elif value < band_low:
            residual = value - band_low
        else:
            residual = 0.0
        half_level = 0.5 * level[i]
        coulomb = (half_level * (upper[i] + lower[i]) + viscous[i]) - viscous[i]
        margin = joint[3, i] * coulomb + joint[6, i] * viscous[i]
        if relief != 0.0:  # admittance.relieved_margin
            size = abs(margin)
            along = residual if margin > 0.0 else -residual
            if along > size:
                margin = margin * (size / along)
        residual = (residual - margin) - gain_uncertainty * feedback[i]
        unknown = abs(gravity[i])
        changed = abs(gravity[i] - gravity_learned[i])
        tolerance = gravity_uncertainty * ((1.0 - confidence[i]) * unknown
                                           + confidence[i] * changed)  # fmt: skip
        spread = (joint[4, i] + tolerance) + half_level * (upper[i] - lower[i]) * narrowing[i]
        residuals[i], uncertainty[i] = residual, spread
        if knee == 0.0:
            w = 1.0
        else:
            floor = spread if spread > 1e-12 or spread != spread else 1e-12
            z = residual / (knee * floor)
            z2 = z * z
            w = z2 / (1.0 + z2)
        weight[i] = w
        drive[i] = residual * w


@kernel
def rest_narrowing(fused_std, own_std, out):
    """``min(fused_std / max(own_std, 1e-9), 1)`` [–] into ``out`` (``ActiveLaw.narrow``).

    Returns nothing (an array returned costs numba ~0.2 µs to box), as every kernel of a
    control period.
    """
    for i in range(out.shape[0]):
        own = own_std[i] if own_std[i] > 1e-9 or own_std[i] != own_std[i] else 1e-9
        ratio = fused_std[i] / own
        out[i] = ratio if ratio < 1.0 or ratio != ratio else 1.0


@kernel
def sliding_velocity(qd, rest_velocity, out):
    """``sign(q̇) · max(|q̇| − v_rest, 0)`` [rad/s] into ``out`` (``ActiveLaw.sliding_velocity``)."""
    for i in range(qd.shape[0]):
        v = qd[i]
        if v > rest_velocity:
            out[i] = v - rest_velocity
        elif v < -rest_velocity:
            out[i] = v + rest_velocity
        else:
            out[i] = 0.0  # at rest (and NaN, as the NumPy dead_zone)


@kernel
def admittance_law(q, qd, drive, constraint, mass, residuals, uncertainty, joint, scalars, q_ref,
                   qd_ref, sustained, damping_weight, signed_weight, feedback, work):  # fmt: skip
    """One period of the admittance and its tracking PD, in place (``feedback`` [Nm]).

    Args:
        q: Joint positions [rad].
        qd: Joint velocities [rad/s].
        drive: Operator drive [Nm].
        constraint: Virtual constraints' torque [Nm].
        mass: M(q) [kg m²], (n, n).
        residuals: The operator's residual before its weight [Nm].
        uncertainty: What the model may read without an operator [Nm].
        joint: Per-joint constants, rows :data:`JOINT_ROWS`.
        scalars: :data:`ADMITTANCE_SCALARS`.
        q_ref: Position reference [rad], updated.
        qd_ref: Velocity reference [rad/s], updated.
        sustained: The push along the motion, averaged over ``push_time`` [Nm], updated.
        damping_weight: Weight that sets the virtual damping [–], written.
        signed_weight: The push's weight signed by it, averaged over ``push_time`` [–],
            updated (:func:`~leadthrough.control.admittance.signed_push_weight`).
        feedback: Tracking torque [Nm], written.
        work: Scratch space, (n, n + 1).
    """
    (limit_aware, reanchor, damping_time, rest, scale, dt, position_gain, velocity_time, knee,
     rest_velocity, average, settle, zone, unwind) = scalars  # fmt: skip
    n = q.shape[0]
    for i in range(n):  # the reference system (k_M M + dt D̃) x = k_M M q̇_ref + dt τ_in
        tau_in = drive[i] + constraint[i]
        push_in = residuals[i] + constraint[i]
        reaction = (q[i] > joint[2, i] and tau_in < 0) or (q[i] < joint[1, i] and tau_in > 0)
        if limit_aware != 0.0 and reaction:  # near a limit, a push away is the stop's reaction
            tau_in = push_in = 0.0
        v, w = qd_ref[i], qd[i]
        lags = (v > 0.0 and 0.0 <= w < v) or (v < 0.0 and v < w <= 0.0)  # lagging
        if abs(q_ref[i] - q[i]) > reanchor:  # tracking lost: re-anchor (reanchored)
            q_ref[i] = q[i]
            qd_ref[i] = w if lags else v
        elif lags:  # a lagging joint's velocity reference relaxes to it (unwound)
            qd_ref[i] = v + unwind * (w - v)
        work[i, n] = dt * tau_in
        v = qd_ref[i]  # what starts or sustains the motion: at rest all of it, moving along
        moving = v / math.sqrt(v * v + rest_velocity * rest_velocity)
        sustained[i] = sustained[i] + average * (push_in * moving - sustained[i])
        along = sustained[i] if sustained[i] > 0.0 or sustained[i] != sustained[i] else 0.0
        idle = push_in * (1.0 - abs(moving))
        push = math.sqrt(idle * idle + along * along)
        sign = 1.0 if push_in > 0.0 else (-1.0 if push_in < 0.0 else push_in)  # np.sign
        if knee == 0.0:
            damping_weight[i] = 1.0
            pushed = sign
        else:
            u = uncertainty[i]
            floor = u if u > 1e-12 or u != u else 1e-12
            z = push / (knee * floor)
            z2 = z * z
            damping_weight[i] = z2 / (1.0 + z2)
            z = push_in / (knee * floor)
            z2 = z * z
            pushed = sign * (z2 / (1.0 + z2))
        signed_weight[i] = signed_weight[i] + average * (pushed - signed_weight[i])
        # the admittance and the joint at rest, no push: the reference follows the joint
        # (settled_reference)
        own = w / math.sqrt(w * w + rest_velocity * rest_velocity)
        resting = (1.0 - abs(moving)) * (1.0 - abs(own))
        q_ref[i] += settle * (resting * (1.0 - damping_weight[i])) * (q[i] - q_ref[i])
    for i in range(n):  # D̃ = S M S / T, S_ii = √((1 + B) / (1 + B w_i)): virtual_damping
        total = 0.0
        s_i = math.sqrt((1.0 + rest) / (1.0 + rest * damping_weight[i]))
        for j in range(n):
            virtual = scale * mass[i, j]
            s_j = math.sqrt((1.0 + rest) / (1.0 + rest * damping_weight[j]))
            work[i, j] = virtual + dt * (s_i * mass[i, j] * s_j / damping_time)
            total += virtual * qd_ref[j]
        work[i, n] += total
    # Gaussian elimination with partial pivoting of the augmented (n, n + 1) system
    for k in range(n):
        pivot, best = k, abs(work[k, k])
        for i in range(k + 1, n):
            if abs(work[i, k]) > best:
                pivot, best = i, abs(work[i, k])
        if pivot != k:
            for j in range(k, n + 1):
                work[k, j], work[pivot, j] = work[pivot, j], work[k, j]
        for i in range(k + 1, n):
            factor = work[i, k] / work[k, k]
            for j in range(k + 1, n + 1):
                work[i, j] -= factor * work[k, j]
    for i in range(n - 1, -1, -1):
        total = work[i, n]
        for j in range(i + 1, n):
            total -= work[i, j] * work[j, n]
        work[i, n] = total / work[i, i]
    for i in range(n):
        velocity = work[i, n]
        cap = joint[5, i]
        if limit_aware != 0.0:  # hold a joint where it is inside the limit zone
            low = joint[1, i] if joint[1, i] < q[i] else q[i]
            high = joint[2, i] if joint[2, i] > q[i] else q[i]
            ahead = high - q_ref[i] if velocity > 0.0 else q_ref[i] - low  # braking_cap
            share = ahead / zone if ahead < zone else 1.0
            cap = cap * math.sqrt(share) if share > 0.0 else 0.0
        velocity = velocity if velocity > -cap or velocity != velocity else -cap
        velocity = velocity if velocity < cap or velocity != velocity else cap
        position = q_ref[i] + dt * velocity
        if limit_aware != 0.0:
            position = position if position > low or position != position else low
            position = position if position < high or position != position else high
            if (position <= low and velocity < 0) or (position >= high and velocity > 0):
                velocity = 0.0
        q_ref[i], qd_ref[i] = position, velocity
        inertia = mass[i, i]
        kp, kd = inertia * position_gain, inertia / velocity_time
        feedback[i] = kp * (position - q[i]) + kd * (velocity - qd[i])
