"""``leadthrough inspect``: the observer and the contact detector over a robot's log."""

from __future__ import annotations

import argparse
import warnings

from leadthrough.cli.arguments import add_robot_arguments, existing_file, existing_log, robot_from
from leadthrough.estimation.log_observer import measured_torque
from leadthrough.experiments import real_logs
from leadthrough.friction.model import FrictionModel
from leadthrough.runtime.readers import read_log

EPILOG = """examples:
  leadthrough inspect ur10e/pushes/ur-static.csv            # a UR10e log (currents)
  leadthrough inspect run.csv --robot my_ur10e.urdf --friction friction.toml --out out/run
  leadthrough inspect panda_gaz2019/ --robot panda          # the Panda's text files (a folder)
"""


def add_arguments(parser: argparse.ArgumentParser, out_directory) -> None:
    """The options of ``inspect`` (``out_directory``: the shared argument type)."""
    parser.add_argument("log", type=existing_log,
                        help="UR CSV, Panda text folder, recording or excitation log")  # fmt: skip
    add_robot_arguments(parser, default="ur10e")  # nominal or identified
    parser.add_argument("--friction", type=existing_file,
                        help="identified friction TOML (default: the robot's own)")  # fmt: skip
    parser.add_argument("--out", type=out_directory, default="out/inspect",
                        help="report directory (default: out/inspect)")  # fmt: skip


def inspect(args: argparse.Namespace) -> int:
    """Read the log, run the observer and the detector, write the report; print a summary."""
    with warnings.catch_warnings(record=True) as notes:  # shown after the work, not before
        warnings.simplefilter("always")
        log = read_log(args.log)  # currents stay currents: the observer applies the robot's K
        robot = robot_from(args)
    friction = FrictionModel.load(args.friction) if args.friction else None
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
