"""The ``leadthrough`` command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from leadthrough import robots
from leadthrough.errors import LeadthroughError

_EPILOG_INFO = """examples:
  leadthrough info                       # the shipped ABB YuMi left arm
  leadthrough info --robot my_arm.toml   # a description file
  leadthrough info --robot panda.urdf --tip panda_hand
"""


def _add_robot_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--robot",
        default="yumi",
        metavar="yumi|FILE",
        help="shipped robot name or a .toml/.urdf description (default: yumi)",
    )
    parser.add_argument("--tip", help="flange link of a URDF (needed when the tree branches)")


def _info(args: argparse.Namespace) -> int:
    from leadthrough.summary import model_summary

    print(model_summary(robots.load(args.robot, tip=args.tip)))
    return 0


_EPILOG_SIMULATE = """examples:
  leadthrough simulate                          # a hand pulls the YuMi's tool along a line
  leadthrough simulate --scenario table_push --out results/
  leadthrough simulate --scenario joint --duration 6 --seed 3
"""


def _simulate(args: argparse.Namespace) -> int:
    from leadthrough.twin.session import run_scenario

    summary = run_scenario(
        robots.load(args.robot, tip=args.tip), args.scenario, args.duration, args.seed, args.out
    )
    print(summary)
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
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
    _add_robot_arguments(info)
    info.set_defaults(run=_info)
    simulate = commands.add_parser(
        "simulate",
        help="run a twin scenario with gravity feed-forward",
        description="Run a shipped scenario of the digital twin under gravity feed-forward and"
        " write a plot of the run and a rendered picture of the arm.",
        epilog=_EPILOG_SIMULATE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _add_robot_arguments(simulate)
    from leadthrough.twin.scenarios import SCENARIOS

    simulate.add_argument("--scenario", default="line", choices=sorted(SCENARIOS))
    simulate.add_argument("--duration", type=float, help="simulated seconds (default: scenario's)")
    simulate.add_argument("--seed", type=int, default=0, help="seed of every random draw")
    simulate.add_argument("--out", default="out", help="directory for the figures (default: out)")
    simulate.set_defaults(run=_simulate)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; errors of leadthrough print as one line and exit 2."""
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except LeadthroughError as error:
        print(f"leadthrough: error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
