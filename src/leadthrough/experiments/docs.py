"""``make docs``: every figure, table and number the README shows, from seeded runs.

``make docs``, i.e. ``MUJOCO_GL=egl python -m leadthrough.experiments.docs [--root DIR]``,
runs the demo, a taught line and its replay, two twin scenarios, the friction identification
on three twins, every thesis experiment and the observer's per-joint runs, all seeded, and
writes

- ``docs/figures/*.png``: the README's figures;
- ``docs/results/*.md``: its tables;
- ``docs/results/numbers.json``: the numbers its text quotes (key → the text shown);

then rewrites the README's generated parts (:mod:`leadthrough.experiments.readme`). Scratch
output goes to ``out/docs``. Wall times are measured on the machine that runs it.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from leadthrough.experiments.friction_study import FrictionStudy, run_friction_study
from leadthrough.experiments.lead_through import plants_table
from leadthrough.experiments.observer import (
    breakaway_with_and_without_dither,
    identified_without_position,
    single_joint_guiding,
    torque_step_response,
)
from leadthrough.experiments.readme import update_readme
from leadthrough.experiments.report import ThesisExperiments, run_experiments, write_experiments
from leadthrough.model import robots
from leadthrough.model.description import RobotDescription
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

#: README figure ← (stage, file written by that stage).
FIGURES = {
    "demo_tool_paths.png": ("demo", "tool_paths.png"),
    "demo_operator_torque.png": ("demo", "operator_torque.png"),
    "demo_arm.png": ("demo", "arm.png"),
    "line.png": ("simulate", "line.png"),
    "table_push_arm.png": ("simulate", "table_push_arm.png"),
    "friction_raw_joint1.png": ("experiments", "fig4_2.png"),
    "friction_fit_joint1.png": ("experiments", "fig4_3.png"),
    "friction_gaussian_joint1.png": ("experiments", "fig4_5.png"),
    "friction_position_joint4.png": ("experiments", "fig4_6.png"),
    "passive_feed_forward.png": ("experiments", "fig4_8.png"),
    "observer_guiding_joint1.png": ("experiments", "fig5_2.png"),
    "observer_dither_joint4.png": ("experiments", "fig5_5.png"),
    "observer_dither_sweep.png": ("experiments", "fig5_3.png"),
    "stability.png": ("experiments", "stability.png"),
    "damping_joint7.png": ("experiments", "fig6_4.png"),
    "end_stop.png": ("experiments", "fig6_6.png"),
    "effort.png": ("experiments", "fig6_7.png"),
    "calibration.png": ("experiments", "calibration.png"),
    "level_error.png": ("experiments", "level_error.png"),
}
#: Joints of the dither table (0-based).
DITHER_JOINTS = (0, 3, 5)
#: The observers of the tables, in their columns' order.
OBSERVER_COLUMNS = ("kalman_time_varying", "kalman_two_level", "classical")
#: The demo's actions (``demo.teaching_actions``, in order) as the README's numbers name them.
DEMO_ACTIONS = ("line", "circle", "press", "lift")


def _f(value: float, digits: int = 2) -> str:
    return f"{value:.{digits}f}"


def _table(header: list[str], align: str, rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(align) + "|"]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows]) + "\n"


def twin_friction_table(robot: RobotDescription) -> str:
    """The twin's true friction per joint (LuGre), as the twin builds it by default."""
    p = DigitalTwin(robot, TwinConfig()).friction.params
    low, high = p.coulomb_level(robot.q_min), p.coulomb_level(robot.q_max)
    rows = [[str(j + 1), _f(p.coulomb[j]), _f(p.static[j]), _f(p.viscous[j]),
             f"{p.bristle_stiffness[j]:.1e}", f"{1e6 * p.static[j] / p.bristle_stiffness[j]:.0f}",
             f"{min(low[j], high[j]):.2f} … {max(low[j], high[j]):.2f}"]
            for j in range(robot.n_joints)]  # fmt: skip
    header = ["joint", "τ_C [Nm]", "τ_S [Nm]", "c [Nm s/rad]", "σ0 [Nm/rad]",
              "pre-sliding τ_S/σ0 [µrad]", "τ_C over the range [Nm]"]  # fmt: skip
    return _table(header, ["---"] + ["---:"] * 5 + ["---"], rows)


