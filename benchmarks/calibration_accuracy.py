"""How well the start-up calibration measures Coulomb levels on sampled plants (issue 13).

On the dry-friction plants of ``twin.plants`` the true level at the calibration pose is
explicit (``DryFrictionParameters.level``, in the units of the measured torque: divided by
the plant's drive gain), so each measured level can be compared with it. Usage::

    python benchmarks/calibration_accuracy.py [--seeds 8] [--stroke 0.005] [--speed 0.05]
        [--bandwidth 6] [--delay 2] [--robot panda] [--dt 0.008] [--predict never]

Prints each plant's relative errors per joint [%] (blank: the joint did not slide both
ways and kept its model), the fastest joint during the calibration and the fastest 0.2–0.5
s after it (the arm left to the controller, nobody touching) [rad/s], then the median, 90th
percentile and largest |error|. ``--delay N`` gives every plant N periods of delay (the
family: 1–2); ``--bandwidth`` the calibration's tracking at 250 Hz (the default 4 Hz;
the previous default was ``--bandwidth 6 --stroke 0.01``); ``--dt`` the control period of
the plants and the controller (below 250 Hz the calibration's tracking follows it,
``CalibrationParameters.at_period``, and the joints whose loop would grow with two periods
of delay track the state predicted for when their command acts,
``CalibrationParameters.predict``); ``--predict never`` tracks the samples on every joint,
``--predict always`` the predicted state on every joint.
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import numpy as np

import leadthrough as lt
from leadthrough.cli.arguments import add_robot_arguments, robot_from
from leadthrough.control.calibration import PREDICTIONS, CalibrationParameters
from leadthrough.control.tracking import VERIFIED_PERIOD
from leadthrough.twin.plants import PlantRanges, sample_plant
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin

#: After the calibration, the window where the arm should rest [s].
REST_WINDOW = (0.2, 0.5)


@dataclasses.dataclass(frozen=True)
class CalibrationFigures:
    """One plant's calibration.

    Attributes:
        errors: Measured over true Coulomb level − 1 per joint [–] (NaN: not measured, or
            refused).
        fastest: Fastest joint during the calibration [rad/s].
        after: Fastest joint in :data:`REST_WINDOW` after it [rad/s].
        accepted: Whether the calibration was accepted.
    """

    errors: np.ndarray
    fastest: float
    after: float
    accepted: bool


def calibrate(
    robot: lt.RobotDescription,
    seed: int,
    calibration: CalibrationParameters,
    ranges: PlantRanges | None = None,
    dt: float = VERIFIED_PERIOD,
) -> CalibrationFigures:
    """The default active controller with ``calibration`` on dry plant ``seed``, at ``dt``."""
    plant = sample_plant(robot, seed, "dry", ranges)
    parameters = dataclasses.replace(lt.LeadThroughParameters(), calibration=calibration)
    controller = lt.LeadThrough(robot, mode="active", dt=dt, parameters=parameters,
                                calibrate=True)  # fmt: skip
    twin = DigitalTwin(robot, dataclasses.replace(plant.config, control_dt=dt))
    end = controller.calibration_time
    sim = simulate(twin, controller, end + REST_WINDOW[1], progress=False)
    speed = np.abs(sim.qd_true)
    fastest = float(speed[sim.t < end].max())
    after = float(speed[sim.t > end + REST_WINDOW[0]].max())
    result = controller.calibration
    if result is None or not result.accepted:
        return CalibrationFigures(np.full(robot.n_joints, np.nan), fastest, after, False)
    sliding = np.full(robot.n_joints, 1e3)  # [rad/s]: far above any Stribeck velocity
    true = plant.config.friction.level(result.pose, sliding) / np.asarray(
        plant.config.sensors.torque_gain
    )
    measured = controller.friction.coulomb_level(result.pose)
    errors = np.where(result.measured, measured / true - 1.0, np.nan)
    return CalibrationFigures(errors, fastest, after, True)


def main(argv: list[str] | None = None) -> None:
    """Command line: see the module docstring."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8, help="dry plants 1..N")
    parser.add_argument("--stroke", type=float, default=CalibrationParameters.stroke)
    parser.add_argument("--speed", type=float, default=CalibrationParameters.speed)
    parser.add_argument("--bandwidth", type=float, default=CalibrationParameters.bandwidth)
    parser.add_argument("--delay", type=int, help="periods of delay of every plant")
    parser.add_argument("--dt", type=float, default=VERIFIED_PERIOD, help="control period [s]")
    parser.add_argument("--predict", choices=PREDICTIONS, default="needed",
                        help="which joints track the predicted state "
                             "(CalibrationParameters.predict)")  # fmt: skip
    add_robot_arguments(parser)
    args = parser.parse_args(argv)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", lt.robots.AssumedDriveDataWarning)
        robot = robot_from(args)
    calibration = CalibrationParameters(stroke=args.stroke, speed=args.speed,
                                        bandwidth=args.bandwidth,
                                        predict=args.predict)  # fmt: skip
    ranges = None if args.delay is None else PlantRanges(delay_periods=(args.delay, args.delay))
    tracking = calibration.at_period(args.dt)
    print(f"{robot.name} at {1 / args.dt:g} Hz: stroke {1e3 * tracking.stroke:.3g} mrad at "
          f"{tracking.speed:g} rad/s, {tracking.bandwidth:.3g} Hz"
          f", predicting {args.predict}; error per joint [%], "
          "fastest joint during | after [rad/s]")  # fmt: skip
    figures = []
    for seed in range(1, args.seeds + 1):
        one = calibrate(robot, seed, calibration, ranges, args.dt)
        figures.append(one)
        cells = " ".join("    " if np.isnan(e) else f"{100 * e:+4.0f}" for e in one.errors)
        refused = "" if one.accepted else "  refused"
        print(f"dry #{seed:<3} {cells}  {one.fastest:5.2f} | {one.after:5.3f}{refused}")
    magnitude = 100 * np.abs(np.array([one.errors for one in figures]))
    print(f"|error|: median {np.nanmedian(magnitude):.1f} %, 90th percentile "
          f"{np.nanpercentile(magnitude, 90):.1f} %, largest {np.nanmax(magnitude):.1f} %, "
          f"{int(np.isnan(magnitude).sum())} joint(s) not measured (refused plants' "
          f"included); fastest joint during "
          f"{max(one.fastest for one in figures):.2f} rad/s, after "
          f"{max(one.after for one in figures):.3f} rad/s; refused "
          f"{sum(not one.accepted for one in figures)} of {len(figures)}")  # fmt: skip


if __name__ == "__main__":
    main()
