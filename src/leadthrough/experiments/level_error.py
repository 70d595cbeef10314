"""How far a level the start-up calibration read is off along the travel, on dry plants.

Each dry plant of ``benchmarks/guiding_quality.py`` has Coulomb levels that move ±15 % with
the joint angle. The calibration reads them at one pose; the controller states each level's
error there as its readings' scatter, growing with the travel from the pose
(:mod:`~leadthrough.friction.measured_level`). This experiment calibrates the default
controller on each plant and sweeps every joint ±``span`` around the calibration pose,
comparing the error it states with the plant's true one (README, *A level read at the pose
is known best there*; ``tests/test_measured_level.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from leadthrough.control.lead_through import LeadThrough
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.twin.plants import sample_plant
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin


@dataclass(frozen=True)
class LevelErrorTrace:
    """One plant's levels along the travel from the calibration pose.

    Attributes:
        plant: Its label, e.g. ``dry #1``.
        offsets: Travel from the calibration pose, every joint at once [rad], (k,).
        true_error: ``|τ_C,true − τ_C,model| / τ_C,model`` there [–], (k, n): the
            calibrated model against the plant's level (in the measured torque's units).
        stated: The relative error the controller states there [–], (k, n).
        far: What the stated error grows to, ``MeasuredLevelError.far`` [–], (n,).
        measured: The joints whose level the calibration read, (n,).
    """

    plant: str
    offsets: FloatArray
    true_error: FloatArray
    stated: FloatArray
    far: FloatArray
    measured: np.ndarray


def level_errors_along_travel(
    robot: RobotDescription,
    seeds: tuple[int, ...] = (1, 2, 3, 4),
    span: float = 1.0,
    points: int = 41,
) -> list[LevelErrorTrace]:
    """Calibrate the default controller on each dry plant; its level errors along the travel.

    Args:
        robot: The nominal description.
        seeds: Plant seeds (``sample_plant(robot, seed, "dry")``).
        span: Travel either side of the calibration pose [rad].
        points: Samples of the travel (odd: the pose itself is one).

    Raises:
        RuntimeError: A plant's calibration was refused (nothing to compare).
    """
    traces = []
    offsets = np.linspace(-span, span, points)
    for seed in seeds:
        plant = sample_plant(robot, seed, "dry")
        controller = LeadThrough(robot, mode="active", calibrate=True)
        simulate(DigitalTwin(robot, plant.config), controller,
                 controller.calibration_time + 0.1, progress=False)  # fmt: skip
        calibration, error = controller.calibration, controller.level_error
        if calibration is None or error is None:
            raise RuntimeError(f"dry #{seed}: the calibration was refused")
        gain = np.asarray(plant.config.sensors.torque_gain, dtype=float)
        true, stated = [], []
        for offset in offsets:
            q = calibration.pose + offset
            modelled = controller.friction.coulomb_level(q)
            true.append(np.abs(plant.config.friction.coulomb_level(q) / gain - modelled)
                        / modelled)  # fmt: skip
            stated.append(error.at(q))
        traces.append(LevelErrorTrace(f"dry #{seed}", offsets, np.array(true), np.array(stated),
                                      error.far.copy(), calibration.measured.copy()))  # fmt: skip
    return traces
