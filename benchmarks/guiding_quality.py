"""Guiding quality, active over passive, on sampled plants, hands and paths (issue 13).

Each case (plant of either friction physics × relaxed or stiff hand × path) is run with
passive and active lead-through, built through the public API with the nominal model and
friction, or with each plant's friction identified first (``--identified``; see
:mod:`leadthrough.experiments.guiding`). Per case and as median / worst:

- effort: RMS hand force while the path moves, active / passive (goal ≤ 0.5 / ≤ 0.65);
- vibration: RMS tool velocity above 4 Hz, active / passive (goal ≤ 1.5 in every case);
- peak tool speed over the path's peak (goal ≤ 1.3 × path + 0.02 m/s);
- residual hand force during the hold, active − passive [N] (goal: median ≤ 0);
- release at speed: stop time (goal ≤ 0.5 s) and drift over 10 s (goal < 1 mrad), of
  both modes;
- the observer (active run): RMS error over the peak operator torque (≤ 10 %), ±2 std
  coverage of moving samples (90–99 %), median std over the peak (≤ 30 %).

Below the table: the cases that break a goal each case must keep (vibration, speed, stops,
drifts), worst first, and those guided without a calibration or with a saturated hand.

``--cases contact``: the hand presses the tool onto a stiff table instead (one case per
plant and hand; the thesis' "stable also in contact with stiff surfaces"): the vibration,
the releases (let go while pressing) and the observer against the whole external torque,
the table's included, are what it judges; the effort is the pressing force's ratio.

Usage:
    python benchmarks/guiding_quality.py [--cases quick|contact] [--save out.json]
        [--compare old.json]
        [--factory module:function]   (the active controller: function(robot, mode))
        [--robot NAME] [--seeds 5-8]  (another arm; plants not developed on)
        [--robot FILE --tip LINK --drive-data FILE]  (an arm of your own: a URDF or TOML)
        [--hands soft,firm]           (other hands of guiding.HANDS: 100 and 1000 N/m;
                                       grasping,stiff-grasping also hold the tool's
                                       orientation, 2 and 10 Nm/rad;
                                       trembling,stiff-trembling: 0.3 mm tremor at 9 Hz)
        [--uncalibrated]              (both modes without the start-up calibration)
        [--plants FIELD=VALUE ...]    (another family: twin.plants.PlantRanges fields, e.g.
                                       position_amplitude=0.25 friction_scale=0.7,1.3)
        [--dt 0.001]                  (another control rate: plants and controllers, 1 kHz)
        [--no-torque-sensor]          (drives that report no torque: tau_measured None)
        [--pace 2]                    (hands twice as slow: lines in 8 s, the circle in 12 s)
        [--grab-at-once]              (hands that grab while the arm calibrates)
        [--rest 5]                    (hands that grab after the arm rested 5 s, nobody
                                       touching: its dither parks after 2 s)
        [--identified]                (both modes with each plant's friction identified
                                       first, as `leadthrough identify` would on the arm)
"""

from __future__ import annotations

import argparse
import functools
import importlib
import json
import math
import sys
import time
from dataclasses import asdict, fields, replace

from leadthrough.cli.arguments import add_robot_arguments, robot_from
from leadthrough.errors import ParameterError, RobotDescriptionError
from leadthrough.experiments.guiding import (
    BENCHMARK_HANDS,
    DIAGNOSTICS,
    GOALS,
    HANDS,
    IdentifiedFirst,
    cases,
    default_factory,
    evaluate,
    uncalibrated_factory,
)
from leadthrough.twin.plants import PlantRanges
from leadthrough.twin.simulator import TwinConfig, TwinError

HEADER = (f"{'case':<30}{'effort a/p':>11}{'vib a/p':>9}{'speed p|a':>12}"
          f"{'resid p|a N':>13}{'stop p|a s':>11}{'drift p|a mrad':>15}{'obs rms':>8}{'cov':>6}"
          f"{'std':>6}{'cal':>5}")  # fmt: skip


