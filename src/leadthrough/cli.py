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
