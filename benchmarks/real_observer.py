"""The observer, contacts and payload on real robot logs (issue 14, items 4-5).

Reads ``../shared/realdata`` (or ``--data DIR``); never copies it. Tables (Markdown):

1. False-alarm level of the UR10e with the nominal URDF: RMS and peak of τ̂_ext per
   joint in free motion (validation runs and no_torque) and at rest (p1…p10), the
   fraction of samples with |τ̂_ext| > 2 std and the RMS of τ̂/std (≈ 1: honest std).
2. Contacts found in the push runs and in the free-motion runs; with the identified
   model also with the nominal friction noise σ (its own σ slows the observer).
3. The Panda, fed its joint torque sensors in free motion: τ̂_ext per joint with the
   shipped description and with the paper's identified inertials.
4. Apparent payload of unloaded UR10e runs: with the nominal model alone, and with
   another unloaded run of other motions as ``unloaded=`` (should read ≈ 0).

Usage:
    python benchmarks/real_observer.py [--data DIR] [--save out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

import leadthrough as lt
from leadthrough.estimation.log_observer import (
    ModelUncertainty,
    false_alarm_table,
    observe_log,
    run_detector,
)
from leadthrough.experiments.real_dynamics import ur10e_dynamics_study
from leadthrough.experiments.real_logs import events_markdown, false_alarm_markdown
from leadthrough.friction.model import FrictionModel

DEFAULT = Path(__file__).resolve().parents[2] / "shared" / "realdata"
FREE = ["validation/ur-20_01_17-ptp_10_points.csv", "validation/collision_free.csv",
        "pushes/no_torque.csv"]  # fmt: skip
STATIC = [f"validation/ur-20_01_17-p{k}.csv" for k in range(1, 11)]
IDENTIFIED = ModelUncertainty(rigid_body=0.03, gravity=0.03)
PUSHES = ["pushes/ur-static.csv", "pushes/link4.csv"]
UNLOADED = ["identification/ur-20_02_12-50sec_12harm.csv",
            "identification/ur-20_02_19_14harm50sec.csv",
            "identification/ur-20_02_19_15harm50sec.csv",
            "identification/ur-20_02_12-40sec_12harm.csv"]  # fmt: skip


def read(root: Path, relative: str, robot: lt.RobotDescription) -> lt.JointLog:
    """A log of ``root`` (read-only)."""
    return lt.read_log(root / "ur10e" / relative, robot=robot)


def false_alarms(
    root: Path,
    robot: lt.RobotDescription,
    results: dict,
    model: str = "nominal URDF",
    friction: FrictionModel | None = None,
) -> None:
    """Table 1 and the free-motion half of table 2 (``friction`` None: the robot's own)."""
    for name, files in (("free motion", FREE), ("at rest", STATIC)):
        observed = [observe_log(read(root, f, robot), robot, friction) for f in files]
        table = false_alarm_table(observed)
        seconds = sum(o.t[-1] - o.t[0] for o in observed)
        print(f"\n### UR10e, {model}, {name}: {len(files)} runs, {seconds:.0f} s\n")
        print(false_alarm_markdown(table))
        results[f"ur10e_{model}_{name}"] = {k: v.tolist() for k, v in table.items()}
        counts = {f: len(run_detector(o)) for f, o in zip(files, observed, strict=True)}
        results[f"ur10e_{model}_{name}_contacts"] = counts
        print(f"\ncontacts detected: {sum(counts.values())} "
              f"({', '.join(f'{Path(f).name}: {c}' for f, c in counts.items())})")  # fmt: skip


def contacts(
    root: Path,
    robot: lt.RobotDescription,
    results: dict,
    label: str = "",
    friction: FrictionModel | None = None,
) -> None:
    """Table 2: the push runs (``friction`` None: the robot's own)."""
    for relative in PUSHES:
        log = read(root, relative, robot)
        events = lt.detect_contacts(log, robot, friction)
        print(f"\n### Contacts in {relative} ({log.duration:.0f} s){label}\n")
        print(events_markdown(events, float(log.t[0])))
        results[relative + label] = [(e.start - log.t[0], e.end - log.t[0], list(e.joints),
                              e.peak.tolist()) for e in events]  # fmt: skip


def panda(root: Path, drive: Path | None, results: dict) -> None:
    """Table 3: the Panda's observer on its sensor torques."""
    folder = root / "panda_gaz2019"
    log = lt.read_log(folder)
    models = {"shipped panda()": lt.robots.panda()}
    if drive is not None:
        models["paper's identified inertials"] = lt.robots.load(
            folder / "panda_identified.urdf", drive_data=drive
        )
    print(f"\n### Panda, free motion ({log.duration:.0f} s at ~1 kHz), joint torque sensors\n")
    scale = np.sqrt(np.mean(log.tau**2, axis=0))
    print("RMS of the measured torque per joint [Nm]: "
          + ", ".join(f"{value:.1f}" for value in scale))  # fmt: skip
    cases = [(name, robot, None) for name, robot in models.items()]
    if drive is not None:  # an identified model deserves a smaller model uncertainty
        name = "paper's identified inertials"
        cases.append((f"{name}, ModelUncertainty(rigid_body=0.03, gravity=0.03)",
                      models[name], IDENTIFIED))  # fmt: skip
    for name, robot, uncertainty in cases:
        table = false_alarm_table([observe_log(log, robot, None, uncertainty)])
        print(f"\n{name}:\n")
        print(false_alarm_markdown(table))
        results[f"panda {name}"] = {k: v.tolist() for k, v in table.items()}


def payload(root: Path, robot: lt.RobotDescription, results: dict) -> None:
    """Table 4: apparent payload of unloaded runs (truth: 0 kg)."""
    logs = [read(root, f, robot) for f in UNLOADED]
    print("\n### Apparent payload of unloaded UR10e runs (truth 0 kg), nominal URDF\n")
    print("| run | alone: mass [kg] | with another run as unloaded= [kg] | COM [m] (alone) |")
    print("|---|---:|---:|---|")
    rows = []
    for k, log in enumerate(logs):
        alone = lt.estimate_payload(log, robot)
        other = lt.estimate_payload(log, robot, unloaded=logs[(k + 1) % len(logs)])
        com = ", ".join(f"{c:+.2f}" for c in alone.com)
        print(f"| {Path(UNLOADED[k]).name} | {alone.mass:+.2f} ± {alone.mass_std:.2f} | "
              f"{other.mass:+.2f} ± {other.mass_std:.2f} | {com} |")  # fmt: skip
        rows.append((alone.mass, alone.mass_std, other.mass, other.mass_std))
    results["payload_unloaded_runs"] = rows


def payload_identified(root: Path, identified: lt.RobotDescription, results: dict) -> None:
    """The apparent payload of unloaded runs not fitted, nominal against identified model."""
    print("\n### Apparent payload of unloaded held-out runs (truth 0 kg), model alone\n")
    print("| run | nominal URDF [kg] | identified [kg] |")
    print("|---|---:|---:|")
    nominal = lt.robots.ur10e()
    for relative in FREE:
        row = [lt.estimate_payload(read(root, relative, robot), robot)
               for robot in (nominal, identified)]  # fmt: skip
        print(f"| {Path(relative).name} | "
              + " | ".join(f"{p.mass:+.2f} ± {p.mass_std:.2f}" for p in row) + " |")  # fmt: skip
        results[f"payload_held_out {relative}"] = [(p.mass, p.mass_std) for p in row]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT, help="the realdata folder")
    parser.add_argument("--save", type=Path, help="write the numbers as JSON")
    args = parser.parse_args()
    if not (args.data / "ur10e").is_dir():
        print(f"real_observer: skipped, real robot logs not found at {args.data}")
        return 0
    warnings.simplefilter("ignore", lt.robots.AssumedDriveDataWarning)
    start = time.perf_counter()
    robot = lt.robots.ur10e()
    results: dict = {}
    false_alarms(args.data, robot, results)
    contacts(args.data, robot, results)
    identified = ur10e_dynamics_study(args.data).identified  # fitted on identification/*harm*
    false_alarms(args.data, identified, results, "identified (lt.identify_dynamics)")
    contacts(args.data, identified, results, ", identified model")
    # the identified model with the nominal friction noise σ: what its own σ costs
    nominal_noise = replace(FrictionModel.from_robot(identified),
                            noise_std=FrictionModel.from_robot(robot).noise_std)  # fmt: skip
    false_alarms(args.data, identified, results, "identified, nominal σ", nominal_noise)
    contacts(args.data, identified, results, ", identified model, nominal σ", nominal_noise)
    payload_identified(args.data, identified, results)
    drive = Path(lt.__file__).parent / "model" / "robots" / "data" / "panda_drive.toml"
    panda(args.data, drive if drive.is_file() else None, results)
    payload(args.data, robot, results)
    print(f"\n({time.perf_counter() - start:.0f} s)")
    if args.save:
        args.save.write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
