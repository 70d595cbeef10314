"""Figures of identification on real logs: friction per joint, torque on a held-out run."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from leadthrough.plots import pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Data points drawn per panel at most (the rest thinned evenly).
_MAX_POINTS = 4000


def plot_joint_friction(
    panels: Sequence[tuple[str, np.ndarray, np.ndarray, Mapping[str, tuple]]], title: str
) -> Figure:
    """One panel per joint: friction samples over velocity and each model's curve.

    Args:
        panels: Per joint ``(label, q̇ [rad/s], τ_f [Nm], {model: (q̇ grid, τ [Nm])})``.
        title: Figure title.
    """
    plt = pyplot()
    columns = 3 if len(panels) > 4 else 2
    rows = int(np.ceil(len(panels) / columns))
    figure, axes = plt.subplots(rows, columns, figsize=(4.2 * columns, 3.2 * rows),
                                constrained_layout=True, squeeze=False)  # fmt: skip
    for axis, (label, qd, tau, curves) in zip(axes.flat, panels, strict=False):
        step = max(1, len(qd) // _MAX_POINTS)
        axis.plot(qd[::step], tau[::step], ".", ms=1.2, color="0.6", label="data")
        for (name, (grid, curve)), style in zip(curves.items(), ("-", "--", ":"), strict=False):
            axis.plot(grid, curve, style, lw=1.6, label=name)
        axis.set_title(label)
        axis.set_xlabel("q̇ [rad/s]")
        axis.set_ylabel("friction torque [Nm]")
        axis.grid(alpha=0.3)
    for axis in list(axes.flat)[len(panels) :]:
        axis.set_visible(False)
    axes.flat[0].legend(fontsize=8)
    figure.suptitle(title)
    return figure


def plot_torque_prediction(
    t: np.ndarray, measured: np.ndarray, predicted: Mapping[str, np.ndarray], title: str
) -> Figure:
    """Measured joint torque and each model's prediction over time, one panel per joint.

    Args:
        t: Times [s], (N,).
        measured: Measured torque [Nm], (N, n).
        predicted: Model name → predicted torque [Nm], (N, n), in the log's units.
        title: Figure title.
    """
    plt = pyplot()
    n = measured.shape[1]
    figure, axes = plt.subplots(n, 1, figsize=(9, 1.7 * n + 0.8), sharex=True,
                                constrained_layout=True)  # fmt: skip
    time = t - t[0]
    for j, axis in enumerate(np.atleast_1d(axes)):
        axis.plot(time, measured[:, j], color="0.55", lw=1.0, label="measured")
        for name, values in predicted.items():
            axis.plot(time, values[:, j], lw=1.0, label=name)
        axis.set_ylabel(f"τ{j + 1} [Nm]")
        axis.grid(alpha=0.3)
    np.atleast_1d(axes)[0].legend(fontsize=8, ncol=len(predicted) + 1, loc="upper right")
    np.atleast_1d(axes)[-1].set_xlabel("t [s]")
    figure.suptitle(title)
    return figure
