"""Joint-space tracking: model feed-forward plus a PD loop (experiments and replay).

    τ = G(q) + M(q) q̈_ref + K_P (q_ref − q) + K_D (q̇_ref − q̇)

with per-joint gains from a bandwidth and a damping ratio on the diagonal of M at a
reference pose, ``K_P = m_ii ω²``, ``K_D = 2 ζ m_ii ω``, so that light wrist joints
and heavy shoulder joints respond alike.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.description import FloatArray
from leadthrough.dynamics import Dynamics


class JointTracker:
    """Tracks joint references with inverse-dynamics feed-forward and a PD loop.

    Args:
        dynamics: Model of the arm.
        bandwidth: Closed-loop bandwidth ω / 2π [Hz] (4 Hz suits 250 Hz control with a
            one-period delay).
        damping_ratio: ζ of each joint loop [–].
        reference_pose: Pose whose mass-matrix diagonal sets the gains [rad] (default home).
    """

    def __init__(
        self,
        dynamics: Dynamics,
        bandwidth: float = 4.0,
        damping_ratio: float = 1.0,
        reference_pose: ArrayLike | None = None,
    ) -> None:
        self.dynamics = dynamics
        pose = dynamics.robot.home() if reference_pose is None else reference_pose
        inertia = np.diag(dynamics.mass(pose))
        omega = 2.0 * np.pi * bandwidth
        self.kp = inertia * omega**2
        self.kd = 2.0 * damping_ratio * inertia * omega

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
        feed_forward = self.dynamics.gravity(q) + self.dynamics.mass(q) @ np.asarray(qdd_ref)
        return feed_forward + self.kp * (q_ref - q) + self.kd * (np.asarray(qd_ref) - qd)
