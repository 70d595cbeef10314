"""Figures of the lead-through experiments, after thesis Figs. 4.8 and 6.4–6.7."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from leadthrough.plots import label_torque_and_velocity, pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from leadthrough.experiments.lead_through import (
        CalibrationCheck,
        EffortComparison,
        EndStopResult,
        GuidedRun,
    )
    from leadthrough.experiments.level_error import LevelErrorTrace


def plot_effort(comparison: EffortComparison, path: str = "line") -> Figure:
    """Fig. 6.7, rigorously: hand force on one path per mode, and RMS force on every path."""
    plt = pyplot()
    figure, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
    for mode, run in comparison.runs[path].items():
        left.plot(run.simulation.t, run.simulation.operator_force, label=f"{mode}")
    left.set_title(f"hand force, {path}")
    left.set_xlabel("t [s]")
    left.set_ylabel("force [N]")
    left.legend()
    paths = list(comparison.runs)
    modes = list(comparison.runs[paths[0]])
    width = 0.8 / len(modes)
    for k, mode in enumerate(modes):
        values = [comparison.runs[p][mode].rms_force for p in paths]
        right.bar(np.arange(len(paths)) + k * width, values, width, label=mode)
    right.set_xticks(np.arange(len(paths)) + width * (len(modes) - 1) / 2, paths)
    right.set_ylabel("RMS hand force [N]")
    right.set_title("the same hand, the same paths")
    right.legend()
    for axis in (left, right):
        axis.grid(alpha=0.3)
    return figure


def plot_feed_forward(run: GuidedRun, joints: tuple[int, ...] = (0, 1, 3)) -> Figure:
    """Fig. 4.8: gravity and friction feed-forward during passive guiding, with velocity."""
    plt = pyplot()
    figure, axes = plt.subplots(len(joints), 1, sharex=True, figsize=(8, 2.4 * len(joints)),
                                constrained_layout=True)  # fmt: skip
    t = run.simulation.t
    for axis, j in zip(np.atleast_1d(axes), joints, strict=True):
        axis.plot(t, run.log["gravity"][:, j], label="gravity")
        axis.plot(t, run.log["friction"][:, j], label="friction compensation")
        axis.set_ylabel(f"joint {j + 1} [Nm]")
        twin = axis.twinx()
        twin.plot(t, run.simulation.qd_true[:, j], color="0.6", lw=0.8)
        twin.set_ylabel("q̇ [rad/s]", color="0.5")
        axis.grid(alpha=0.3)
        axis.legend(fontsize="small", loc="upper left")
    np.atleast_1d(axes)[-1].set_xlabel("t [s]")
    return figure


def plot_damping(runs: dict[str, GuidedRun], joint: int) -> Figure:
    """Figs. 6.4–6.5: high and low virtual damping: torques and velocities of one joint."""
    plt = pyplot()
    figure, axes = plt.subplots(2, len(runs), sharex=True, figsize=(12, 6), constrained_layout=True)
    for column, (label, run) in enumerate(runs.items()):
        sim, log = run.simulation, run.log
        feedback = log["command"][:, joint] - log["gravity"][:, joint] - log["friction"][:, joint]
        top, bottom = axes[0, column], axes[1, column]
        top.plot(sim.t, sim.tau_ext[:, joint], "k", lw=2, label="true operator torque")
        top.plot(sim.t, log["estimate"][:, joint], label="estimate")
        top.plot(sim.t, feedback - log["dither"][:, joint], label="admittance (PD) torque")
        top.set_title(label)
        top.legend(fontsize="small")
        bottom.plot(sim.t, sim.qd_true[:, joint], label="velocity")
        label_torque_and_velocity(top, bottom)
    return figure


def plot_end_stop(results: dict[str, EndStopResult]) -> Figure:
    """Fig. 6.6: a joint pushed into its end-stop and let go, thesis settings vs defaults."""
    plt = pyplot()
    figure, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    for label, result in results.items():
        sim, j = result.simulation, result.joint
        moved = f"{label}: moved {result.travel_after_release:.2f} rad after release"
        axes[0].plot(sim.t, sim.q_true[:, j], label=moved)
        axes[1].plot(sim.t, result.log["estimate"][:, j], label=f"{label}: estimate")
    release = next(iter(results.values())).release
    limit = next(iter(results.values()))
    for axis in axes:
        axis.axvline(release, color="0.5", ls="--")
        axis.grid(alpha=0.3)
        axis.legend(fontsize="small")
    axes[0].set_ylabel(f"joint {limit.joint + 1} angle [rad]")
    axes[1].set_ylabel("estimated torque [Nm]")
    axes[1].set_xlabel("t [s] (dashed: the hand lets go)")
    return figure


def plot_calibration(checks: list[CalibrationCheck]) -> Figure:
    """What the start-up calibration measured against the truth, every plant and joint."""
    plt = pyplot()
    figure, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    for check in checks:
        result = check.calibration
        label = check.plant
        if check.true_payload or result.payload > 0.05:
            label += f" (payload {result.payload:.2f} kg, true {check.true_payload:.2f})"
        measured = (
            np.ones_like(result.friction_scale, bool)
            if result.measured is None
            else result.measured
        )
        # a level not measured keeps the model's (scale 1): no measurement to compare
        left.plot(check.true_friction_scale[measured], result.friction_scale[measured], "o")
        right.plot(check.true_gravity_error, result.gravity_error, "o", label=label)
    for axis, unit in ((left, "[–]"), (right, "[Nm]")):
        low, high = axis.get_xlim()
        axis.plot([low, high], [low, high], "k--", lw=0.8, label="measured = true")
        axis.set_xlabel(f"true {unit}")
        axis.set_ylabel(f"measured {unit}")
        axis.grid(alpha=0.3)
    left.set_title("Coulomb level over the model's, per joint measured")
    right.set_title("gravity error G_model − G_true, per joint")
    right.legend(fontsize=8)
    return figure


def plot_level_error(traces: list[LevelErrorTrace]) -> Figure:
    """A level read at the calibration pose: its true error and the stated one along the travel.

    One panel per plant; per joint the calibration read, solid: how far the plant's
    level is from the calibrated model's, dashed: the error the controller states (the
    readings' scatter at the pose, growing with the travel).
    """
    from matplotlib.lines import Line2D

    plt = pyplot()
    columns = min(len(traces), 2)
    rows = -(-len(traces) // columns)
    figure, axes = plt.subplots(rows, columns, figsize=(6 * columns, 3.6 * rows), sharex=True,
                                sharey=True, constrained_layout=True, squeeze=False)  # fmt: skip
    for axis, trace in zip(axes.flat, traces, strict=False):
        for j in np.flatnonzero(trace.measured):
            color = f"C{j}"  # a joint's colour in every panel
            axis.plot(trace.offsets, 100 * trace.true_error[:, j], lw=1.2, color=color)
            axis.plot(trace.offsets, 100 * trace.stated[:, j], "--", lw=1.0, color=color)
        axis.set_title(f"{trace.plant}: true (solid) and stated (dashed) level error")
        axis.set_xlabel("travel from the calibration pose [rad]")
        axis.set_ylabel("relative error [%]")
        axis.grid(alpha=0.3)
    read = sorted({int(j) for trace in traces for j in np.flatnonzero(trace.measured)})
    handles = [Line2D([], [], color=f"C{j}", label=f"joint {j + 1}") for j in read]
    axes.flat[0].legend(handles=handles, fontsize=8, ncol=2)  # every joint read on any plant
    for axis in list(axes.flat)[len(traces) :]:
        axis.set_visible(False)
    return figure
