"""Figures of the observer experiments, after thesis Figs. 5.2–5.6."""

from __future__ import annotations

from typing import TYPE_CHECKING

from leadthrough.plots import label_torque_and_velocity, pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from leadthrough.experiments.observer import BreakawayResult, DitherSweep, ObserverRun

_LABELS = {"kalman_time_varying": "Kalman, time-varying", "kalman_two_level": "Kalman, two-level",
           "classical": "classical observer"}  # fmt: skip


def plot_estimate_vs_truth(run: ObserverRun, title: str = "") -> Figure:
    """Fig. 5.2: true external torque, each estimate (±2 std for the Kalman one), velocity."""
    plt = pyplot()
    j, sim = run.joint, run.simulation
    figure, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    best = run.estimates["kalman_time_varying"][:, j]
    band = 2.0 * run.stds["kalman_time_varying"][:, j]
    top.fill_between(sim.t, best - band, best + band, color="tab:blue", alpha=0.15,
                     label="±2 std (time-varying)")  # fmt: skip
    top.plot(sim.t, sim.tau_ext[:, j], color="k", lw=2, label="true τ_ext")
    for name, estimate in run.estimates.items():
        top.plot(sim.t, estimate[:, j], label=_LABELS.get(name, name))
    top.set_ylabel(f"joint {j + 1} torque [Nm]")
    top.legend(fontsize="small", ncols=2)
    bottom.plot(sim.t, sim.qd_true[:, j], color="tab:green")
    bottom.set_ylabel("velocity [rad/s]")
    bottom.set_xlabel("t [s]")
    for axis in (top, bottom):
        axis.grid(alpha=0.3)
    top.set_title(title or f"Joint {j + 1}: estimated against true external torque")
    return figure


def plot_breakaway(result: BreakawayResult) -> Figure:
    """Figs. 5.5–5.6: a rising push without and with dither: torques, estimate, velocity."""
    plt = pyplot()
    figure, axes = plt.subplots(2, 2, sharex=True, figsize=(11, 6), constrained_layout=True)
    for column, key in enumerate(("no_dither", "dither")):
        run = result.runs[key]
        j, sim = run.joint, run.simulation
        top, bottom = axes[0, column], axes[1, column]
        top.plot(sim.t, sim.tau_ext[:, j], color="k", lw=2, label="true push")
        top.plot(sim.t, run.estimates["kalman_time_varying"][:, j], label="Kalman estimate")
        top.plot(sim.t, run.dither[:, j], color="0.6", lw=0.8, label="dither torque")
        top.axhline(result.breakaway[key], color="tab:red", ls="--",
                    label=f"breakaway {result.breakaway[key]:.2f} Nm")  # fmt: skip
        top.set_title(f"joint {j + 1}, {key.replace('_', ' ')}")
        top.legend(fontsize="small")
        bottom.plot(sim.t, sim.qd_true[:, j], color="tab:green")
        label_torque_and_velocity(top, bottom)
    return figure


def plot_dither_sweep(sweep: DitherSweep) -> Figure:
    """Figs. 5.3–5.4: velocity noise and tool vibration against dither frequency.

    The vibration is the thesis' 6-norm (eq. 5.21) of the flange's linear acceleration
    [m/s²] and the wrist joints' angular accelerations [rad/s²], mixed as there.
    """
    plt = pyplot()
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    left.plot(sweep.frequencies, sweep.velocity_noise * 1e3, "o-")
    left.set_ylabel("RMS joint velocity at rest [mrad/s]")
    right.plot(sweep.frequencies, sweep.tool_vibration, "o-", color="tab:red")
    right.set_ylabel("RMS ‖a‖₆, eq. 5.21 [m/s² and rad/s², mixed]")
    for axis in (left, right):
        axis.set_xlabel("dither frequency [Hz]")
        axis.grid(alpha=0.3)
    return figure
