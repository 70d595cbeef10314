"""Time of one LeadThrough.step for the YuMi (passive and active), from Python.

Usage:
    python benchmarks/bench_step.py [--calls N] [--save FILE] [--compare FILE]
"""

from __future__ import annotations

import numpy as np

import leadthrough as lt
from timing import parser, report, time_per_call


def main() -> None:
    args = parser(__doc__.splitlines()[0]).parse_args()
    robot = lt.robots.yumi()
    rng = np.random.default_rng(0)
    q = robot.home()
    tau = lt.Dynamics(robot).gravity(q)
    results = {}
    for mode in ("passive", "active"):
        controller = lt.LeadThrough(robot, mode)
        state = {"k": 0}

        def step(controller: lt.LeadThrough = controller, state: dict = state) -> None:
            state["k"] += 1
            qd = np.full(robot.n_joints, 0.05) + 1e-4 * rng.standard_normal(robot.n_joints)
            controller.step(q + 0.004 * state["k"] * 0.05, qd, tau)

        results[f"step, {mode}"] = time_per_call(step, args.calls)
    print(f"{robot.name}, {args.calls} calls each, one thread")
    report(results, args.save, args.compare)
    worst = max(stats["p99_us"] for stats in results.values())
    print(f"a 1 kHz loop leaves {1000.0 / worst:.1f}× the p99 step time")


if __name__ == "__main__":
    main()
