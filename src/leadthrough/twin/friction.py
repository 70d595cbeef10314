"""True joint friction of the digital twin: LuGre with Stribeck, viscous and cable terms.

The plant's friction is deliberately richer than the controller's sigmoid model
(SPEC §3, §9; thesis §4.1): it sticks (pre-sliding bristles), breaks away above a
static level, drops along a Stribeck curve to Coulomb, adds viscous friction, and its
Coulomb level depends on the joint position (the cable-twist effect of thesis §4.1.3).

Model (LuGre, Canudas de Wit et al. 1995), per joint, bristle deflection ``z`` [rad]::

    g(v, q)  = τ_C(q) + (τ_S − τ_C) · exp(−(v / v_s)²)          Stribeck curve [Nm]
    τ_C(q)   = τ_C · (1 + β · tanh((q − q_n) / w))                cable twist [Nm]
    ż        = v − σ0 · |v| · z / g(v, q)
    τ_f      = σ0 · z + σ1 · ż + c · v                            friction of SPEC §1 [Nm]

Sign: :meth:`LuGreFriction.torque` returns ``−τ_f``, the torque friction *applies* to
the joint (it opposes the motion), arm side, so the simulator adds it to the joint
torques (``qfrc_applied += friction.torque(q, qd)``). ``τ_f`` itself is the term on the
left of SPEC §1's ``M q̈ + C q̇ + G + τ_f = τ + τ_ext``.

Cable twist: ``tanh`` is smooth, odd and bounded, so ``|τ_C(q) − τ_C| < β τ_C``
everywhere; with ``q_n`` the middle of the range and ``w`` a quarter of it, the ends of
the range see ``τ_C (1 ∓ β tanh 2) = τ_C (1 ∓ 0.964 β)``: the two extremes differ by
``2 tanh(2) β τ_C`` (29 % of τ_C at the default β = 0.15), as the thesis observed
(Fig. 4.6: "significantly different" Coulomb levels at the two ends of a stroke).

Bristle update: over one step ``dt`` with ``v`` and ``q`` frozen, the ``z`` ODE is linear
and is solved exactly: ``z⁺ = z_ss + (z − z_ss) · exp(−σ0 |v| dt / g)`` with
``z_ss = g · sign(v) / σ0``. ``z⁺`` lies between ``z`` and ``z_ss``, so
``|σ0 z| ≤ max g`` for any ``dt``: the update is unconditionally stable. ``ż`` is the
step average ``(z⁺ − z) / dt`` and the returned torque uses ``z⁺``.

Stability of the coupled simulation: the plant integrates this torque *explicitly*
with semi-implicit Euler. In stick the bristle is a spring σ0 with damper σ1 + c on the
joint inertia ``I``; using ``z⁺`` (advanced with the current ``v``) makes the pair
symplectic Euler, whose recursion ``λ² − (2 − a − b) λ + (1 − b)`` is stable iff
``a + 2b < 4`` and ``b < 2``, with ``a = σ0 dt² / I`` and ``b = (σ1 + c) dt / I``.
Hence :func:`stable_bristle_stiffness` (``a = 0.25``, ω dt = 0.5, 13 steps per
bristle period) and :func:`stable_bristle_damping` (ζ = 0.5, capped at ``σ1 dt / I ≤ 1``).
For an arm, ``M(q) ⪰ diag(G_r² J_m)`` (the armature is on the diagonal and the link
inertia is positive semi-definite), so the reflected rotor inertia is a safe per-joint
``I`` for every pose: it is :meth:`TwinFrictionParameters.from_robot`'s default.

Breakaway depends on the loading rate, as in LuGre ("varying break-away force") and
in real joints: a load between τ_C and τ_S applied slowly sticks with deflection
``−(τ_S/σ0) ln(1 − F/τ_S)``, but a step load excites bristle velocities up to about
``F / √(σ0 I)``; above v_s the level g drops toward τ_C and the joint may break away.

At 2 kHz the stability cap holds σ0 below the stiffness of a 1e-5 rad pre-sliding
displacement (the textbook value): with the YuMi defaults τ_S / σ0 is 1.6e-5 to
1.8e-4 rad (wrist joints, I ≈ 0.005 kg m²), the price of explicit coupling.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from functools import partial

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.compiled import kernel
from leadthrough.errors import InputShapeError
from leadthrough.model.description import RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.twin.errors import FrictionParameterError
from leadthrough.validation import real

FloatArray = NDArray[np.float64]

#: Smallest Coulomb level used inside the model [Nm], so that g(v, q) > 0 always.
_MIN_LEVEL = 1e-9


def stable_bristle_stiffness(inertia: ArrayLike, dt: float, margin: float = 0.25) -> FloatArray:
    """Bristle stiffness an explicit semi-implicit Euler plant integrates stably.

    Args:
        inertia: Smallest effective inertia of each joint [kg m²], shape (n,), > 0.
        dt: Physics timestep of the plant [s], > 0.
        margin: ``σ0 dt² / I`` [–]; stability needs < 4 (minus twice the damping
            ratio ``(σ1 + c) dt / I``); 0.25 keeps 13 steps per bristle period.

    Returns:
        σ0 = margin · I / dt² [Nm/rad], shape (n,).
    """
    inertia = _positive("inertia", inertia)
    return margin * inertia / (_positive("dt", dt) ** 2)


def stable_bristle_damping(
    stiffness: ArrayLike,
    inertia: ArrayLike,
    dt: float,
    *,
    damping_ratio: float = 0.5,
    max_step_ratio: float = 1.0,
) -> FloatArray:
    """Bristle damping σ1 for a damping ratio, capped for an explicit plant.

    Args:
        stiffness: Bristle stiffness σ0 [Nm/rad], shape (n,).
        inertia: Smallest effective inertia of each joint [kg m²], shape (n,), > 0.
        dt: Physics timestep of the plant [s], > 0.
        damping_ratio: ζ of the stuck joint's bristle mode [–] (0.5: the classic
            ``σ1 = √(σ0 m)`` choice of Canudas de Wit et al. for unit mass).
        max_step_ratio: Cap on ``σ1 dt / I`` [–]; explicit damping is unstable at 2.

    Returns:
        σ1 = min(2 ζ √(σ0 I), max_step_ratio · I / dt) [Nm s/rad], shape (n,).
    """
    inertia = _positive("inertia", inertia)
    stiffness = np.asarray(stiffness, dtype=float)
    critical = 2.0 * damping_ratio * np.sqrt(stiffness * inertia)
    return np.minimum(critical, max_step_ratio * inertia / _positive("dt", dt))


def smallest_effective_inertia(robot: RobotDescription, samples: int = 64) -> FloatArray:
    """Per joint, the smallest inertia ``1 / (M⁻¹)ᵢᵢ`` over seeded random poses [kg m²].

    It is what joint i feels when all other joints are free; the bristle stiffness of
    the true friction is chosen against it so that the explicit 2 kHz step is stable.
    Never below the reflected rotor inertia ``G_r² J_m``.
    """
    dynamics = Dynamics(robot)
    poses = np.random.default_rng(0).uniform(robot.q_min, robot.q_max, (samples, robot.n_joints))
    inverse_diagonals = np.array([np.diag(np.linalg.inv(dynamics.mass(q))) for q in poses])
    return 1.0 / inverse_diagonals.max(axis=0)


def randomized_friction(
    robot: RobotDescription, rng: np.random.Generator, dt: float = 0.0005
) -> TwinFrictionParameters:
    """True friction drawn around the description's, for tests that nothing is tuned to one set.

    Per joint τ_C and c are scaled by U(0.5, 1.5); for the whole arm the static ratio is
    U(1.1, 1.6), the Stribeck velocity U(0.003, 0.03) rad/s and the cable amplitude U(0, 0.25).
    """
    n = robot.n_joints
    joints = []
    for joint, k_coulomb, k_viscous in zip(robot.joints, rng.uniform(0.5, 1.5, n),
                                           rng.uniform(0.5, 1.5, n), strict=True):  # fmt: skip
        friction = replace(joint.friction, coulomb=joint.friction.coulomb * k_coulomb,
                           viscous=joint.friction.viscous * k_viscous)  # fmt: skip
        joints.append(replace(joint, friction=friction))
    scaled = replace(robot, joints=tuple(joints))
    return TwinFrictionParameters.from_robot(
        scaled,
        static_ratio=rng.uniform(1.1, 1.6),
        stribeck_velocity=rng.uniform(0.003, 0.03),
        cable_amplitude=rng.uniform(0.0, 0.25),
        inertia=smallest_effective_inertia(robot),
        dt=dt,
    )


@dataclass(frozen=True, eq=False)
class TwinFrictionParameters:
    """Per-joint parameters of the twin's LuGre friction, arm side.

    Each field is an array of shape (n,) (a scalar is used for every joint); all are
    read-only after validation.

    Attributes:
        coulomb: Coulomb level τ_C at ``cable_neutral`` [Nm], ≥ 0.
        static: Static (breakaway) level τ_S at ``cable_neutral`` [Nm], ≥ coulomb.
        stribeck_velocity: Stribeck velocity v_s [rad/s], > 0.
        viscous: Viscous coefficient c [Nm s/rad], ≥ 0.
        bristle_stiffness: Bristle stiffness σ0 [Nm/rad], > 0.
        bristle_damping: Bristle damping σ1 [Nm s/rad], ≥ 0.
        cable_amplitude: Relative amplitude β of the position-dependent Coulomb term
            [–], 0 ≤ β < 1.
        cable_neutral: Position q_n where τ_C(q) = τ_C [rad].
        cable_width: Position scale w of the tanh [rad], > 0.
    """

    coulomb: FloatArray
    static: FloatArray
    stribeck_velocity: FloatArray
    viscous: FloatArray
    bristle_stiffness: FloatArray
    bristle_damping: FloatArray
    cable_amplitude: FloatArray
    cable_neutral: FloatArray
    cable_width: FloatArray

    def __post_init__(self) -> None:
        names = [item.name for item in fields(self)]
        arrays = {name: _finite(name, getattr(self, name)) for name in names}
        try:
            shape = np.broadcast_shapes(*(array.shape for array in arrays.values()))
        except ValueError:
            shapes = {name: array.shape for name, array in arrays.items()}
            raise FrictionParameterError("coulomb", f"shapes do not match: {shapes}") from None
        if len(shape) != 1 or shape[0] == 0:
            raise FrictionParameterError("coulomb", f"expected shape (n,), n ≥ 1, got {shape}")
        for name, array in arrays.items():
            array = np.array(np.broadcast_to(array, shape))
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        for name in ("coulomb", "viscous", "bristle_damping", "cable_amplitude"):
            _check_all(name, getattr(self, name), getattr(self, name) >= 0.0, "≥ 0")
        for name in ("stribeck_velocity", "bristle_stiffness", "cable_width"):
            _check_all(name, getattr(self, name), getattr(self, name) > 0.0, "> 0")
        _check_all("cable_amplitude", self.cable_amplitude, self.cable_amplitude < 1.0, "< 1")
        ok = self.static >= self.coulomb
        _check_all("static", self.static, ok, "≥ coulomb", self.coulomb)

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return int(self.coulomb.shape[0])

    def coulomb_level(self, q: ArrayLike) -> FloatArray:
        """Position-dependent Coulomb level τ_C(q) = τ_C (1 + β tanh((q − q_n)/w)) [Nm].

        Args:
            q: Joint positions [rad], shape (..., n).

        Returns:
            τ_C(q) [Nm], shape (..., n); within τ_C (1 ± β).
        """
        shift = (np.asarray(q, dtype=float) - self.cable_neutral) / self.cable_width
        return self.coulomb * (1.0 + self.cable_amplitude * np.tanh(shift))

    @classmethod
    def from_robot(
        cls,
        robot: RobotDescription,
        *,
        static_ratio: float = 1.3,
        stribeck_velocity: float = 0.01,
        cable_amplitude: float = 0.15,
        presliding: float = 1e-5,
        bristle_stiffness: ArrayLike | None = None,
        bristle_damping: ArrayLike | None = None,
        inertia: ArrayLike | None = None,
        dt: float | None = 0.0005,
        damping_ratio: float = 0.5,
        scale: float = 1.0,
    ) -> TwinFrictionParameters:
        """Twin friction grounded in a robot's friction table (thesis Table 4.1 for YuMi).

        Args:
            robot: Description whose ``joints[i].friction`` gives τ_C and c.
            static_ratio: τ_S / τ_C [–], ≥ 1; 1.3 is mid-range of the 1.1–1.5 seen in
                geared robot joints (Armstrong-Hélouvry et al. 1994).
            stribeck_velocity: v_s [rad/s]; 0.01 puts the stiction bump in the band
                where the controller's sigmoid changes sign (B = 2–3 mrad/s, Table 4.1)
                and its compensation is off (q̇₀ = 3 mrad/s, thesis §4.2.2).
            cable_amplitude: β [–], the same for every joint.
            presliding: Pre-sliding displacement at breakaway τ_S / σ0 [rad] that sets
                the default σ0 (before the stability cap).
            bristle_stiffness: σ0 [Nm/rad]; default τ_S / presliding, capped by
                :func:`stable_bristle_stiffness` when ``dt`` is given.
            bristle_damping: σ1 [Nm s/rad]; default :func:`stable_bristle_damping` (ζ =
                ``damping_ratio``, capped when ``dt`` is given).
            inertia: Smallest effective inertia per joint [kg m²]; default the
                reflected rotor inertias ``G_r² J_m``, a lower bound of M(q)'s diagonal.
            dt: Plant physics timestep [s] the defaults must be stable at (2 kHz);
                None derives σ0 and σ1 without the explicit-integration caps.
            damping_ratio: ζ of the bristle mode for the default σ1 [–].
            scale: Multiplies τ_C, τ_S and c [–], ≥ 0: a model-error knob.

        Returns:
            The parameters; the cable term is centred mid-range with w a quarter of the
            range, so τ_C(q) spans τ_C (1 ∓ 0.964 β) from q_min to q_max.

        Raises:
            FrictionParameterError: If an argument is out of range.
        """
        scale = _number("scale", scale, 0.0)
        ratio = _number("static_ratio", static_ratio, 1.0)
        friction = [joint.friction for joint in robot.joints]
        coulomb = scale * np.array([item.coulomb for item in friction])
        static = ratio * coulomb
        inertia_used = robot.reflected_rotor_inertias if inertia is None else inertia
        if inertia is None and dt is not None and np.any(inertia_used <= 0.0):
            j = int(np.flatnonzero(inertia_used <= 0.0)[0])
            reason = "robot has no rotor inertia to bound σ0 and σ1 at dt; pass inertia="
            raise FrictionParameterError(f"inertia[{j}]", reason)
        stiffness = bristle_stiffness
        if stiffness is None:
            level = np.maximum(static, _MIN_LEVEL)
            stiffness = level / _number("presliding", presliding, 0.0, strict=True)
            if dt is not None:
                stiffness = np.minimum(stiffness, stable_bristle_stiffness(inertia_used, dt))
        damping = bristle_damping
        if damping is None:
            if dt is not None:
                damping = stable_bristle_damping(
                    stiffness, inertia_used, dt, damping_ratio=damping_ratio
                )
            else:
                damping = 2.0 * damping_ratio * np.sqrt(stiffness * np.asarray(inertia_used))
        return cls(
            coulomb=coulomb,
            static=static,
            stribeck_velocity=stribeck_velocity,
            viscous=scale * np.array([item.viscous for item in friction]),
            bristle_stiffness=stiffness,
            bristle_damping=damping,
            cable_amplitude=cable_amplitude,
            cable_neutral=0.5 * (robot.q_min + robot.q_max),
            cable_width=0.25 * (robot.q_max - robot.q_min),
        )


@kernel
def _lugre_step(q, v, constants, bristle_torque, base, out):
    """One exact bristle step per joint (see the module docstring), compiled: ~1 µs for 7 joints.

    ``constants`` rows: τ_C, β τ_C, 1/w, q_n/w, τ_S − τ_C, −1/v_s², −σ0 dt, σ1/(σ0 dt), c
    (one argument, not nine: the call itself is what a 2 kHz loop pays for).
    ``bristle_torque`` (σ0 z) is advanced in place; ``out`` receives ``base − τ_f`` [Nm].
    """
    coulomb, cable_gain, inv_width, neutral_scaled, excess = constants[:5]
    neg_inv_vs2, neg_sigma0_dt, rate_gain, viscous = constants[5:]
    for i in range(q.shape[0]):
        level = (coulomb[i] + cable_gain[i] * math.tanh(q[i] * inv_width[i] - neutral_scaled[i])
                 + excess[i] * math.exp(v[i] * v[i] * neg_inv_vs2[i]))  # fmt: skip
        decay = math.expm1(abs(v[i]) * neg_sigma0_dt[i] / level)  # exp(−σ0 |v| dt / g) − 1
        change = (math.copysign(level, v[i]) - bristle_torque[i]) * decay  # −σ0 (z⁺ − z)
        bristle_torque[i] -= change
        out[i] = base[i] + rate_gain[i] * change - bristle_torque[i] - viscous[i] * v[i]


class LuGreFriction:
    """LuGre joint friction with its bristle state, stepped at a fixed ``dt``.

    In the plant's 2 kHz step (MuJoCo ``data``)::

        friction = LuGreFriction(TwinFrictionParameters.from_robot(robot), dt=0.0005)
        data.qfrc_applied[:] = tau_motor + friction.torque(data.qpos, data.qvel)
    """

    def __init__(self, params: TwinFrictionParameters, dt: float) -> None:
        """Set up the model with zero bristle deflection.

        Args:
            params: Friction parameters of the n joints.
            dt: Time advanced by each :meth:`torque` call [s], > 0.
        """
        self._params = params
        self._dt = _number("dt", dt, 0.0, strict=True)
        n = params.n_joints
        self._shape = (n,)
        coulomb = np.maximum(params.coulomb, _MIN_LEVEL)
        self._coulomb = coulomb
        self._cable_gain = coulomb * params.cable_amplitude
        self._inv_width = 1.0 / params.cable_width
        self._neutral_scaled = params.cable_neutral / params.cable_width
        self._excess = params.static - params.coulomb
        self._neg_inv_vs2 = -1.0 / params.stribeck_velocity**2
        self._neg_sigma0_dt = -params.bristle_stiffness * self._dt
        self._rate_gain = params.bristle_damping / (params.bristle_stiffness * self._dt)
        self._viscous = params.viscous.copy()
        self._constants = np.array([
            coulomb, self._cable_gain, self._inv_width, self._neutral_scaled, self._excess,
            self._neg_inv_vs2, self._neg_sigma0_dt, self._rate_gain, self._viscous,
        ])  # fmt: skip
        self._bristle_torque = np.zeros(n)  # σ0 z [Nm]
        self._zeros = np.zeros(n)

    @property
    def params(self) -> TwinFrictionParameters:
        """The friction parameters."""
        return self._params

    @property
    def dt(self) -> float:
        """Time advanced by each :meth:`torque` call [s]."""
        return self._dt

    @property
    def bristle_state(self) -> FloatArray:
        """Bristle deflection z [rad], shape (n,), a read-only copy."""
        z = self._bristle_torque / self._params.bristle_stiffness
        z.setflags(write=False)
        return z

    def reset(self) -> None:
        """Relax the bristles (z = 0)."""
        self._bristle_torque[:] = 0.0

    def torque(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Advance the bristles by ``dt`` and return the friction torque on the joints.

        Args:
            q: Joint positions [rad], shape (n,).
            qd: Joint velocities [rad/s], shape (n,), held over the step.

        Returns:
            −τ_f = −(σ0 z⁺ + σ1 ż + c q̇), the torque friction applies [Nm], arm side,
            shape (n,): add it to the joint torques.
        """
        q = np.asarray(q, dtype=float)
        v = np.asarray(qd, dtype=float)
        if q.shape != self._shape or v.shape != self._shape:
            bad, name = (q, "q") if q.shape != self._shape else (v, "qd")
            raise InputShapeError(name, self._shape, bad.shape)
        out = np.empty(self._shape)
        self.add_torque(q, v, self._zeros, out)
        return out

    def add_torque(self, q: FloatArray, qd: FloatArray, base: FloatArray, out: FloatArray) -> None:
        """Fast path of :meth:`torque`: ``out = base + friction torque``, bristles advanced.

        No checks: all arguments are float64 arrays of shape (n,); ``out`` may be a MuJoCo
        buffer such as ``qfrc_applied``.
        """
        self.bind(q, qd, base, out)()

    def bind(
        self, q: FloatArray, qd: FloatArray, base: FloatArray, out: FloatArray
    ) -> Callable[[], None]:
        """A call-with-no-arguments :meth:`add_torque` on these (persistent) buffers.

        For the simulator's 2 kHz loop, where ``q``, ``qd`` (MuJoCo's state views), ``base``
        and ``out`` are the same arrays every step: it saves the argument handling.
        """
        return partial(_lugre_step, q, qd, self._constants, self._bristle_torque, base, out)

    def steady_state(self, qd: ArrayLike, q: ArrayLike) -> FloatArray:
        """Friction torque applied at constant sliding velocity: −(g(q̇, q) sign(q̇) + c q̇).

        Args:
            qd: Joint velocities [rad/s], shape (..., n).
            q: Joint positions [rad], broadcastable to ``qd``.

        Returns:
            The steady-state torque friction applies [Nm], shape of ``qd`` broadcast
            with ``q``; zero at q̇ = 0.
        """
        p = self._params
        v = np.asarray(qd, dtype=float)
        level = p.coulomb_level(q) + (p.static - p.coulomb) * np.exp(
            -((v / p.stribeck_velocity) ** 2)
        )
        return -(np.sign(v) * level + p.viscous * v)