def row(name: str, f: dict[str, float]) -> str:
    """One line of the table."""
    return (f"{name:<30}{f['effort']:>11.2f}{f['vibration']:>9.2f}"
            f"{f['speed_passive']:>6.2f}|{f['speed']:<5.2f}"
            f"{f['residual_passive']:>7.1f}|{f['residual_active']:<5.1f}"
            f"{f['stop_passive']:>6.2f}|{f['stop']:<4.2f}"
            f"{f['drift_passive']:>8.2f}|{f['drift']:<6.2f}{100 * f['obs_rms']:>7.0f}%"
            f"{100 * f['obs_cov']:>5.0f}%{100 * f['obs_std']:>5.0f}%"
            f"{'yes' if f['calibrated'] else 'NO':>5}")  # fmt: skip


def print_summary(stats: dict[str, dict[str, float]], old: dict | None) -> None:
    """Median / worst with the goals (and the compared run's, when given)."""
    print(f"\n{'figure':<14}{'median':>9}{'worst':>9}  {'goal':<38}{'met':>4}"
          + ("   before: median / worst" if old else ""))  # fmt: skip
    lines = [(name, goal, "yes" if check(stats[name]["median"], stats[name]["worst"]) else "NO")
             for name, _, goal, check in GOALS]  # fmt: skip
    lines += [(name, f"({text})", "") for name, _, text in DIAGNOSTICS]
    for name, goal, met in lines:
        s, before = stats[name], ""
        if old and name in old:
            before = f"   {old[name]['median']:.3g} / {old[name]['worst']:.3g}"
        print(f"{name:<14}{s['median']:>9.3g}{s['worst']:>9.3g}  {goal:<38}{met:>4}{before}")


def uncalibrated_line(results: dict[str, dict[str, float]]) -> str:
    """How many cases the active controller guided without an accepted calibration.

    A refused calibration shows in one column of one row only; counted here, a plant family
    that the calibration refuses (seeds 9–12 did, 14 of 56 cases) cannot hide in the table.
    """
    missing = [name for name, f in results.items() if not f["calibrated"]]
    return f"guided without a calibration: {len(missing)} of {len(results)} cases" + (
        f" ({_first_names(missing)})" if missing else ""
    )


#: The goals every case must keep by itself (:data:`GOALS` whose check reads the worst only).
PER_CASE_GOALS = ("vibration", "speed", "stop", "drift", "stop_passive", "drift_passive")
#: The passive run's figure beside an active per-case goal that the same hand and plant may
#: break in either mode: a joint that sticks while the hand's spring loads, then breaks away,
#: throws the arm past the path's speed in passive mode too (the UR arms' relaxed lines).
PASSIVE_COUNTERPART = {"speed": "speed_passive"}


def over_goal_line(results: dict[str, dict[str, float]]) -> str:
    """Which cases break a goal that every case must keep, worst first, per figure.

    The summary's worst is one case; a set can hold several above the goal, and which ones
    they are (and whether a change moved the tail to another case) is what a variant is
    judged on. E.g. ``over a per-case goal: vibration 2 of 28 (lugre#2 relaxed upwards 2.12,
    dry#1 relaxed upwards 1.66)``. Where passive mode can break the same goal
    (:data:`PASSIVE_COUNTERPART`), how many cases it breaks follows: ``speed 4 of 28 (…;
    passive mode 8 of 28)``.
    """
    checks = {name: check for name, _, _, check in GOALS if name in PER_CASE_GOALS}
    parts = []
    for name in PER_CASE_GOALS:
        over = sorted(((f[name], case) for case, f in results.items()
                       if not checks[name](f[name], f[name])), reverse=True)  # fmt: skip
        if over:
            named = _first_names([f"{case} {value:.3g}" for value, case in over])
            if name in PASSIVE_COUNTERPART:
                twin = PASSIVE_COUNTERPART[name]
                passive = sum(not checks[name](f[twin], f[twin]) for f in results.values())
                named += f"; passive mode {passive} of {len(results)}"
            parts.append(f"{name} {len(over)} of {len(results)} ({named})")
    return "over a per-case goal: " + ("; ".join(parts) if parts else "none")


def _first_names(names: list[str]) -> str:
    """The first three case names, then "…" if there are more."""
    return ", ".join(names[:3]) + (", …" if len(names) > 3 else "")


