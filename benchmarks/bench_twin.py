"""Real-time factor of the closed loop on the twin: simulated seconds per wall second.

A trivial controller (gravity feed-forward) runs against the YuMi twin (physics at
2 kHz, control at 250 Hz, LuGre friction, sensors, logging) in two scenarios: nobody
touching the arm, and a hand pulling the tool along a line. Median of several runs.

Usage:
    python benchmarks/bench_twin.py [--runs N] [--seconds S] [--save FILE] [--compare FILE]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import leadthrough as lt
from leadthrough.control.feedforward import GravityCompensation
from leadthrough.twin.runner import simulate
from leadthrough.twin.scenarios import scenario


def real_time_factor(name: str, seconds: float, robot: lt.RobotDescription) -> float:
    """Simulated seconds per wall second of one closed-loop run of scenario ``name``."""
    twin = scenario(name, robot).twin(robot)
    controller = GravityCompensation(lt.Dynamics(robot))
    start = time.perf_counter()
    simulate(twin, controller, seconds, progress=False)
    return seconds / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated time per run")
    parser.add_argument("--save", type=Path)
    parser.add_argument("--compare", type=Path)
    args = parser.parse_args()
    robot = lt.robots.yumi()
    real_time_factor("idle", 0.2, robot)  # warm-up: JIT-compiled friction, caches
    before = json.loads(args.compare.read_text()) if args.compare else {}
    results = {}
    print(f"{'scenario':<12}{'median RTF':>12}{'min':>8}{'max':>8}{'vs before':>11}")
    for name in ("idle", "line"):
        factors = [real_time_factor(name, args.seconds, robot) for _ in range(args.runs)]
        median = statistics.median(factors)
        results[name] = {"median_rtf": median, "runs": factors}
        ratio = f"{median / before[name]['median_rtf']:.2f}x" if name in before else ""
        print(f"{name:<12}{median:>12.1f}{min(factors):>8.1f}{max(factors):>8.1f}{ratio:>11}")
    if args.save:
        args.save.write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
