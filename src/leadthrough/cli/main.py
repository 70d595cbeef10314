"""The ``leadthrough`` command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from leadthrough.cli import arguments as arg
from leadthrough.errors import LeadthroughError, ParameterError

_EPILOG_INFO = """examples:
  leadthrough info                       # the shipped ABB YuMi left arm
  leadthrough info --robot ur10e         # shipped: yumi, panda, ur5, ur10e
  leadthrough info --robot my_arm.toml   # a description file
  leadthrough info --robot panda.urdf --tip panda_hand
  leadthrough info --robot arm.urdf --tip tool0 --drive-data arm_drive.toml
"""


def _info(args: argparse.Namespace) -> int:
    from leadthrough.cli.summary import model_summary

    print(model_summary(arg.robot_from(args)))
    return 0


_EPILOG_SIMULATE = """examples:
  leadthrough simulate                          # a hand pulls the YuMi's tool along a line
  leadthrough simulate --scenario table_push --out results/
  leadthrough simulate --scenario joint --duration 6 --seed 3
"""


def _simulate(args: argparse.Namespace) -> int:
    from leadthrough.twin.session import run_scenario

    summary = run_scenario(arg.robot_from(args), args.scenario, args.duration, args.seed, args.out)
    print(summary)
    return 0


_EPILOG_IDENTIFY = """examples:
  leadthrough identify                         # excite every joint of the YuMi twin, fit, plot
  leadthrough identify --joints 1,4 --out results/friction
  leadthrough identify --random-friction --seed 3   # a twin with other friction
  leadthrough identify --log robot.csv   # excitation logs: run,t,q1..,qd1..,tau1..
  leadthrough identify --robot ur10e --log run1.csv run2.csv --held-out run3.csv
                                         # a real arm's logs: friction, dynamics, held-out
  leadthrough identify --realdata ../shared/realdata --out out/real
                                         # the public UR10e and Panda logs vs published
"""


def _identify(args: argparse.Namespace) -> int:
    from leadthrough.cli.identify import (
        identify,
        identify_real,
        parse_joints,
        real_logs,
        refuse_repeated_runs,
        refuse_taught_recordings,
    )

    refuse_repeated_runs(args.log or [], args.held_out)
    if args.held_out and not args.log:
        raise ParameterError("--held-out", "needs --log (the runs to fit)")
    if args.realdata is not None and args.log:
        raise ParameterError("--realdata", "give either --realdata or --log, not both")
    if args.realdata is not None or real_logs(args.log, args.held_out):
        _refuse_twin_options(args)
        refuse_taught_recordings([*(args.log or []), *args.held_out])
        print(identify_real(args))
        return 0
    robot = arg.robot_from(args)
    summary = identify(
        robot,
        args.out,
        log=args.log[0] if args.log else None,
        save_log=args.save_log,
        joints=parse_joints(args.joints, robot.n_joints),
        seed=0 if args.seed is None else args.seed,
        random_friction=args.random_friction,
    )
    print(summary)
    return 0


#: ``identify`` options of the twin's experiment and the project's excitation logs only.
_TWIN_OPTIONS = {"joints": "--joints", "save_log": "--save-log", "seed": "--seed",
                 "random_friction": "--random-friction"}  # fmt: skip


def _refuse_twin_options(args: argparse.Namespace) -> None:
    """A real arm's runs identify every joint that moved: twin-only options are mistakes."""
    given = [flag for name, flag in _TWIN_OPTIONS.items()  # `--seed 0` is given too
             if getattr(args, name) is not None and getattr(args, name) is not False]  # fmt: skip
    if given:
        raise ParameterError(given[0], "applies to the twin's experiment and the project's "
                             "excitation logs only; a real arm's runs (--log, --realdata) "
                             "identify every joint that moved in them")  # fmt: skip


_EPILOG_DEMO = """examples:
  leadthrough demo                 # identify, teach (recorded), replay, report in out/demo
  leadthrough demo --out /tmp/demo
  leadthrough demo --robot panda --out out/demo-panda   # shipped: yumi, panda, ur5, ur10e
"""

_EPILOG_TEACH = """examples:
  leadthrough teach                  # a hand teaches a line, recorded to out/taught.mcap
  leadthrough teach --path circle --mode passive --out circle.mcap
  leadthrough teach --friction out/friction/friction.toml --duration 8
  leadthrough teach --robot ur5 --out ur5.mcap   # then: leadthrough replay ur5.mcap
"""

_EPILOG_REPLAY = """examples:
  leadthrough replay out/taught.mcap
  leadthrough replay out/taught.mcap --time-scale 2 --out out/replay
"""


