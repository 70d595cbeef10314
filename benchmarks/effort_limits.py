"""Where the operator's effort in active mode comes from: the admittance driven by the truth.

The twin knows the operator's joint torque. A LeadThrough whose admittance is driven by it,
instead of by the observer's estimate, shows what a better estimate could gain under each
rule of which joints are assisted. Printed: RMS hand force over that of passive mode, the
same hand on the same paths (seed 1, friction identified on the realistic twin).

Usage:
    python benchmarks/effort_limits.py
"""

from __future__ import annotations

import numpy as np

import leadthrough as lt
from leadthrough.control.active_law import ActiveLaw
from leadthrough.control.admittance import dead_zone
from leadthrough.experiments.friction_study import run_friction_study
from leadthrough.experiments.lead_through import PATHS, guided_run
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.simulator import DigitalTwin


class TruthLaw(ActiveLaw):
    """The active law with the twin's true operator torque as its input.

    Attributes:
        twin: The twin whose truth is read (never available on a robot).
        rule: ``"moving"``: only joints moving the way the torque pushes; ``"engaged"``:
            every joint while one moves that way; ``"dead-zone"``: every joint, through a
            dead-zone of 0.2 τ_C.
    """

    compiled = False  # the NumPy law, whose drive this replaces
    twin: DigitalTwin
    rule: str

    def _update_drive(self, estimate, q, qd, gravity) -> None:
        super()._update_drive(estimate, q, qd, gravity)  # the bias keeps learning as usual
        tau = self.twin.truth.tau_operator
        with_motion = (np.sign(qd) * tau > 0.0) & (
            np.abs(qd) > self.parameters.compensation.dead_band
        )
        if self.rule == "moving":
            self.drive = np.where(with_motion, tau, 0.0)
        elif self.rule == "engaged":
            self.drive = tau if with_motion.any() else np.zeros_like(tau)
        else:
            self.drive = dead_zone(tau, 0.2 * self.friction.coulomb)


class TruthDriven(lt.LeadThrough):
    """Active lead-through whose admittance input is the twin's true operator torque."""

    law_class = TruthLaw

    def __init__(self, robot, friction, twin: DigitalTwin, rule: str) -> None:
        super().__init__(robot, "active", friction=friction)
        self.law.twin, self.law.rule = twin, rule


def rms_force(robot, friction, path: str, rule: str) -> float:
    """RMS hand force [N] over the path's duration, the truth-driven controller on the twin."""

    def truth_driven(twin: DigitalTwin) -> TruthDriven:
        return TruthDriven(robot, friction, twin, rule)

    return guided_run(robot, path, "active", friction, controller_for=truth_driven).rms_force


def main() -> None:
    robot = lt.robots.yumi()
    friction = run_friction_study(robot, twin_config=REALISTIC_TWIN).model
    passive = {path: guided_run(robot, path, "passive", friction).rms_force for path in PATHS}
    rows = {"the estimate (defaults)": [guided_run(robot, path, "active", friction).rms_force
                                         for path in PATHS]}  # fmt: skip
    for rule, label in (("moving", "the truth, joints moving with it"),
                        ("engaged", "the truth, every joint while one moves with it"),
                        ("dead-zone", "the truth, through a 0.2 τ_C dead-zone")):  # fmt: skip
        rows[label] = [rms_force(robot, friction, path, rule) for path in PATHS]
    print(f"{'admittance driven by':<50}" + "".join(f"{path:>16}" for path in PATHS))
    for label, forces in rows.items():
        ratios = [force / passive[path] for force, path in zip(forces, PATHS, strict=True)]
        print(f"{label:<50}" + "".join(f"{ratio:>16.2f}" for ratio in ratios))


if __name__ == "__main__":
    main()
