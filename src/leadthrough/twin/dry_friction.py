"""A second friction physics for the twin: MuJoCo's own dry-friction constraint.

The default twin friction (:mod:`leadthrough.twin.friction`) is a LuGre torque the
twin computes and applies. This one lets MuJoCo's solver stick and slide the joints:
every physics step the level of the ``frictionloss`` constraint of each degree of
freedom is recomputed from the joint's state, and viscous friction is MuJoCo's joint
``damping`` (integrated implicitly)::

    level(q, q̇) = [τ_C + (τ_S − τ_C) · exp(−(q̇ / v_s)²)] · (1 + a · sin(k q + φ))   [Nm]
    τ_f         = frictionloss(level) + c · q̇                                           [Nm]

Stribeck: the level is ``τ_S`` at rest and decays to Coulomb ``τ_C`` above the Stribeck
velocity ``v_s``. Position dependence: ``±a`` (15 %) sinusoidal in the joint angle with
``k`` [rad/rad] and a phase ``φ`` per joint (drawn by the plant sampler). A joint under
a torque below the level stays put (up to the constraint's softness), above it slides.

The constraint force is MuJoCo's (``efc_force`` of the ``FRICTION_DOF`` rows), not a
torque of ours: the controllers meet a friction they were not written against.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.twin.errors import FrictionParameterError

#: Softness of the dry-friction constraint (MuJoCo ``solref``: time constant [s], ratio;
#: ``solimp``: impedance). A soft friction constraint creeps under a torque below its
#: level at ``v ≈ R τ / b`` (regulariser ``R ∝ (1 − d) / d``, ``b = 2 / time constant``):
#: impedance d = 0.9999 and 4 physics steps keep the creep below ~1e-5 rad/s.
FRICTION_SOLREF = (0.002, 1.0)
FRICTION_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)


@dataclass(frozen=True)
class DryFrictionParameters:
    """Per-joint parameters of the MuJoCo dry friction, arm side; arrays of shape (n,).

    Attributes:
        coulomb: Coulomb level τ_C [Nm], ≥ 0.
        static: Level at rest τ_S [Nm], ≥ coulomb (stiction ratio τ_S / τ_C).
        stribeck_velocity: Stribeck velocity v_s [rad/s], > 0.
        viscous: Viscous coefficient c [Nm s/rad], ≥ 0.
        position_amplitude: Relative amplitude a of the position dependence [–], in [0, 1).
        position_wavenumber: k [rad⁻¹ of joint angle], ≥ 0.
        position_phase: φ [rad].
    """

    coulomb: FloatArray
    static: FloatArray
    stribeck_velocity: FloatArray
    viscous: FloatArray
    position_amplitude: FloatArray
    position_wavenumber: FloatArray
    position_phase: FloatArray

    def __post_init__(self) -> None:
        arrays = {
            f.name: np.atleast_1d(np.asarray(getattr(self, f.name), float)) for f in fields(self)
        }
        try:
            shape = np.broadcast_shapes(*(array.shape for array in arrays.values()))
        except ValueError:
            raise FrictionParameterError("coulomb", "per-joint shapes do not match") from None
        if len(shape) != 1:
            raise FrictionParameterError("coulomb", f"expected shape (n,), got {shape}")
        for name, array in arrays.items():
            array = np.array(np.broadcast_to(array, shape))
            if not np.all(np.isfinite(array)):
                raise FrictionParameterError(name, "must be finite")
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        _require(self.coulomb >= 0.0, "coulomb", "≥ 0", self.coulomb)
        _require(self.static >= self.coulomb, "static", "≥ coulomb", self.static)
        _require(self.stribeck_velocity > 0.0, "stribeck_velocity", "> 0", self.stribeck_velocity)
        _require(self.viscous >= 0.0, "viscous", "≥ 0", self.viscous)
        amplitude = self.position_amplitude
        _require(
            (amplitude >= 0.0) & (amplitude < 1.0), "position_amplitude", "in [0, 1)", amplitude
        )
        _require(self.position_wavenumber >= 0.0, "position_wavenumber", "≥ 0",
                 self.position_wavenumber)  # fmt: skip

    @property
    def n_joints(self) -> int:
        """Number of joints."""
        return int(self.coulomb.shape[0])

    @classmethod
    def from_robot(
        cls,
        robot: RobotDescription,
        *,
        static_ratio: ArrayLike = 1.3,
        stribeck_velocity: ArrayLike = 0.02,
        scale: ArrayLike = 1.0,
        position_amplitude: float = 0.15,
        position_wavenumber: float = 2.0,
        position_phase: ArrayLike = 0.0,
    ) -> DryFrictionParameters:
        """Dry friction grounded in the description's friction table (Coulomb and viscous).

        Args:
            robot: Description whose ``joints[i].friction`` gives τ_C and c.
            static_ratio: τ_S / τ_C [–], scalar or per joint.
            stribeck_velocity: v_s [rad/s], scalar or per joint.
            scale: Multiplies τ_C, τ_S and c [–], scalar or per joint (a model error).
            position_amplitude: a [–] (±15 % by default).
            position_wavenumber: k [1/rad]: 2 gives one period per π rad of joint travel.
            position_phase: φ [rad], scalar or per joint.
        """
        coulomb = np.array([joint.friction.coulomb for joint in robot.joints]) * scale
        viscous = np.array([joint.friction.viscous for joint in robot.joints]) * scale
        return cls(coulomb, np.asarray(static_ratio) * coulomb, stribeck_velocity, viscous,
                   position_amplitude, position_wavenumber, position_phase)  # fmt: skip

    def level(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Dry-friction level [Nm] at joint angles ``q`` [rad] and velocities ``qd`` [rad/s]."""
        v = np.asarray(qd, dtype=float) / self.stribeck_velocity
        stribeck = self.coulomb + (self.static - self.coulomb) * np.exp(-(v * v))
        return stribeck * self._position_factor(q)

    def coulomb_level(self, q: ArrayLike) -> FloatArray:
        """Sliding level, Stribeck's rise gone, at joint angles ``q`` [rad]: τ_C(q) [Nm]."""
        return self.coulomb * self._position_factor(q)

    def _position_factor(self, q: ArrayLike) -> FloatArray:
        """1 + a sin(k q + φ) [–]."""
        angle = self.position_wavenumber * np.asarray(q, dtype=float) + self.position_phase
        return 1.0 + self.position_amplitude * np.sin(angle)


