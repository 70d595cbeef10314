"""What the observer reads while nobody guides the arm is model error: learn it, remove it.

A momentum observer on an imperfect model reads a torque even when nobody touches the
arm: the weight of a payload, a mass or centre-of-mass error, a friction offset, a
friction level that is off while the released arm still moves. Fed to an admittance,
that becomes motion (SPEC §6). This component learns it as a bias, as fast as nobody
guides (at rest, or coasting after a release), and says how much error may remain:
before anything is learned,
the whole uncertainty of the gravity model (``gravity_uncertainty · |G(q)|``: masses and
drive gains); once the
bias is learned at a pose, only the uncertainty of how gravity *changed* since then
(``gravity_uncertainty · |G(q) − G(q_learned)|``). The dead-zone of the controller uses it.

Only a joint that slides vouches for its gravity model: at rest its friction may hold
any gravity error below breakaway unseen (thesis §5.3), and the bias learned there holds
what the readings show (a torque offset), not that error. So each joint's confidence
grows only as fast as it slides with nobody guiding (a released arm coasting); learned at
rest, it let an uncalibrated arm that had rested 5 s run 0.4 rad once let go, with masses
10 % and drive gains 20 % off (docs/guiding_results.md, *Hands that take the arm after a
rest*).
"""

from __future__ import annotations

import numpy as np

from leadthrough.model.description import FloatArray


class ModelErrorBias:
    """A bias learned while nobody guides, with the gravity uncertainty that remains.

    Args:
        n_joints: Number of joints.
        learning_time: Time constant of the learning [s] (when nobody guides at all).
        gravity_uncertainty: Relative error of the gravity model [–] (masses, drive gains).
    """

    def __init__(self, n_joints: int, learning_time: float, gravity_uncertainty: float) -> None:
        self.learning_time = learning_time
        self.gravity_uncertainty = gravity_uncertainty
        self.bias = np.zeros(n_joints)
        #: per joint, 0: nothing learned, → 1 after a few learning times sliding unguided
        self.confidence = np.zeros(n_joints)
        #: G at the poses the bias was learned, weighted as it was learned [Nm]
        self.gravity_learned = np.zeros(n_joints)

    def update(
        self,
        estimate: FloatArray,
        gravity: FloatArray,
        dt: float,
        bound: FloatArray,
        sliding: FloatArray,
        unguided: float = 1.0,
    ) -> FloatArray:
        """Learn as fast as nobody guides; return the estimate minus the bias [Nm].

        Args:
            estimate: Observer estimate [Nm].
            gravity: G(q) [Nm].
            dt: Period [s].
            bound: Largest plausible model error per joint [Nm]: the bias never exceeds it,
                so a push against an end-stop or an operator holding the arm still is not
                learned as model error.
            sliding: How much each joint slides, in [0, 1] (0 at rest, 1 where its
                friction is known up to its level): scales its confidence's rate.
            unguided: How sure it is that nobody guides, in [0, 1]: scales the learning
                rate (0: learn nothing, e.g. at an end-stop or while the operator pushes).
        """
        residual = estimate - self.bias
        if unguided > 0.0:
            rate = unguided * dt / self.learning_time
            # np.clip's result (NaN included) at half its cost
            self.bias = np.minimum(np.maximum(self.bias + rate * residual, -bound), bound)
            self.gravity_learned = self.gravity_learned + rate * (gravity - self.gravity_learned)
            self.confidence += rate * sliding * (1.0 - self.confidence)
        return estimate - self.bias

    def calibrate(self, bias: FloatArray, gravity: FloatArray) -> None:
        """Take a bias measured by the start-up calibration at a pose where G = ``gravity``."""
        self.bias = np.array(bias, dtype=float)
        self.gravity_learned = np.array(gravity, dtype=float)
        self.confidence = np.ones_like(self.bias)

    def tolerance(self, gravity: FloatArray) -> FloatArray:
        """Error that may remain after removing the bias [Nm].

        The gravity model's, per joint: all of it until the joint slid with nobody guiding
        (or a calibration measured it), only its change since the bias was learned after.
        """
        unknown = np.abs(gravity)
        changed = np.abs(gravity - self.gravity_learned)
        gravity_error = (1.0 - self.confidence) * unknown + self.confidence * changed
        return self.gravity_uncertainty * gravity_error
