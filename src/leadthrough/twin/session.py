"""Run a shipped scenario end to end: simulate, plot, render, summarise; `leadthrough simulate`."""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from leadthrough.control.feedforward import GravityCompensation
from leadthrough.model.description import RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.twin.render import RenderError, render_arm, save_png
from leadthrough.twin.runner import simulate
from leadthrough.twin.scenarios import scenario
from leadthrough.twin.simulator import TwinConfig


def run_scenario(
    robot: RobotDescription, name: str, duration: float | None, seed: int, out: str | Path
) -> str:
    """Simulate scenario ``name`` under gravity feed-forward; write figures; return a summary."""
    chosen = scenario(name, robot, replace(TwinConfig(), seed=seed))
    twin = chosen.twin(robot)
    duration = chosen.duration if duration is None else duration
    start = time.perf_counter()
    result = simulate(twin, GravityCompensation(Dynamics(robot)), duration)
    wall = time.perf_counter() - start
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    figure = result.plot()
    figure.suptitle(f"{chosen.name}: {chosen.description}")
    figure.savefig(out / f"{chosen.name}.png", dpi=120)
    lines = [
        f"scenario {chosen.name}: {chosen.description}",
        f"  simulated {duration:.2f} s in {wall:.2f} s ({duration / wall:.2g}× real time)",
        f"  largest hand force {result.operator_force.max():.1f} N, "
        f"tool travel {np.ptp(result.flange_position, axis=0).max() * 1000:.0f} mm",
        f"  largest true external torque {np.abs(result.tau_ext).max():.2f} Nm",
        f"  plot: {out / (chosen.name + '.png')}",
    ]
    try:
        path = save_png(render_arm(twin.model, twin.data), out / f"{chosen.name}_arm.png")
        lines.append(f"  picture: {path}")
    except RenderError as error:
        lines.append(f"  picture: not rendered ({error})")
    return "\n".join(lines)
