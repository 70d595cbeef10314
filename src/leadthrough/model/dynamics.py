"""Rigid-body dynamics of a described arm, on Pinocchio.

The equation of motion of the whole project (SPEC §1), all torques arm side [Nm]:

    M(q) q̈ + C(q, q̇) q̇ + G(q) + τ_f(q, q̇) = τ + τ_ext

``M`` includes the reflected rotor inertia ``G_r² J_m`` on its diagonal and ``C`` is
the Christoffel factorisation, so that ``Ṁ = C + Cᵀ`` and the generalized momentum
``p = M q̇`` obeys ``ṗ = τ + Cᵀ q̇ − G − τ_f + τ_ext``. Friction is not part of this
class (see the friction model).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from leadthrough.compiled import kernel
from leadthrough.errors import InputShapeError
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.pinocchio_model import FLANGE_FRAME, TCP_FRAME, build_model
from leadthrough.model.snapshot import ModelSnapshot

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class Dynamics:
    """Gravity, mass matrix, Coriolis, momentum, flange and tool kinematics of one arm.

    Built once from a description; each call costs a few microseconds. Not
    thread-safe: it owns one Pinocchio ``Data`` (make one ``Dynamics`` per thread).
    Every method returns a fresh array the caller may keep.

    Args:
        robot: The arm to model.
    """

    def __init__(self, robot: RobotDescription) -> None:
        self.robot = robot
        self.model = build_model(robot)
        self.data = self.model.createData()
        self.n = robot.n_joints
        self._flange = self.model.getFrameId(FLANGE_FRAME)
        self._tcp = self.model.getFrameId(TCP_FRAME)
        self._lower_triangle = np.tril(np.ones((self.n, self.n), dtype=bool), -1)

    def snapshot(self, q: ArrayLike, qd: ArrayLike) -> ModelSnapshot:
        """Everything a control period needs of the model at (q [rad], q̇ [rad/s]), once.

        G(q), M(q), Cᵀ(q, q̇) q̇, the TCP Jacobian and pose (see :class:`ModelSnapshot`).
        """
        q, qd = self._vector(q, "q").copy(), self._vector(qd, "qd").copy()
        model, data, n = self.model, self.data, self.n
        gravity = pin.computeGeneralizedGravity(model, data, q).copy()
        upper = pin.crba(model, data, q)  # M's upper triangle (Pinocchio's own array)
        mass, drift = np.empty((n, n)), np.empty(n)
        _mass_and_drift(upper, pin.computeCoriolisMatrix(model, data, q, qd), qd, mass, drift)
        jacobian = pin.computeFrameJacobian(model, data, q, self._tcp, _WORLD_ALIGNED)
        pose = pin.updateFramePlacement(model, data, self._tcp).homogeneous  # a new array
        return ModelSnapshot(q, qd, gravity, mass, drift, jacobian, pose)

    def gravity(self, q: ArrayLike) -> FloatArray:
        """Gravity torque G(q) [Nm], shape (n,): the torque that holds the arm still."""
        return pin.computeGeneralizedGravity(self.model, self.data, self._vector(q, "q")).copy()

    def mass(self, q: ArrayLike) -> FloatArray:
        """Joint-space inertia matrix M(q) [kg m²], (n, n), rotor inertias included."""
        return self._mass(self._vector(q, "q"))

    def _mass(self, q: FloatArray) -> FloatArray:
        mass = pin.crba(self.model, self.data, q).copy()  # its upper triangle is M's
        np.copyto(mass, mass.T, where=self._lower_triangle)
        return mass

    def coriolis(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Coriolis/centrifugal matrix C(q, q̇) [kg m²/s], (n, n), Christoffel form."""
        q, qd = self._vector(q, "q"), self._vector(qd, "qd")
        return pin.computeCoriolisMatrix(self.model, self.data, q, qd).copy()

    def coriolis_transpose_times_velocity(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """The term Cᵀ(q, q̇) q̇ [Nm] of the momentum dynamics, shape (n,)."""
        q, qd = self._vector(q, "q"), self._vector(qd, "qd")
        return pin.computeCoriolisMatrix(self.model, self.data, q, qd).T @ qd

    def momentum(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Generalized momentum p = M(q) q̇ [kg m²/s], shape (n,)."""
        return self.mass(q) @ self._vector(qd, "qd")

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Rigid-body torque M q̈ + C q̇ + G [Nm] (no friction), shape (n,)."""
        q, qd, qdd = self._vector(q, "q"), self._vector(qd, "qd"), self._vector(qdd, "qdd")
        return pin.rnea(self.model, self.data, q, qd, qdd).copy()

    def potential_energy(self, q: ArrayLike) -> float:
        """Gravitational potential energy V(q) [J], zero at the world origin height."""
        return float(pin.computePotentialEnergy(self.model, self.data, self._vector(q, "q")))

    def jacobian(self, q: ArrayLike) -> FloatArray:
        """Flange Jacobian [m/rad; rad/rad], (6, n): rows (v, ω) in world axes.

        ``v`` is the velocity of the flange origin and ``ω`` the angular velocity, both
        in world coordinates, so a flange wrench F = (f, m) in world axes gives
        ``τ_ext = Jᵀ F``.
        """
        q = self._vector(q, "q")
        jacobian = pin.computeFrameJacobian(self.model, self.data, q, self._flange, _WORLD_ALIGNED)
        return np.reshape(jacobian, (6, self.model.nv))  # one joint: Pinocchio gives (6,)

    def pose(self, q: ArrayLike) -> FloatArray:
        """Flange pose in the world frame as a 4×4 homogeneous matrix [m]."""
        q = self._vector(q, "q")
        return pin.updateFramePlacement(
            self.model, self._forward_kinematics(q), self._flange
        ).homogeneous.copy()

    def tool_jacobian(self, q: ArrayLike) -> FloatArray:
        """Jacobian of the tool centre point (``robot.tcp``), (6, n), as :meth:`jacobian`."""
        q = self._vector(q, "q")
        return pin.computeFrameJacobian(self.model, self.data, q, self._tcp, _WORLD_ALIGNED)

    def tool_pose(self, q: ArrayLike) -> FloatArray:
        """Pose of the tool centre point in the world frame, 4×4 homogeneous [m]."""
        q = self._vector(q, "q")
        return pin.updateFramePlacement(
            self.model, self._forward_kinematics(q), self._tcp
        ).homogeneous.copy()

    def _forward_kinematics(self, q: FloatArray) -> pin.Data:
        pin.forwardKinematics(self.model, self.data, q)
        return self.data

    def _vector(self, value: ArrayLike, name: str) -> FloatArray:
        array = np.asarray(value, dtype=float)
        if array.shape != (self.n,):
            raise InputShapeError(name, (self.n,), array.shape)
        return array


@kernel
def _mass_and_drift(upper, coriolis, qd, mass, drift):  # fmt: skip
    """M(q) from its upper triangle and Cᵀ(q, q̇) q̇ [Nm], into ``mass`` and ``drift``.

    What ``Dynamics.mass`` (the upper triangle mirrored) and
    ``coriolis_transpose_times_velocity`` (``C.T @ q̇``) compute, in one compiled pass
    over Pinocchio's arrays.
    """
    n = qd.shape[0]
    for i in range(n):
        total = 0.0
        for j in range(n):
            mass[i, j] = upper[i, j] if j >= i else upper[j, i]
            total += coriolis[j, i] * qd[j]
        drift[i] = total
