"""The tool wrench read from the estimated joint torques: ``F̂ = (Jᵀ)⁺ τ̂_ext`` (SPEC §10).

With the TCP Jacobian ``J`` (rows v, ω in world axes) a wrench ``F = (f, m)`` applied at
the tool centre point gives the joint torques ``τ_ext = Jᵀ F`` (SPEC §1). The wrench read
back is the least-squares one, ``F̂ = (Jᵀ)⁺ τ̂_ext``, and since it is linear in τ̂ its
covariance follows exactly: ``Σ_F = (Jᵀ)⁺ Σ_τ (Jᵀ)⁺ᵀ``, with ``Σ_τ`` the observer's
(diagonal: each joint is its own filter, ``diag(std²)``).

Near a singular pose the joints cannot feel a wrench along the lost direction: the
pseudo-inverse drops directions whose singular value is below ``rcond`` times the
largest, and the wrench reads zero along them (and so does its covariance: read
``covariance`` as the spread of what is observable).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import InputShapeError
from leadthrough.validation import FloatArray


@dataclass(frozen=True, eq=False)
class ToolWrench:
    """A wrench at the tool centre point, world axes, with its covariance.

    Attributes:
        force: Force applied to the tool [N], (3,).
        torque: Moment about the TCP [Nm], (3,).
        covariance: Covariance of (force, torque) [N², N Nm, Nm²], (6, 6).
    """

    force: FloatArray
    torque: FloatArray
    covariance: FloatArray

    @property
    def vector(self) -> FloatArray:
        """(force [N], torque [Nm]) as one (6,) vector."""
        return np.concatenate([self.force, self.torque])

    @property
    def std(self) -> FloatArray:
        """Standard deviations of (force [N], torque [Nm]), (6,)."""
        return np.sqrt(np.clip(np.diagonal(self.covariance), 0.0, None))


def tool_wrench(
    jacobian: ArrayLike,
    tau_ext: ArrayLike,
    tau_std: ArrayLike | None = None,
    rcond: float = 1e-4,
) -> ToolWrench:
    """The wrench at the TCP that explains the joint torques ``tau_ext``, and its covariance.

    Args:
        jacobian: TCP Jacobian [m/rad; rad/rad], (6, n), rows (v, ω) in world axes.
        tau_ext: Estimated external joint torques [Nm], (n,).
        tau_std: Their standard deviations [Nm], (n,), independent joints; None: zero
            covariance.
        rcond: Singular values below ``rcond`` × the largest count as zero [–].
    """
    jacobian = np.asarray(jacobian, dtype=float)
    n = jacobian.shape[1] if jacobian.ndim == 2 else 0
    if jacobian.shape != (6, n) or n == 0:
        raise InputShapeError("jacobian", (6, max(n, 1)), jacobian.shape)
    tau = np.asarray(tau_ext, dtype=float)
    if tau.shape != (n,):
        raise InputShapeError("tau_ext", (n,), tau.shape)
    inverse = np.linalg.pinv(jacobian.T, rcond=rcond)  # (6, n)
    wrench = inverse @ tau
    if tau_std is None:
        covariance = np.zeros((6, 6))
    else:
        std = np.asarray(tau_std, dtype=float)
        if std.shape != (n,):
            raise InputShapeError("tau_std", (n,), std.shape)
        covariance = (inverse * std**2) @ inverse.T
    return ToolWrench(wrench[:3], wrench[3:], covariance)
