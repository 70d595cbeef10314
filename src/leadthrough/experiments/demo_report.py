"""The demo's report: Markdown with PNG figures (plots draw, the demo computed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from leadthrough.experiments.demo import (
    DemoResult,
    figures_by_action,
    hand_force_rms,
    hands_on_tool,
    intended_position,
    path_smoothness,
    teaching_actions,
)
from leadthrough.model.description import RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.plots import pyplot
from leadthrough.twin.operator import HandParameters
from leadthrough.twin.session_operator import TeachingSession


def write_report(result: DemoResult, robot: RobotDescription, out: Path) -> Path:
    """Write ``out/report.md`` and its figures; return the report's path."""
    plt = pyplot()
    figures = {
        "tool_paths.png": _tool_paths(result, robot),
        "operator_torque.png": _operator_torque(result),
        "operator_effort.png": _effort(result, robot),
    }
    for name, figure in figures.items():
        figure.savefig(out / name, dpi=100)
        plt.close(figure)
    picture = _picture(result, robot, out / "arm.png")
    report = out / "report.md"
    report.write_text(_markdown(result, picture, robot), encoding="utf-8")
    return report


def _tool_paths(result: DemoResult, robot: RobotDescription):
    plt = pyplot()
    taught = result.taught.flange_position
    replayed = result.replayed.flange_position
    meant = intended_position(result.taught, teaching_actions(robot))
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.8), constrained_layout=True)
    for axis, (i, j, label) in zip(axes, ((0, 1, "top view (x, y)"), (1, 2, "side view (y, z)")),
                                   strict=True):  # fmt: skip
        axis.plot(meant[:, i], meant[:, j], color="0.55", lw=1.0, ls=":",
                  label="where the hands pulled (each from where the tool was)")  # fmt: skip
        axis.plot(taught[:, i], taught[:, j], lw=2.5, label="taught (operator guiding)")
        axis.plot(replayed[:, i], replayed[:, j], "--", label="replayed")
        axis.set_title(label)
        axis.set_xlabel("xyz"[i] + " [m]")
        axis.set_ylabel("xyz"[j] + " [m]")
        axis.axis("equal")
        axis.grid(alpha=0.3)
        axis.legend(fontsize="small")
    return figure


def _operator_torque(result: DemoResult):
    """Every joint's true and estimated operator torque, small multiples in two columns."""
    plt = pyplot()
    sim = result.taught
    n = sim.tau_ext.shape[1]
    rows = (n + 1) // 2
    figure, axes = plt.subplots(rows, 2, sharex=True, figsize=(12, 2.2 * rows),
                                constrained_layout=True, squeeze=False)  # fmt: skip
    for j, axis in enumerate(axes.flat):
        if j >= n:
            axis.set_visible(False)
            continue
        estimate, band = result.estimate[:, j], 2.0 * result.estimate_std[:, j]
        axis.fill_between(sim.t, estimate - band, estimate + band, color="tab:blue", alpha=0.15,
                          label="±2 std (how far the estimate may be off)")  # fmt: skip
        axis.plot(sim.t, sim.tau_ext[:, j], "k", lw=1.5, label="true (operator + table)")
        axis.plot(sim.t, estimate, color="tab:blue", label="estimated from motor torques")
        axis.set_ylim(np.percentile(sim.tau_ext[:, j], 0.5) - 1.5,
                      np.percentile(sim.tau_ext[:, j], 99.5) + 1.5)  # fmt: skip
        axis.set_ylabel(f"joint {j + 1} [Nm]")
        axis.grid(alpha=0.3)
    axes[0, 0].legend(fontsize="small")
    for axis in axes[-1]:
        axis.set_xlabel("t [s]")
    if n % 2 and rows > 1:  # an empty last cell: the plot above it carries the time axis
        axes[-2, 1].xaxis.set_tick_params(labelbottom=True)
        axes[-2, 1].set_xlabel("t [s]")
    return figure


def _effort(result: DemoResult, robot: RobotDescription):
    plt = pyplot()
    sim, passive = result.taught, result.passive
    figure, axis = plt.subplots(figsize=(10, 3.5), constrained_layout=True)
    axis.plot(passive.t, passive.operator_force, color="tab:gray", lw=1.0,
              label="the same session, passive mode")  # fmt: skip
    axis.plot(sim.t, sim.operator_force, color="k", label="active lead-through (taught)")
    axis.legend(fontsize="small", loc="center left")
    for action in teaching_actions(robot):
        axis.axvspan(action.start, action.stop, alpha=0.1)
        axis.text(action.start, axis.get_ylim()[1] * 0.9, action.label, fontsize="small")
    axis.set_xlabel("t [s]")
    axis.set_ylabel("operator's hand force [N]")
    axis.grid(alpha=0.3)
    return figure