def _finite(name: str, value: ArrayLike) -> FloatArray:
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise FrictionParameterError(name, f"expected numbers, got {value!r}") from None
    if array.ndim > 1:
        raise FrictionParameterError(name, f"expected shape (n,) or a scalar, got {array.shape}")
    bad = np.flatnonzero(~np.isfinite(np.atleast_1d(array)))
    if bad.size:
        raise FrictionParameterError(f"{name}[{bad[0]}]", "must be finite")
    return array


def _check_all(
    name: str, values: FloatArray, ok: FloatArray, rule: str, bound: FloatArray | None = None
) -> None:
    bad = np.flatnonzero(~ok)
    if bad.size:
        j = int(bad[0])
        limit = "" if bound is None else f" ({bound[j]:g})"
        raise FrictionParameterError(f"{name}[{j}]", f"must be {rule}{limit}, got {values[j]:g}")


def _number(name: str, value: object, minimum: float, *, strict: bool = False) -> float:
    return real(name, value, minimum=minimum, strict=strict, error=FrictionParameterError)


def _positive(name: str, value: ArrayLike) -> FloatArray:
    array = np.asarray(value, dtype=float)
    bad = np.flatnonzero(~(np.atleast_1d(array) > 0.0) | ~np.isfinite(np.atleast_1d(array)))
    if bad.size:
        where = f"{name}[{bad[0]}]" if array.ndim else name
        got = np.atleast_1d(array)[bad[0]]
        raise FrictionParameterError(where, f"must be finite and > 0, got {got:g}")
    return array
