"""The joints' estimates read together: the operator pushes with a force at the tool.

Each joint's observer sees only its own joint. Where a joint stands still, friction may
hold any push below breakaway unseen, and its estimate says so with a std as wide as the
stiction band (the blind spot at rest). But an operator who guides the arm by its tool
applies one force ``f`` there, and it loads every joint at once, ``τ = J_vᵀ f``
(``J_v`` the TCP's translational Jacobian, world axes): the joints that slide read
their share of ``f`` well, and with it the share of the joints that stick. The model is

    τ = J_vᵀ f + ε,     f ~ N(0, σ_f² I),     ε ~ N(0, diag(σ_ε²)),
    τ̂ = τ + n,          n ~ N(0, diag(s²))      (s: each joint's own std)

with ``ε`` what a force at the tool does not explain (a moment of the hand, a push on a
link, the model's errors), of size ``σ_ε,i = spread · τ_C,i`` on each joint. The
posterior of ``τ`` given ``τ̂`` has, with ``D = diag(s² + σ_ε²)``,
``A = J_v D⁻¹ J_vᵀ + I / σ_f²`` (3 × 3) and ``f̂ = A⁻¹ J_v D⁻¹ τ̂``::

    mean_i = τ̂_i − (s_i² / D_ii) (τ̂_i − J_v,iᵀ f̂)
    var_i  = s_i² − s_i⁴ (1 / D_ii − J_v,iᵀ A⁻¹ J_v,i / D_ii²)

a joint whose own std is small keeps its reading (``s ≪ σ_ε``); a sticking one takes its
share of the force the others read, and its std narrows as far as they determine it.
A 3 × 3 solve per period (:func:`fuse`, compiled); :func:`fuse_reference` is the same
posterior from the n × n covariances, what the tests hold it to.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from leadthrough.compiled import kernel
from leadthrough.errors import ParameterError
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.validation import real


@dataclass(frozen=True)
class ToolForceParameters:
    """The prior of the fusion: a force at the tool, and what it leaves unexplained.

    Attributes:
        force_std: σ_f, std of the force at the tool before any reading [N]: broad, so
            that the readings, not the prior, decide it.
        spread: σ_ε,i = spread · τ_C,i: torques a force at the tool does not explain, per
            joint, relative to its Coulomb level [–]. A sliding joint (std ≪ σ_ε) keeps its
            own reading; a sticking one (std ≈ τ_C) takes most of its value from the
            force the others read.
    """

    force_std: float = 100.0
    spread: float = 0.3

    def __post_init__(self) -> None:
        real("force_std", self.force_std, minimum=0.0, strict=True, error=ParameterError)
        real("spread", self.spread, minimum=0.0, strict=True, error=ParameterError)


class ToolForceFusion:
    """The fusion of one arm's estimates (:func:`fuse`), with its outputs.

    Args:
        friction: The friction model in use (σ_ε = ``spread`` · its Coulomb levels).
        parameters: The prior.

    Attributes:
        mean: The latest posterior mean of τ_ext [Nm] (zeros before the first update).
        std: Its std [Nm].
        updated: Whether :meth:`update` ran since the fusion was built.
    """

    def __init__(self, friction: FrictionModel, parameters: ToolForceParameters) -> None:
        self.parameters = parameters
        self.other_std = parameters.spread * np.asarray(friction.coulomb, dtype=float)
        self.mean = np.zeros(friction.n_joints)
        self.std = np.zeros(friction.n_joints)
        self.updated = False
        self._prior_precision = 1.0 / parameters.force_std**2
        self._work = np.zeros((3, 8))  # the kernel's scratch space: no allocation per period

    def update(self, estimate: FloatArray, std: FloatArray, jacobian: FloatArray) -> FloatArray:
        """Fuse this period's estimates (see :func:`fuse`); returns :attr:`mean` [Nm]."""
        _fuse(estimate, std, jacobian, self.other_std, self._prior_precision, self.mean,
              self.std, self._work)  # fmt: skip
        self.updated = True
        return self.mean