def saturated_line(results: dict[str, dict[str, float]]) -> str:
    """The cases whose hand could not pull the arm along its path, or "" when none.

    Its force reached the hand's limit (``guiding.SATURATED``): the path left the arm's
    reach from its home pose, or met a singularity; such a case measures the arm's
    workspace, not its controller (e.g. the 20 cm upward line of a smaller arm).
    """
    stuck = [name for name, f in results.items() if f.get("hand_saturated")]
    if not stuck:
        return ""
    return (
        f"the hand saturated (path out of reach or through a singularity): {len(stuck)} "
        f"of {len(results)} cases ({_first_names(stuck)}); their figures measure the workspace"
    )


def parse_seeds(text: str) -> list[int]:
    """``"5-8"`` → [5, 6, 7, 8]; ``"5,9"`` → [5, 9]."""
    seeds: list[int] = []
    for part in text.split(","):
        low, _, high = part.partition("-")
        seeds += range(int(low), int(high or low) + 1)
    return seeds


def plant_ranges(settings: list[str] | None) -> PlantRanges:
    """The plant family: :class:`PlantRanges` with ``FIELD=VALUE`` settings replacing ranges.

    VALUE is one number for a scalar field (``position_amplitude=0.25``) and ``LOW,HIGH``
    for a range (``friction_scale=0.7,1.3``; whole numbers for ``delay_periods``).

    Raises:
        ValueError: An unknown field, a malformed value or one outside what the field allows
            (one line naming it).
    """
    defaults, changes = PlantRanges(), {}
    # the ranges (--enabling-device and --no-torque-sensor set the switches)
    known = [f.name for f in fields(PlantRanges) if not isinstance(f.default, bool)]
    for setting in settings or []:
        name, _, text = setting.partition("=")
        if name not in known:
            raise ValueError(f"--plants: unknown field {name!r}, choose from {', '.join(known)}")
        default = getattr(defaults, name)
        kind = type(default[0]) if isinstance(default, tuple) else type(default)
        try:
            numbers = tuple(kind(x) for x in text.split(","))
        except ValueError:
            numbers = ()
        if len(numbers) != (len(default) if isinstance(default, tuple) else 1):
            form = "LOW,HIGH" if isinstance(default, tuple) else "one number"
            raise ValueError(f"--plants: {name} takes {form}, got {text!r}")
        changes[name] = numbers if isinstance(default, tuple) else numbers[0]
    try:
        return replace(defaults, **changes)
    except ParameterError as error:
        raise ValueError(f"--plants: {error}") from None


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", choices=("full", "quick", "contact"), default="full")
    add_robot_arguments(parser)  # --robot, --tip, --drive-data, as the command line's
    parser.add_argument(
        "--uncalibrated",
        action="store_true",
        help="both modes without the start-up calibration (the constructor's default)",
    )
    parser.add_argument(
        "--seeds",
        default="1-4",
        help="plant seeds of the full set, e.g. 5-8 or 5,9 (default 1-4, the development "
        "seeds; others are plants the defaults were not developed on)",
    )
    parser.add_argument(
        "--hands",
        default=",".join(BENCHMARK_HANDS),
        help=f"hands of the full set, from {', '.join(HANDS)} (default "
        f"{','.join(BENCHMARK_HANDS)}; the circle takes the first)",
    )
    parser.add_argument(
        "--plants",
        nargs="+",
        metavar="FIELD=VALUE",
        help="draw the plants from another family: fields of twin.plants.PlantRanges, e.g. "
        "position_amplitude=0.25 friction_scale=0.7,1.3 (default: the family the defaults "
        "were developed on)",
    )
    parser.add_argument(
        "--enabling-device",
        action="store_true",
        help="plants with a hand-guiding enabling device, held while the hand holds the arm "
        "and let go with it (JointState.enabling)",
    )
    parser.add_argument("--save", help="write the per-case figures and the summary to JSON")
    parser.add_argument("--compare", help="a JSON saved before: print its summary alongside")
    parser.add_argument(
        "--factory",
        help="module:function building the active controller "
        "from (robot, mode); default lt.LeadThrough(robot, mode=mode, dt=0.004, calibrate=True)",
    )
    parser.add_argument(
        "--dt",
        type=float,
        default=0.004,
        help="control period [s] of the plants and both default controllers (default 0.004, "
        "250 Hz; 0.001 for a 1 kHz arm; the delay stays 1-2 periods)",
    )
    parser.add_argument(
        "--pace",
        type=float,
        default=1.0,
        help="the hands' paths take this many times their duration (default 1: lines in "
        "4 s, the circle in 6 s; 2 is a hand twice as slow)",
    )
    parser.add_argument(
        "--grab-at-once",
        action="store_true",
        help="every hand grabs as the run starts, while the arm calibrates (an operator who "
        "does not wait): both modes",
    )
    parser.add_argument(
        "--rest",
        type=float,
        default=0.0,
        help="every hand grabs after the arm rested this long [s], nobody touching, after "
        "the calibration or from the start without one (default 0; the dither parks after "
        "2 s): both modes",
    )
    parser.add_argument(
        "--no-torque-sensor",
        action="store_true",
        help="plants whose drives report no torque (JointState.tau_measured None): both "
        "modes take the command they sent for it",
    )
    parser.add_argument(
        "--identified",
        action="store_true",
        help="identify each plant's friction first (the excitation of leadthrough identify, "
        "about 10 s per plant) and build both modes with it instead of the nominal friction",
    )
    args = parser.parse_args(argv)
    old = None
    if args.compare:  # read before the run: a wrong file must not cost the run's results
        try:
            with open(args.compare) as handle:
                old = json.load(handle)["summary"]
        except (OSError, ValueError, KeyError, TypeError) as error:
            parser.error(f"--compare {args.compare}: not a saved run ({error})")
    built = uncalibrated_factory if args.uncalibrated else default_factory
    factory = passive_factory = functools.partial(built, dt=args.dt)
    if args.identified:
        if args.factory:
            parser.error("--identified builds the default controllers: drop --factory")
        factory = passive_factory = IdentifiedFirst(built, args.dt)
    if args.factory:
        module, _, name = args.factory.partition(":")
        factory = getattr(importlib.import_module(module), name)
    seeds, hands = parse_seeds(args.seeds), args.hands.split(",")
    unknown = sorted(set(hands) - set(HANDS))
    if unknown:
        parser.error(f"unknown hand(s) {', '.join(unknown)}: choose from {', '.join(HANDS)}")
    try:
        ranges = replace(plant_ranges(args.plants), enabling_device=args.enabling_device,
                         torque_sensor=not args.no_torque_sensor)  # fmt: skip
    except ValueError as error:
        parser.error(str(error))
    try:
        TwinConfig(control_dt=args.dt)  # a period the twin can run
    except (ParameterError, TwinError) as error:
        parser.error(f"--dt: {error}")
    try:
        robot = robot_from(args)
    except RobotDescriptionError as error:
        parser.error(str(error))
    if not (math.isfinite(args.pace) and args.pace > 0.0):
        parser.error(f"--pace must be a number > 0, got {args.pace:g}")
    try:
        total = len(cases(args.cases, seeds, hands, ranges, args.pace, args.grab_at_once,
                          args.rest))  # fmt: skip
    except ParameterError as error:
        parser.error(f"--{error}")  # "--rest: …", the field the error names
    start = time.perf_counter()

    def report(name: str, figures: dict[str, float]) -> None:
        print(row(name, figures), flush=True)
        done = len(reported) + 1
        reported.append(name)
        print(f"  [{done}/{total}, {time.perf_counter() - start:.0f} s]", end="\r",
              file=sys.stderr, flush=True)  # fmt: skip

    reported: list[str] = []
    print(HEADER)
    results, stats = evaluate(args.cases, factory, robot, report, seeds,
                              passive_factory, hands, ranges, args.pace,
                              args.grab_at_once, args.rest)  # fmt: skip
    print_summary(stats, old)
    print(over_goal_line(results))
    print(uncalibrated_line(results))
    saturated = saturated_line(results)
    if saturated:
        print(saturated)
    if args.save:
        with open(args.save, "w") as handle:
            json.dump({"cases": results, "summary": stats, "family": asdict(ranges)}, handle,
                      indent=1)  # fmt: skip
        print(f"saved {args.save}")


if __name__ == "__main__":
    main()
