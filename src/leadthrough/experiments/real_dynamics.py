"""The UR10e's dynamics identified from its real excitation runs, judged on held-out runs.

Fitted on the multi-joint Fourier excitation runs ``identification/*harm*.csv`` (the ten
2020 runs of 20–58 s; the 2019 runs are short repeats of one trajectory), with the
friction of each joint's own jointwise run as the friction prior. Judged on runs not
fitted, ``validation/ur-20_01_17-ptp_10_points.csv`` and ``validation/collision_free.csv``:
torque prediction RMS per joint of ours, of the nominal URDF (the shipped description)
and of the published parameters (Mamedov & Mikhel's link inertials, rotor inertias,
linear friction with its offset), each in the log's torque units
(:mod:`leadthrough.identification.prediction`).

The published link inertials are not physically consistent (link 4's inertia is not
positive definite), so they cannot make a description; their torque is computed from
the same regressor the identification uses.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from leadthrough.experiments.real_friction import published_value, quietly, ur10e_friction
from leadthrough.friction.model import FrictionModel
from leadthrough.identification.dynamics import DynamicsReport, DynamicsSettings, identify_dynamics
from leadthrough.identification.prediction import gain_ratio, prediction_error, rms
from leadthrough.identification.regressor import regressor_rows
from leadthrough.identification.smoothing import smooth_derivative
from leadthrough.logs.log import JointLog
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.runtime.readers import read_log

#: The held-out runs, by the name the tables use.
HELD_OUT = {"ptp_10_points": "validation/ur-20_01_17-ptp_10_points.csv",
            "collision_free": "validation/collision_free.csv"}  # fmt: skip
#: The fitted runs (glob under ``ur10e/``).
FITTED = "identification/*harm*.csv"
MODELS = ("nominal", "published", "ours")


@dataclass(frozen=True, eq=False)
class DynamicsStudy:
    """An identification of the UR10e and its held-out errors.

    Attributes:
        nominal: The shipped description (the prior).
        identified: The identified description.
        report: The fit report.
        friction_prior: Friction from the jointwise runs.
        fitted: Names of the fitted runs.
        held_out: The held-out logs by name.
        errors: Held-out torque errors [Nm] by run name, then model name, (N, n).
    """

    nominal: RobotDescription
    identified: RobotDescription
    report: DynamicsReport
    friction_prior: FrictionModel
    fitted: tuple[str, ...]
    held_out: dict[str, JointLog]
    errors: dict[str, dict[str, FloatArray]]

    def rms(self, run: str, model: str) -> FloatArray:
        """RMS per joint of a model's error on a held-out run [Nm]."""
        return rms(self.errors[run][model])

    def percent(self, run: str, model: str) -> float:
        """RMS of all joints' errors over the RMS of all joints' torques [%]."""
        tau = self.held_out[run].tau
        return 100.0 * float(np.sqrt(np.mean(self.errors[run][model] ** 2) / np.mean(tau**2)))


def ur10e_dynamics_study(
    folder: str | Path, settings: DynamicsSettings | None = None
) -> DynamicsStudy:
    """Identify the UR10e from its excitation runs and score three models on held-out runs."""
    from leadthrough.model.robots.registry import ur10e

    root = Path(folder) / "ur10e"
    nominal = quietly(ur10e)
    rows = ur10e_friction(folder, nominal)
    prior = _combined_friction(rows)
    paths = sorted(root.glob(FITTED))
    logs = [quietly(read_log, path, nominal) for path in paths]
    identified, report = identify_dynamics(logs, nominal, prior, settings=settings)
    held_out = {name: quietly(read_log, root / path, nominal) for name, path in HELD_OUT.items()}
    published = published_parameters(root / "description", nominal)
    errors = {name: {"nominal": prediction_error(log, nominal),
                     "published": published_error(log, nominal, published),
                     "ours": prediction_error(log, identified, report.offset)}
              for name, log in held_out.items()}  # fmt: skip
    return DynamicsStudy(nominal, identified, report, prior, tuple(p.name for p in paths),
                         held_out, errors)  # fmt: skip


def _combined_friction(rows: list) -> FrictionModel:
    """One model whose joint j is the one identified from joint j's own run."""
    values = {name: np.array([getattr(row.model, name)[row.joint] for row in rows])
              for name in ("coulomb", "slope", "half_width", "viscous", "noise_std")}  # fmt: skip
    return FrictionModel(**values)


def published_parameters(description: Path, nominal: RobotDescription) -> FloatArray:
    """The published parameter vector in the layout of the identification's regressor."""
    model = pin.buildModelFromUrdf(str(description / "ur10e_published_identification.urdf"))
    n = nominal.n_joints
    inertial = np.concatenate([model.inertias[i + 1].toDynamicParameters() for i in range(n)])
    armature = published_value(description, "rotor_inertia")
    linear = np.array(published_value(description, "linear_friction"))
    return np.concatenate([inertial, armature, linear[:, 1], linear[:, 0], linear[:, 2]])


def published_error(log: JointLog, nominal: RobotDescription, parameters: FloatArray) -> FloatArray:
    """Measured minus published-model torque [Nm], (N, n) (published K = the nominal's)."""
    qd, qdd = smooth_derivative(log.t, log.qd, 0.03)
    friction = FrictionModel.from_robot(nominal)  # the sharp sigmoid: sign(q̇) of the paper
    rows = regressor_rows(nominal, friction, log.q, qd, qdd)
    predicted = (rows @ parameters).reshape(log.q.shape)
    return log.tau - gain_ratio(log, nominal) * predicted


def dynamics_table(study: DynamicsStudy) -> str:
    """Markdown: held-out RMS per joint of each model, and the RMS over all joints in %."""
    n = study.nominal.n_joints
    head = "| run | model | " + " | ".join(f"joint {j + 1} [Nm]" for j in range(n))
    lines = [head + " | all joints [% of torque] |", "|---" * (n + 3) + "|"]
    for run in study.held_out:
        for model in MODELS:
            values = " | ".join(f"{v:.2f}" for v in study.rms(run, model))
            lines.append(f"| {run} | {model} | {values} | {study.percent(run, model):.1f} |")
    return "\n".join(lines)


def panda_split_study(folder: str | Path) -> dict[str, FloatArray]:
    """The Panda's one excitation run: fitted on its first half, judged on its second.

    The halves are not independent runs (one Fourier trajectory, ~21 s), so this checks
    the fit on a robot with joint torque sensors, not generalisation. Prior: the shipped
    ``lt.robots.panda()``.

    Returns:
        Torque prediction RMS per joint [Nm] on the second half: "nominal" and "ours".
    """
    from leadthrough.model.robots.registry import panda

    robot = quietly(panda)
    log = quietly(read_log, Path(folder) / "panda_gaz2019", robot)
    half = log.n_samples // 2
    first, second = (JointLog(t=log.t[part], q=log.q[part], qd=log.qd[part], tau=log.tau[part])
                     for part in (slice(0, half), slice(half, None)))  # fmt: skip
    identified, report = identify_dynamics(first, robot)
    return {"nominal": rms(prediction_error(second, robot)),
            "ours": rms(prediction_error(second, identified, report.offset))}  # fmt: skip
