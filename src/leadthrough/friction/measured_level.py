"""How far a Coulomb level read at one pose may be off elsewhere: its error grows with the travel.

The start-up calibration reads each joint's level at the pose the arm rests at, to the
scatter of its readings there (``Calibration.coulomb_spread``). Away from that pose the
level changes with the joint angle, which no reading at one pose sees: on the real UR10e's
jointwise runs it moves ±8 to ±22 % along 1.8–2.8 rad on joints 1–3 (at most 0.25 of the
level per radian over a stroke; ``friction.along_travel``), and on the plant family of
``benchmarks/guiding_quality.py`` by ±15 % with two periods per turn (at most 0.3 per
radian). So a level read at ``q₀`` to a relative ``e₀`` is off at ``q`` by at most::

    e(q) = min(e₀ + s |q − q₀|, e_far)

per joint, with ``s`` the fastest relative change of a level per radian (the calibration's
``level_slope``) and ``e_far`` the error the controller allows the level anywhere (the
model's plus the reading's, at most ``friction_accuracy``). Near the pose where it was
read, a level is known to its reading; far from it, to ``e_far``, as without this.

A level identified over a stroke (``leadthrough identify``) is known to its model's error
over the stroke its samples slid over, ``q₀ ± w``, and beyond it only as far as the same
slope allows: ``e(q) = min(e₀ + s max(|q − q₀| − w, 0), e_far)`` (``span`` w; 0 for a
reading at one pose).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from leadthrough.compiled import kernel
from leadthrough.model.description import FloatArray


@dataclass(frozen=True, eq=False)
class MeasuredLevelError:
    """The relative error of Coulomb levels read at one pose, at any pose [–].

    Attributes:
        pose: Where the levels were read, q₀ [rad], (n,).
        at_pose: Their relative error there, e₀ [–], (n,): the reading's. A joint that was
            not read has ``at_pose == far``.
        far: The error anywhere, e_far [–], (n,): what it grows to, never more.
        slope: Fastest relative change of a level with its joint angle, s [1/rad].
        span: Half-width of the stroke about ``pose`` over which the level is known to
            ``at_pose``, w [rad], (n,); None: a reading at one pose (w = 0).
    """

    pose: FloatArray
    at_pose: FloatArray
    far: FloatArray
    slope: float
    span: FloatArray | None = None

    def __post_init__(self) -> None:
        if self.span is None:  # a reading at one pose
            object.__setattr__(self, "span", np.zeros_like(self.far, dtype=float))

    def at(self, q: FloatArray, out: FloatArray | None = None) -> FloatArray:
        """``e(q) = min(e₀ + s max(|q − q₀| − w, 0), e_far)`` per joint [–] (into ``out``)."""
        out = np.empty_like(self.far) if out is None else out
        _grown(np.asarray(q, dtype=float), self.pose, self.at_pose, self.far,
               float(self.slope), self.span, out)  # fmt: skip
        return out


@kernel
def _grown(q, pose, at_pose, far, slope, span, out):
    """:meth:`MeasuredLevelError.at`, in place (one call per control period)."""
    for i in range(q.shape[0]):
        beyond = abs(q[i] - pose[i]) - span[i]
        grown = at_pose[i] + slope * (beyond if beyond > 0.0 else 0.0)
        out[i] = grown if grown < far[i] else far[i]
