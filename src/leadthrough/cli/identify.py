"""``leadthrough identify``: friction identification on the twin or from a log file."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from leadthrough.errors import ParameterError
from leadthrough.experiments.friction_study import FrictionStudy, run_friction_study
from leadthrough.friction.model import PARAMETER_COLUMNS
from leadthrough.model.description import RobotDescription

FIGURES = {
    "fig4_2_raw_vs_filtered": "plot_raw_and_compensated",
    "fig4_3_sigmoid_fit": "plot_sigmoid_fit",
    "fig4_5_gaussian_model": "plot_gaussian_model",
    "fig4_6_position_dependence": "plot_position_dependence",
}


def parse_joints(text: str | None, n: int) -> list[int] | None:
    """``"1,4"`` → [0, 3] (1-based on the command line); None → all joints."""
    if text is None:
        return None
    try:
        joints = [int(item) - 1 for item in text.split(",") if item.strip()]
    except ValueError:
        raise ParameterError("joints", f"expected numbers like 1,4, got {text!r}") from None
    bad = [j + 1 for j in joints if not 0 <= j < n]
    if bad or not joints:
        raise ParameterError("joints", f"joints are numbered 1 to {n}, got {text!r}")
    twice = [j + 1 for k, j in enumerate(joints) if j in joints[:k]]
    if twice:
        raise ParameterError("joints", f"joint {twice[0]} is given twice in {text!r} "
                                       "(each joint is identified once)")  # fmt: skip
    return joints


def refuse_repeated_runs(logs: Sequence[Path], held_out: Sequence[Path] = ()) -> None:
    """Refuse a run named twice in ``--log`` and ``--held-out``.

    Twice: the same file however spelt, or a Panda text log named by its folder and by
    one of its files (:func:`~leadthrough.runtime.readers.run_path`).

    Raises:
        ParameterError: A ``--log`` run given twice (it would be fitted twice), or a
            ``--held-out`` one given twice or fitted too.
    """
    from leadthrough.logs.runs import refuse_repeated
    from leadthrough.runtime.readers import run_path

    named = [*(("--log", path) for path in logs), *(("--held-out", path) for path in held_out)]
    refuse_repeated((option, str(path), run_path(Path(path))) for option, path in named)


def refuse_taught_recordings(paths: Sequence[Path]) -> None:
    """Refuse a teaching recording (``.mcap``) as a run to identify from or judge on.

    A hand was on the arm: the motor torques balance its dynamics plus the operator's
    push, which the fit would take for friction and inertia. Every recording the project
    writes is of a taught session (``teach``, ``demo``, ``run_teaching``); replays and
    excitations are not recorded, so no recording is one nobody touched.

    Raises:
        LogError: A path is a recording, named with what to give instead.
    """
    from leadthrough.logs.rows import LogError
    from leadthrough.runtime.readers import detect_format

    for path in paths:
        if detect_format(Path(path)) == "recording":
            raise LogError(
                f"{path}: a teaching recording: the hand on the arm would be fitted "
                "as friction; identify from a log nobody touched (an excitation)"
            )


def identify(
    robot: RobotDescription,
    out: Path,
    *,
    log: Path | None = None,
    save_log: Path | None = None,
    joints: Sequence[int] | None = None,
    seed: int = 0,
    random_friction: bool = False,
    progress: bool | None = None,
) -> str:
    """Run the study, write parameters, report and figures into ``out``; return a summary."""
    out.mkdir(parents=True, exist_ok=True)
    if log is not None:
        from leadthrough.friction.logs import load_logs

        study = run_friction_study(robot, logs=load_logs(log), joints=joints)
    else:
        study = run_friction_study(robot, twin_config=_twin_config(robot, seed, random_friction),
                                   joints=joints, progress=progress)  # fmt: skip
    if save_log is not None:
        from leadthrough.friction.logs import save_logs

        save_logs(study.logs, save_log)
    study.model.save(out / "friction.toml")
    summary = summarise(study, out)
    missing = study.report.not_identified_note()
    if missing:
        warnings.warn(missing, stacklevel=2)
    (out / "identification.txt").write_text(summary + "\n", encoding="utf-8")
    _figures(study, out)
    return summary


def real_logs(paths: Sequence[Path] | None, held_out: Sequence[Path] = ()) -> bool:
    """Whether ``--log`` names a real arm's runs (anything but one project excitation log).

    With ``held_out`` runs, one excitation log is a run too: the held-out runs judge the
    dynamics, which only a real arm's runs identify (they were ignored).

    Raises:
        LogError: A file is in no known log format (found before any work starts).
    """
    from leadthrough.runtime.readers import detect_format

    formats = [detect_format(Path(path)) for path in [*(paths or []), *held_out]]
    return bool(paths) and (len(paths) > 1 or bool(held_out) or formats[0] != "excitation")


def identify_real(args: object) -> str:
    """``--realdata`` or real ``--log`` runs: friction, dynamics, report.md with figures."""
    from leadthrough.cli.arguments import robot_from
    from leadthrough.experiments.real_report import write_logs_report, write_realdata_report

    if args.realdata is not None:
        return write_realdata_report(args.realdata, args.out)
    robot = robot_from(args)
    return write_logs_report(robot, args.log, args.held_out, args.out)


def _twin_config(robot: RobotDescription, seed: int, random_friction: bool) -> object:
    from leadthrough.twin.friction import randomized_friction
    from leadthrough.twin.simulator import TwinConfig

    friction = randomized_friction(robot, np.random.default_rng(seed)) if random_friction else None
    return TwinConfig(seed=seed, friction=friction)


def summarise(study: FrictionStudy, out: Path) -> str:
    """The identified parameters, their fit quality and, on the twin, the errors."""
    model, joints = study.model, study.report.joints
    source = (f"twin, {study.simulated_seconds:.0f} s of excitation" if study.truth is not None
              else "log file")  # fmt: skip
    lines = [
        f"friction of {study.robot.name} identified from the {source} "
        f"in {study.seconds:.1f} s of wall time",
        "",
        _fixed_width("joint", PARAMETER_COLUMNS),
    ]
    lines += [_fixed_width(str(j + 1), model.parameter_cells(j)) for j in joints]
    lines += ["", str(study.report)]
    missing = study.report.not_identified_note()
    if missing:
        lines += ["", missing]
    errors = study.errors()
    if errors is not None:
        coulomb, viscous = errors
        lines += [
            "",
            "against the twin's true sliding friction (mid-range):",
            "  τ_C error [%]: " + " ".join(_percent(coulomb[j]) for j in joints),
            "  c error [%]:   " + " ".join(_percent(viscous[j]) for j in joints),
        ]
        if not np.all(np.isfinite(np.concatenate([coulomb[list(joints)], viscous[list(joints)]]))):
            lines.append("  (–: the twin's true value is 0, no relative error)")
    lines.append(f"parameters: {out / 'friction.toml'}")
    return "\n".join(lines)


#: Widths of the summary's columns: the joint, then :data:`PARAMETER_COLUMNS`.
_WIDTHS = (5, 10, 14, 11, 11, 9, 8, 8)


def _fixed_width(first: str, cells: Sequence[str]) -> str:
    """One row of the summary's table, each cell right-aligned in its column."""
    return "".join(f"{cell:>{width}}" for cell, width in zip((first, *cells), _WIDTHS,
                                                             strict=True))  # fmt: skip


def _percent(error: float) -> str:
    """A relative error in %, signed; "–" when it has none (the true value is 0)."""
    return f"{100 * error:+.2f}" if np.isfinite(error) else "–"


def _figures(study: FrictionStudy, out: Path) -> None:
    from leadthrough.plots import friction, pyplot

    plt = pyplot()
    for j in study.report.joints:
        for name, function in FIGURES.items():
            figure = getattr(friction, function)(study, j)
            figure.savefig(out / f"joint{j + 1}_{name}.png", dpi=110)
            plt.close(figure)