def _picture(result: DemoResult, robot: RobotDescription, path: Path) -> str:
    """A rendered picture of the arm mid-teaching, or why there is none."""
    from leadthrough.twin.mjcf import TableSurface
    from leadthrough.twin.render import RenderError, render_arm, save_png
    from leadthrough.twin.simulator import DigitalTwin, TwinConfig

    middle = len(result.taught.t) // 2
    flange = Dynamics(robot).pose(robot.home())[:3, 3]
    twin = DigitalTwin(robot, TwinConfig(table=TableSurface(flange[2] - 0.12)),
                       q0=result.taught.q_true[middle])  # fmt: skip
    try:
        save_png(render_arm(twin.model, twin.data, lookat=tuple(flange - [0.1, 0.0, 0.1])), path)
    except RenderError as error:
        return f"(no picture: {error})"
    return f"![the arm mid-teaching]({path.name})"


def _first_hand(result: DemoResult, robot: RobotDescription) -> HandParameters:
    """The impedance of the session's first hand on the tool."""
    for _, hand, _ in hands_on_tool(result.taught, teaching_actions(robot)):
        return hand.parameters
    raise ValueError("the teaching session has no hand on the tool")


def _markdown(result: DemoResult, picture: str, robot: RobotDescription) -> str:
    name = robot.name
    errors, sim = result.replay_error, result.taught
    smooth = path_smoothness(sim, teaching_actions(robot))
    hand = _first_hand(result, robot)
    passive = path_smoothness(result.passive, teaching_actions(robot))
    force, passive_force = hand_force_rms(sim), hand_force_rms(result.passive)
    events = [e for e in result.events if e[1] not in ("mode",)]
    event_lines = "\n".join(f"| {t:.2f} | {kind} | {detail} |" for t, kind, detail in events[:20])
    seconds = ", ".join(f"{name} {value:.1f} s" for name, value in result.seconds.items())
    return f"""# leadthrough demo: teaching the simulated {name} by hand

A simulated operator guides the {name} twin with **active lead-through**: the controller
sees only motor torques and encoders; the operator's torques are estimated by the
momentum Kalman observer. The session was recorded to `{result.recording_path.name}`
(MCAP: open it in Foxglove) and replayed.

{picture}

## Replay
Joint RMS error **{1000 * errors["joint_rms"]:.2f} mrad**
(max {1000 * errors["joint_max"]:.2f} mrad),
tool path RMS error **{1000 * errors["tool_rms"]:.2f} mm**.

![tool paths](tool_paths.png)

Dotted: the path each hand pulled the tool along, from where the tool was when it took it.
A hand is a spring of {hand.stiffness:.0f} N/m with a damper: where the taught path is off
its path, it pulls harder, {hand.stiffness / 100:.0f} N per cm. The press aims
{100 * TeachingSession.press_depth:.0f} cm past the table's top, which stops the tool.

## What the operator did, and what the robot estimated
![operator torque](operator_torque.png)

Estimation error over the session (all joints, moving samples): RMS
{_estimation_rms(result):.3f} Nm.

![effort](operator_effort.png)

Operator's hand force: RMS **{force:.2f} N**, peak {sim.operator_force.max():.1f} N; the
same session guided in passive mode (the thesis' gravity and friction compensation, no
observer in the loop): RMS {passive_force:.2f} N, peak {result.passive.operator_force.max():.1f} N
(active / passive **{force / passive_force:.2f}**).

Smoothness of the taught path: tool velocity above 4 Hz, RMS over the session,
**{1e3 * smooth["taught"]:.1f} mm/s** against {1e3 * smooth["intended"]:.1f} mm/s in the
paths the operator's hand followed (RMS tool speed {1e3 * smooth["speed"]:.0f} mm/s);
passive mode {1e3 * passive["taught"]:.1f} mm/s. Action by action (the same figures over
each action's time; hand force RMS over it):

{_action_table(result, robot)}

## Supervisor events
| t [s] | kind | detail |
|---|---|---|
{event_lines or "| – | – | none |"}

Wall time: {seconds}. Friction identified first and saved to `friction.toml`.
"""


def _action_table(result: DemoResult, robot: RobotDescription) -> str:
    """Smoothness and effort of each action, active against passive (Markdown table)."""
    actions = teaching_actions(robot)
    active = figures_by_action(result.taught, actions)
    passive = figures_by_action(result.passive, actions)
    rows = [f"| {a.label} | {1e3 * a.vibration:.1f} | {1e3 * p.vibration:.1f} | "
            f"{1e3 * a.intended:.2f} | {a.force:.1f} | {p.force:.1f} |"
            for a, p in zip(active, passive, strict=True)]  # fmt: skip
    header = ("| what the hand did | above 4 Hz, active [mm/s] | passive [mm/s] | "
              "the hand's path [mm/s] | hand force, active [N] | passive [N] |\n"
              "|---|---:|---:|---:|---:|---:|")  # fmt: skip
    return "\n".join([header, *rows])


def _estimation_rms(result: DemoResult) -> float:
    sim = result.taught
    moving = np.abs(sim.qd_true) > 0.01
    error = (result.estimate - sim.tau_ext)[moving]
    return float(np.sqrt(np.mean(error**2))) if error.size else float("nan")
