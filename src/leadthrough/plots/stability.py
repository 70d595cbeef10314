"""The stable region of active lead-through over hand stiffness and virtual inertia."""

from __future__ import annotations

from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, NullLocator, ScalarFormatter

from leadthrough.experiments.stability import MARGIN, StabilityMap
from leadthrough.plots import pyplot


def plot_stability_map(result: StabilityMap) -> Figure:
    """One panel per delay: least damping ratio ζ, the ζ = 0 border and the chosen k_M."""
    plt = pyplot()
    figure, axes = plt.subplots(1, len(result.delays), figsize=(5.2 * len(result.delays), 4.2),
                                sharey=True, squeeze=False)  # fmt: skip
    for axis, delay, damping in zip(axes[0], result.delays, result.damping, strict=True):
        mesh = axis.pcolormesh(result.stiffness, result.inertia_scale, damping, cmap="RdYlGn",
                               vmin=-0.3, vmax=0.6, shading="nearest")  # fmt: skip
        axis.contour(result.stiffness, result.inertia_scale, damping, levels=[0.0, MARGIN],
                     colors=["k", "k"], linestyles=["-", "--"])  # fmt: skip
        axis.axhline(
            result.chosen, color="tab:blue", lw=2, label=f"default k_M = {result.chosen:g}"
        )
        axis.axhline(0.3, color="tab:purple", lw=1.5, ls=":", label="previous k_M = 0.3")
        axis.set(xscale="log", yscale="log", xlabel="hand stiffness [N/m]",
                 title=f"command delay {delay} period{'s' if delay > 1 else ''}")  # fmt: skip
        axis.legend(loc="lower right", fontsize=8)
        axis.yaxis.set_major_locator(FixedLocator([0.2, 0.3, 0.5, 1.0, 2.0, 4.0]))
        axis.yaxis.set_minor_locator(NullLocator())
        axis.yaxis.set_major_formatter(ScalarFormatter())
    axes[0][0].set_ylabel("virtual inertia k_M [× M(q)]")
    bar = figure.colorbar(mesh, ax=axes[0].tolist())
    bar.set_label(f"least damping ratio ζ [–] (— ζ = 0, - - ζ = {MARGIN:g})")
    return figure
