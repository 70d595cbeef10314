"""Warm-up: compile every kernel a controller will call before its control loop starts.

The compiled parts of a step (:mod:`leadthrough.compiled`) are built by numba at their
first call: ~2 s in the first process after an install, ~0.4 s later (loaded from the disk
cache), and again, for a few ms, on the first call with other argument types — the first
fault, the first braking. On a 1 kHz robot each is a string of missed deadlines at the
worst moment. :func:`exercise` runs a throwaway replica of the controller (built from the
same robot, friction and parameters objects: the arrays the kernels see have the same types,
read-only flags included, as the controller's own) through the samples that reach every
compiled path: rest, a measured torque, a joint above its speed limit, a NaN reading and the
safe stop after it. The controller itself is not touched.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from leadthrough.logs.sample import JointState
from leadthrough.model.description import FloatArray


def exercise(replica: Any, q: FloatArray, speed_limits: FloatArray) -> float:
    """Step ``replica`` through every compiled path; return the time it took [s].

    Args:
        replica: A controller built like the one to warm up (``step(state)``, ``dt``),
            used up by this.
        q: A pose inside the joint limits [rad].
        speed_limits: The joint speed limits [rad/s] (one joint is sampled 1.2× above).
    """
    start = time.perf_counter()
    n, dt = q.shape[0], float(replica.dt)
    still, fast = np.zeros(n), np.zeros(n)
    fast[-1] = 1.2 * speed_limits[-1]
    broken = q.copy()
    broken[0] = np.nan
    drift = 1e-6 * np.arange(1, n + 1)  # readings that change: no frozen encoder
    samples = [(q, still, None), (q + drift, still, None), (q, still, np.zeros(n)),
               (q + drift, still, np.full(n, 0.1)), (q, fast, np.zeros(n)),
               (broken, still, np.zeros(n)), (q + drift, still, np.zeros(n)),
               (q, still, None)]  # fmt: skip
    for k, (position, velocity, torque) in enumerate(samples):
        replica.step(JointState(k * dt, position, velocity, torque))
    return time.perf_counter() - start
