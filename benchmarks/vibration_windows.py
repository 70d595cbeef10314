"""Where in a guiding case the tool shakes, passive against active (issue 13 diagnosis).

The benchmark's vibration figure is one number per case; this splits it into windows of the
held run, so that a case above the goal shows *when* active mode shakes more than passive::

    PYTHONPATH=src python benchmarks/vibration_windows.py lugre 24 stiff sideways
"""

from __future__ import annotations

import argparse

from leadthrough.experiments.guiding import HANDS, PATH_NAMES, Case, vibration_windows


def main() -> None:
    """Print the tool velocity above 4 Hz per window, both modes [mm/s]."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("physics", choices=("dry", "lugre"))
    parser.add_argument("seed", type=int)
    parser.add_argument("hand", choices=tuple(HANDS))
    parser.add_argument("path", choices=PATH_NAMES)
    parser.add_argument("--window", type=float, default=0.5, help="window length [s]")
    args = parser.parse_args()
    case = Case(args.physics, args.seed, args.hand, args.path)
    starts, passive = vibration_windows(case, "passive", args.window)
    _, active = vibration_windows(case, "active", args.window)
    print(f"{case.name}: tool velocity above 4 Hz, RMS per {args.window:g} s window [mm/s]")
    print(" from [s]  passive   active")
    for start, p, a in zip(starts, passive, active, strict=True):
        print(f"{start:9.1f} {1e3 * p:8.2f} {1e3 * a:8.2f}")


if __name__ == "__main__":
    main()
