"""Identification on real robots' logs (issue 14): friction and dynamics against published values.

Friction: each UR10e joint from its jointwise run and each Panda joint from its excitation
run (``lt.identify_friction`` defaults), residual RMS of ours and of the published model on
the same samples. Dynamics: ``lt.identify_dynamics`` on the UR10e's excitation runs, torque
prediction RMS per joint on the held-out runs, ours against the nominal URDF and the
published parameters. Skips with one line when the logs are absent.

Usage:
    python benchmarks/real_identification.py [--realdata DIR] [--save out.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

#: ``../shared/realdata`` beside the repository.
REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--realdata", type=Path, default=REALDATA, help="the logs' folder")
    parser.add_argument("--save", help="write the numbers to JSON")
    args = parser.parse_args()
    if not (args.realdata / "ur10e").is_dir() or not (args.realdata / "panda_gaz2019").is_dir():
        print(f"real_identification: skipped, no real robot logs at {args.realdata}")
        return
    from leadthrough.experiments.real_dynamics import (
        dynamics_table,
        panda_split_study,
        ur10e_dynamics_study,
    )
    from leadthrough.experiments.real_friction import (
        friction_table,
        panda_friction,
        ur10e_friction,
    )

    start = time.perf_counter()
    rows = ur10e_friction(args.realdata) + panda_friction(args.realdata)
    friction_seconds = time.perf_counter() - start
    print(f"Friction (fit {friction_seconds:.1f} s): residual RMS on the same samples\n")
    print(friction_table(rows))
    start = time.perf_counter()
    study = ur10e_dynamics_study(args.realdata)
    seconds = time.perf_counter() - start
    print(f"\nUR10e dynamics fitted on {len(study.fitted)} excitation runs ({seconds:.1f} s, "
          "friction included); held-out torque prediction RMS:\n")  # fmt: skip
    print(dynamics_table(study))
    gains = " ".join(f"{g:.3f}" for g in study.report.gain_scale)
    print(f"\ndrive-gain scale g per joint: {gains}")
    panda = panda_split_study(args.realdata)
    print("\nPanda, fitted on the first half of its run, torque RMS on the second half [Nm]:\n")
    print("| model | " + " | ".join(f"joint {j + 1}" for j in range(7)) + " |")
    print("|---" * 8 + "|")
    for model, values in panda.items():
        print(f"| {model} | " + " | ".join(f"{v:.2f}" for v in values) + " |")
    if args.save:
        numbers = {
            "friction": [{"robot": r.robot, "joint": r.joint + 1, "rms_ours": r.rms_ours,
                          "rms_published": r.rms_published} for r in rows],
            "dynamics": {run: {model: study.rms(run, model).tolist() for model in
                               ("nominal", "published", "ours")} for run in study.held_out},
            "percent": {run: {model: study.percent(run, model) for model in
                              ("nominal", "published", "ours")} for run in study.held_out},
            "gain_scale": study.report.gain_scale.tolist(),
            "panda_second_half": {model: values.tolist() for model, values in panda.items()},
        }  # fmt: skip
        Path(args.save).write_text(json.dumps(numbers, indent=1), encoding="utf-8")
        print(f"saved {args.save}")


if __name__ == "__main__":
    main()
