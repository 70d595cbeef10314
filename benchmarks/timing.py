"""Timing helpers shared by the benchmarks: per-call medians and tails, JSON save/compare."""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np


def time_per_call(function: Callable[[], object], calls: int, warmup: int = 200) -> dict:
    """Median, p99 and mean wall time of ``function()`` [µs], each call timed on its own."""
    for _ in range(warmup):
        function()
    samples = np.empty(calls)
    clock = time.perf_counter_ns
    for i in range(calls):
        start = clock()
        function()
        samples[i] = clock() - start
    samples /= 1e3
    return {
        "median_us": float(np.median(samples)),
        "p99_us": float(np.percentile(samples, 99)),
        "mean_us": float(np.mean(samples)),
        "calls": calls,
    }


def parser(description: str) -> argparse.ArgumentParser:
    """Common options: --calls, --save FILE, --compare FILE."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--calls", type=int, default=20000, help="timed calls per function")
    parser.add_argument("--save", type=Path, help="write the results as JSON")
    parser.add_argument("--compare", type=Path, help="JSON of an earlier run to compare against")
    return parser


def report(results: dict[str, dict], save: Path | None, compare: Path | None) -> None:
    """Print a table (with ratios to an earlier run when given) and optionally save JSON."""
    before = json.loads(compare.read_text()) if compare else {}
    print(f"{'function':<36}{'median [µs]':>13}{'p99 [µs]':>11}{'vs before':>11}")
    for name, stats in results.items():
        ratio = ""
        if name in before:
            ratio = f"{stats['median_us'] / before[name]['median_us']:.2f}x"
        print(f"{name:<36}{stats['median_us']:>13.2f}{stats['p99_us']:>11.2f}{ratio:>11}")
    if save:
        save.parent.mkdir(parents=True, exist_ok=True)
        save.write_text(json.dumps(results, indent=2))
        print(f"saved to {save}")
