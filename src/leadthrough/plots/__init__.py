"""Figures (matplotlib, imported lazily). Plotting draws what result objects computed."""


def pyplot():
    """matplotlib.pyplot; on Agg (files only, no screen needed) unless a backend was chosen.

    A backend chosen by the user (a notebook's, ``MPLBACKEND``, ``matplotlib.use``, a
    matplotlibrc) is kept: only where matplotlib would pick one itself is Agg selected.
    """
    import matplotlib

    if not _backend_chosen(matplotlib):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _backend_chosen(matplotlib) -> bool:
    """Whether matplotlib's backend was chosen already (without making it choose one)."""
    try:
        return matplotlib.get_backend(auto_select=False) is not None  # matplotlib ≥ 3.10
    except TypeError:
        return matplotlib.rcParams._get_backend_or_none() is not None


def label_torque_and_velocity(top, bottom) -> None:
    """Axis labels and grids of a torque-over-velocity pair of panels."""
    bottom.set_xlabel("t [s]")
    top.set_ylabel("torque [Nm]")
    bottom.set_ylabel("velocity [rad/s]")
    for axis in (top, bottom):
        axis.grid(alpha=0.3)
