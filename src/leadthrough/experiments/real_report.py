"""Reports of identification on real logs: ``report.md``, figures, tables, identified TOML.

Two entry points, both behind ``leadthrough identify``:

- :func:`write_realdata_report`: the public logs of ``../shared/realdata`` (a UR10e and a
  Panda), compared with what their labs published;
- :func:`write_logs_report`: a user's own logs of any description (friction and
  dynamics from the fitted logs, torque prediction on held-out logs).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from leadthrough.estimation.log_observer import measured_torque
from leadthrough.experiments.real_dynamics import dynamics_table, ur10e_dynamics_study
from leadthrough.experiments.real_friction import (
    JointFriction,
    friction_table,
    panda_friction,
    ur10e_friction,
)
from leadthrough.friction.identification import (
    FitReport,
    FrictionSamples,
    IdentificationError,
    fit_friction,
    friction_samples,
)
from leadthrough.friction.model import PARAMETER_COLUMNS, FrictionModel
from leadthrough.identification.dynamics import identify_dynamics
from leadthrough.identification.prediction import prediction_error, rms
from leadthrough.logs.log import JointLog
from leadthrough.model.description import RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.model.robots.toml_format import save_robot
from leadthrough.runtime.readers import read_log


def write_realdata_report(folder: Path, out: Path) -> str:
    """Identify the UR10e and the Panda of ``folder`` and write the comparison into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    ur, panda = ur10e_friction(folder), panda_friction(folder)
    _save_friction_figure(
        ur, "UR10e: friction of each joint's jointwise run", out / "ur10e_friction.png"
    )
    _save_friction_figure(
        panda, "Panda: friction on the excitation run", out / "panda_friction.png"
    )
    study = ur10e_dynamics_study(folder)
    for run, log in study.held_out.items():
        predicted = {model: log.tau - error for model, error in study.errors[run].items()}
        _save_prediction_figure(log.t, log.tau, predicted, f"UR10e, held-out run {run}",
                                out / f"ur10e_held_out_{run}.png")  # fmt: skip
    save_robot(study.identified, out / "ur10e_identified.toml")
    gains = ", ".join(f"{g:.3f}" for g in study.report.gain_scale)
    text = "\n".join([
        "# Identification on real robots' logs", "",
        f"Data: `{folder}` (not shipped). Friction: each UR10e joint from its jointwise run, the "
        "Panda's joints from its excitation run; residual RMS of each model on the same samples.",
        "", friction_table(ur + panda), "",
        "![UR10e friction](ur10e_friction.png)", "", "![Panda friction](panda_friction.png)", "",
        f"Dynamics of the UR10e fitted on {len(study.fitted)} excitation runs "
        f"({', '.join(study.fitted)}); torque prediction RMS on runs not fitted:", "",
        dynamics_table(study), "",
        f"Drive-gain scale g (identified K = g K): {gains}.", "",
        *[f"![held-out {run}](ur10e_held_out_{run}.png)" for run in study.held_out], "",
        "Identified description: `ur10e_identified.toml` "
        "(`lt.robots.load(\"ur10e_identified.toml\")`).",
    ])  # fmt: skip
    (out / "report.md").write_text(text + "\n", encoding="utf-8")
    return text


