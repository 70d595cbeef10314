"""``leadthrough inspect``: the observer and the contact detector over a robot's log."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from leadthrough.cli.arguments import add_robot_arguments, existing_file, existing_log, robot_from
from leadthrough.errors import RobotDescriptionError
from leadthrough.estimation.log_observer import measured_torque
from leadthrough.experiments import real_logs
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import RobotDescription
from leadthrough.runtime.readers import detect_format, read_log
from leadthrough.runtime.recording import read_recording

EPILOG = """examples:
  leadthrough inspect ur10e/pushes/ur-static.csv            # a UR10e log (currents)
  leadthrough inspect run.csv --robot my_ur10e.urdf --friction friction.toml --out out/run
  leadthrough inspect panda_gaz2019/ --robot panda          # the Panda's text files (a folder)
"""


def add_arguments(parser: argparse.ArgumentParser, out_directory) -> None:
    """The options of ``inspect`` (``out_directory``: the shared argument type)."""
    parser.add_argument("log", type=existing_log,
                        help="UR CSV, Panda text folder, recording or excitation log")  # fmt: skip
    add_robot_arguments(parser, default=None,  # nominal or identified
                        shown="a recording's own robot, else ur10e")  # fmt: skip
    parser.add_argument("--friction", type=existing_file,
                        help="identified friction TOML (default: the robot's own)")  # fmt: skip
    parser.add_argument("--out", type=out_directory, default="out/inspect",
                        help="report directory (default: out/inspect)")  # fmt: skip


def inspect(args: argparse.Namespace) -> int:
    """Read the log, run the observer and the detector, write the report; print a summary."""
    with warnings.catch_warnings(record=True) as notes:  # shown after the work, not before
        warnings.simplefilter("always")
        log = read_log(args.log)  # currents stay currents: the observer applies the robot's K
        robot = _robot_of(args)
    friction = FrictionModel.load(args.friction) if args.friction else None
    if friction is not None and friction.n_joints != robot.n_joints:
        raise RobotDescriptionError(str(args.friction), "friction", f"{friction.n_joints} "
                                    f"joints, but {robot.name} has {robot.n_joints}")  # fmt: skip
    measured_torque(log, robot)  # joint count, torque or currents and K: checked before the work
    inspection = real_logs.inspect_log(log, robot, friction)
    report = real_logs.write_inspection(inspection, str(args.log), args.out)
    observed = inspection.observed
    print(f"{args.log}: {observed.t[-1] - observed.t[0]:.1f} s at {1 / observed.dt:.0f} Hz, "
          f"{len(inspection.events)} contact(s)")  # fmt: skip
    print(f"  {real_logs.supervisor_markdown(inspection.fault)}")  # the report's words
    if inspection.gaps:
        print(f"  {real_logs.gaps_markdown(inspection.gaps, float(observed.t[0]))}")
    for event in inspection.events:
        joints = ",".join(str(j + 1) for j in event.joints)
        print(f"  {event.start - observed.t[0]:7.2f} … {event.end - observed.t[0]:7.2f} s  "
              f"joints {joints}  peak {event.peak_torque:.1f} Nm")  # fmt: skip
    print(f"report: {report}")
    for note in notes:  # on stderr, one line each, as identify's (cli.arguments.one_line_warnings)
        warnings.warn_explicit(note.message, note.category, note.filename, note.lineno)
    return 0


def _robot_of(args: argparse.Namespace) -> RobotDescription:
    """The robot ``--robot`` names; without it a recording's own, else the UR10e.

    A recording names the robot it was taught on: one of another name is refused (a YuMi
    recording inspected as a Panda read 42.7 Nm "contacts" on joints 1–4).
    """
    recorded = None
    if detect_format(Path(args.log)) == "recording":
        recorded = read_recording(args.log).robot
    if args.robot is None:
        if recorded is not None:
            return recorded
        args.robot = "ur10e"
    robot = robot_from(args)
    if recorded is not None and recorded.name != robot.name:
        raise RobotDescriptionError(str(args.robot), "", f"{args.log} was recorded on "
                                    f"{recorded.name!r}, not {robot.name!r}: leave --robot out "
                                    "to use the recording's own")  # fmt: skip
    return robot
