"""The model of the arm at one sample, computed once per control period.

Like mink's ``Configuration.update()``: each period the controller asks
:meth:`~leadthrough.model.dynamics.Dynamics.snapshot` once for the state it read, and hands
the same :class:`ModelSnapshot` to the feed-forward, the observer, the admittance, the
constraints and the safety supervisor. Nothing downstream recomputes G, M, the Jacobian
or the tool pose at the same q.
"""

from __future__ import annotations

from dataclasses import dataclass

from leadthrough.validation import FloatArray


@dataclass(frozen=True, eq=False)
class ModelSnapshot:
    """The rigid-body model at one state (SPEC §1 conventions), all arrays fresh.

    Attributes:
        q: Joint readings [rad], (n,).
        qd: Joint velocities [rad/s], (n,).
        gravity: G(q) [Nm], (n,).
        mass: M(q) [kg m²], (n, n), reflected rotor inertias included.
        coriolis_drift: Cᵀ(q, q̇) q̇ [Nm], (n,), the momentum observer's drift term.
        tool_jacobian: Jacobian of the tool centre point (TCP) [m/rad; rad/rad], (6, n):
            rows (v, ω), world axes, v the velocity of the TCP origin.
        tool_pose: Pose of the TCP in the world, 4×4 homogeneous [m].
    """

    q: FloatArray
    qd: FloatArray
    gravity: FloatArray
    mass: FloatArray
    coriolis_drift: FloatArray
    tool_jacobian: FloatArray
    tool_pose: FloatArray

    @property
    def inertia(self) -> FloatArray:
        """Joint inertias m_ii(q), the diagonal of M(q) [kg m²], (n,)."""
        return self.mass.diagonal().copy()

    @property
    def tool_position(self) -> FloatArray:
        """Position of the TCP in the world [m], (3,)."""
        return self.tool_pose[:3, 3].copy()

    @property
    def tool_velocity(self) -> FloatArray:
        """Linear velocity of the TCP, world axes [m/s], (3,)."""
        return self.tool_jacobian[:3] @ self.qd
