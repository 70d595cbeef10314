"""Coupled stability of active lead-through with a hand, linearised, per joint.

The loop a hand closes through active lead-through: the hand pushes the arm, the
observer estimates that push with a lag, the admittance turns the estimate into a
velocity reference, the PD tracks it after the command delay, the arm moves, and the
hand's spring pushes back. Lag in that loop acts as negative damping; with an admittance
*lighter* than the arm it grows with the hand's stiffness until the loop oscillates (the
6–18× vibration measured on an unseen plant with k_M = 0.3).

Each joint i is taken alone (decoupled, as the observer and the gains are): arm inertia
m_ii(q), a hand of Cartesian stiffness K_h and damping B_h seen through the joint's
lever (k = K_h |J_v,i|², b = B_h |J_v,i|², with J_v the translational Jacobian at the
flange), and the mass of the operator's hand and forearm moving with the tool, m_h
|J_v,i|², which the controller's model (its observer, admittance and gains) does not
know, the exact stationary Kalman gains of the observer while moving, the admittance
``k_M m ẍ_ref + D̃ ẋ_ref = τ̂`` (implicit in D̃, as the controller integrates it), the
PD ``K_P (x_ref − x) + K_D (ẋ_ref − ẋ)`` and ``delay`` periods between command and
torque. The closed loop is a linear map of the state over one period. Its oscillatory modes
(the hand's spring against the virtual inertia) are what an operator feels as vibration:
each eigenvalue λ is a continuous mode ``s = ln(λ) / dt`` with damping ratio
``ζ = −Re(s) / |s|``; ζ < 0 is an oscillation that grows. One eigenvalue is exactly 1 for
every setting (any pose where the arm rests with the hand is an equilibrium): it is
left out.

Nonlinear effects (friction, stiction, saturation) are not in the model: they add damping
in practice, so the region is a conservative guide, checked on the plants of
``benchmarks/guiding_quality.py``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.estimation.observer import sliding_gains
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics

#: Joint speed at which the observer's stationary gains are taken [rad/s] (moving).
MOVING_SPEED = 0.1
#: Damping ratio the defaults keep with every hand up to 3000 N/m [–].
MARGIN = 0.15


@dataclass(frozen=True)
class JointLoop:
    """One joint of the arm coupled with a hand, in joint space.

    Attributes:
        inertia: m_ii [kg m²].
        stiffness: Hand stiffness seen at the joint [Nm/rad].
        damping: Hand damping seen at the joint [Nm s/rad].
        observer_gains: Stationary Kalman gains (K_p [–], K_τ [1/s]), and K_ṙ [1/s²] for
            the ``"smooth_rate"`` observer (which also estimates the torque's rate).
        hand_inertia: The hand's own mass seen at the joint [kg m²]: it moves with the arm,
            and the controller's model does not know it (the observer reads its inertial
            force as the operator's).
    """

    inertia: float
    stiffness: float
    damping: float
    observer_gains: tuple[float, ...]
    hand_inertia: float = 0.0


def loop_matrix(
    joint: JointLoop, parameters: LeadThroughParameters, dt: float, delay: int
) -> FloatArray:
    """State transition of the closed loop over one period, (7 + delay)² (or 8 + delay).

    State: q, q̇ (the arm), p̂, τ̂ (the observer), q_ref, q̇_ref (the admittance), the
    torque applied over the last period and ``delay`` commands on their way; with three
    observer gains the observer's torque rate ṙ̂ comes after the queue. The velocity
    reference is unwound every period (as if the joint always lagged) unless
    ``unwind_time`` is None.
    """
    m, p = joint.inertia, parameters  # the model's inertia: the controller's gains use it
    moved = m + joint.hand_inertia  # what the torques move: the arm and the hand's mass
    spring = np.array([[0.0, 1.0], [-joint.stiffness / moved, -joint.damping / moved]])
    arm = expm(np.block([[spring, np.array([[0.0], [1.0 / moved]])],
                         [np.zeros((1, 3))]]) * dt)  # fmt: skip
    virtual_mass = p.inertia_scale * m
    virtual_damping = m / p.damping_time
    kp, kd = m * (2.0 * np.pi * p.position_bandwidth) ** 2, m / p.velocity_time
    unwind = 0.0 if p.unwind_time is None else dt / (p.unwind_time + dt)
    gain_p, gain_tau, gain_rate = (*joint.observer_gains, 0.0)[:3]
    rates = len(joint.observer_gains) - 2  # 0, or 1 for the smooth-rate observer

    def step(x: FloatArray) -> FloatArray:
        q, qd, p_hat, tau_hat, q_ref, qd_ref, applied = x[:7]
        queue, rate = list(x[7 : 7 + delay]), x[7 + delay :]
        prior = p_hat + dt * (applied + tau_hat + 0.5 * dt * np.sum(rate))
        innovation = m * qd - prior
        p_hat = prior + gain_p * innovation
        tau_hat = tau_hat + dt * np.sum(rate) + gain_tau * innovation
        rate = rate + gain_rate * innovation
        qd_ref = qd_ref + unwind * (qd - qd_ref)  # unwound, as if the joint always lagged
        qd_ref = (virtual_mass * qd_ref + dt * tau_hat) / (virtual_mass + dt * virtual_damping)
        q_ref = q_ref + dt * qd_ref
        command = kp * (q_ref - q) + kd * (qd_ref - qd)
        queue.append(command)
        torque = queue.pop(0)
        q, qd = arm[:2, :2] @ np.array([q, qd]) + arm[:2, 2] * torque
        return np.array([q, qd, p_hat, tau_hat, q_ref, qd_ref, torque, *queue, *rate])

    size = 7 + delay + rates
    return np.column_stack([step(unit) for unit in np.eye(size)])


def least_damping(matrix: FloatArray, dt: float) -> float:
    """Smallest damping ratio ζ [–] of the loop's oscillatory modes (< 0: unstable).

    Modes slower than 0.5 Hz are the admittance's own drift, not a vibration.
    """
    eigenvalues = np.linalg.eigvals(matrix).astype(complex)
    eigenvalues = eigenvalues[(np.abs(eigenvalues - 1.0) > 1e-6) & (np.abs(eigenvalues) > 1e-9)]
    modes = np.log(eigenvalues) / dt
    oscillating = modes[np.abs(modes.imag) > 2.0 * np.pi * 0.5]
    if not oscillating.size:
        return 1.0
    return float(np.min(-oscillating.real / np.abs(oscillating)))


def joint_loops(
    robot: RobotDescription,
    parameters: LeadThroughParameters,
    hand_stiffness: float,
    hand_damping: float,
    dt: float,
    q: FloatArray | None = None,
    hand_mass: float = 0.0,
) -> list[JointLoop]:
    """Every joint of ``robot`` at ``q`` (default home) held by the hand, one loop each.

    ``hand_mass`` [kg]: the operator's hand and forearm moving with the tool.
    """
    dynamics = Dynamics(robot)
    q = robot.home() if q is None else q
    inertia = np.diag(dynamics.mass(q))
    lever2 = np.sum(dynamics.jacobian(q)[:3] ** 2, axis=0)
    friction_std = FrictionModel.from_robot(robot).std(np.full(robot.n_joints, MOVING_SPEED))
    observer = parameters.observer
    loops = []
    for i in range(robot.n_joints):
        gains = sliding_gains(observer, float(friction_std[i]), dt)
        hand = (hand_stiffness * lever2[i], hand_damping * lever2[i])
        loops.append(JointLoop(float(inertia[i]), *hand, tuple(float(g) for g in gains),
                               hand_mass * float(lever2[i])))  # fmt: skip
    return loops


def worst_damping(
    robot: RobotDescription,
    parameters: LeadThroughParameters,
    hand_stiffness: float,
    hand_damping: float,
    dt: float = 0.004,
    delay: int = 1,
    hand_mass: float = 0.0,
) -> float:
    """Smallest damping ratio over the joints of ``robot`` at home [–] (< 0: unstable).

    ``hand_mass`` [kg]: the operator's hand and forearm moving with the tool
    (:func:`joint_loops`).

    The unwinding of a lagging joint's reference (``unwind_time``) acts only while the
    joint lags, part of each cycle; a linear loop cannot switch, so it is taken both
    always on and always off, and the smaller ζ counts. (On the YuMi with a firm hand it
    costs the defaults' loop ζ, 0.32 → 0.19, and helps a light admittance's.)

    The law's gains are those the controller runs at ``dt``: below 250 Hz its velocity
    loop softened and its unwinding slowed by as much
    (:meth:`~leadthrough.control.parameters.LeadThroughParameters.at_period`).
    """
    parameters = parameters.at_period(dt)
    loops = joint_loops(robot, parameters, hand_stiffness, hand_damping, dt,
                        hand_mass=hand_mass)  # fmt: skip
    variants = [parameters]
    if parameters.unwind_time is not None:
        variants.append(dataclasses.replace(parameters, unwind_time=None))
    return min(least_damping(loop_matrix(loop, variant, dt, delay), dt)
               for loop in loops for variant in variants)  # fmt: skip


@dataclass(frozen=True, eq=False)
class StabilityMap:
    """Least damping ratio over hand stiffness and virtual inertia, for some delays.

    Attributes:
        stiffness: Hand stiffnesses [N/m], (S,).
        inertia_scale: Virtual inertia scales k_M [–], (K,).
        delays: Command delays [periods].
        damping: Smallest damping ratio over the joints [–], (len(delays), K, S).
        chosen: The defaults' k_M [–].
    """

    stiffness: FloatArray
    inertia_scale: FloatArray
    delays: tuple[int, ...]
    damping: FloatArray
    chosen: float

    def stable_scales(self, up_to: float, margin: float = MARGIN) -> FloatArray:
        """The k_M [–] whose ζ stays ≥ ``margin`` for every hand up to ``up_to`` [N/m]."""
        hands = self.stiffness <= up_to
        return self.inertia_scale[np.all(self.damping[:, :, hands] >= margin, axis=(0, 2))]


def stability_map(
    robot: RobotDescription,
    parameters: LeadThroughParameters | None = None,
    stiffness: FloatArray | None = None,
    inertia_scale: FloatArray | None = None,
    delays: tuple[int, ...] = (1, 2),
    dt: float = 0.004,
) -> StabilityMap:
    """The stable region of the defaults' law over hand stiffness × k_M (hand ζ as a person's).

    The hand's damping grows with its stiffness as a person's arm does when it stiffens
    (about 30 N s/m relaxed at 300 N/m, 100 N s/m stiff at 3000 N/m: B_h = 1.8 √K_h).
    """
    parameters = parameters or LeadThroughParameters()
    stiffness = np.geomspace(100.0, 10000.0, 13) if stiffness is None else stiffness
    inertia_scale = np.geomspace(0.2, 4.0, 14) if inertia_scale is None else inertia_scale
    damping = np.empty((len(delays), inertia_scale.size, stiffness.size))
    for d, delay in enumerate(delays):
        for k, scale in enumerate(inertia_scale):
            scaled = _with(parameters, inertia_scale=float(scale))
            for s, hand in enumerate(stiffness):
                damping[d, k, s] = worst_damping(robot, scaled, float(hand),
                                                 1.8 * float(np.sqrt(hand)), dt, delay)  # fmt: skip
    return StabilityMap(stiffness, inertia_scale, tuple(delays), damping, parameters.inertia_scale)


def _with(parameters: LeadThroughParameters, **changes: float) -> LeadThroughParameters:
    return LeadThroughParameters(**{**parameters.__dict__, **changes})
