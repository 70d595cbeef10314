"""How well the start-up calibration measures Coulomb levels on sampled plants (issue 13).

On the dry-friction plants of ``twin.plants`` the true level at the calibration pose is
explicit (``DryFrictionParameters.level``, in the units of the measured torque: divided by
the plant's drive gain), so each measured level can be compared with it. Usage::

    python benchmarks/calibration_accuracy.py [--seeds 8] [--stroke 0.005] [--speed 0.05]

Prints each plant's relative errors per joint [%] (blank: the joint did not slide both
ways and kept its model) and the median, 90th percentile and largest |error|.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

import leadthrough as lt
from leadthrough.control.calibration import CalibrationParameters
from leadthrough.twin.plants import sample_plant
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin


def level_errors(robot: lt.RobotDescription, seed: int, calibration: CalibrationParameters):
    """Measured over true Coulomb level − 1 per joint (NaN: not measured) on dry plant ``seed``."""
    plant = sample_plant(robot, seed, "dry")
    parameters = dataclasses.replace(lt.LeadThroughParameters(), calibration=calibration)
    controller = lt.LeadThrough(robot, mode="active", parameters=parameters, calibrate=True)
    twin = DigitalTwin(robot, plant.config)
    simulate(twin, controller, controller.calibration_time + 0.05, progress=False)
    result = controller.calibration
    if result is None or not result.accepted:
        return np.full(robot.n_joints, np.nan)
    sliding = np.full(robot.n_joints, 1e3)  # [rad/s]: far above any Stribeck velocity
    true = plant.config.friction.level(result.pose, sliding) / np.asarray(
        plant.config.sensors.torque_gain
    )
    measured = controller.friction.coulomb_level(result.pose)
    return np.where(result.measured, measured / true - 1.0, np.nan)


def main(argv: list[str] | None = None) -> None:
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8, help="dry plants 1..N")
    parser.add_argument("--stroke", type=float, default=CalibrationParameters.stroke)
    parser.add_argument("--speed", type=float, default=CalibrationParameters.speed)
    args = parser.parse_args(argv)
    robot = lt.robots.yumi()
    calibration = CalibrationParameters(stroke=args.stroke, speed=args.speed)
    print(f"stroke {1e3 * args.stroke:g} mrad at {args.speed:g} rad/s; error per joint [%]")
    errors = []
    for seed in range(1, args.seeds + 1):
        error = level_errors(robot, seed, calibration)
        errors.append(error)
        cells = " ".join("    " if np.isnan(e) else f"{100 * e:+4.0f}" for e in error)
        print(f"dry #{seed:<3} {cells}")
    magnitude = 100 * np.abs(np.array(errors))
    print(f"|error|: median {np.nanmedian(magnitude):.1f} %, 90th percentile "
          f"{np.nanpercentile(magnitude, 90):.1f} %, largest {np.nanmax(magnitude):.1f} %, "
          f"{int(np.isnan(magnitude).sum())} joint(s) not measured")  # fmt: skip


if __name__ == "__main__":
    main()
