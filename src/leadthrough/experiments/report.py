"""``leadthrough experiments``: the thesis' experiments (chapters 4-6) on the twin, one report.

:func:`run_experiments` computes (a :class:`ThesisExperiments`); :func:`write_experiments`
draws the figures and writes the Markdown report (``make docs`` reuses both).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.experiments.friction_study import FrictionStudy, run_friction_study
from leadthrough.experiments.lead_through import (
    CalibrationCheck,
    EffortComparison,
    EndStopResult,
    GuidedRun,
    ReleaseResult,
    calibration_checks,
    damping_runs,
    effort_comparison,
    end_stop,
    passive_feed_forward,
    plants_table,
    robustness,
)
from leadthrough.experiments.level_error import LevelErrorTrace, level_errors_along_travel
from leadthrough.experiments.observer import (
    BreakawayResult,
    DitherSweep,
    ObserverRun,
    breakaway_with_and_without_dither,
    dither_frequency_sweep,
    identified_without_position,
    single_joint_guiding,
)
from leadthrough.experiments.stability import StabilityMap, stability_map
from leadthrough.model.description import RobotDescription
from leadthrough.plots import friction as friction_plots
from leadthrough.plots import lead_through as lead_through_plots
from leadthrough.plots import observer as observer_plots
from leadthrough.plots import pyplot
from leadthrough.plots.stability import plot_stability_map
from leadthrough.twin.presets import REALISTIC_TWIN

#: Peak speed of the identification's faster run [rad/s] (runtime.excitation.DEFAULT_RUNS).
EXCITATION_SPEED = 0.6


@dataclass(frozen=True, eq=False)
class ThesisExperiments:
    """Every experiment of the report, on the realistic twin (see each function)."""

    study: FrictionStudy
    passive: GuidedRun
    guided: ObserverRun
    breakaway: BreakawayResult
    sweep: DitherSweep
    stability: StabilityMap
    damping: dict
    end_stops: dict[str, EndStopResult]
    effort: EffortComparison
    calibration: list[CalibrationCheck]
    releases: dict[str, ReleaseResult]
    level_errors: list[LevelErrorTrace]


def run_experiments(
    robot: RobotDescription, say: Callable[[str], None] = print
) -> ThesisExperiments:
    """Run every experiment on the realistic twin (friction identified there first)."""
    say("friction identification (Figs. 4.2, 4.3, 4.5, 4.6) …")
    study = run_friction_study(robot, twin_config=REALISTIC_TWIN, progress=True)
    friction = study.model
    say("passive lead-through (Fig. 4.8) …")
    passive = passive_feed_forward(robot, friction)
    say("observer (Figs. 5.2–5.6) …")
    observed = identified_without_position(friction)
    guided = single_joint_guiding(robot, observed)
    breakaway = breakaway_with_and_without_dither(robot, observed, joint=3)
    sweep = dither_frequency_sweep(robot, observed)
    say("active lead-through (Figs. 6.4–6.7) …")
    stable = stability_map(robot)
    damping = damping_runs(robot, friction)
    stops = {"thesis settings": end_stop(robot, LeadThroughParameters.thesis_unstable(), friction),
             "defaults": end_stop(robot, None, friction)}  # fmt: skip
    effort = effort_comparison(robot, friction)
    say("start-up calibration and other plants …")
    checks = calibration_checks(robot, friction)
    releases = robustness(robot, friction)
    say("a level read at the calibration pose, along the travel (dry plants) …")
    level_errors = level_errors_along_travel(robot)
    return ThesisExperiments(study, passive, guided, breakaway, sweep, stable, damping, stops,
                             effort, checks, releases, level_errors)  # fmt: skip


def write_experiments(
    robot: RobotDescription,
    out: Path,
    say: Callable[[str], None] = print,
    experiments: ThesisExperiments | None = None,
) -> Path:
    """Run every experiment on the realistic twin; write ``out/experiments.md`` and figures."""
    out.mkdir(parents=True, exist_ok=True)
    e = run_experiments(robot, say) if experiments is None else experiments
    sections: list[str] = []

    def figure(name: str, made: object, caption: str) -> None:
        made.savefig(out / name, dpi=100)
        pyplot().close(made)
        sections.append(f"### {caption}\n![{caption}]({name})\n")

    sections.append(f"## Friction\n{identification_summary(e.study)}\n")
    for name, plot, joint, caption in (
        ("fig4_2.png", friction_plots.plot_raw_and_compensated, 0, "Fig. 4.2: raw and "
                                                                   "compensated friction data"),
        ("fig4_3.png", friction_plots.plot_sigmoid_fit, 0, "Fig. 4.3: fitted sigmoids"),
        ("fig4_5.png", friction_plots.plot_gaussian_model, 0, "Fig. 4.5: Gaussian friction model"),
        ("fig4_6.png", friction_plots.plot_position_dependence, 3, "Fig. 4.6: position dependence"),
    ):  # fmt: skip
        figure(name, plot(e.study, joint), f"{caption}, joint {joint + 1}")
    sections.append("## Passive lead-through\n")
    figure("fig4_8.png", lead_through_plots.plot_feed_forward(e.passive),
           "Fig. 4.8: feed-forward torques during passive guiding")  # fmt: skip
    sections.append("## Observer\n")
    figure("fig5_2.png", observer_plots.plot_estimate_vs_truth(e.guided),
           "Fig. 5.2: estimated vs true torque, joint 1")  # fmt: skip
    figure("fig5_5.png", observer_plots.plot_breakaway(e.breakaway),
           f"Figs. 5.5–5.6: dithering, breakaway ratio {e.breakaway.ratio:.2f}")  # fmt: skip
    figure("fig5_3.png", observer_plots.plot_dither_sweep(e.sweep),
           "Figs. 5.3–5.4: dither frequency sweep")  # fmt: skip
    sections.append("## Active lead-through\n")
    figure("stability.png", plot_stability_map(e.stability),
           f"coupled stability with a hand: k_M in {e.stability.stable_scales(3000.0).min():.2g}"
           "–4 keeps ζ ≥ 0.15 up to 3000 N/m")  # fmt: skip
    figure("fig6_4.png", lead_through_plots.plot_damping(e.damping, 6),
           "Figs. 6.4–6.5: high and low virtual damping, joint 7")  # fmt: skip
    figure("fig6_6.png", lead_through_plots.plot_end_stop(e.end_stops), "Fig. 6.6: end-stop")
    figure("fig6_7.png", lead_through_plots.plot_effort(e.effort),
           "Fig. 6.7: operator effort, the same hand on the same paths")  # fmt: skip
    sections.append(e.effort.table() + "\n")
    sections.append("## Start-up calibration, and the defaults on other plants\n")
    figure("calibration.png", lead_through_plots.plot_calibration(e.calibration),
           "the start-up calibration against each plant's truth")  # fmt: skip
    sections.append(plants_table(e.calibration, e.releases) + "\n")
    figure(
        "level_error.png",
        lead_through_plots.plot_level_error(e.level_errors),
        "a level read at the calibration pose: its true and stated error along the travel",
    )
    report = out / "experiments.md"
    report.write_text("# leadthrough: the thesis' experiments on the twin\n\n"
                      + "\n".join(sections), encoding="utf-8")  # fmt: skip
    return report


def identification_summary(study: FrictionStudy) -> str:
    """The largest identification errors, and why the viscous one is large where it is."""
    coulomb, viscous = study.errors()
    j = int(np.nanargmax(np.abs(viscous)))
    c = float(study.truth[1][j])
    rms = study.report.residual_rms
    return (f"Identified in {study.seconds:.1f} s; largest error against the twin: τ_C "
            f"{100 * np.nanmax(np.abs(coulomb)):.2f} %, c {100 * abs(viscous[j]):.2f} % (joint "
            f"{j + 1}). Joint {j + 1}'s viscous torque is small: c = {c:.3g} Nm s/rad gives "
            f"{EXCITATION_SPEED * c:.3f} Nm at the excitation's {EXCITATION_SPEED} rad/s, of the "
            f"order of what the realistic twin's model error (masses ±5 %, centres of mass "
            f"±5 mm) leaves in the fit (residual RMS {rms[j]:.4f} Nm, median over the joints "
            f"{np.nanmedian(rms):.4f} Nm). With exact centres of mass, or an excitation three "
            "times faster, the error is a few per cent (see the README).")  # fmt: skip