def _demo(args: argparse.Namespace) -> int:
    from leadthrough.experiments.demo import run_demo
    from leadthrough.experiments.demo_report import write_report

    robot = arg.robot_from(args)
    out = args.out
    result = run_demo(out, robot)
    print("4/4 writing the report …")
    report = write_report(result, robot, out)
    errors = result.replay_error
    print(f"replay: joint RMS {1000 * errors['joint_rms']:.2f} mrad, "
          f"tool RMS {1000 * errors['tool_rms']:.2f} mm")  # fmt: skip
    print(f"report: {report}")
    return 0


def _teach(args: argparse.Namespace) -> int:
    from leadthrough.experiments.teach import teach_on_twin

    robot = arg.robot_from(args)
    print(teach_on_twin(robot, args.out, args.path, args.mode, args.duration, args.friction,
                        args.seed, overwrite=args.force))  # fmt: skip
    return 0


def _replay(args: argparse.Namespace) -> int:
    from leadthrough.experiments.teach import replay_on_twin

    print(replay_on_twin(args.recording, args.out, args.time_scale, args.seed,
                         partial=args.partial))  # fmt: skip
    return 0


def _experiments(args: argparse.Namespace) -> int:
    from leadthrough.experiments.report import write_experiments

    report = write_experiments(arg.robot_from(args), args.out)
    print(f"report: {report}")
    return 0


def _inspect(args: argparse.Namespace) -> int:
    from leadthrough.cli.inspect import inspect

    return inspect(args)


