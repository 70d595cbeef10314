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

The hand may push elsewhere: on a link, or a joint by itself. The second hypothesis gives
each joint a torque of the same size as a force at the tool would, but each its own,

    τ_i ~ N(0, σ_f² ‖J_v,i‖² + σ_ε,i²)   independently,

and the two are weighed by how well each explains the readings (their evidence,
``N(τ̂; 0, C)`` with ``C_tool = σ_f² J_vᵀ J_v + D``, computed from the same 3 × 3 form:
``τ̂ᵀ C⁻¹ τ̂ = Σ τ̂_i² / D_ii − b̂ᵀ f̂`` and ``det C = det D · σ_f⁶ · det A``) and
``ToolForceParameters.tool_prior``. The estimate is the mixture of the two posteriors, its
std the mixture's. Readings a force at the tool loads together keep the tool's posterior
(weight ≈ 1); a push it cannot make (a UR10e's joint 4 pushed alone with 8 Nm, read 4.6
by the tool's model) keeps each joint's own. :func:`mixture_reference` computes it from the
n × n covariances.
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
        tool_prior: Probability that the hand pushes at the tool rather than elsewhere
            before any reading [–], in (0, 1); 0.5: neither is favoured. None: the tool's
            model only (a push elsewhere is read as far as a force at the tool explains it).
    """

    force_std: float = 100.0
    spread: float = 0.3
    tool_prior: float | None = 0.5

    def __post_init__(self) -> None:
        real("force_std", self.force_std, minimum=0.0, strict=True, error=ParameterError)
        real("spread", self.spread, minimum=0.0, strict=True, error=ParameterError)
        if self.tool_prior is not None:
            prior = real("tool_prior", self.tool_prior, minimum=0.0, strict=True,
                         error=ParameterError)  # fmt: skip
            if prior >= 1.0:
                raise ParameterError("tool_prior", f"must be below 1 (None: the tool only), "
                                     f"got {prior:g}")  # fmt: skip

    @property
    def log_prior_odds(self) -> float:
        """``log(p / (1 − p))`` of ``tool_prior`` p; +inf for None (the tool's model only)."""
        if self.tool_prior is None:
            return math.inf
        return math.log(self.tool_prior / (1.0 - self.tool_prior))


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
        #: the posterior probability that the hand pushes at the tool, latest period [–]
        self.weight = 1.0
        self._prior_precision = 1.0 / parameters.force_std**2
        self._log_prior_odds = parameters.log_prior_odds
        self._work = np.zeros((3, 8))  # the kernel's scratch space: no allocation per period

    def update(self, estimate: FloatArray, std: FloatArray, jacobian: FloatArray) -> FloatArray:
        """Fuse this period's estimates (see :func:`fuse`); returns :attr:`mean` [Nm]."""
        self.weight = _fuse(estimate, std, jacobian, self.other_std, self._prior_precision,
                            self._log_prior_odds, self.mean, self.std, self._work)  # fmt: skip
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


def mixture_reference(
    estimate: FloatArray, std: FloatArray, jacobian: FloatArray, other_std: FloatArray,
    force_std: float, tool_prior: float,
) -> tuple[FloatArray, FloatArray, float]:  # fmt: skip
    """The mixture of the module docstring from the n × n covariances: mean, std, weight.

    Arguments as :func:`fuse_reference`'s, and ``tool_prior`` in (0, 1); the weight is the
    posterior probability of the force at the tool.
    """
    translational = np.asarray(jacobian, dtype=float)[:3]
    s2 = np.asarray(std, dtype=float) ** 2
    tool_mean, tool_std = fuse_reference(estimate, std, jacobian, other_std, force_std)
    elsewhere = force_std**2 * np.sum(translational**2, axis=0) + other_std**2
    covariances = (force_std**2 * translational.T @ translational + np.diag(other_std**2 + s2),
                   np.diag(elsewhere + s2))  # fmt: skip
    evidence = [-0.5 * (estimate @ np.linalg.solve(c, estimate) + np.linalg.slogdet(c)[1])
                for c in covariances]  # fmt: skip
    odds = evidence[0] - evidence[1] + math.log(tool_prior / (1.0 - tool_prior))
    weight = 0.5 * (1.0 + math.tanh(0.5 * odds))  # 1 / (1 + e^(−odds)), without overflow
    share = elsewhere / (elsewhere + s2)  # of each joint's own reading, under the second
    other_mean, other_var = estimate * share, s2 * share
    mean = weight * tool_mean + (1.0 - weight) * other_mean
    second = weight * (tool_std**2 + tool_mean**2) + (1.0 - weight) * (other_var + other_mean**2)
    return mean, np.sqrt(np.maximum(second - mean**2, 0.0)), weight


def fuse(
    estimate: FloatArray, std: FloatArray, jacobian: FloatArray, other_std: FloatArray,
    force_std: float, mean: FloatArray, fused_std: FloatArray, tool_prior: float | None = None,
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
        tool_prior: None: the tool's posterior; else the mixture with a push elsewhere
            (:func:`mixture_reference`).
    """
    odds = ToolForceParameters(tool_prior=tool_prior).log_prior_odds
    _fuse(estimate, std, jacobian, other_std, 1.0 / force_std**2, odds, mean, fused_std,
          np.zeros((3, 8)))  # fmt: skip
    return mean, fused_std


@kernel
def _fuse(estimate, std, jacobian, other_std, prior_precision, log_prior_odds, mean, fused_std,
          work):  # fmt: skip
    """:func:`fuse` in place, by the 3 × 3 form of the module docstring; the tool's weight.

    ``work`` (3, 8) is scratch space: A, A⁻¹, J_v D⁻¹ τ̂ and f̂ in columns 0–2, 3–5, 6, 7.
    ``log_prior_odds`` +inf: the tool's posterior alone (weight 1).
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
    if not log_prior_odds < math.inf:
        return 1.0
    # the evidence of each hypothesis, log N(τ̂; 0, C) but the common −n/2 log 2π
    explained = b[0] * force[0] + b[1] * force[1] + b[2] * force[2]
    tool = math.log(determinant) - 3.0 * math.log(prior_precision) - explained
    other = 0.0
    for i in range(n):
        d = std[i] * std[i] + other_std[i] * other_std[i]
        tool += estimate[i] * estimate[i] / d + math.log(d)
        elsewhere = (jacobian[0, i] ** 2 + jacobian[1, i] ** 2 + jacobian[2, i] ** 2) / (
            prior_precision) + other_std[i] * other_std[i]  # fmt: skip
        d = elsewhere + std[i] * std[i]
        other += estimate[i] * estimate[i] / d + math.log(d)
    odds = 0.5 * (other - tool) + log_prior_odds
    weight = 1.0 / (1.0 + math.exp(-odds)) if odds > -700.0 else 0.0
    for i in range(n):  # the mixture of the two posteriors
        s2 = std[i] * std[i]
        elsewhere = (jacobian[0, i] ** 2 + jacobian[1, i] ** 2 + jacobian[2, i] ** 2) / (
            prior_precision) + other_std[i] * other_std[i]  # fmt: skip
        own_mean = estimate[i] * elsewhere / (elsewhere + s2)
        own_variance = s2 * elsewhere / (elsewhere + s2)
        tool_mean, tool_variance = mean[i], fused_std[i] * fused_std[i]
        mixed = weight * tool_mean + (1.0 - weight) * own_mean
        second = weight * (tool_variance + tool_mean * tool_mean) + (1.0 - weight) * (
            own_variance + own_mean * own_mean)  # fmt: skip
        mean[i] = mixed
        variance = second - mixed * mixed
        fused_std[i] = math.sqrt(variance) if variance > 0.0 else 0.0
    return weight