def write_logs_report(
    robot: RobotDescription, logs: Sequence[Path], held_out: Sequence[Path], out: Path
) -> str:
    """Friction and dynamics of ``robot`` from ``logs``, judged on ``held_out`` logs.

    Every log is read and every fit and prediction made before anything is written: a
    log that cannot be read leaves ``out`` as it was (a held-out log was read after the
    friction figure had been written, beside an earlier run's report).
    """
    fitted = [_users_log(path, robot) for path in logs]
    judged = [(path, _users_log(path, robot)) for path in held_out]
    prior, _, _ = _friction_fit(fitted, Dynamics(robot), logs)
    identified, report = identify_dynamics(fitted, robot, prior)
    # the friction saved is fitted again on the rigid body saved with it, and on the torque
    # its drive gains say the arm felt: fitted on the nominal one, it was a second, worse
    # friction (a plant 25 % heavier than its URDF: a level 18 % low, σ 4–6× too wide)
    felt = [replace(log, tau=log.tau * report.gain_scale) for log in fitted]
    friction, friction_report, samples = _friction_fit(felt, Dynamics(identified), logs)
    predictions = [(path, log, {"nominal": prediction_error(log, robot),
                                "ours": prediction_error(log, identified, report.offset)})
                   for path, log in judged]  # fmt: skip
    missing = friction_report.not_identified_note()
    if missing:
        warnings.warn(missing, stacklevel=2)
    panels = []
    for j in friction_report.joints:
        mine = samples.moved[:, j]
        grid = np.linspace(*np.percentile(samples.qd[mine, j], [0.5, 99.5]), 300)
        velocity = np.zeros((grid.size, robot.n_joints))
        velocity[:, j] = grid
        panels.append((f"joint {j + 1}", samples.qd[mine, j], samples.tau_friction[mine, j],
                       {"ours": (grid, friction.mean(velocity)[:, j])}))  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    _save_friction_figure(panels, f"{robot.name}: friction", out / "friction.png", raw=True)
    lines = [f"# Identification of {robot.name}", "", f"Fitted on: {', '.join(map(str, logs))}.",
             "", "Friction:", "", "```", str(friction_report), "```", "",
             *friction_values(friction, friction_report.joints), "",
             *([missing, ""] if missing else []), "Dynamics fit:", "",
             "```", str(report), "```", "", "![friction](friction.png)", ""]  # fmt: skip
    for index, (path, log, errors) in enumerate(predictions):
        predicted = {name: log.tau - error for name, error in errors.items()}
        name = f"held_out_{index + 1}.png"
        _save_prediction_figure(log.t, log.tau, predicted, f"held-out {path.name}", out / name)
        lines += [f"Held-out `{path}`: torque prediction RMS per joint [Nm]", "",
                  *_rms_rows(errors), "", f"![{path.name}]({name})", ""]  # fmt: skip
    save_robot(identified, out / "identified.toml")
    friction.save(out / "friction.toml")
    lines.append("Identified description: `identified.toml`; friction: `friction.toml`.")
    text = "\n".join(lines)
    (out / "report.md").write_text(text + "\n", encoding="utf-8")
    return text


def _friction_fit(
    fitted: Sequence[JointLog], dynamics: Dynamics, logs: Sequence[Path]
) -> tuple[FrictionModel, FitReport, FrictionSamples]:
    """The friction of ``fitted`` on the rigid body of ``dynamics``, and its samples.

    Raises:
        IdentificationError: The fit failed; the message names every run (``logs``).
    """
    samples = friction_samples(fitted, dynamics)
    try:
        friction, report = fit_friction(samples, dynamics)
    except IdentificationError as error:  # about every run together: name them
        raise IdentificationError(f"{', '.join(map(str, logs))}: {error}") from None
    return friction, report, samples


def _users_log(path: Path, robot: RobotDescription) -> JointLog:
    """A log of the user's robot, its torque for ``robot`` checked before any fit.

    Its reader's warnings are shown (rows dropped as corrupted): it is not the public
    data, whose known warnings the other reports silence.
    """
    log = read_log(path, robot)
    measured_torque(log, robot)  # one line if there is none, or currents without K
    return log


def friction_values(friction: FrictionModel, joints: Sequence[int]) -> list[str]:
    """A Markdown table of the identified joints' friction parameters (SPEC §4 names)."""
    rows = ["| joint | " + " | ".join(PARAMETER_COLUMNS) + " |",
            "|---:" * (len(PARAMETER_COLUMNS) + 1) + "|"]  # fmt: skip
    rows += [f"| {j + 1} | " + " | ".join(friction.parameter_cells(j)) + " |" for j in joints]
    return rows


def _rms_rows(errors: dict) -> list[str]:
    n = next(iter(errors.values())).shape[1]
    rows = ["| model | " + " | ".join(f"joint {j + 1}" for j in range(n)) + " |",
            "|---" * (n + 1) + "|"]  # fmt: skip
    for name, error in errors.items():
        rows.append(f"| {name} | " + " | ".join(f"{v:.2f}" for v in rms(error)) + " |")
    return rows


def _save_friction_figure(rows: list, title: str, path: Path, raw: bool = False) -> None:
    from leadthrough.plots import pyplot
    from leadthrough.plots.real_identification import plot_joint_friction

    panels = rows if raw else [_panel(row) for row in rows]
    figure = plot_joint_friction(panels, title)
    figure.savefig(path, dpi=110)
    pyplot().close(figure)


def _panel(row: JointFriction) -> tuple:
    grid = np.linspace(*np.percentile(row.qd, [0.5, 99.5]), 300)
    middle = np.full_like(grid, np.median(row.q))
    curves = {"ours": (grid, row.ours(grid, middle)),
              "published": (grid, row.published(grid, middle))}  # fmt: skip
    return (f"joint {row.joint + 1}", row.qd, row.tau_friction, curves)


def _save_prediction_figure(t, measured, predicted, title: str, path: Path) -> None:
    from leadthrough.plots import pyplot
    from leadthrough.plots.real_identification import plot_torque_prediction

    figure = plot_torque_prediction(t, measured, predicted, title)
    figure.savefig(path, dpi=110)
    pyplot().close(figure)
