"""estimate_payload on UR10e twins with known payloads: error, std and ±3 std coverage.

Each case: a seeded plant (link masses ±5 %, COMs ±5 mm), a payload of 0.5–3 kg with its
centre of mass up to 5 cm off the flange axis and 2–10 cm out, a 20 s Fourier excitation
(±0.4 rad first harmonic). Estimated three ways: with an unloaded run of the same motion
(exact drive gains), with the nominal model alone (exact gains), and with drive gains 8 %
above nominal (default ``gain_error``). Prints each case and the median / worst.

Usage:
    python benchmarks/payload_twin.py [--cases N] [--save out.json]
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

import leadthrough as lt
from leadthrough.experiments.payload_runs import record
from leadthrough.twin.mjcf import Payload
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.sensors import SensorModel

AMPLITUDE = 0.4
EXACT = lt.PayloadParameters(gain_error=0.0)
WAYS = ("unloaded", "alone", "gain +8 %")


def case(robot: lt.RobotDescription, seed: int) -> dict[str, tuple[float, float, float]]:
    """(mass error [kg], mass std [kg], COM error norm [m]) of each way for one seeded case."""
    rng = np.random.default_rng(seed)
    payload = Payload(float(rng.uniform(0.5, 3.0)),
                      (*rng.uniform(-0.05, 0.05, 2), float(rng.uniform(0.02, 0.1))))  # fmt: skip
    error = ModelError(mass_error=0.05, com_error=0.005)
    gains = SensorModel(torque_gain=(1.08,) * robot.n_joints)
    runs = {
        key: record(robot, p, error, seed=seed, motion_seed=seed, amplitude=AMPLITUDE, sensors=s)
        for key, p, s in (("loaded", payload, None), ("empty", None, None),
                          ("loaded_gain", payload, gains), ("empty_gain", None, gains))
    }  # fmt: skip
    estimates = {
        "unloaded": lt.estimate_payload(runs["loaded"], robot, unloaded=runs["empty"],
                                        parameters=EXACT),
        "alone": lt.estimate_payload(runs["loaded"], robot, parameters=EXACT),
        "gain +8 %": lt.estimate_payload(runs["loaded_gain"], robot, unloaded=runs["empty_gain"]),
    }  # fmt: skip
    truth = np.asarray(payload.com)
    return {"mass": payload.mass, **{
        way: (e.mass - payload.mass, e.mass_std, float(np.linalg.norm(e.com - truth)))
        for way, e in estimates.items()}}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=10)
    parser.add_argument("--save", type=Path)
    args = parser.parse_args()
    warnings.simplefilter("ignore", lt.robots.AssumedDriveDataWarning)
    robot = lt.robots.ur10e()
    start = time.perf_counter()
    results = [case(robot, seed) for seed in range(args.cases)]
    print("| case | mass [kg] | " + " | ".join(f"{w}: Δm ± std [kg]" for w in WAYS) + " |")
    print("|---:|---:|" + "---:|" * len(WAYS))
    for k, r in enumerate(results):
        cells = " | ".join(f"{r[w][0]:+.3f} ± {r[w][1]:.3f}" for w in WAYS)
        print(f"| {k} | {r['mass']:.2f} | {cells} |")
    print("\n| way | median \\|Δm\\| [kg] | worst \\|Δm\\| [kg] | median std [kg] | "
          "truth within ±3 std | median COM error [mm] |")  # fmt: skip
    print("|---|---:|---:|---:|---:|---:|")
    for way in WAYS:
        error = np.array([abs(r[way][0]) for r in results])
        std = np.array([r[way][1] for r in results])
        com = np.array([r[way][2] for r in results])
        print(
            f"| {way} | {np.median(error):.3f} | {error.max():.3f} | {np.median(std):.3f} | "
            f"{np.sum(error <= 3 * std)}/{len(results)} | {1000 * np.median(com):.1f} |"
        )
    print(f"\n({time.perf_counter() - start:.0f} s)")
    if args.save:
        args.save.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
