"""The controller's joint friction: a velocity-dependent Gaussian (thesis §4.1, SPEC §3).

Per joint, two sigmoids bound the friction torque (thesis eqs. 4.2–4.3), with
``τ_C,max = +τ_C(q)`` and ``τ_C,min = −τ_C(q)``::

    τ_f,max(q̇) = −τ_C + 2 τ_C · s(A (q̇ + B)) + c q̇          s(x) = 1 / (1 + e^−x)
    τ_f,min(q̇) = −τ_C + 2 τ_C · s(A (q̇ − B)) + c q̇

Their average is the mean friction (4.4) and their half difference the Coulomb
uncertainty (4.5); a constant term ``σ`` adds measurement noise and irregularities::

    mean(q̇) = (τ_f,max + τ_f,min) / 2 = τ_C (s(A(q̇+B)) + s(A(q̇−B)) − 1) + c q̇
    v_C(q̇)  = (τ_f,max − τ_f,min) / 2 = τ_C (s(A(q̇+B)) − s(A(q̇−B)))
    std(q̇)  = sqrt(v_C² + σ²)

so that at rest the friction is anywhere within ±τ_C (mean 0, large std) and once
moving it is known to within ``σ``. Beyond the thesis, two things.

Real joints' friction is higher than the Coulomb level at low sliding speeds (stiction
and the Stribeck curve: up to ``(1 + e) τ_C`` below a Stribeck velocity ``v_s``), which
the sigmoids do not describe. Asked for (``stiction_excess`` e > 0; 0 by default, the
thesis' band), the model's band holds it once the joint slides, its mean kept::

    x(q̇) = ½ e · exp(−(q̇ / v_s)²) · (1 − v_C⁰(q̇) / τ_C)        (v_C⁰ the sigmoids' own)
    τ_f,max += x τ_C,    τ_f,min −= x τ_C,    so  v_C = v_C⁰ + x τ_C,  mean unchanged

``1 − v_C⁰ / τ_C`` is 0 at rest (where the thesis' band stands) and 1 once sliding.
The mean stays the thesis': a model that assumed the excess would overstate the friction
of a joint that has less, and a released arm would read that as a push along its
motion; for the same reason the active law never reads the excess (it is drag, never a
push along the motion: ``ActiveLaw.use_friction``). The friction then lies between the
mean and ``e`` above it, which the ±2 std band (std = v_C, as the thesis takes it) reaches
with half of ``e``.

The Coulomb level may depend on the joint position (the cable effect of §4.1.3),
smoothly, with two parameters::

    τ_C(q) = τ_C · (1 + k₁ u + k₂ u²),   u = clip((q − q_mid) / q_half, −1, 1)

``q_mid ± q_half`` is the span the dependence describes (the joint range, or the stroke an
identification saw); beyond it the level holds its end value instead of extrapolating the
quadratic, so a level positive over u ∈ [−1, 1] (checked on construction) is positive at
every joint position.

Friction here is the ``τ_f`` of SPEC §1 (``M q̈ + C q̇ + G + τ_f = τ + τ_ext``): it has
the sign of the motion. Everything is vectorised: arrays broadcast as (..., n).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w
from numpy.typing import ArrayLike, NDArray

from leadthrough.compiled import kernel
from leadthrough.errors import InputShapeError, ParameterError
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.validation import real_array

_PARAMETERS = ("coulomb", "slope", "half_width", "viscous", "noise_std")
_POSITION = ("position_linear", "position_quadratic", "position_mid", "position_half_range")
_ERROR = ("relative_error",)
_STRIBECK = ("stiction_excess", "stribeck_velocity")
#: Relative error of the Coulomb levels of a model that does not say (Table 4.1 was tuned by
#: hand: the project's robustness target, friction off by ±20 %).
DEFAULT_RELATIVE_ERROR = 0.2
#: Stiction excess of a model that does not say [–]: none, the thesis' band. Geared joints'
#: static friction is 1.1–1.5× their Coulomb level (Armstrong-Hélouvry 1994; the plant
#: family of issue 13), which 0.5 holds: on the guiding benchmark that band covers the
#: slow slips of a press (68 → 83 % of the moving samples) and costs 0.01 (the YuMi) to 0.04
#: (the UR10e) of passive's effort through the estimate (docs/active_mode_log.md, *A band
#: that holds the Stribeck range*), so it is asked for, not the default.
DEFAULT_STICTION_EXCESS = 0.0
#: Stribeck velocity of a model that does not say [rad/s]: the top of the plant family's
#: 0.005–0.03 rad/s (the issue's plant 0.02).
DEFAULT_STRIBECK_VELOCITY = 0.03
#: Largest q̇ (in values) whose sigmoid terms are remembered: one sample of any arm.
_REMEMBERED_SIZE = 64
#: Speeds beyond this many Stribeck velocities see the bump held at its value there.
_BUMP_END = 20.0
#: Default of the optional fields: ``__post_init__`` fills in an (n,) array.
_FILLED_IN: Any = None


def sigmoid(x: FloatArray) -> FloatArray:
    """The logistic function 1 / (1 + e^−x), computed without overflow."""
    return 0.5 * (1.0 + np.tanh(0.5 * x))


#: Column names of :meth:`FrictionModel.parameter_cells` (the thesis' symbols, with units).
PARAMETER_COLUMNS = ("τ_C [Nm]", "c [Nm s/rad]", "A [s/rad]", "B [rad/s]", "σ [Nm]", "k₁", "k₂")


@dataclass(frozen=True, eq=False)
class FrictionModel:
    """Gaussian joint friction of n joints; every attribute is an (n,) array.

    Attributes:
        coulomb: Coulomb level τ_C at ``position_mid`` [Nm], ≥ 0.
        slope: Sigmoid slope A [s/rad], > 0.
        half_width: Sigmoid half-width B [rad/s], ≥ 0.
        viscous: Viscous coefficient c [Nm s/rad], ≥ 0.
        noise_std: Velocity-independent standard deviation σ [Nm], ≥ 0.
        position_linear: k₁ of the position-dependent Coulomb level [–].
        position_quadratic: k₂ of the position-dependent Coulomb level [–].
        position_mid: Joint reading where u = 0 [rad].
        position_half_range: Travel from ``position_mid`` to an end of the span the
            position dependence describes, u = ±1 [rad], > 0; beyond the span the level
            holds its end value.
        relative_error: How far the true Coulomb level may be from this model's, as a
            fraction [–] (0.2 unless an identification measured it along the travel,
            :mod:`leadthrough.friction.along_travel`); the active law's friction margin,
            the compensation's ceiling and the observer's band are sized with it.
        stiction_excess: e, how far above τ_C(q) the friction of a joint sliding slower
            than ``stribeck_velocity`` may be, as a fraction of it [–], ≥ 0 (it widens the
            band, not the mean; 0: the thesis' model).
        stribeck_velocity: v_s, the speed over which that excess fades [rad/s], > 0.
        identified: Per joint, whether an identification measured its friction on this
            arm (``leadthrough identify`` sets it: a joint it did not fit keeps its prior's
            values, a data sheet's); None: not stated, as in files written before it was
            saved. ``LeadThrough`` counts a joint's level as measured where it is True, and
            on every joint of a model given to it that does not state it.
    """

    coulomb: FloatArray
    slope: FloatArray
    half_width: FloatArray
    viscous: FloatArray
    noise_std: FloatArray
    position_linear: FloatArray = _FILLED_IN
    position_quadratic: FloatArray = _FILLED_IN
    position_mid: FloatArray = _FILLED_IN
    position_half_range: FloatArray = _FILLED_IN
    relative_error: FloatArray = _FILLED_IN
    stiction_excess: FloatArray = _FILLED_IN
    stribeck_velocity: FloatArray = _FILLED_IN
    identified: NDArray[np.bool_] | None = None

    def __post_init__(self) -> None:
        given = {name: getattr(self, name)
                 for name in _PARAMETERS + _POSITION + _ERROR + _STRIBECK}  # fmt: skip
        lengths = [np.size(value) for value in given.values() if value is not None]
        n = max(set(lengths), key=lengths.count)  # the length most fields agree on
        defaults = {"position_linear": 0.0, "position_quadratic": 0.0, "position_mid": 0.0,
                    "position_half_range": 1.0, "relative_error": DEFAULT_RELATIVE_ERROR,
                    "stiction_excess": DEFAULT_STICTION_EXCESS,
                    "stribeck_velocity": DEFAULT_STRIBECK_VELOCITY}  # fmt: skip
        for name, value in given.items():
            if value is None:
                value = np.full(n, defaults[name])
            if np.shape(value) == (n,) and np.asarray(value).dtype.kind in "fiu":
                _require(name, np.isfinite(np.asarray(value, dtype=float)), "finite")
            object.__setattr__(self, name, real_array(name, value, (n,), error=ParameterError))
        for name in ("coulomb", "half_width", "viscous", "noise_std", "relative_error",
                     "stiction_excess"):  # fmt: skip
            _require(name, getattr(self, name) >= 0.0, "≥ 0")
        _require("slope", self.slope > 0.0, "> 0")
        _require("stribeck_velocity", self.stribeck_velocity > 0.0, "> 0")
        _require("position_half_range", self.position_half_range > 0.0, "> 0")
        _require("position_linear", level_stays_positive(self.position_linear,
                 self.position_quadratic), "such that τ_C(q) > 0 over the whole range")  # fmt: skip
        if self.identified is not None:
            flags = np.asarray(self.identified)
            if flags.shape != (n,) or flags.dtype != np.bool_:
                raise ParameterError("identified", f"must be {n} booleans, one per joint, "
                                     f"got {self.identified!r}")  # fmt: skip
            object.__setattr__(self, "identified", flags.copy())

    @cached_property
    def _half_slope(self) -> FloatArray:
        """A / 2 [s/rad], (n,)."""
        return 0.5 * self.slope

    @cached_property
    def _half_slope_width(self) -> FloatArray:
        """A B / 2 [–], (n,)."""
        return 0.5 * self.slope * self.half_width

    @cached_property
    def _position_dependent(self) -> bool:
        return self.has_position_dependence

    @cached_property
    def _inverse_stribeck(self) -> FloatArray:
        """1 / v_s [s/rad], (n,)."""
        return 1.0 / self.stribeck_velocity

    @cached_property
    def _half_excess(self) -> FloatArray:
        """½ e [–], (n,)."""
        return 0.5 * self.stiction_excess

    @cached_property
    def _has_excess(self) -> bool:
        """Whether any joint has a stiction excess (else the thesis' pair, as it is)."""
        return bool(np.any(self.stiction_excess))

    @property
    def level_std(self) -> FloatArray:
        """Standard deviation of the Coulomb levels' relative error [–], (n,).

        ``relative_error`` bounds the error: the true level lies anywhere within ±that
        fraction of this model's. A level spread evenly over ±a has the std a / √3, which
        is what a ±2 std band must cover (with ``relative_error`` as the std it covered
        99.7 % of the moving samples of ``benchmarks/guiding_quality.py``: honest, but
        wider than an error band should be).
        """
        return self.relative_error / np.sqrt(3.0)

    def without_stiction_excess(self) -> FrictionModel:
        """This model with the thesis' band: no stiction excess (``stiction_excess`` 0)."""
        if not self._has_excess:
            return self
        return replace(self, stiction_excess=np.zeros(self.n_joints))

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return self.coulomb.shape[0]

    @property
    def has_position_dependence(self) -> bool:
        """Whether the Coulomb level depends on the joint position."""
        return bool(np.any(self.position_linear) or np.any(self.position_quadratic))

    @classmethod
    def from_robot(cls, robot: RobotDescription) -> FrictionModel:
        """The friction parameters of a description (thesis Table 4.1 for the YuMi)."""
        values = {name: np.array([getattr(joint.friction, name) for joint in robot.joints])
                  for name in _PARAMETERS}  # fmt: skip
        return cls(**values)

    def coulomb_level(self, q: ArrayLike | None = None) -> FloatArray:
        """Coulomb level τ_C(q) [Nm], (..., n); ``q=None`` gives the mid-range level."""
        if q is None or (not self._position_dependent and np.ndim(q) <= 1):
            return self.coulomb
        if not self._position_dependent:  # a batch of poses: one row each, like the others
            return np.broadcast_to(self.coulomb, np.shape(q)).copy()
        u = (np.asarray(q, dtype=float) - self.position_mid) / self.position_half_range
        u = np.clip(u, -1.0, 1.0)  # hold the end values beyond the span: never extrapolate
        return self.coulomb * (1.0 + self.position_linear * u + self.position_quadratic * u * u)

    def sigmoid_terms(
        self, qd: ArrayLike, q: ArrayLike | None
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """τ_C(q), c q̇ and tanh(A (q̇ ± B) / 2) ± x(q̇), the terms of every output below.

        Since 2 s(x) − 1 = tanh(x/2), the sigmoid pair, mean and uncertainty are sums and
        differences of the two tanh terms: one evaluation serves them all. The stiction
        excess x (module docstring) widens the pair without moving its mean.

        Raises:
            InputShapeError: ``qd`` or ``q`` has a last axis of neither one value per
                joint nor 1 (NumPy's broadcasting: every joint at that value; a (k, 1)
                column gives the (k, n) table of every joint at each of k velocities).
        """
        qd = np.asarray(qd, dtype=float)
        self._check_joint_axis("qd", qd)
        if q is not None:
            self._check_joint_axis("q", np.asarray(q))
        small = qd.size <= _REMEMBERED_SIZE  # one control period's q̇: remember the terms
        if small:
            shape_q = None if q is None else (np.shape(q), np.asarray(q, float).tobytes())
            key = (qd.shape, qd.tobytes(), shape_q)
            last = self._last[0]  # one read: another thread may replace it, not tear it
            if last is not None and last[0] == key:
                return last[1]  # type: ignore[no-any-return]
        centre = self._half_slope * qd
        upper = np.tanh(centre + self._half_slope_width)
        lower = np.tanh(centre - self._half_slope_width)
        if self._has_excess:
            # beyond 20 v_s the bump is below 1e-173: held there, it neither under- nor
            # overflows
            ratio = np.minimum(np.abs(qd) * self._inverse_stribeck, _BUMP_END)
            excess = self._half_excess * np.exp(-ratio * ratio)
            excess = excess * (1.0 + 0.5 * (lower - upper))  # 0 at rest, whole once sliding
            upper, lower = upper + excess, lower - excess
        terms = self.coulomb_level(q), self.viscous * qd, upper, lower
        if small:
            self._last[0] = (key, terms)
        return terms

    def _check_joint_axis(self, name: str, value: NDArray[Any]) -> None:
        """Raise unless ``value``'s last axis is one value per joint, or 1, or absent."""
        n = self.coulomb.shape[0]
        if value.ndim and value.shape[-1] not in (n, 1):
            raise InputShapeError(f"{name} (one value per joint on the last axis)", (n,),
                                  value.shape)  # fmt: skip

    def terms_into(self, qd: FloatArray, q: FloatArray, out: FloatArray) -> FloatArray:
        """:meth:`sigmoid_terms` of one sample, written into ``out`` in one compiled pass.

        The control period's form: no arrays allocated, nothing remembered.

        Args:
            qd: Joint velocities [rad/s], (n,) floats.
            q: Joint positions [rad], (n,) floats.
            out: (4, n) floats, written with the rows τ_C(q), c q̇, tanh(A (q̇ + B) / 2)
                + x(q̇) and tanh(A (q̇ − B) / 2) − x(q̇).

        Returns:
            ``out``.
        """
        _sigmoid_terms(qd, q, self._term_rows, self._position_dependent, out)
        return out

    @cached_property
    def _term_rows(self) -> FloatArray:
        """The per-joint constants of :func:`_sigmoid_terms`, (10, n)."""
        return np.array([self.coulomb, self.position_linear, self.position_quadratic,
                         self.position_mid, self.position_half_range, self._half_slope,
                         self._half_slope_width, self.viscous, self._half_excess,
                         self._inverse_stribeck])  # fmt: skip

    @cached_property
    def _last(self) -> list[tuple | None]:
        """The latest (key, terms) of :meth:`sigmoid_terms`, in a one-element list.

        A control period asks for the mean, the std and the uncertainty at the same
        (q̇, q): the observer, then the controller.
        """
        return [None]

    def bounds(self, qd: ArrayLike, q: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """The sigmoid pair (τ_f,max, τ_f,min) of eqs. (4.2)–(4.3) [Nm], each (..., n)."""
        level, viscous, upper, lower = self.sigmoid_terms(qd, q)
        return level * upper + viscous, level * lower + viscous

    def mean(self, qd: ArrayLike, q: ArrayLike | None = None) -> FloatArray:
        """Mean friction torque, eq. (4.4) [Nm], (..., n), with the sign of q̇."""
        level, viscous, upper, lower = self.sigmoid_terms(qd, q)
        return 0.5 * level * (upper + lower) + viscous

    def coulomb_uncertainty(self, qd: ArrayLike, q: ArrayLike | None = None) -> FloatArray:
        """Coulomb uncertainty v_C, eq. (4.5) [Nm], (..., n): ≈ τ_C at rest, → 0 moving."""
        level, _, upper, lower = self.sigmoid_terms(qd, q)
        return 0.5 * level * (upper - lower)

    def std(self, qd: ArrayLike, q: ArrayLike | None = None) -> FloatArray:
        """Standard deviation of the friction torque, sqrt(v_C² + σ²) [Nm], (..., n)."""
        return np.hypot(self.coulomb_uncertainty(qd, q), self.noise_std)

    def mean_and_std(
        self, qd: ArrayLike, q: ArrayLike | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """:meth:`mean` and :meth:`std` in one evaluation (the observer's hot path)."""
        level, viscous, upper, lower = self.sigmoid_terms(qd, q)
        half_level = 0.5 * level
        return half_level * (upper + lower) + viscous, np.hypot(half_level * (upper - lower),
                                                                self.noise_std)  # fmt: skip

    def parameter_cells(self, joint: int) -> list[str]:
        """Joint ``joint``'s parameters as text, in the order of :data:`PARAMETER_COLUMNS`."""
        j = joint
        return [f"{self.coulomb[j]:.4f}", f"{self.viscous[j]:.4f}", f"{self.slope[j]:.0f}",
                f"{self.half_width[j]:.2e}", f"{self.noise_std[j]:.4f}",
                f"{self.position_linear[j]:.3f}", f"{self.position_quadratic[j]:.3f}"]  # fmt: skip

    def to_dict(self) -> dict[str, list[float] | list[bool]]:
        """Plain-data form (lists per parameter) for TOML; ``identified`` where stated."""
        names = _PARAMETERS + _ERROR + _STRIBECK + (_POSITION if self.has_position_dependence
                                                    else ())  # fmt: skip
        plain: dict[str, list[float] | list[bool]] = {name: getattr(self, name).tolist()
                                                      for name in names}  # fmt: skip
        if self.identified is not None:
            plain["identified"] = self.identified.tolist()
        return plain

    def save(self, path: str | Path) -> None:
        """Write the parameters to a TOML file (a ``[friction]`` table of per-joint lists)."""
        Path(path).write_text(tomli_w.dumps({"friction": self.to_dict()}), encoding="utf-8")

    @classmethod
    def load(cls, path: str | Path) -> FrictionModel:
        """Read parameters written by :meth:`save`; errors name the file and the field."""
        import tomllib

        from leadthrough.errors import RobotDescriptionError

        try:
            table = tomllib.loads(Path(path).read_text(encoding="utf-8"))["friction"]
            known = {field.name for field in fields(cls)}
            unknown = sorted(set(table) - known)
            if unknown:
                raise ParameterError(unknown[0], "unknown key")
            return cls(**table)
        except (OSError, UnicodeDecodeError) as error:
            raise RobotDescriptionError(str(path), "", f"cannot read: {error}") from None
        except (tomllib.TOMLDecodeError, KeyError, TypeError) as error:
            raise RobotDescriptionError(str(path), "friction", f"malformed: {error}") from None
        except ParameterError as error:
            raise RobotDescriptionError(str(path), f"friction.{error.parameter}",
                                        error.reason) from None  # fmt: skip


@kernel
def _sigmoid_terms(qd, q, rows, position_dependent, out):  # fmt: skip
    """:meth:`FrictionModel.sigmoid_terms` of one sample into ``out`` (4, n), compiled.

    The same arithmetic, in the same order, as the NumPy code (the level clipped to the
    span as ``np.clip``, NaN passing through; the stiction excess after the pair); ``rows`` are
    :attr:`FrictionModel._term_rows`.
    """
    for i in range(qd.shape[0]):
        level = rows[0, i]
        if position_dependent:
            u = (q[i] - rows[3, i]) / rows[4, i]
            u = -1.0 if u < -1.0 else (1.0 if u > 1.0 else u)
            level = level * (1.0 + rows[1, i] * u + rows[2, i] * u * u)
        centre = rows[5, i] * qd[i]
        upper = math.tanh(centre + rows[6, i])
        lower = math.tanh(centre - rows[6, i])
        if rows[8, i] != 0.0:  # the stiction excess (none: the thesis' pair as it is)
            ratio = abs(qd[i]) * rows[9, i]
            ratio = ratio if ratio < _BUMP_END or ratio != ratio else _BUMP_END  # np.minimum
            excess = rows[8, i] * math.exp(-ratio * ratio) * (1.0 + 0.5 * (lower - upper))
            upper, lower = upper + excess, lower - excess
        out[0, i] = level
        out[1, i] = rows[7, i] * qd[i]
        out[2, i] = upper
        out[3, i] = lower


def level_stays_positive(linear: ArrayLike, quadratic: ArrayLike) -> NDArray[np.bool_]:
    """Whether 1 + k₁ u + k₂ u² > 0 for all u in [−1, 1], per joint (so τ_C(q) > 0 for all q)."""
    linear, quadratic = np.asarray(linear, dtype=float), np.asarray(quadratic, dtype=float)
    vertex = np.clip(-linear / np.where(quadratic == 0.0, np.inf, 2.0 * quadratic), -1.0, 1.0)
    candidates = np.stack([-np.ones_like(linear), np.ones_like(linear), vertex])
    return np.all(1.0 + linear * candidates + quadratic * candidates**2 > 0.0, axis=0)


def _require(name: str, ok: NDArray[np.bool_], rule: str) -> None:
    bad = np.flatnonzero(~ok)
    if bad.size:
        raise ParameterError(f"{name}[{bad[0]}]", f"must be {rule}")
