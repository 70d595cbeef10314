"""Figures of twin runs (matplotlib, imported lazily). Plotting never computes."""

from __future__ import annotations

from typing import TYPE_CHECKING

from leadthrough.plots import pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from leadthrough.twin.runner import SimulationResult


def plot_simulation(result: SimulationResult, joints: list[int] | None = None) -> Figure:
    """Joint angles, true external torque and operator force against time.

    Args:
        result: A closed-loop run.
        joints: 0-based joints to show (default: all).
    """
    plt = pyplot()
    joints = list(range(result.q.shape[1])) if joints is None else joints
    figure, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 7), constrained_layout=True)
    for j in joints:
        axes[0].plot(result.t, result.q_true[:, j], label=f"joint {j + 1}")
        axes[1].plot(result.t, result.tau_ext[:, j], label=f"joint {j + 1}")
    axes[2].plot(result.t, result.operator_force, color="k")
    axes[0].set_ylabel("q [rad]")
    axes[1].set_ylabel("true τ_ext [Nm]")
    axes[2].set_ylabel("hand force [N]")
    axes[2].set_xlabel("t [s]")
    axes[0].legend(ncols=4, fontsize="small")
    for axis in axes:
        axis.grid(alpha=0.3)
    return figure
