"""Joint-space tracking by computed torque (experiments, excitation and replay).

    τ = G(q) + M(q) (q̈_ref + ω² (q_ref − q) + 2ζω (q̇_ref − q̇))

The gains are ``K_P = M(q) ω²`` and ``K_D = 2ζω M(q)``, the full inertia matrix of the
current pose, so that every mode of the arm, not only every joint, has the bandwidth ω:
light wrist joints and heavy shoulder joints respond alike, a joint whose inertia drops
as the arm folds (the YuMi's joint 3 by 4×) keeps its bandwidth, and coupled joints do
too. Per-joint gains ``m_ii(q) ω²`` give a loop gain ``ω² M⁻¹ diag(M)`` instead, whose
eigenvalues grow without bound near a pose where two joint axes align (the Panda's
joints 1 and 3 at q₂ = 0: the excitation of its joint 2 ran away at 4.3 rad/s).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics


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
        bandwidth: float = 4.0,
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
