"""How far the start-up calibration's readings move between its cycles (``max_drift``).

A joint's readings, averaged over both directions, must not move from the calibration
motion's first cycle to its last by more than ``CalibrationParameters.max_drift`` of what
the joint carries at the pose (its Coulomb level plus the gravity error read): at one pose
the model's errors stay as they are, so a reading that moves is a push that changes, a hand.
Three kinds of run, each the calibration of ``LeadThrough(robot, calibrate=True)``:

- nobody touching: the plants of ``benchmarks/guiding_quality.py`` (seeds 1..N, dry and
  LuGre) of each robot, and the YuMi's at 125 Hz and 1 kHz;
- an unknown payload at the flange of the nominal twin (the arm sags under it as the run
  starts, and the readings miss its inertia while the tracking's integral takes it up);
- a relaxed hand (300 N/m) that grabs the tool as the run starts and pulls it along the
  benchmark's paths (the YuMi's plants of ``--hand-seeds``).

Prints each run's largest ratio (``CalibrationRun.drift_ratio``; NaN for a run the push
bound stopped early, before any reading) and whether the calibration was accepted, then
the largest and smallest ratio of each kind, and draws them against the limit. Usage::

    python benchmarks/calibration_drift.py [--seeds 8] [--hand-seeds 1,2,9,10,11]
        [--out docs/bench/calibration_drift.png]
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from unittest import mock

import numpy as np

import leadthrough as lt
from leadthrough.control.calibration import Calibration, CalibrationParameters, CalibrationRun
from leadthrough.experiments.guiding import HANDS, PATH_NAMES, case_path
from leadthrough.twin.mjcf import Payload
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.operator import Hand
from leadthrough.twin.plants import sample_plant
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

#: Robots whose untouched plants are calibrated, and the YuMi's other control periods [s].
ROBOTS = ("yumi", "ur10e", "ur5", "panda")
OTHER_PERIODS = (0.008, 0.001)
#: Unknown payloads at the flange [kg] per robot.
PAYLOADS = {"yumi": (0.5, 1.0, 1.5, 2.3), "ur10e": (2.0, 5.0), "panda": (1.0, 2.0, 3.0)}


@dataclasses.dataclass(frozen=True)
class Run:
    """One calibration: its kind, label, largest drift ratio [–] and whether accepted."""

    kind: str
    label: str
    ratio: float
    accepted: bool


@contextmanager
def largest_ratios() -> Iterator[list[float]]:
    """While open, each calibration judged appends its largest drift ratio (NaN: none)."""
    ratios: list[float] = []
    judge = CalibrationRun.judge

    def judging(run: CalibrationRun, *args: np.ndarray) -> Calibration:
        result = judge(run, *args)
        ratios.append(np.nan if run.drift_ratio is None else float(np.max(run.drift_ratio)))
        return result

    with mock.patch.object(CalibrationRun, "judge", judging):
        yield ratios


def calibrate(robot: lt.RobotDescription, twin: DigitalTwin, ratios: list[float]) -> tuple[
    float, bool
]:  # fmt: skip
    """Run the start-up calibration of ``robot`` on ``twin``: (largest ratio, accepted)."""
    controller = lt.LeadThrough(robot, calibrate=True, dt=twin.dt)
    simulate(twin, controller, controller.calibration_time + 0.05, progress=False)
    accepted = controller.calibration is not None and controller.calibration.accepted
    # the last judged: the controller's warm-up, before the first period, judges its own
    ratio = ratios[-1] if ratios else np.nan
    ratios.clear()
    return ratio, accepted


def untouched(seeds: int) -> Iterator[tuple[str, Callable[[list[float]], tuple[float, bool]]]]:
    """Nobody touching: each robot's plants, and the YuMi's at the other periods."""
    settings = [(name, 0.004) for name in ROBOTS] + [("yumi", dt) for dt in OTHER_PERIODS]
    for name, dt in settings:
        robot = lt.robots.load(name)
        for physics in ("dry", "lugre"):
            for seed in range(1, seeds + 1):
                config = dataclasses.replace(sample_plant(robot, seed, physics).config,
                                             control_dt=dt)  # fmt: skip
                label = f"{name} {physics}#{seed} {1.0 / dt:.0f} Hz"
                yield label, lambda ratios, r=robot, c=config: calibrate(r, DigitalTwin(r, c),
                                                                         ratios)  # fmt: skip


def payloads() -> Iterator[tuple[str, Callable[[list[float]], tuple[float, bool]]]]:
    """An unknown payload at the flange of each robot's nominal twin (masses ±5 %)."""
    for name, masses in PAYLOADS.items():
        robot = lt.robots.load(name)
        for mass in masses:
            load = Payload(mass, (0.0, 0.0, 0.0))
            error = ModelError(mass_error=0.05, com_error=0.005, payload=load)
            config = TwinConfig(model_error=error, seed=1)
            yield f"{name} {mass:g} kg", lambda ratios, r=robot, c=config: calibrate(
                r, DigitalTwin(r, c), ratios)  # fmt: skip