def fuse_reference(
    estimate: FloatArray, std: FloatArray, jacobian: FloatArray, other_std: FloatArray,
    force_std: float,
) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """Posterior mean and std of τ [Nm] from the n × n covariances (the module's model).

    Args:
        estimate: Each joint's estimate τ̂ [Nm], (n,).
        std: Its std s [Nm], (n,).
        jacobian: TCP Jacobian [m/rad; rad/rad], (6, n) or its translational rows (3, n).
        other_std: σ_ε [Nm], (n,).
        force_std: σ_f [N].
    """
    translational = np.asarray(jacobian, dtype=float)[:3]
    prior = force_std**2 * translational.T @ translational + np.diag(other_std**2)
    noise = np.diag(std**2)
    gain = np.linalg.solve(prior + noise, prior).T  # P (P + S)⁻¹, both symmetric
    covariance = prior - gain @ prior
    return gain @ estimate, np.sqrt(np.maximum(np.diag(covariance), 0.0))


def fuse(
    estimate: FloatArray, std: FloatArray, jacobian: FloatArray, other_std: FloatArray,
    force_std: float, mean: FloatArray, fused_std: FloatArray,
) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """:func:`fuse_reference` by the 3 × 3 form of the module docstring, into the outputs.

    Args:
        estimate: Each joint's estimate τ̂ [Nm], (n,).
        std: Its std s [Nm], (n,).
        jacobian: TCP Jacobian, (6, n) (its first three rows are used).
        other_std: σ_ε [Nm], (n,).
        force_std: σ_f [N].
        mean: Written: the posterior mean [Nm], (n,).
        fused_std: Written: the posterior std [Nm], (n,).
    """
    _fuse(estimate, std, jacobian, other_std, 1.0 / force_std**2, mean, fused_std,
          np.zeros((3, 8)))  # fmt: skip
    return mean, fused_std


@kernel
def _fuse(estimate, std, jacobian, other_std, prior_precision, mean, fused_std, work):
    """:func:`fuse` in place, by the 3 × 3 form of the module docstring.

    ``work`` (3, 8) is scratch space: A, A⁻¹, J_v D⁻¹ τ̂ and f̂ in columns 0–2, 3–5, 6, 7.
    """
    n = estimate.shape[0]
    work[:] = 0.0
    a, inverse, b, force = work[:, 0:3], work[:, 3:6], work[:, 6], work[:, 7]
    for r in range(3):
        a[r, r] = prior_precision  # A = J_v D⁻¹ J_vᵀ + I / σ_f²
    for i in range(n):
        w = 1.0 / (std[i] * std[i] + other_std[i] * other_std[i])
        for r in range(3):
            b[r] += jacobian[r, i] * w * estimate[i]
            for c in range(3):
                a[r, c] += jacobian[r, i] * w * jacobian[c, i]
    inverse[0, 0] = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    inverse[1, 0] = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    inverse[2, 0] = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    inverse[0, 1] = a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]
    inverse[1, 1] = a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]
    inverse[2, 1] = a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]
    inverse[0, 2] = a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    inverse[1, 2] = a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]
    inverse[2, 2] = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    determinant = a[0, 0] * inverse[0, 0] + a[0, 1] * inverse[1, 0] + a[0, 2] * inverse[2, 0]
    for r in range(3):  # A⁻¹ by cofactors (A symmetric), then f̂ = A⁻¹ J_v D⁻¹ τ̂
        for c in range(3):
            inverse[r, c] /= determinant
        for c in range(3):
            force[r] += inverse[r, c] * b[c]
    for i in range(n):
        s2 = std[i] * std[i]
        w = 1.0 / (s2 + other_std[i] * other_std[i])
        along = jacobian[0, i] * force[0] + jacobian[1, i] * force[1] + jacobian[2, i] * force[2]
        quadratic = 0.0
        for r in range(3):
            for c in range(3):
                quadratic += jacobian[r, i] * inverse[r, c] * jacobian[c, i]
        mean[i] = estimate[i] - s2 * w * (estimate[i] - along)
        variance = s2 - s2 * s2 * (w - quadratic * w * w)
        fused_std[i] = math.sqrt(variance) if variance > 0.0 else 0.0
