"""Time per call of the lt.Dynamics functions for the YuMi, from Python.

Usage:
    python benchmarks/bench_dynamics.py [--calls N] [--save FILE] [--compare FILE]
"""

from __future__ import annotations

from itertools import cycle

import numpy as np

import leadthrough as lt
from timing import parser, report, time_per_call


def _same_pose(function, q):
    return lambda: function(q)


def main() -> None:
    args = parser(__doc__.splitlines()[0]).parse_args()
    robot = lt.robots.yumi()
    dynamics = lt.Dynamics(robot)
    rng = np.random.default_rng(0)
    poses = cycle(rng.uniform(robot.q_min, robot.q_max, (64, robot.n_joints)))  # a new q each call
    qd = rng.uniform(-1.0, 1.0, robot.n_joints)
    functions = {
        "gravity(q)": lambda: dynamics.gravity(next(poses)),
        "mass(q)": lambda: dynamics.mass(next(poses)),
        "mass(q), same q again (remembered)": _same_pose(dynamics.mass, next(poses)),
        "coriolis(q, qd)": lambda: dynamics.coriolis(next(poses), qd),
        "coriolis_transpose_times_velocity": lambda: dynamics.coriolis_transpose_times_velocity(
            next(poses), qd
        ),
        "momentum(q, qd)": lambda: dynamics.momentum(next(poses), qd),
        "jacobian(q)": lambda: dynamics.jacobian(next(poses)),
        "pose(q)": lambda: dynamics.pose(next(poses)),
    }
    results = {name: time_per_call(function, args.calls) for name, function in functions.items()}
    print(f"{robot.name}, {args.calls} calls each, one thread")
    report(results, args.save, args.compare)


if __name__ == "__main__":
    main()
