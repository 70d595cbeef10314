"""Where the effort goes: active over passive hand force where a loaded joint sticks, and elsewhere.

The benchmark's effort is one RMS over the path. This splits each case's path into the
samples where some joint the operator loads stands still in the active run (stiction
holds a push the motor torques cannot show) and the rest, where every loaded joint
slides (:func:`leadthrough.experiments.guiding.effort_split`; it reads the twin's true
operator torque, a diagnosis)::

    PYTHONPATH=src:benchmarks python benchmarks/effort_windows.py [--seeds 1-4]
"""

from __future__ import annotations

import argparse

import numpy as np

from guiding_quality import parse_seeds
from leadthrough.experiments.guiding import cases, effort_split


def main() -> None:
    """Print the split of every case of the seeds, then medians and quartiles."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="1-4", help="plant seeds, e.g. 1-4 or 5,9")
    args = parser.parse_args()
    rows = []
    print(f"{'case':32s} {'stuck time':>10s} {'stuck share':>11s} {'stuck':>6s} "
          f"{'sliding':>7s} {'effort':>6s}")  # fmt: skip
    for case in cases("full", seeds=parse_seeds(args.seeds)):
        split = effort_split(case)
        rows.append(split)
        print(f"{case.name:32s} {split.stuck_time:10.2f} {split.stuck_share:11.2f} "
              f"{split.stuck_ratio:6.2f} {split.sliding_ratio:7.2f} {split.ratio:6.2f}",
              flush=True)  # fmt: skip
    table = np.array(rows, dtype=float)
    for name, column in zip(rows[0]._fields, table.T, strict=True):
        low, median, high = np.nanpercentile(column, [25, 50, 75])
        print(f"{name:14s} median {median:.2f} (quartiles {low:.2f}–{high:.2f})")


if __name__ == "__main__":
    main()
