"""Time per call of the lt.Dynamics functions for the YuMi, from Python.

Usage:
    python benchmarks/bench_dynamics.py [--calls N] [--save FILE] [--compare FILE]
"""

from __future__ import annotations

import numpy as np

import leadthrough as lt
from timing import parser, report, time_per_call


def main() -> None:
    args = parser(__doc__.splitlines()[0]).parse_args()
    robot = lt.robots.yumi()
    dynamics = lt.Dynamics(robot)
    rng = np.random.default_rng(0)
    q = rng.uniform(robot.q_min, robot.q_max)
    qd = rng.uniform(-1.0, 1.0, robot.n_joints)
    functions = {
        "gravity(q)": lambda: dynamics.gravity(q),
        "mass(q)": lambda: dynamics.mass(q),
        "coriolis(q, qd)": lambda: dynamics.coriolis(q, qd),
        "coriolis_transpose_times_velocity": lambda: dynamics.coriolis_transpose_times_velocity(
            q, qd
        ),
        "momentum(q, qd)": lambda: dynamics.momentum(q, qd),
        "jacobian(q)": lambda: dynamics.jacobian(q),
        "pose(q)": lambda: dynamics.pose(q),
    }
    results = {name: time_per_call(function, args.calls) for name, function in functions.items()}
    print(f"{robot.name}, {args.calls} calls each, one thread")
    report(results, args.save, args.compare)


if __name__ == "__main__":
    main()