def identification_table(studies: dict[str, FrictionStudy]) -> str:
    """Per joint, the identified τ_C and c against each twin's truth [%]."""
    n = next(iter(studies.values())).robot.n_joints
    rows = []
    for label, study in studies.items():
        coulomb, viscous = study.errors()
        rows.append([f"τ_C error, {label} [%]", *(f"{100 * e:+.2f}" for e in coulomb)])
        rows.append([f"c error, {label} [%]", *(f"{100 * e:+.2f}" for e in viscous)])
    return _table(["joint", *(str(j + 1) for j in range(n))], ["---"] + ["---:"] * n, rows)


def observer_table(robot: RobotDescription, friction: object) -> str:
    """Per joint: accuracy while a hand turns it, and the response to a torque step."""
    rows = []
    for j in range(robot.n_joints):
        run = single_joint_guiding(robot, friction, joint=j)
        step = torque_step_response(robot, friction, joint=j)
        accuracy = {name: run.accuracy(name) for name in OBSERVER_COLUMNS}
        rise = " / ".join(f"{1000 * step.rise_after_motion[name]:.0f}" for name in OBSERVER_COLUMNS)
        ratios = [f"{100 * accuracy[name]['rms_over_peak']:.1f} %" for name in OBSERVER_COLUMNS]
        rows.append([str(j + 1), _f(accuracy["classical"]["peak_torque"]), *ratios,
                     ", ".join(f"{100 * accuracy[name]['within_2_std']:.0f} %"
                               for name in OBSERVER_COLUMNS[:2]), rise])  # fmt: skip
    header = ["joint", "peak [Nm]", "RMS/peak TV", "RMS/peak 2L", "RMS/peak classical",
              "in ±2 std (TV, 2L)", "63 % after motion TV / 2L / classical [ms]"]  # fmt: skip
    return _table(header, ["---"] + ["---:"] * 5 + ["---"], rows)


def dither_table(robot: RobotDescription, friction: object) -> str:
    """Breakaway under a rising push, and when the observer sees it, without / with dither."""
    rows = []
    for j in DITHER_JOINTS:
        result = breakaway_with_and_without_dither(robot, friction, joint=j)
        b, d = result.breakaway, result.detection_delay
        rows.append([str(j + 1), _f(b["no_dither"]), _f(b["dither"]), _f(result.ratio),
                     f"{d['no_dither']:.2f} / {d['dither']:.2f}"])  # fmt: skip
    header = [
        "joint",
        "breakaway without [Nm]",
        "with dither [Nm]",
        "ratio",
        "push seen (estimate ≥ ½ τ_C) after it reached ½ τ_C: without / with [s]",
    ]
    return _table(header, ["---", "---:", "---:", "---:", "---"], rows)


def viscous_table(
    robot: RobotDescription, joint: int = 4, seeds: tuple[int, ...] = (1, 2, 3)
) -> str:
    """Joint 5's viscous error on realistic twins, and what makes it small.

    The default excitation, the same twins with exact centres of mass, and a faster run.
    """
    from leadthrough.friction.identification import fit_friction, friction_samples
    from leadthrough.model.dynamics import Dynamics
    from leadthrough.runtime.excitation import DEFAULT_RUNS, friction_experiment

    dynamics = Dynamics(robot)
    fast = (
        DEFAULT_RUNS[0],
        replace(DEFAULT_RUNS[1], peak_velocity=3 * DEFAULT_RUNS[1].peak_velocity),
    )
    exact_com = replace(REALISTIC_TWIN.model_error, com_error=0.0)
    cases = {"default excitation": ({}, DEFAULT_RUNS),
             "centres of mass exact": ({"model_error": exact_com}, DEFAULT_RUNS),
             f"faster run, {fast[1].peak_velocity:g} rad/s": ({}, fast)}  # fmt: skip
    rows = []
    for label, (change, runs) in cases.items():
        errors = []
        for seed in seeds:
            twin = DigitalTwin(robot, replace(REALISTIC_TWIN, seed=seed, **change))
            logs = friction_experiment(twin, dynamics, [joint], runs=runs)
            model, _ = fit_friction(friction_samples(logs, dynamics), dynamics, [joint])
            errors.append(model.viscous[joint] / twin.friction.params.viscous[joint] - 1.0)
        rows.append([label, *(f"{100 * e:+.1f}" for e in errors)])
    header = [f"joint {joint + 1}, c error [%]", *(f"twin seed {seed}" for seed in seeds)]
    return _table(header, ["---"] + ["---:"] * len(seeds), rows)


