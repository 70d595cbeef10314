"""Joint-space tracking by computed torque, and the bandwidth a tracking loop may have.

The tracker serves the experiments, the excitation and the replay; the bandwidths of
those loops and of the start-up calibration's follow the control period (below).

    τ = G(q) + M(q) (q̈_ref + ω² (q_ref − q) + 2ζω (q̇_ref − q̇))

The gains are ``K_P = M(q) ω²`` and ``K_D = 2ζω M(q)``, the full inertia matrix of the
current pose, so that every mode of the arm, not only every joint, has the bandwidth ω:
light wrist joints and heavy shoulder joints respond alike, a joint whose inertia drops
as the arm folds (the YuMi's joint 3 by 4×) keeps its bandwidth, and coupled joints do
too. Per-joint gains ``m_ii(q) ω²`` give a loop gain ``ω² M⁻¹ diag(M)`` instead, whose
eigenvalues grow without bound near a pose where two joint axes align (the Panda's
joints 1 and 3 at q₂ = 0: the excitation of its joint 2 ran away at 4.3 rad/s).

A bandwidth is chosen for a control period. The loop's delay is counted in periods (the
command acts one period after the sample, over a period, on a velocity the robot
low-passes): at a slower rate the same bandwidth leaves less phase, and at 125 Hz the
6 Hz start-up calibration ran away or jumped 42–48 mrad off its 10 mrad stroke on 5 of
the 8 plants of seeds 1–4 (``benchmarks/guiding_quality.py --dt 0.008``).
:func:`period_bandwidth` gives the bandwidth that keeps, at a slower rate, the damping the
loop has at :data:`VERIFIED_PERIOD`, where the defaults were verified on the plant family;
:func:`loop_damping` is that loop, linearised.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics

#: Control period at which the tracking bandwidths were chosen and verified on the plant
#: family of ``benchmarks/guiding_quality.py`` (the calibration's and the replay's 4 Hz) [s].
VERIFIED_PERIOD = 0.004
#: Periods between a sample and the command it gives reaching the drive, in the loop model
#: of :func:`loop_damping` [–] (the plant family's delays are 1–2 periods).
LOOP_DELAY = 1
#: The plant family's longest delay [periods]: a loop that must not grow on any of its
#: plants must decay with it.
LONGEST_DELAY = 2
#: Cut-off of the low-pass the loop model assumes in the robot's joint velocity [Hz]: the
#: slowest of the plant family (15–40 Hz, a differenced encoder filtered).
VELOCITY_CUTOFF = 15.0

#: The tracker's bandwidth at :data:`VERIFIED_PERIOD` [Hz] (4 Hz suits 250 Hz control with
#: a one-period delay; :func:`period_bandwidth` gives it at another period).
BANDWIDTH = 4.0

#: Gains per unit inertia of a bandwidth ω [rad/s]: (K_P [1/s²], K_D [1/s], K_I [1/s³]).
LoopGains = Callable[[float], tuple[float, float, float]]


def pd_gains(damping_ratio: float = 1.0, integral_share: float = 0.0) -> LoopGains:
    """``ω ↦ (ω², 2ζω, s ω³)``: a PD of damping ratio ζ and an integral of share s [–].

    With the integral a fixed share of ω³ the loop keeps its shape at any bandwidth
    (``K_I = K_P / T_I`` with ``T_I = 1 / (s ω)``).
    """

    def gains(omega: float) -> tuple[float, float, float]:
        return omega**2, 2.0 * damping_ratio * omega, integral_share * omega**3

    return gains


def predicted_state(
    q: FloatArray, qd: FloatArray, acceleration: FloatArray, period: float
) -> tuple[FloatArray, FloatArray]:
    """The joint state one ``period`` [s] ahead, under the last acceleration commanded.

    A command computed from a sample acts one period later (:data:`LOOP_DELAY`), when the
    arm has moved on under the command before it: tracking the state predicted for then
    (``q + T q̇ + T² a / 2``, ``q̇ + T a``, with ``a`` the acceleration [rad/s²] the previous
    command asked of computed torque, less an integral's share, which holds a load the
    model lacks and accelerates nothing) instead of the sample takes that period out of
    the loop. What the prediction does not know (a second period of delay, the robot's
    velocity filter, friction the model lacks) the loop's margin must still cover.
    """
    return q + period * (qd + 0.5 * period * acceleration), qd + period * acceleration


def loop_damping(
    gains: tuple[float, float, float],
    dt: float,
    delay: int = LOOP_DELAY,
    velocity_cutoff: float = VELOCITY_CUTOFF,
    predicted: bool = False,
    viscous: float = 0.0,
) -> float:
    """Least damping ratio of one joint's tracking loop, linearised [–] (< 0: it grows).

    Per unit inertia (computed torque leaves each mode a double integrator): the
    controller samples the position and a velocity low-passed at ``velocity_cutoff``
    [Hz], commands ``K_P e − K_D v + K_I ∫e`` (``gains``, per unit inertia), and the
    command acts ``delay`` periods later, held over a period ``dt`` [s]. ``predicted``:
    ``e`` and ``v`` are taken one period ahead (:func:`predicted_state`, the filtered
    velocity standing for the joint's). ``viscous`` [1/s]: the joint's own viscous friction
    per unit inertia, ``b / m_ii``, which damps the arm. Each eigenvalue λ of the map over
    one period is a mode ``s = ln(λ) / dt`` of damping ratio ``−Re(s) / |s|`` (λ = 1, the
    resting mode of a loop without position feedback, left out).
    """
    from scipy.linalg import expm  # not at import: ``import leadthrough`` stays light

    stiffness, damping, integral = gains
    cutoff = 2.0 * np.pi * velocity_cutoff
    arm = np.array([[0.0, 1.0, 0.0, 0.0],  # q, q̇, the filtered velocity, and the torque
                    [0.0, -viscous, 0.0, 1.0],
                    [0.0, cutoff, -cutoff, 0.0],
                    [0.0, 0.0, 0.0, 0.0]])  # fmt: skip
    held = expm(arm * dt)[:3]  # over one period, the torque held
    has_integral = integral != 0.0

    def step(x: FloatArray) -> FloatArray:
        q, qd, v = x[:3]
        queue = list(x[3 + has_integral :])
        tracked, velocity = q, v  # what the command acts on
        if predicted:  # the newest command in the queue, less its integral (x[3] then)
            acceleration = queue[-1] - (integral * x[3] if has_integral else 0.0)
            tracked, velocity = predicted_state(q, v, acceleration, dt)
        accumulated = x[3] - dt * tracked if has_integral else 0.0  # ∫e, e = −q
        queue.append(-stiffness * tracked - damping * velocity + integral * accumulated)
        moved = held @ np.array([q, qd, v, queue.pop(0)])
        return np.array([*moved, *([accumulated] if has_integral else []), *queue])

    size = 3 + has_integral + delay
    eigenvalues = np.linalg.eigvals(np.column_stack([step(unit) for unit in np.eye(size)]))
    # a mode at λ = 1 (no position feedback: any position is an equilibrium) neither
    # grows nor decays, and has no damping ratio
    kept = (np.abs(eigenvalues) > 1e-12) & (np.abs(eigenvalues - 1.0) > 1e-9)
    modes = np.log(eigenvalues[kept].astype(complex)) / dt
    return float(np.min(-modes.real / np.abs(modes)))


def decaying_damping(gains: tuple[float, float, float], dt: float,
                     delay: int = LONGEST_DELAY) -> float:  # fmt: skip
    """The least viscous friction per unit inertia [1/s] with which a loop decays.

    The loop of :func:`loop_damping` tracking the samples, ``delay`` periods of delay at
    the period ``dt`` [s]: 0 where it decays without friction; else the ``b / m`` above
    which it decays (bisected to 1e-3 1/s), a joint with less needs more than its own
    friction (``CalibrationParameters.predict``). Offline: it takes ~30 linearisations.
    """

    def grows(viscous: float) -> bool:
        return loop_damping(gains, dt, delay, viscous=viscous) < 0.0

    if not grows(0.0):
        return 0.0
    low, high = 0.0, 1.0
    while grows(high):
        low, high = high, 2.0 * high
        if high > 1e6:  # no friction damps it: every joint needs the prediction
            return np.inf
    return _bisected(grows, low, high, 1e-3)[1]


def _bisected(
    below: Callable[[float], bool], low: float, high: float, tolerance: float
) -> tuple[float, float]:
    """``(low, high)`` narrowed to ``tolerance`` around where ``below`` turns False.

    ``below(low)`` holds and ``below(high)`` does not; so it stays.
    """
    while high - low > tolerance:
        middle = 0.5 * (low + high)
        low, high = (middle, high) if below(middle) else (low, middle)
    return low, high


#: Bandwidths :func:`period_bandwidth` tries below its ceiling, as fractions of it [–]:
#: the loop's least damping is not monotonic in the bandwidth (an integral that is a
#: fixed share of the loop's time lowers it at low bandwidths too), so a grid, then a
#: bisection between the largest point that keeps the margin and the next one up.
_SCAN = np.geomspace(1.0, 0.02, 60)


def period_bandwidth(
    ceiling: float, dt: float, gains: LoopGains, damping: float | None = None
) -> float:
    """The bandwidth [Hz] a loop of ``gains`` may have at period ``dt`` [s].

    ``ceiling`` [Hz] at :data:`VERIFIED_PERIOD` or faster; at a slower rate, the largest
    bandwidth up to it whose :func:`loop_damping` (one period of delay) is no less than
    ``damping`` [–], by default the ceiling's at :data:`VERIFIED_PERIOD` (at 125 Hz, 6 Hz →
    3.92 Hz for a PD with ζ = 1; the start-up calibration asks for 0.14: 4 Hz → 3.95 Hz),
    or, where no bandwidth down to 2 % of the ceiling keeps that much at ``dt`` (a loop
    damped 0.7 at 250 Hz, an integral that takes damping at any bandwidth; a ``damping``
    asked for above what any keeps), no less than the most any of them keeps.
    """
    if dt <= VERIFIED_PERIOD * (1.0 + 1e-6):  # a measured period's last digits change nothing
        return ceiling

    def loop(fraction: float) -> float:
        return loop_damping(gains(2.0 * np.pi * fraction * ceiling), dt)

    scanned = np.array([loop(fraction) for fraction in _SCAN])
    if damping is None:
        damping = loop_damping(gains(2.0 * np.pi * ceiling), VERIFIED_PERIOD)
    target = min(damping, scanned.max())
    index = int(np.argmax(scanned >= target))  # the first, i.e. the largest, that keeps it
    if index == 0:
        return ceiling

    def keeps(fraction: float) -> bool:
        return loop(fraction) >= target

    # between a fraction that keeps it and the next one up, which does not
    low, _ = _bisected(keeps, _SCAN[index], _SCAN[index - 1], 1e-4)
    return float(low * ceiling)


class JointTracker:
    """Tracks joint references with computed torque: inverse dynamics of a PD's acceleration.

    Args:
        dynamics: Model of the arm.
        bandwidth: Closed-loop bandwidth ω / 2π [Hz] (4 Hz suits 250 Hz control with a
            one-period delay).
        damping_ratio: ζ of each joint loop [–].
        reference_pose: Pose of the gains :attr:`kp` and :attr:`kd` [rad] (default home);
            :meth:`torque` uses those of the current pose.
    """

    def __init__(
        self,
        dynamics: Dynamics,
        bandwidth: float = BANDWIDTH,
        damping_ratio: float = 1.0,
        reference_pose: ArrayLike | None = None,
    ) -> None:
        self.dynamics = dynamics
        pose = dynamics.robot.home() if reference_pose is None else reference_pose
        omega = 2.0 * np.pi * bandwidth
        self._stiffness, self._damping = omega**2, 2.0 * damping_ratio * omega  # per kg m²
        self.kp, self.kd = self.gains(np.diag(dynamics.mass(pose)))

    def gains(self, inertia: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(K_P [Nm/rad], K_D [Nm s/rad])`` for the inertias ``inertia`` [kg m²].

        The diagonal of M gives each joint's own gains (:attr:`kp`, :attr:`kd`), M itself
        the matrices :meth:`torque` uses.
        """
        return inertia * self._stiffness, inertia * self._damping

    def torque(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        q_ref: ArrayLike,
        qd_ref: ArrayLike,
        qdd_ref: ArrayLike,
    ) -> FloatArray:
        """Command [Nm] for measured q [rad], q̇ [rad/s] and the reference (q, q̇, q̈)."""
        q = np.asarray(q, dtype=float)
        wanted = (np.asarray(qdd_ref) + self._stiffness * (np.asarray(q_ref) - q)
                  + self._damping * (np.asarray(qd_ref) - np.asarray(qd)))  # fmt: skip
        return self.dynamics.gravity(q) + self.dynamics.mass(q) @ wanted
