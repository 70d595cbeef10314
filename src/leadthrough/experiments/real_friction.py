"""Friction identified on real robots' logs, against what the labs that recorded them published.

The UR10e: each joint from its own jointwise run (``jointwise/ur-20_01_22-joint_k.csv``,
joint k alone on a ~0.1 Hz sinusoidal velocity), torque K·i with the description's drive
gains; published: Mamedov & Mikhel's linear ``f_v q̇ + f_c sign(q̇) + f_0``. The Panda:
every joint from its one excitation run (joint torque sensors); published: Gaz et al.'s
sigmoid ``φ1 s(φ2 (q̇ + φ3)) − φ1 s(φ2 φ3)``. Both models are scored on the same friction
samples (measured torque minus the rigid-body torque of the same description), every
sample of the run in which the joint moved, slow ones included.

The logs are read from a folder laid out as ``../shared/realdata`` (never shipped).
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from leadthrough.friction.identification import FitReport, fit_friction, friction_samples
from leadthrough.friction.model import FrictionModel, sigmoid
from leadthrough.logs.log import JointLog
from leadthrough.logs.rows import LogError
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.runtime.readers import read_log

#: A friction curve: (q̇ [rad/s], q [rad]) of one joint → torque [Nm].
Curve = Callable[[FloatArray, FloatArray], FloatArray]


@dataclass(frozen=True, eq=False)
class JointFriction:
    """One joint's identified friction, the published curve and the samples both are scored on.

    Attributes:
        robot: Robot name.
        joint: Joint index (0-based).
        model: The identified model (all joints; only ``joint`` is identified here).
        published: The published friction curve of this joint.
        published_text: The published parameters, as a short text.
        q: Joint position of the samples [rad].
        qd: Filtered joint velocity of the samples [rad/s].
        tau_friction: Measured torque minus rigid-body torque [Nm].
        report: The fit report.
    """

    robot: str
    joint: int
    model: FrictionModel
    published: Curve
    published_text: str
    q: FloatArray
    qd: FloatArray
    tau_friction: FloatArray
    report: FitReport

    def ours(self, qd: FloatArray, q: FloatArray | None = None) -> FloatArray:
        """Mean of the identified model for this joint [Nm]."""
        n, j = self.model.n_joints, self.joint
        qd_all = np.zeros((len(qd), n))
        qd_all[:, j] = qd
        q_all = np.tile(self.model.position_mid, (len(qd), 1))
        if q is not None:
            q_all[:, j] = q
        return self.model.mean(qd_all, q_all)[:, j]

    @property
    def rms_ours(self) -> float:
        """Residual RMS of the identified model on the samples [Nm]."""
        return _rms(self.tau_friction - self.ours(self.qd, self.q))

    @property
    def rms_published(self) -> float:
        """Residual RMS of the published model on the same samples [Nm]."""
        return _rms(self.tau_friction - self.published(self.qd, self.q))

    def min_level(self, q_min: float, q_max: float) -> float:
        """Smallest Coulomb level τ_C(q) over [q_min, q_max] [Nm]."""
        q = np.tile(self.model.position_mid, (2001, 1))
        q[:, self.joint] = np.linspace(q_min, q_max, 2001)
        level = np.broadcast_to(self.model.coulomb_level(q), q.shape)
        return float(np.min(level[:, self.joint]))


def _rms(x: FloatArray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def identify_joint(log: JointLog, robot: RobotDescription, joint: int) -> tuple:
    """(model, report, q, q̇, τ_f) of ``joint`` from ``log`` with the default settings."""
    dynamics = Dynamics(robot)
    samples = friction_samples(log, dynamics)
    model, report = fit_friction(samples, dynamics, joints=[joint])
    mine = samples.moved[:, joint]
    return (model, report, samples.q[mine, joint], samples.qd[mine, joint],
            samples.tau_friction[mine, joint])  # fmt: skip


def published_value(description: Path, prefix: str) -> list:
    """The value of the first key starting with ``prefix`` in the published JSON.

    ``description/published_identification.json`` of ``../shared/realdata/ur10e``.

    Raises:
        LogError: One line naming the file: it cannot be read, is not JSON, or has no
            such key (a malformed file ended in a JSONDecodeError or StopIteration).
    """
    path = description / "published_identification.json"
    try:
        table = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise LogError(f"{path}: cannot read the published identification ({error})") from None
    found = [value for key, value in table.items() if key.startswith(prefix)] if isinstance(
        table, dict) else []  # fmt: skip
    if not found:
        raise LogError(f"{path}: no {prefix}* entry: not the published identification")
    return found[0]


def ur10e_friction(
    folder: str | Path, robot: RobotDescription | None = None
) -> list[JointFriction]:
    """Each UR10e joint from its jointwise run, with the published linear friction."""
    from leadthrough.model.robots.registry import ur10e

    folder = Path(folder) / "ur10e"
    robot = robot or quietly(ur10e)
    linear = published_value(folder / "description", "linear_friction")
    rows = []
    for j in range(robot.n_joints):
        log = quietly(read_log, folder / "jointwise" / f"ur-20_01_22-joint_{j + 1}.csv", robot)
        model, report, q, qd, tau = identify_joint(log, robot, j)
        fv, fc, f0 = linear[j]
        curve = _linear_curve(fv, fc, f0)
        text = f"f_c {fc:.2f}, f_v {fv:.2f}, f_0 {f0:+.2f}"
        rows.append(JointFriction("ur10e", j, model, curve, text, q, qd, tau, report))
    return rows


def panda_friction(
    folder: str | Path, robot: RobotDescription | None = None
) -> list[JointFriction]:
    """Each Panda joint from the excitation run, with Gaz et al.'s sigmoid (Table I).

    The default description is the paper's identified URDF in the data folder (so the
    rigid-body torque removed is the one their friction was fitted with).
    """
    from leadthrough.model.robots.urdf import from_urdf

    folder = Path(folder) / "panda_gaz2019"
    robot = robot or quietly(from_urdf, folder / "panda_identified.urdf")
    table = json.loads((folder / "published_identification.json").read_text())
    phi = next(value for key, value in table.items() if key.startswith("friction_sigmoid"))
    log = quietly(read_log, folder, robot)
    dynamics = Dynamics(robot)
    samples = friction_samples(log, dynamics)
    model, report = fit_friction(samples, dynamics)
    rows = []
    for j in range(robot.n_joints):
        p1, p2, p3 = (phi[name][j] for name in ("phi1_Nm", "phi2_s_per_rad", "phi3_rad_per_s"))
        text = f"φ1 {p1:.3f}, φ2 {p2:.2f}, φ3 {p3:+.4f}"
        q, qd, tau = samples.q[:, j], samples.qd[:, j], samples.tau_friction[:, j]
        rows.append(JointFriction("panda", j, model, _sigmoid_curve(p1, p2, p3), text,
                                  q, qd, tau, report))  # fmt: skip
    return rows


def _linear_curve(fv: float, fc: float, f0: float) -> Curve:
    return lambda qd, q: fv * qd + fc * np.sign(qd) + f0


def _sigmoid_curve(p1: float, p2: float, p3: float) -> Curve:
    return lambda qd, q: p1 * sigmoid(p2 * (qd + p3)) - p1 * sigmoid(p2 * p3)


def quietly(function: Callable, *args: object) -> object:
    """Call ``function`` without its warnings (assumed drive data, dropped rows: known)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return function(*args)


def friction_table(rows: list[JointFriction]) -> str:
    """Markdown table: ours against the published model, residual RMS of each."""
    lines = ["| robot | joint | ours τ_C [Nm] | ours c [Nm s/rad] | published | "
             "RMS ours [Nm] | RMS published [Nm] |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    for row in rows:
        j = row.joint
        lines.append(f"| {row.robot} | {j + 1} | {row.model.coulomb[j]:.3f} | "
                     f"{row.model.viscous[j]:.3f} | {row.published_text} | "
                     f"{row.rms_ours:.3f} | {row.rms_published:.3f} |")  # fmt: skip
    return "\n".join(lines)
