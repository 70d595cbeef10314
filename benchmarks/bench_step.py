"""Time of one LeadThrough.step for the YuMi against the model calls it needs, in one run.

Each period the step gets a new pose (every joint swings ±0.3 rad at its own phase and
0.2 Hz, the velocities noisy); right after it, the model calls a step cannot do without
are timed at the same state: G(q), M(q), Cᵀ(q, q̇) q̇ and the TCP Jacobian (public
``Dynamics`` methods). Interleaving them makes the ratio step / model robust to the
machine's load, and so does the p99 of the step's CPU time (this process's, without
the time other processes took; the wall-clock p99 is what a loop would have met).
Passive, active (calibrate=False, the description's friction), active with two
virtual constraints, and active with the compensation following the push (the path of an
arm whose start-up calibration was accepted, ``follow_push``). Then the start-up
calibration on a sampled plant (dry #1 of ``benchmarks/guiding_quality.py``) at 250 Hz and
1 kHz: the median of its periods and its last one, which reads the run and rebuilds the
model (wall clock, a warmed-up controller).

Usage:
    python benchmarks/bench_step.py [--calls N] [--save FILE] [--compare FILE]
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

import leadthrough as lt
from leadthrough.control.constraints import Box, Plane
from leadthrough.friction.compensation import CoulombCompensationParameters
from leadthrough.logs.sample import JointState
from leadthrough.safety.supervisor import SupervisorState
from leadthrough.twin.plants import sample_plant
from leadthrough.twin.simulator import DigitalTwin
from timing import parser, report

#: The compensation following the push, as it does once a start-up calibration is accepted.
FOLLOWING = lt.LeadThroughParameters(
    compensation=CoulombCompensationParameters(follow_push="always")
)
CONSTRAINTS = (Plane(point=(0.3, 0.0, 0.0), normal=(0.0, 0.0, 1.0)),
               Box(lower=(-1.0, -1.0, -1.0), upper=(1.0, 1.0, 1.0)))  # fmt: skip


def timed(controller: lt.LeadThrough, calls: int, warmup: int = 200) -> dict:
    """Median and p99 [µs] of the step and of its model calls, and their ratio."""
    robot, dynamics = controller.robot, lt.Dynamics(controller.robot)
    rng = np.random.default_rng(0)
    home, phases = robot.home(), np.linspace(0.0, 2.0 * np.pi, robot.n_joints, endpoint=False)
    omega, clock, cpu_clock = 2.0 * np.pi * 0.2, time.perf_counter_ns, time.process_time_ns
    tau = dynamics.gravity(home)
    step_ns, model_ns, cpu_ns = np.empty(calls), np.empty(calls), np.empty(calls)
    for k in range(warmup + calls):
        t = controller.dt * (k + 1)
        q = home + 0.3 * np.sin(omega * t + phases)
        qd = 0.3 * omega * np.cos(omega * t + phases) + 1e-4 * rng.standard_normal(robot.n_joints)
        sample = JointState(t, q, qd, tau)
        cpu, start = cpu_clock(), clock()
        controller.step(sample)
        middle, cpu_end = clock(), cpu_clock()
        dynamics.gravity(q)
        dynamics.mass(q)
        dynamics.coriolis_transpose_times_velocity(q, qd)
        dynamics.tool_jacobian(q)
        end = clock()
        if k >= warmup:
            step_ns[k - warmup], model_ns[k - warmup] = middle - start, end - middle
            cpu_ns[k - warmup] = cpu_end - cpu
    if controller.state is SupervisorState.FAULT:
        raise SystemExit(f"the benchmark faulted: {controller.supervisor.fault_reason}")
    step, model = step_ns / 1e3, model_ns / 1e3
    return {"median_us": float(np.median(step)), "p99_us": float(np.percentile(step, 99)),
            "mean_us": float(np.mean(step)), "model_median_us": float(np.median(model)),
            "ratio": float(np.median(step) / np.median(model)),
            "cpu_p99_us": float(np.percentile(cpu_ns / 1e3, 99)), "calls": calls}  # fmt: skip


def calibration_periods(robot: lt.RobotDescription, dt: float) -> tuple[float, float]:
    """Median period of the start-up calibration and its last one [µs], on dry #1's twin."""
    controller = lt.LeadThrough(robot, "active", dt=dt, calibrate=True)
    controller.warm_up()
    plant = sample_plant(robot, 1, "dry")
    twin = DigitalTwin(robot, replace(plant.config, control_dt=dt))
    periods = []
    while controller.calibrating:
        state = twin.read_state()
        start = time.perf_counter_ns()
        command = controller.step(state)
        periods.append((time.perf_counter_ns() - start) / 1e3)
        twin.send_torque(command)
    return float(np.median(periods[:-1])), periods[-1]


def main() -> None:
    args = parser(__doc__.splitlines()[0]).parse_args()
    robot = lt.robots.yumi()
    controllers = {
        "step, passive": lt.LeadThrough(robot, "passive"),
        "step, active": lt.LeadThrough(robot, "active"),
        "step, active, 2 constraints": lt.LeadThrough(robot, "active", constraints=CONSTRAINTS),
        # a calibrated arm's path: the compensation follows the push (follow_push)
        "step, active, following the push": lt.LeadThrough(robot, "active", parameters=FOLLOWING),
    }
    results = {name: timed(controller, args.calls) for name, controller in controllers.items()}
    print(f"{robot.name}, {args.calls} steps each at varying poses, one thread")
    report(results, args.save, args.compare)
    print(f"\n{'':<36}{'model [µs]':>13}{'step / model':>14}{'p99, CPU [µs]':>15}")
    for name, stats in results.items():
        print(f"{name:<36}{stats['model_median_us']:>13.2f}{stats['ratio']:>13.1f}×"
              f"{stats['cpu_p99_us']:>15.1f}")  # fmt: skip
    worst = max(stats["p99_us"] for stats in results.values())
    print(f"a 1 kHz loop leaves {1000.0 / worst:.1f}× the worst p99 step time")
    for rate in (250, 1000):
        median, last = calibration_periods(robot, 1.0 / rate)
        print(
            f"start-up calibration at {rate} Hz: median period {median:.0f} µs, "
            f"its last {last / 1e3:.2f} ms"
        )


if __name__ == "__main__":
    main()
