"""Guiding quality, active over passive, on sampled plants, hands and paths (issue 13).

Each case (plant of either friction physics × relaxed or stiff hand × path) is run with
passive and active lead-through, built through the public API with the nominal model and
friction (see :mod:`leadthrough.experiments.guiding`). Per case and as median / worst:

- effort: RMS hand force while the path moves, active / passive (goal ≤ 0.5 / ≤ 0.65);
- vibration: RMS tool velocity above 4 Hz, active / passive (goal ≤ 1.5 in every case);
- peak tool speed over the path's peak (goal ≤ 1.3 × path + 0.02 m/s);
- residual hand force during the hold, active − passive [N] (goal: median ≤ 0);
- release at speed: stop time (goal ≤ 0.5 s) and drift over 10 s (goal < 1 mrad);
- the observer (active run): RMS error over the peak operator torque (≤ 10 %), ±2 std
  coverage of moving samples (90–99 %), median std over the peak (≤ 30 %).

Usage:
    python benchmarks/guiding_quality.py [--cases quick] [--save out.json] [--compare old.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

import leadthrough as lt
from leadthrough.experiments.guiding import CaseResult, cases, run_case

COLUMNS = ("effort", "vibration", "speed", "residual", "stop", "drift", "obs_rms", "obs_cov",
           "obs_std")  # fmt: skip
HEADER = (f"{'case':<30}{'effort a/p':>11}{'vib a/p':>9}{'speed p|a':>12}{'resid p|a N':>13}"
          f"{'stop s':>8}{'drift mrad':>11}{'obs rms':>8}{'cov':>6}{'std':>6}")  # fmt: skip


def figures(passive: CaseResult, active: CaseResult) -> dict[str, float]:
    """The benchmark's figures of one case (ratios of active over passive where stated)."""
    allowed = 1.3 * active.path_peak_speed + 0.02
    return {
        "effort": active.rms_force / passive.rms_force,
        "vibration": active.vibration / passive.vibration,
        "speed_passive": passive.peak_speed / allowed,
        "speed": active.peak_speed / allowed,
        "residual_passive": passive.residual_force,
        "residual_active": active.residual_force,
        "residual": active.residual_force - passive.residual_force,
        "stop": active.stop_time,
        "drift": 1e3 * active.drift,
        "obs_rms": active.observer_rms,
        "obs_cov": active.observer_coverage,
        "obs_std": active.observer_std,
        "max_joint_speed": active.max_joint_speed,
    }


def row(name: str, f: dict[str, float]) -> str:
    """One line of the table."""
    return (f"{name:<30}{f['effort']:>11.2f}{f['vibration']:>9.2f}"
            f"{f['speed_passive']:>6.2f}|{f['speed']:<5.2f}"
            f"{f['residual_passive']:>7.1f}|{f['residual_active']:<5.1f}"
            f"{f['stop']:>8.2f}{f['drift']:>11.2f}{100 * f['obs_rms']:>7.0f}%"
            f"{100 * f['obs_cov']:>5.0f}%{100 * f['obs_std']:>5.0f}%")  # fmt: skip


#: (figure, which end is worst, goal text, check on (median, worst)).
GOALS = (
    ("effort", max, "median ≤ 0.5, worst ≤ 0.65", lambda m, w: m <= 0.5 and w <= 0.65),
    ("vibration", max, "≤ 1.5 in every case", lambda m, w: w <= 1.5),
    ("speed", max, "peak ≤ 1.3 × path + 0.02 m/s (≤ 1)", lambda m, w: w <= 1.0),
    ("residual", max, "active − passive, median ≤ 0 N", lambda m, w: m <= 0.0),
    ("stop", max, "≤ 0.5 s", lambda m, w: w <= 0.5),
    ("drift", max, "< 1 mrad over 10 s", lambda m, w: w < 1.0),
    ("obs_rms", max, "≤ 10 % of peak (mean over joints)", lambda m, w: m <= 0.1),
    ("obs_cov", min, "90–99 %", lambda m, w: 0.9 <= m <= 0.99),
    ("obs_std", max, "median std ≤ 30 % of peak", lambda m, w: m <= 0.3),
)


def summary(results: dict[str, dict[str, float]]) -> dict[str, dict[str, float]]:
    """Median and worst of every figure over the cases."""
    out = {}
    for name, worst, _, _ in GOALS:
        values = np.array([f[name] for f in results.values()])
        out[name] = {"median": float(np.nanmedian(values)), "worst": float(worst(values))}
    return out


def print_summary(stats: dict[str, dict[str, float]], old: dict | None) -> None:
    """Median / worst with the goals (and the compared run's, when given)."""
    print(f"\n{'figure':<11}{'median':>9}{'worst':>9}  {'goal':<38}{'met':>4}"
          + ("   before: median / worst" if old else ""))  # fmt: skip
    for name, _, goal, check in GOALS:
        s = stats[name]
        met = "yes" if check(s["median"], s["worst"]) else "NO"
        before = ""
        if old and name in old:
            before = f"   {old[name]['median']:.3g} / {old[name]['worst']:.3g}"
        print(f"{name:<11}{s['median']:>9.3g}{s['worst']:>9.3g}  {goal:<38}{met:>4}{before}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", choices=("full", "quick"), default="full")
    parser.add_argument("--save", help="write the per-case figures and the summary to JSON")
    parser.add_argument("--compare", help="a JSON saved before: print its summary alongside")
    args = parser.parse_args(argv)
    robot = lt.robots.yumi()
    chosen = cases(args.cases)
    results: dict[str, dict[str, float]] = {}
    start = time.perf_counter()
    print(HEADER)
    for k, case in enumerate(chosen, 1):
        passive = run_case(case, "passive", robot=robot)
        active = run_case(case, "active", robot=robot)
        results[case.name] = figures(passive, active)
        print(row(case.name, results[case.name]), flush=True)
        print(f"  [{k}/{len(chosen)}, {time.perf_counter() - start:.0f} s]", end="\r",
              file=sys.stderr, flush=True)  # fmt: skip
    stats = summary(results)
    old = None
    if args.compare:
        with open(args.compare) as handle:
            old = json.load(handle)["summary"]
    print_summary(stats, old)
    if args.save:
        with open(args.save, "w") as handle:
            json.dump({"cases": results, "summary": stats}, handle, indent=1)
        print(f"saved {args.save}")


if __name__ == "__main__":
    main()
