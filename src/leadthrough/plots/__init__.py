"""Figures (matplotlib, imported lazily). Plotting draws what result objects computed."""


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend (no screen needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def label_torque_and_velocity(top, bottom) -> None:
    """Axis labels and grids of a torque-over-velocity pair of panels."""
    bottom.set_xlabel("t [s]")
    top.set_ylabel("torque [Nm]")
    bottom.set_ylabel("velocity [rad/s]")
    for axis in (top, bottom):
        axis.grid(alpha=0.3)