def effort_summary(e: ThesisExperiments) -> str:
    """RMS hand force per path: none, passive, active, and the path errors."""
    rows = []
    for path, runs in e.effort.runs.items():
        rows.append([path.replace("_", " "), *(_f(runs[m].rms_force) for m in runs),
                     f"**{_f(e.effort.ratio(path))}**",
                     f"{1e3 * runs['active'].path_error:.1f} / "
                     f"{1e3 * runs['passive'].path_error:.1f}"])  # fmt: skip
    header = ["path", "none [N]", "passive [N]", "active [N]", "active / passive",
              "path error active / passive [mm]"]  # fmt: skip
    return _table(header, ["---"] + ["---:"] * 5, rows)


def _identify(robot: RobotDescription, seed: int, random_friction: bool) -> FrictionStudy:
    from leadthrough.twin.friction import randomized_friction

    friction = randomized_friction(robot, np.random.default_rng(seed)) if random_friction else None
    return run_friction_study(robot, twin_config=TwinConfig(seed=seed, friction=friction))


def _demo(robot: RobotDescription, out: Path, numbers: dict[str, str]) -> Path:
    from leadthrough.experiments.demo import (
        figures_by_action,
        hand_force_rms,
        path_smoothness,
        run_demo,
        teaching_actions,
    )
    from leadthrough.experiments.demo_report import write_report

    start = time.perf_counter()
    result = run_demo(out, robot, say=lambda text: None)
    write_report(result, robot, out)
    errors, sim = result.replay_error, result.taught
    numbers |= {
        "demo.seconds": f"{time.perf_counter() - start:.0f}",
        "demo.joint_rms_mrad": _f(1e3 * errors["joint_rms"]),
        "demo.joint_max_mrad": f"{1e3 * errors['joint_max']:.0f}",
        "demo.tool_rms_mm": _f(1e3 * errors["tool_rms"]),
        "demo.tool_max_mm": f"{1e3 * errors['tool_max']:.1f}",
        "demo.force_rms_n": _f(hand_force_rms(sim)),
        "demo.passive_force_rms_n": _f(hand_force_rms(result.passive)),
    }
    actions = teaching_actions(robot)
    smooth = path_smoothness(sim, actions)
    numbers |= {f"demo.vibration_{key}_mm_s": _f(1e3 * value) for key, value in smooth.items()}
    passive = path_smoothness(result.passive, actions)["taught"]
    numbers["demo.vibration_passive_mm_s"] = _f(1e3 * passive)
    by_action = zip(DEMO_ACTIONS, figures_by_action(sim, actions),
                    figures_by_action(result.passive, actions), strict=True)  # fmt: skip
    for name, active_figures, passive_figures in by_action:
        numbers[f"demo.{name}.vibration_mm_s"] = f"{1e3 * active_figures.vibration:.1f}"
        numbers[f"demo.{name}.passive_vibration_mm_s"] = f"{1e3 * passive_figures.vibration:.1f}"
        numbers[f"demo.{name}.force_n"] = f"{active_figures.force:.1f}"
        numbers[f"demo.{name}.passive_force_n"] = f"{passive_figures.force:.1f}"
    return out / "friction.toml"


def _line(robot: RobotDescription, out: Path, friction: Path, numbers: dict[str, str]) -> None:
    from leadthrough.experiments.teach import replay_recording, teach_on_twin
    from leadthrough.runtime.recording import read_recording

    path = out / "taught.mcap"
    teach_on_twin(robot, path, "line", friction_file=friction, overwrite=True)
    recording = read_recording(path)
    _, errors, _ = replay_recording(robot, recording.t, recording.q, None,
                                    replace(REALISTIC_TWIN, seed=1))  # fmt: skip
    numbers |= {"line.joint_rms_mrad": _f(1e3 * errors["joint_rms"]),
                "line.tool_rms_mm": _f(1e3 * errors["tool_rms"])}  # fmt: skip


