"""Figure of the observer over a recorded log: τ̂_ext with its ±2 std band and contacts."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from leadthrough.plots import pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from leadthrough.estimation.contacts import ContactEvent
    from leadthrough.estimation.log_observer import ObservedLog


def plot_observed_log(
    observed: ObservedLog, events: Sequence[ContactEvent], title: str = ""
) -> Figure:
    """One small panel per joint: τ̂_ext [Nm] over time [s], ±2 std, contacts shaded.

    Time is from the log's first sample; each detected contact is shaded on every panel
    and outlined in red on the joints that crossed the threshold.
    """
    plt = pyplot()
    n = observed.tau_ext.shape[1]
    columns = 2 if n > 3 else 1
    rows = int(np.ceil(n / columns))
    figure, axes = plt.subplots(rows, columns, figsize=(6.5 * columns, 1.9 * rows + 0.8),
                                sharex=True, constrained_layout=True, squeeze=False)  # fmt: skip
    t = observed.t - observed.t[0]
    band = 2.0 * observed.std
    for joint, axis in enumerate(axes.flat):
        if joint >= n:  # an empty slot: the panel above it gets the time axis
            axis.set_visible(False)
            above = axes.flat[joint - columns]
            above.tick_params(labelbottom=True)
            above.set_xlabel("time from the log's start [s]")
            continue
        estimate = observed.tau_ext[:, joint]
        axis.fill_between(t, estimate - band[:, joint], estimate + band[:, joint],
                          color="tab:blue", alpha=0.2, lw=0, label="τ̂_ext ± 2 std")  # fmt: skip
        axis.plot(t, estimate, color="tab:blue", lw=0.9, label="τ̂_ext")
        for event in events:
            start, end = event.start - observed.t[0], event.end - observed.t[0]
            hit = joint in event.joints
            axis.axvspan(start, end, color="tab:red" if hit else "0.6",
                         alpha=0.25 if hit else 0.12, lw=0)  # fmt: skip
        axis.axhline(0.0, color="0.3", lw=0.5)
        axis.set_ylabel(f"joint {joint + 1} [Nm]")
        axis.grid(alpha=0.3)
    for axis in axes[-1]:
        axis.set_xlabel("time from the log's start [s]")
    axes.flat[0].legend(loc="upper right", fontsize=8)
    figure.suptitle(title or "estimated external torque, contacts shaded (red: joint involved)")
    return figure
