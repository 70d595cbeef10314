"""Replay on the plant family: faults and tracking errors of a taught path on every plant.

The replay's defaults were first measured on the reference twin only; this replays one
taught path (:func:`leadthrough.experiments.replay_quality.taught_path`) on each plant of
the guiding benchmark's family, both friction physics, at a control period::

    PYTHONPATH=src:benchmarks python benchmarks/replay_quality.py [--seeds 1-8] [--dt 0.008]
        [--bandwidth HZ] [--robot NAME]

``--bandwidth`` sets ``ReplayParameters.bandwidth`` (the tracking's at 250 Hz and faster).
"""

from __future__ import annotations

import argparse

import numpy as np

from guiding_quality import parse_seeds
from leadthrough.cli.arguments import add_robot_arguments, robot_from
from leadthrough.control.replay import ReplayParameters
from leadthrough.experiments.replay_quality import replay_on_plant


def main() -> None:
    """Print one line per plant, then the faults and the median / worst errors."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="1-8", help="plant seeds, e.g. 1-8 or 5,9")
    parser.add_argument("--dt", type=float, default=0.004, help="control period [s]")
    parser.add_argument("--bandwidth", type=float, help="tracking bandwidth [Hz]")
    add_robot_arguments(parser)  # --robot, --tip, --drive-data, as the command line's
    args = parser.parse_args()
    parameters = None if args.bandwidth is None else ReplayParameters(bandwidth=args.bandwidth)
    robot = robot_from(args)
    rows = []
    print(f"{'plant':10s} {'delay':>5s} {'fault':>5s} {'joint RMS':>9s} {'max':>7s} "
          f"{'tool RMS':>8s} {'peak':>6s}   [mrad, mm, rad/s]")  # fmt: skip
    for seed in parse_seeds(args.seeds):
        for physics in ("dry", "lugre"):
            row = replay_on_plant(robot, seed, physics, args.dt, parameters)
            rows.append(row)
            print(f"{row.plant:10s} {row.delay:5d} {'yes' if row.faulted else 'no':>5s} "
                  f"{1e3 * row.joint_rms:9.2f} {1e3 * row.joint_max:7.1f} "
                  f"{1e3 * row.tool_rms:8.2f} {row.peak_speed:6.2f}", flush=True)  # fmt: skip
    joint = 1e3 * np.array([row.joint_rms for row in rows])
    tool = 1e3 * np.array([row.tool_rms for row in rows])
    print(f"dt {args.dt:g} s: {sum(row.faulted for row in rows)} of {len(rows)} faulted; "
          f"joint RMS median {np.median(joint):.2f}, worst {joint.max():.2f} mrad; tool RMS "
          f"median {np.median(tool):.2f}, worst {tool.max():.2f} mm; fastest joint "
          f"{max(row.peak_speed for row in rows):.2f} rad/s")  # fmt: skip


if __name__ == "__main__":
    main()