def _add(commands, name: str, help_text: str, description: str, epilog: str, run):
    parser = commands.add_parser(name, help=help_text, description=description, epilog=epilog,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    parser.set_defaults(run=run)
    return parser


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = arg.OneLineParser(
        prog="leadthrough",
        description="Sensorless kinesthetic teaching of robot arms.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    info = commands.add_parser(
        "info",
        help="summarise a robot model",
        description="Joints with limits, masses, gravity torques at home and the condition of M.",
        epilog=_EPILOG_INFO,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    arg.add_robot_arguments(info)
    info.set_defaults(run=_info)
    simulate = commands.add_parser(
        "simulate",
        help="run a twin scenario with gravity feed-forward",
        description="Run a shipped scenario of the digital twin under gravity feed-forward and"
        " write a plot of the run and a rendered picture of the arm.",
        epilog=_EPILOG_SIMULATE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    arg.add_robot_arguments(simulate)
    from leadthrough.twin.scenarios import SCENARIOS

    simulate.add_argument("--scenario", default="line", choices=sorted(SCENARIOS))
    simulate.add_argument("--duration", type=arg.seconds,
                          help="simulated seconds, at most 600 (default: scenario's)")  # fmt: skip
    simulate.add_argument("--seed", type=arg.seed, default=0, help="seed of every random draw")
    simulate.add_argument("--out", type=arg.out_directory, default="out",
                          help="directory for the figures (default: out)")  # fmt: skip
    simulate.set_defaults(run=_simulate)
    identify = commands.add_parser(
        "identify",
        help="identify joint friction (twin experiment or log file)",
        description="Run the friction identification experiment of thesis §4.1.1 on the twin (or"
        " read logs), fit the Gaussian friction model, write it as TOML with figures 4.2-4.6.",
        epilog=_EPILOG_IDENTIFY,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    arg.add_robot_arguments(identify)
    identify.add_argument(
        "--log",
        type=arg.existing_log,
        nargs="+",
        help="read logs instead of the twin: the project's excitation logs (.csv or .npz), or"
        " a real arm's runs (UR CSV, a Panda text folder) to identify friction and dynamics"
        " (not a teaching recording, .mcap: a hand was on the arm)",
    )
    identify.add_argument("--held-out", type=arg.existing_log, nargs="+", default=[],
                          help="runs not fitted, to judge the identified dynamics on")  # fmt: skip
    identify.add_argument("--realdata", type=arg.realdata_directory,
                          help="folder of the public UR10e and Panda logs (../shared/realdata):"
                          " identify them and compare with the published values")  # fmt: skip
    identify.add_argument(
        "--save-log", type=arg.log_file, help="also write the logs (.csv or .npz)"
    )
    identify.add_argument("--joints", help="joints to identify, 1-based, e.g. 1,4 (default all)")
    identify.add_argument("--seed", type=arg.seed, help="seed of the twin (default 0)")
    identify.add_argument("--random-friction", action="store_true",
                          help="give the twin randomly drawn friction (seeded)")  # fmt: skip
    identify.add_argument(
        "--out", type=arg.out_directory, default="out/friction", help="output directory"
    )
    identify.set_defaults(run=_identify)
    demo = _add(commands, "demo", "the main job: teach, record and replay on the twin",
                "Identify the twin's friction, let a simulated operator teach the arm (default: the"
                " YuMi) a path with"
                " active lead-through (recorded), replay it, and write a report with figures.",
                _EPILOG_DEMO, _demo)  # fmt: skip
    arg.add_robot_arguments(demo)
    demo.add_argument(
        "--out",
        type=arg.out_directory,
        default="out/demo",
        help="report directory (default: out/demo)",
    )
    teach = _add(commands, "teach", "teach the twin a path with a simulated hand, recorded",
                 "A simulated operator guides the twin with lead-through; the session is recorded"
                 " to an MCAP file.", _EPILOG_TEACH, _teach)  # fmt: skip
    arg.add_robot_arguments(teach)
    teach.add_argument("--path", default="line", choices=["line", "circle", "point_to_point"])
    teach.add_argument("--mode", default="active", choices=["active", "passive"])
    teach.add_argument(
        "--duration", type=arg.seconds, help="seconds taught, at most 600 (default: the path's)"
    )
    teach.add_argument(
        "--friction",
        type=arg.existing_file,
        help="identified friction TOML (default: the robot file's nominal one)",
    )
    teach.add_argument("--seed", type=arg.seed, default=0)
    teach.add_argument(
        "--out", type=arg.new_file, default="out/taught.mcap", help="recording to write"
    )
    teach.add_argument("--force", action="store_true", help="overwrite an existing recording")
    replay = _add(commands, "replay", "replay a recorded path on the twin",
                  "Plan (filter, pauses as waypoints, limits checked) and replay a recording on"
                  " the twin; print the tracking errors and write a figure.",
                  _EPILOG_REPLAY, _replay)  # fmt: skip
    replay.add_argument(
        "recording", type=arg.existing_file, help="an MCAP recording of a teaching session"
    )
    replay.add_argument(
        "--time-scale",
        type=arg.time_scale,
        default=1.0,
        help=">1 slower, <1 faster, within 0.05 … 20 (default: 1)",
    )
    replay.add_argument(
        "--partial",
        action="store_true",
        help="replay what was recovered of an unfinished or damaged recording",
    )
    replay.add_argument("--seed", type=arg.seed, default=0)
    replay.add_argument(
        "--out", type=arg.out_directory, default="out/replay", help="figure directory"
    )
    experiments = _add(commands, "experiments", "every thesis experiment on the twin, one report",
                       "Reproduce the figures of thesis chapters 4-6 on the realistic"
                       " twin into one Markdown report.",
                       "examples:\n  leadthrough experiments --out out/experiments\n",
                       _experiments)  # fmt: skip
    arg.add_robot_arguments(experiments)
    experiments.add_argument(
        "--out", type=arg.out_directory, default="out/experiments", help="report directory"
    )
    from leadthrough.cli.inspect import EPILOG, add_arguments

    inspect = _add(commands, "inspect", "the observer and contacts over a robot's log",
                   "Run the momentum observer over a log at its own rate (currents → K·i), detect"
                   " contacts and write report.md with τ̂_ext ± 2 std per joint and the"
                   " false-alarm table.", EPILOG, _inspect)  # fmt: skip
    add_arguments(inspect, arg.out_directory)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; every mistake prints one line on stderr and returns 2.

    Ctrl-C prints one line and returns 130; a closed stdout (``| head``) ends quietly with 0.
    """
    try:
        from leadthrough.twin.render import prefer_offscreen_gl

        prefer_offscreen_gl()  # the commands that draw the arm render offscreen
        parser = build_parser()
        args = parser.parse_args(argv)
        if args.command == "teach":
            arg.refuse_overwrite(args.out, args.force)
    except SystemExit as exit:  # --help (0) or a one-line argument error (2)
        return exit.code if isinstance(exit.code, int) else 2
    except KeyboardInterrupt:  # while the commands' modules load: nothing was done yet
        print("leadthrough: interrupted while starting: nothing was done", file=sys.stderr)
        return 130
    try:
        with arg.one_line_warnings():
            return args.run(args)
    except LeadthroughError as error:
        print(f"leadthrough: error: {' '.join(str(error).split())}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as interrupt:
        print(f"leadthrough: interrupted{f': {interrupt}' if str(interrupt) else ''}",
              file=sys.stderr)  # fmt: skip
        return 130
    except BrokenPipeError:
        return arg.quiet_broken_pipe()
    except OSError as error:  # a folder that cannot be created, a full disk, a lost mount
        place = f": {error.filename}" if error.filename else ""
        print(f"leadthrough: error: {error.strerror or error}{place}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
