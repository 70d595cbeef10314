"""Feed-forward torques computed from the model alone."""

from __future__ import annotations

from numpy.typing import ArrayLike

from leadthrough.description import FloatArray
from leadthrough.dynamics import Dynamics


class GravityCompensation:
    """The controller of thesis §4.2.1: command the gravity torque, ``τ = G(q)``.

    With it alone the arm floats and joint friction holds it where it is left.

    Args:
        dynamics: Model of the arm.
    """

    def __init__(self, dynamics: Dynamics) -> None:
        self.dynamics = dynamics

    def step(
        self, q: ArrayLike, qd: ArrayLike, tau_measured: ArrayLike | None = None
    ) -> FloatArray:
        """Gravity torque [Nm] at the joint readings ``q`` [rad]."""
        return self.dynamics.gravity(q)