def hands(seeds: list[int]) -> Iterator[tuple[str, Callable[[list[float]], tuple[float, bool]]]]:
    """A relaxed hand that grabs the YuMi's tool at once and pulls it along each path."""
    robot = lt.robots.yumi()
    for physics in ("dry", "lugre"):
        for seed in seeds:
            config = sample_plant(robot, seed, physics).config
            for path in PATH_NAMES:
                hand = Hand.from_parameters(case_path(robot, path), HANDS["relaxed"])
                yield f"{physics}#{seed} {path}", lambda ratios, c=config, h=hand: calibrate(
                    robot, DigitalTwin(robot, c, operator=h), ratios)  # fmt: skip


def plot(runs: list[Run], limit: float, out: Path) -> None:
    """Each run's largest ratio by kind, refused ones hollow, and the limit [PNG]."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = list(dict.fromkeys(run.kind for run in runs))
    fig, ax = plt.subplots(figsize=(7.0, 4.0))
    rng = np.random.default_rng(0)
    for k, kind in enumerate(kinds):
        for accepted, marker in ((True, "o"), (False, "x")):
            values = [r.ratio for r in runs if r.kind == kind and r.accepted == accepted]
            if values:
                x = k + rng.uniform(-0.2, 0.2, len(values))
                ax.scatter(x, np.maximum(values, 1e-4), marker=marker, s=18,
                           color=f"C{k}", label=None)  # fmt: skip
    ax.axhline(limit, color="k", linestyle="--", label=f"max_drift = {limit:g}")
    ax.set_yscale("log")
    ax.set_xticks(range(len(kinds)), kinds)
    ax.set_ylabel("readings' change / (level + gravity error read)")
    ax.set_title("Start-up calibration: how far the readings move between cycles\n"
                 "(o accepted, x refused)")  # fmt: skip
    ax.legend(loc="upper left")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    """Run every kind, print each run and the extremes, draw the figure."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=8, help="untouched plants 1..N per robot")
    parser.add_argument("--hand-seeds", default="1,2,9,10,11", help="YuMi plants a hand grabs")
    parser.add_argument("--out", type=Path, default=Path("docs/bench/calibration_drift.png"))
    args = parser.parse_args(argv)
    hand_seeds = [int(x) for x in args.hand_seeds.split(",")]
    kinds = (("nobody touching", untouched(args.seeds)), ("unknown payload", payloads()),
             ("a hand at once", hands(hand_seeds)))  # fmt: skip
    runs = []
    with largest_ratios() as ratios:
        for kind, cases in kinds:
            for label, run in cases:
                ratio, accepted = run(ratios)
                runs.append(Run(kind, label, ratio, accepted))
                print(f"{kind:16s} {label:28s} {ratio:7.3f}  "
                      f"{'accepted' if accepted else 'refused'}", flush=True)  # fmt: skip
    limit = CalibrationParameters().max_drift
    for kind, _ in kinds:
        values = np.array([r.ratio for r in runs if r.kind == kind])
        refused = sum(not r.accepted for r in runs if r.kind == kind)
        print(f"{kind}: largest {np.nanmax(values):.3f}, smallest {np.nanmin(values):.3f}, "
              f"above {limit:g}: {int(np.sum(values > limit))} of {len(values)}, "
              f"refused {refused}")  # fmt: skip
    plot(runs, limit, args.out)
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
