"""Real-time factor of the closed loop on the twin: simulated seconds per wall second.

The YuMi twin (physics at 2 kHz, control at 250 Hz, LuGre friction, sensors, ground
truth, logging) against a trivial controller (gravity feed-forward) with nobody touching
the arm (``idle``) and with a hand pulling the tool along a line (``line``); then the
whole stack: active lead-through on the line at 250 Hz and at 1 kHz (dt = 1 ms). The
column ``MuJoCo`` is the real-time factor of the bare ``mj_step`` loop of the same model,
measured in the same run: the ceiling of any Python around it; ``CPU RTF`` counts this
process's CPU time instead of the wall clock (robust to other processes' load). Median of
several runs.

Usage:
    python benchmarks/bench_twin.py [--runs N] [--seconds S] [--save FILE] [--compare FILE]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from dataclasses import replace
from pathlib import Path

import mujoco

import leadthrough as lt
from leadthrough.control.feedforward import GravityCompensation
from leadthrough.twin.runner import simulate
from leadthrough.twin.scenarios import scenario
from leadthrough.twin.simulator import DigitalTwin

#: name: (scenario, controller, control period [s])
RUNS = {
    "idle": ("idle", "gravity", 0.004),
    "line": ("line", "gravity", 0.004),
    "line, active lead-through": ("line", "active", 0.004),
    "line, active lead-through, 1 kHz": ("line", "active", 0.001),
}


def twin_for(name: str, robot: lt.RobotDescription) -> DigitalTwin:
    """The twin of run ``name``, its control period set."""
    chosen_scenario, _, dt = RUNS[name]
    chosen = scenario(chosen_scenario, robot)
    return DigitalTwin(robot, replace(chosen.config, control_dt=dt), chosen.operator, chosen.q0)


def real_time_factor(name: str, seconds: float, robot: lt.RobotDescription) -> tuple[float, float]:
    """Simulated seconds per wall second, and per CPU second, of one closed-loop run ``name``.

    The CPU-time factor leaves out what other processes took from this one: on a loaded
    machine it is what the code costs, the wall-time factor what it got.
    """
    _, kind, dt = RUNS[name]
    twin = twin_for(name, robot)
    controller = (GravityCompensation(lt.Dynamics(robot)) if kind == "gravity"
                  else lt.LeadThrough(robot, kind, dt=dt))  # fmt: skip
    start, cpu = time.perf_counter(), time.process_time()
    simulate(twin, controller, seconds, progress=False)
    return seconds / (time.perf_counter() - start), seconds / (time.process_time() - cpu)


def physics_factor(seconds: float, robot: lt.RobotDescription) -> float:
    """Real-time factor of ``mj_step`` alone on the line scenario's model."""
    twin = twin_for("line", robot)
    steps = round(seconds / twin.config.physics_dt)
    model, data, step = twin.model, twin.data, mujoco.mj_step
    start = time.perf_counter()
    for _ in range(steps):
        step(model, data)
    return seconds / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated time per run")
    parser.add_argument("--save", type=Path)
    parser.add_argument("--compare", type=Path)
    args = parser.parse_args()
    robot = lt.robots.yumi()
    for name in RUNS:  # warm-up: JIT-compiled kernels, caches
        real_time_factor(name, 0.1, robot)
    before = json.loads(args.compare.read_text()) if args.compare else {}
    results = {}
    print(f"{'run':<36}{'median RTF':>12}{'min':>8}{'max':>8}{'CPU RTF':>9}{'MuJoCo':>8}"
          f"{'vs before':>11}")  # fmt: skip
    for name in RUNS:
        factors, cpu_factors, ceilings = [], [], []
        for _ in range(args.runs):  # interleaved: the machine's load hits both alike
            wall, cpu = real_time_factor(name, args.seconds, robot)
            factors.append(wall)
            cpu_factors.append(cpu)
            ceilings.append(physics_factor(min(args.seconds, 1.0), robot))
        median = statistics.median(factors)
        results[name] = {"median_rtf": median, "runs": factors,
                         "cpu_rtf": statistics.median(cpu_factors),
                         "mujoco_rtf": statistics.median(ceilings)}  # fmt: skip
        ratio = f"{median / before[name]['median_rtf']:.2f}x" if name in before else ""
        print(f"{name:<36}{median:>12.1f}{min(factors):>8.1f}{max(factors):>8.1f}"
              f"{results[name]['cpu_rtf']:>9.1f}{results[name]['mujoco_rtf']:>8.0f}"
              f"{ratio:>11}")  # fmt: skip
    if args.save:
        args.save.parent.mkdir(parents=True, exist_ok=True)
        args.save.write_text(json.dumps(results, indent=2))
        print(f"saved to {args.save}")


if __name__ == "__main__":
    main()
