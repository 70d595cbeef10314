"""A joint's Coulomb level measured along its travel, from its up and down strokes.

Where a joint passes the same position both ways while the other joints stand where they
stood, whatever depends on the arm's pose alone is the same on both strokes: gravity, and
the error a rigid-body model makes in it (a nominal URDF's masses, a drive gain on a
gravity-loaded joint). Friction changes sign. So in a bin of the travel, with the viscous
term removed::

    level(bin) = (mean τ_f(up) − mean τ_f(down)) / 2,    τ_f = τ − (M q̈ + C q̇ + G) − c q̇

is the Coulomb level there, free of any pose-only model error, which the sliding
residual of the least-squares fit is not. Its largest relative deviation from the fitted
``τ_C(q)`` is what the model mis-states along the travel the logs cover: the friction
error a controller must allow for (``FrictionModel.relative_error``; the active law's
friction margin and the compensation's ceiling), not inflated by gravity error, which the
start-up calibration and the learned bias handle.

Only samples with the other joints within :data:`STILL` of where they mostly stood count:
a run that moves one joint at a time (the UR10e's jointwise runs, the project's friction
excitation) has them, a multi-joint excitation has too few, and the identification then
falls back on the residual's spread.

Measured on the real UR10e's jointwise runs (README, *Real robots' logs*): levels that move
±8 to ±22 % along 1.8–2.8 rad on joints 1–3 and within ±2 % on the wrists.
"""

from __future__ import annotations

import numpy as np

from leadthrough.model.description import FloatArray

#: Bins of the sliding travel (between its 3rd and 97th percentiles) compared both ways.
LEVEL_BINS = 10
#: Sliding samples a bin needs in each direction to count.
BIN_SAMPLES = 20
#: Fewest bins passed both ways for a level error to be measured.
MINIMUM_BINS = 3
#: Largest distance of the other joints from their median position over the samples [rad].
STILL = 0.005


def level_along_travel(
    q: FloatArray, qd: FloatArray, tau_friction: FloatArray, viscous: float,
    others: FloatArray | None = None, bins: int = LEVEL_BINS,
) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """The Coulomb level in bins of one joint's travel, from its sliding samples.

    Args:
        q: Joint positions of the sliding samples [rad], (N,).
        qd: Their velocities [rad/s], (N,); none of them 0.
        tau_friction: Their friction torques τ − (M q̈ + C q̇ + G) [Nm], (N,).
        viscous: The viscous coefficient c removed first [Nm s/rad].
        others: The other joints' positions at those samples [rad], (N, n − 1); only
            samples with every one within :data:`STILL` of its median count. None: the
            other joints stood still.
        bins: How many bins the travel is cut into.

    Returns:
        (centres [rad], levels [Nm]) of the bins passed at least :data:`BIN_SAMPLES`
        times each way; empty arrays when none is.
    """
    if others is not None and others.size:
        still = np.all(np.abs(others - np.median(others, axis=0)) <= STILL, axis=1)
        q, qd, tau_friction = q[still], qd[still], tau_friction[still]
    if q.size < 2 * BIN_SAMPLES:
        return np.empty(0), np.empty(0)
    coulomb_part = tau_friction - viscous * qd
    low, high = np.percentile(q, [3.0, 97.0])
    edges = np.linspace(low, high, bins + 1)
    which = np.clip(np.searchsorted(edges, q, side="right") - 1, 0, bins - 1)
    inside = (q >= edges[0]) & (q <= edges[-1])
    centres, levels = [], []
    for b in range(bins):
        mine = inside & (which == b)
        up, down = mine & (qd > 0.0), mine & (qd < 0.0)
        if up.sum() >= BIN_SAMPLES and down.sum() >= BIN_SAMPLES:
            centres.append(0.5 * (edges[b] + edges[b + 1]))
            levels.append(0.5 * (coulomb_part[up].mean() - coulomb_part[down].mean()))
    return np.asarray(centres), np.asarray(levels)


def level_error(levels: FloatArray, modelled: FloatArray) -> float:
    """Largest relative deviation of measured ``levels`` from the ``modelled`` ones [–].

    NaN when fewer than :data:`MINIMUM_BINS` bins were measured (too little travel passed
    both ways to say), or a modelled level is 0.
    """
    if levels.size < MINIMUM_BINS or not np.all(modelled > 0.0):
        return float("nan")
    return float(np.max(np.abs(levels / modelled - 1.0)))
