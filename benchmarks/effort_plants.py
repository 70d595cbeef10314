"""Operator effort of active over passive mode on every plant of the robustness table.

The defaults are judged on plants that are not the twin they were developed on: each
plant's hand force RMS in active mode over that in passive mode, the same hand on the same
paths, friction identified on the realistic twin; then the realistic twin with other seeds
(other mass and centre-of-mass errors, other sensor noise).

Usage:
    python benchmarks/effort_plants.py
"""

from __future__ import annotations

from dataclasses import replace

import leadthrough as lt
from leadthrough.experiments.friction_study import run_friction_study
from leadthrough.experiments.lead_through import PATHS, PLANTS, guided_run
from leadthrough.twin.presets import REALISTIC_TWIN


def main() -> None:
    robot = lt.robots.yumi()
    friction = run_friction_study(robot, twin_config=REALISTIC_TWIN).model
    print(f"{'plant':<36}" + "".join(f"{path:>16}" for path in PATHS))
    seeds = {f"realistic, twin seed {seed}": replace(REALISTIC_TWIN, seed=seed) for seed in (2, 3)}
    for name, config in {**PLANTS, **seeds}.items():
        ratios = []
        for path in PATHS:
            active = guided_run(robot, path, "active", friction, config).rms_force
            ratios.append(active / guided_run(robot, path, "passive", friction, config).rms_force)
        print(f"{name:<36}" + "".join(f"{ratio:>16.2f}" for ratio in ratios), flush=True)


if __name__ == "__main__":
    main()
