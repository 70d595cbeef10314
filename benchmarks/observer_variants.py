r"""Controller factories for ``guiding_quality.py --factory``: the defaults, another observer.

Usage (from the repository root)::

    PYTHONPATH=src:benchmarks python benchmarks/guiding_quality.py \
        --factory observer_variants:smooth_rate
"""

from __future__ import annotations

import dataclasses

import leadthrough as lt

#: The smooth-rate observer's fields (see :func:`smooth_rate`).
SMOOTH_RATE = {"variant": "smooth_rate", "torque_rate_noise": 1e3, "measurement_noise": 1e-8}


def with_observer(
    robot: lt.RobotDescription, mode: str, calibrate: bool = True, **observer: object
) -> lt.LeadThrough:
    """The default controller of ``mode`` with the observer fields ``observer`` changed."""
    defaults = lt.LeadThroughParameters()
    tuned = dataclasses.replace(defaults.observer, **observer)  # type: ignore[arg-type]
    parameters = dataclasses.replace(defaults, observer=tuned)
    return lt.LeadThrough(robot, mode=mode, dt=0.004, calibrate=calibrate, parameters=parameters)


def smooth_rate(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The defaults with the ``"smooth_rate"`` observer, Q_r = 1e3 Nm²/s³ and R = 1e-8.

    R = 1e-8 (kg m²/s)² s is a momentum noise of 1.6e-3 kg m²/s per 4 ms sample, about
    3 mrad/s of velocity noise on a 0.5 kg m² joint: a differenced encoder's level (the
    thesis' 1e-6 is 10× that in std). With it the variant's bandwidth while moving is
    ≈ 18 Hz, the default observer's ≈ 15 Hz, which the stability analysis assumes.
    """
    return with_observer(robot, mode, **SMOOTH_RATE)


def uncalibrated(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """The default controller without the start-up calibration."""
    return with_observer(robot, mode, calibrate=False)


def smooth_rate_uncalibrated(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
    """:func:`smooth_rate` without the start-up calibration (which reads the observer)."""
    return with_observer(robot, mode, calibrate=False, **SMOOTH_RATE)
