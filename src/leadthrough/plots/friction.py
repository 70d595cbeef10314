"""Figures of the friction identification, after thesis Figs. 4.2, 4.3, 4.5 and 4.6."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from leadthrough.plots import pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from leadthrough.experiments.friction_study import FrictionStudy


def plot_raw_and_compensated(study: FrictionStudy, joint: int) -> Figure:
    """Fig. 4.2: raw motor torque against raw velocity, and the filtered friction torque."""
    plt = pyplot()
    qd_raw, tau_raw = study.raw_samples(joint)
    _, qd, tau_f = study.joint_samples(joint)
    figure, axis = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    axis.plot(qd_raw, tau_raw, ".", ms=1.5, color="tab:blue", label="raw motor torque")
    axis.plot(qd, tau_f, ".", ms=1.5, color="tab:red",
              label="filtered, gravity and inertia removed")  # fmt: skip
    _finish(axis, f"Joint {joint + 1}: identification data", "torque [Nm]")
    return figure


def plot_sigmoid_fit(study: FrictionStudy, joint: int) -> Figure:
    """Fig. 4.3: friction torque and the two fitted sigmoids τ_f,max and τ_f,min."""
    plt = pyplot()
    _, qd, tau_f = study.joint_samples(joint)
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    zoom = 8.0 * (study.model.half_width[joint] + 4.0 / study.model.slope[joint])
    for axis, limit in zip(axes, (None, zoom), strict=True):
        grid = np.linspace(-limit, limit, 801) if limit else np.linspace(qd.min(), qd.max(), 801)
        curves = study.model_curves(joint, grid)
        axis.plot(qd, tau_f, ".", ms=1.5, color="0.6", label="measured friction")
        axis.plot(grid, curves["upper"], color="tab:red", label="τ_f,max (4.2)")
        axis.plot(grid, curves["lower"], color="tab:orange", label="τ_f,min (4.3)")
        if limit is not None:
            axis.set_xlim(-limit, limit)
        _finish(axis, f"Joint {joint + 1}: fitted sigmoids" + (" (zoom)" if limit else ""),
                "friction torque [Nm]")  # fmt: skip
    return figure


def plot_gaussian_model(study: FrictionStudy, joint: int) -> Figure:
    """Fig. 4.5: the Gaussian friction model, mean ± 2 std against velocity."""
    plt = pyplot()
    limit = 20.0 * (study.model.half_width[joint] + 4.0 / study.model.slope[joint])
    grid = np.linspace(-limit, limit, 2001)
    curves = study.model_curves(joint, grid)
    figure, axis = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    axis.fill_between(grid, curves["mean"] - 2 * curves["std"], curves["mean"] + 2 * curves["std"],
                      color="tab:red", alpha=0.2, label="mean ± 2 std")  # fmt: skip
    axis.plot(grid, curves["mean"], color="tab:blue", label="mean (4.4)")
    axis.plot(grid, curves["std"], color="tab:red", label="std: sqrt(v_C² + σ²) (4.5)")
    _finish(axis, f"Joint {joint + 1}: friction as a Gaussian variable", "torque [Nm]")
    return figure


def plot_position_dependence(study: FrictionStudy, joint: int) -> Figure:
    """Fig. 4.6: Coulomb part of the sliding friction against position, and τ_C(q)."""
    plt = pyplot()
    q, qd, tau_f = study.joint_samples(joint)
    sliding = np.abs(qd) > 0.04
    coulomb_part = (tau_f - study.model.viscous[joint] * qd)[sliding]
    grid = np.linspace(q.min(), q.max(), 400)
    level = study.coulomb_over_position(joint, grid)
    figure, axis = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    axis.plot(q[sliding], coulomb_part, ".", ms=1.5, color="0.6", label="τ_f − c q̇, sliding")
    axis.plot(grid, level, color="tab:red", label="identified ±τ_C(q)")
    axis.plot(grid, -level, color="tab:red")
    axis.set_xlabel("joint position [rad]")
    axis.set_ylabel("Coulomb friction [Nm]")
    axis.set_title(f"Joint {joint + 1}: position dependence (cable effect)")
    axis.grid(alpha=0.3)
    axis.legend(fontsize="small")
    return figure


def _finish(axis, title: str, ylabel: str) -> None:
    axis.set_xlabel("joint velocity [rad/s]")
    axis.set_ylabel(ylabel)
    axis.set_title(title)
    axis.grid(alpha=0.3)
    axis.legend(fontsize="small", markerscale=6)