def _experiment_numbers(e: ThesisExperiments) -> dict[str, str]:
    stops = e.end_stops
    release = e.releases[next(iter(e.releases))]
    return {
        "end_stop.thesis_rad": _f(stops["thesis settings"].travel_after_release),
        "end_stop.defaults_rad": _f(stops["defaults"].travel_after_release),
        "release.stop_s": _f(release.stop_time),
        "release.drift_mrad": f"{1e3 * release.drift:.1f}",
        "breakaway.ratio": _f(e.breakaway.ratio),
        "stability.k_m_min": f"{e.stability.stable_scales(3000.0).min():.2g}",
    }


def generate(root: Path, say: Callable[[str], None] = print) -> list[Path]:
    """Run everything (seeded), write figures, tables and numbers under ``root/docs``."""
    robot = robots.yumi()
    work, figures, results = root / "out" / "docs", root / "docs" / "figures", root / "docs/results"
    for directory in (work, figures, results):
        directory.mkdir(parents=True, exist_ok=True)
    numbers: dict[str, str] = {}
    tables: dict[str, str] = {"twin_friction.md": twin_friction_table(robot)}
    say("demo (identify, teach, replay) …")
    friction = _demo(robot, work / "demo", numbers)
    say("a taught line and its replay …")
    _line(robot, work / "line", friction, numbers)
    say("twin scenarios …")
    from leadthrough.twin.session import run_scenario

    for name in ("line", "table_push"):
        run_scenario(robot, name, None, 0, work / "simulate")
    say("friction identification on three twins …")
    studies = {"default twin": _identify(robot, 0, False),
               "random twin seed 2": _identify(robot, 2, True)}  # fmt: skip
    numbers |= {
        "identify.seconds": f"{studies['default twin'].seconds:.1f}",
        "identify.simulated_s": f"{studies['default twin'].simulated_seconds:.0f}",
    }
    experiments = run_experiments(robot, say)
    studies["realistic twin"] = experiments.study
    tables["identification.md"] = identification_table(studies)
    write_experiments(robot, work / "experiments", say, experiments)
    numbers |= _experiment_numbers(experiments)
    tables |= {
        "effort.md": effort_summary(experiments),
        "calibration.md": plants_table(experiments.calibration, experiments.releases) + "\n",
    }
    say("observer, every joint …")
    observed = identified_without_position(experiments.study.model)
    tables["observer.md"] = observer_table(robot, observed)
    tables["dither.md"] = dither_table(robot, observed)
    say("joint 5's viscous friction on realistic twins …")
    tables["viscous_joint5.md"] = viscous_table(robot)
    written = []
    for name, (stage, source) in FIGURES.items():
        written.append(Path(shutil.copyfile(work / stage / source, figures / name)))
    for name, text in tables.items():
        (results / name).write_text(text, encoding="utf-8")
        written.append(results / name)
    (results / "numbers.json").write_text(json.dumps(numbers, indent=1, sort_keys=True) + "\n",
                                          encoding="utf-8")  # fmt: skip
    return [*written, results / "numbers.json"]


def main(argv: list[str] | None = None) -> int:
    """Regenerate the docs under ``--root`` (default: the current directory) and the README."""
    parser = argparse.ArgumentParser(prog="python -m leadthrough.experiments.docs")
    parser.add_argument("--root", type=Path, default=Path(), help="repository root")
    args = parser.parse_args(argv)
    if not os.environ.get("MUJOCO_GL"):  # read when MuJoCo was imported, above
        print(
            "error: set MUJOCO_GL (e.g. egl) before running this; make docs does", file=sys.stderr
        )
        return 2
    start = time.perf_counter()
    written = generate(args.root)
    changed = update_readme(args.root / "README.md", args.root)
    print(f"{len(written)} files written in {time.perf_counter() - start:.0f} s; README "
          f"{'updated' if changed else 'unchanged'}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