class DryFriction:
    """Sets MuJoCo's ``frictionloss`` and ``damping`` from :class:`DryFrictionParameters`.

    Args:
        params: The friction parameters.
        model: The MuJoCo model whose first n degrees of freedom are the joints.
        data: Its data.
    """

    def __init__(
        self, params: DryFrictionParameters, model: mujoco.MjModel, data: mujoco.MjData
    ) -> None:
        self._params = params
        self._model, self._data = model, data
        n = params.n_joints
        model.dof_damping[:n] = params.viscous
        model.dof_solref[:n] = FRICTION_SOLREF
        model.dof_solimp[:n] = FRICTION_SOLIMP
        self._rows = np.zeros(0, dtype=int)

    @property
    def params(self) -> DryFrictionParameters:
        """The friction parameters."""
        return self._params

    def reset(self) -> None:
        """Set the levels at the current (resting) state."""
        n = self._params.n_joints
        self._model.dof_frictionloss[:n] = self._params.level(self._data.qpos[:n], np.zeros(n))

    def bind(
        self, q: FloatArray, qd: FloatArray, base: FloatArray, out: FloatArray
    ) -> Callable[[], None]:
        """A no-argument step for the simulator's loop: levels updated, ``out = base``.

        Same contract as :meth:`LuGreFriction.bind`: ``out`` (``qfrc_applied``) receives the
        motor and operator torques; friction itself acts through the constraint solver.
        """
        params, losses, n = self._params, self._model.dof_frictionloss, self._params.n_joints

        def step() -> None:
            losses[:n] = params.level(q[:n], qd[:n])
            out[:] = base

        return step

    def torque(self) -> FloatArray:
        """Friction torque the joints felt in the last physics step [Nm], arm side, (n,)."""
        model, data, n = self._model, self._data, self._params.n_joints
        tau = -model.dof_damping[:n] * data.qvel[:n]
        rows = np.flatnonzero(
            data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF
        )
        np.add.at(tau, data.efc_id[rows], data.efc_force[rows])
        return tau


def _require(ok: FloatArray, name: str, rule: str, values: FloatArray) -> None:
    bad = np.flatnonzero(~np.asarray(ok))
    if bad.size:
        j = int(bad[0])
        raise FrictionParameterError(f"{name}[{j}]", f"must be {rule}, got {values[j]:g}")
