"""The torque the model misses, read after the fact from the generalized momentum's balance.

The generalized momentum ``p = M(q) q̇`` obeys ``ṗ = τ − G(q) − τ_f(q̇) + Cᵀ(q, q̇) q̇ +
τ_miss`` (SPEC §5), where ``τ_miss`` is the operator's torque plus every model error. The
momentum the model leaves unexplained,

    u(t) = p(t) − ∫ (τ − G − τ_f + Cᵀq̇) dt,

therefore grows at ``τ_miss``, and over a stretch ``[a, b]`` the torque the model missed
on average is ``(u_b − u_a) / (t_b − t_a)``: the momentum observer's residual (thesis
§3.3), without the observer's first-order filter. Read one sample late, ``q̇`` is the
encoders' central difference, without the lag of a robot's filtered velocity (15–40 Hz
on the plants of ``benchmarks/guiding_quality.py``, ~25 ms with the delay), which the
observer takes as it comes: the inertial torque of a motion's reversals passes into its
estimate through that lag, and does not into ``u``.

:class:`MomentumBalance` keeps ``u`` sample by sample, one sample behind the robot (a few
model evaluations per period, ~16 µs on the YuMi); :func:`stretch_readings` turns it into
readings over the stretches a joint slides at a given pace. The start-up calibration reads
the model's error that way (:mod:`~leadthrough.control.calibration`).
"""

from __future__ import annotations

import itertools

import numpy as np

from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics


class MomentumBalance:
    """The momentum the model does not explain, ``u``, kept one sample behind the robot.

    Args:
        dynamics: The arm's model.
        friction: The friction model (its mean is what the model explains).
    """

    def __init__(self, dynamics: Dynamics, friction: FrictionModel) -> None:
        self.dynamics, self.friction = dynamics, friction
        self._t: list[float] = []
        self._q: list[FloatArray] = []
        self._tau: list[FloatArray] = []
        self._velocity: list[FloatArray] = []
        self._unexplained: list[FloatArray] = []
        self._explained: FloatArray | None = None  # ∫ (τ − G − τ_f + Cᵀq̇) dt so far [Nm s]

    def __len__(self) -> int:
        """Samples added."""
        return len(self._t)

    def add(self, t: float, q: FloatArray, tau: FloatArray) -> None:
        """One sample: time [s], joint positions [rad], torque applied over the period [Nm].

        Settles the sample before it, whose central difference is now known. A sample
        that does not come after the last one (a driver that delivers a sample twice, or
        a 1 kHz loop fed 500 Hz data) is left out: no time passed to balance over (its zero
        interval stopped a YuMi's calibration with a ZeroDivisionError).
        """
        if self._t and not float(t) > self._t[-1]:
            return
        self._t.append(float(t))
        self._q.append(np.array(q, dtype=float))
        self._tau.append(np.array(tau, dtype=float))
        n = len(self._t)
        if n == 2:
            self._settle(0, self._difference(1))  # the first sample: its forward difference
        elif n > 2:
            self._settle(n - 2, self._central(n - 2))

    def arrays(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Times [s], joint velocities [rad/s] and ``u`` [kg m²/s] of every sample so far.

        The last sample's velocity is its backward difference. Each (N, n) but the times.
        """
        n, joints = len(self._t), self.dynamics.robot.n_joints
        if n < 2:
            return np.array(self._t), np.zeros((n, joints)), np.zeros((n, joints))
        last = self._difference(n - 1)
        unexplained, _ = self._balanced(n - 1, last)
        return (np.array(self._t), np.array([*self._velocity, last]),
                np.array([*self._unexplained, unexplained]))  # fmt: skip

    def _difference(self, k: int) -> FloatArray:
        """``(q_k − q_{k−1}) / (t_k − t_{k−1})`` [rad/s]: the velocity at either end of the run."""
        return (self._q[k] - self._q[k - 1]) / (self._t[k] - self._t[k - 1])

    def _central(self, k: int) -> FloatArray:
        """Velocity at sample ``k`` from its neighbours, for uneven steps [rad/s]."""
        before, after = self._t[k] - self._t[k - 1], self._t[k + 1] - self._t[k]
        a = -after / (before * (before + after))
        b = (after - before) / (before * after)
        c = before / (after * (before + after))
        return a * self._q[k - 1] + b * self._q[k] + c * self._q[k + 1]

    def _settle(self, k: int, velocity: FloatArray) -> None:
        """Keep sample ``k``'s velocity and ``u``."""
        unexplained, self._explained = self._balanced(k, velocity)
        self._velocity.append(velocity)
        self._unexplained.append(unexplained)

    def _balanced(self, k: int, velocity: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``u`` at sample ``k`` and the balance integrated up to it."""
        q, dynamics = self._q[k], self.dynamics
        balance = (self._tau[k] - dynamics.gravity(q) - self.friction.mean(velocity, q)
                   + dynamics.coriolis_transpose_times_velocity(q, velocity))  # fmt: skip
        step = self._t[k] - self._t[k - 1] if k > 0 else 0.0
        explained = balance * step
        if self._explained is not None:
            explained = self._explained + explained
        return dynamics.momentum(q, velocity) - explained, explained


def stretch_readings(
    t: FloatArray, velocity: FloatArray, unexplained: FloatArray, pace: tuple[float, float]
) -> FloatArray:
    """Per sample, the torque the model missed over the stretch at pace it belongs to [Nm].

    Args:
        t: Sample times [s], (N,).
        velocity: Joint velocities [rad/s], (N, n).
        unexplained: ``u`` [kg m²/s], (N, n) (:meth:`MomentumBalance.arrays`).
        pace: Slowest and fastest speed of a joint sliding at pace [rad/s] (exclusive,
            inclusive).

    Returns:
        ``(u_b − u_a) / (t_b − t_a)`` over each stretch ``[a, b]`` of at least three samples
        in which a joint moves one way at pace, on every sample of it; NaN elsewhere.
    """
    speed = np.abs(velocity)
    direction = np.where((speed > pace[0]) & (speed <= pace[1]), np.sign(velocity), 0.0)
    readings = np.full(velocity.shape, np.nan)
    for joint in range(velocity.shape[1]):
        for first, last in _stretches(direction[:, joint]):
            gained = unexplained[last, joint] - unexplained[first, joint]
            readings[first : last + 1, joint] = gained / (t[last] - t[first])
    return readings


def _stretches(direction: FloatArray) -> list[tuple[int, int]]:
    """First and last index of each run of ≥ 3 equal nonzero values of ``direction``."""
    changes = np.flatnonzero(np.diff(direction) != 0.0) + 1
    bounds = np.concatenate([[0], changes, [len(direction)]])
    return [(int(a), int(b) - 1) for a, b in itertools.pairwise(bounds)
            if b - a >= 3 and direction[a] != 0.0]  # fmt: skip
