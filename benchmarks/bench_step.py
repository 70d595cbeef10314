"""Time of one LeadThrough.step for the YuMi (passive and active), from Python.

Usage:
    python benchmarks/bench_step.py [--calls N] [--save FILE] [--compare FILE]
"""

from __future__ import annotations

import numpy as np

import leadthrough as lt
from leadthrough.safety.supervisor import SupervisorState
from timing import parser, report, time_per_call


def main() -> None:
    args = parser(__doc__.splitlines()[0]).parse_args()
    robot = lt.robots.yumi()
    rng = np.random.default_rng(0)
    home = robot.home()
    tau = lt.Dynamics(robot).gravity(home)
    omega = 2.0 * np.pi * 0.2  # every joint swings ±0.1 rad at 0.2 Hz: teaching, never a fault
    results = {}
    for mode in ("passive", "active"):
        controller = lt.LeadThrough(robot, mode, calibrate=True)
        state = {"k": 0}

        def step(controller: lt.LeadThrough = controller, state: dict = state) -> None:
            state["k"] += 1
            t = controller.dt * state["k"]
            q = home + 0.1 * np.sin(omega * t)
            qd = 0.1 * omega * np.cos(omega * t) + 1e-4 * rng.standard_normal(robot.n_joints)
            controller.step(q, qd, tau)

        calibration = round(controller.parameters.calibration.duration / controller.dt) + 1
        for _ in range(calibration):  # time the teaching steps, not the start-up calibration
            step()
        results[f"step, {mode}"] = time_per_call(step, args.calls)
        if controller.state is SupervisorState.FAULT:
            raise SystemExit(
                f"{mode}: the benchmark faulted ({controller.supervisor.fault_reason})"
            )
    print(f"{robot.name}, {args.calls} calls each, one thread")
    report(results, args.save, args.compare)
    worst = max(stats["p99_us"] for stats in results.values())
    print(f"a 1 kHz loop leaves {1000.0 / worst:.1f}× the p99 step time")


if __name__ == "__main__":
    main()
