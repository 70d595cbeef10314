"""``leadthrough experiments``: every experiment of SPEC §12 from the twin, in one report."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.experiments.friction_study import run_friction_study
from leadthrough.experiments.lead_through import (
    calibration_checks,
    damping_runs,
    effort_comparison,
    end_stop,
    passive_feed_forward,
    plants_table,
    robustness,
)
from leadthrough.experiments.observer import (
    breakaway_with_and_without_dither,
    dither_frequency_sweep,
    identified_without_position,
    single_joint_guiding,
)
from leadthrough.experiments.stability import stability_map
from leadthrough.model.description import RobotDescription
from leadthrough.plots import friction as friction_plots
from leadthrough.plots import lead_through as lead_through_plots
from leadthrough.plots import observer as observer_plots
from leadthrough.plots import pyplot
from leadthrough.plots.stability import plot_stability_map
from leadthrough.twin.presets import REALISTIC_TWIN


def write_experiments(
    robot: RobotDescription, out: Path, say: Callable[[str], None] = print
) -> Path:
    """Run every experiment on the realistic twin; write ``out/experiments.md`` and figures."""
    out.mkdir(parents=True, exist_ok=True)
    sections: list[str] = []

    def figure(name: str, made: object, caption: str) -> None:
        made.savefig(out / name, dpi=100)
        pyplot().close(made)
        sections.append(f"### {caption}\n![{caption}]({name})\n")

    say("friction identification (Figs. 4.2, 4.3, 4.5, 4.6) …")
    study = run_friction_study(robot, twin_config=REALISTIC_TWIN, progress=True)
    friction = study.model
    coulomb, viscous = study.errors()
    sections.append(f"## Friction\nIdentified in {study.seconds:.1f} s; largest error against "
                    f"the twin: τ_C {100 * abs(coulomb).max():.2f} %, c "
                    f"{100 * abs(viscous).max():.2f} %.\n")  # fmt: skip
    for name, plot, joint, caption in (
        ("fig4_2.png", friction_plots.plot_raw_and_compensated, 0, "Fig. 4.2: raw and "
                                                                   "compensated friction data"),
        ("fig4_3.png", friction_plots.plot_sigmoid_fit, 0, "Fig. 4.3: fitted sigmoids"),
        ("fig4_5.png", friction_plots.plot_gaussian_model, 0, "Fig. 4.5: Gaussian friction model"),
        ("fig4_6.png", friction_plots.plot_position_dependence, 3, "Fig. 4.6: position dependence"),
    ):  # fmt: skip
        figure(name, plot(study, joint), f"{caption}, joint {joint + 1}")
    say("passive lead-through (Fig. 4.8) …")
    sections.append("## Passive lead-through\n")
    passive = passive_feed_forward(robot, friction)
    figure("fig4_8.png", lead_through_plots.plot_feed_forward(passive),
           "Fig. 4.8: feed-forward torques during passive guiding")  # fmt: skip
    say("observer (Figs. 5.2–5.6) …")
    observed = identified_without_position(friction)
    sections.append("## Observer\n")
    guided = single_joint_guiding(robot, observed)
    figure("fig5_2.png", observer_plots.plot_estimate_vs_truth(guided),
           "Fig. 5.2: estimated vs true torque, joint 1")  # fmt: skip
    breakaway = breakaway_with_and_without_dither(robot, observed, joint=3)
    figure("fig5_5.png", observer_plots.plot_breakaway(breakaway),
           f"Figs. 5.5–5.6: dithering, breakaway ratio {breakaway.ratio:.2f}")  # fmt: skip
    figure("fig5_3.png", observer_plots.plot_dither_sweep(dither_frequency_sweep(robot, observed)),
           "Figs. 5.3–5.4: dither frequency sweep")  # fmt: skip
    say("active lead-through (Figs. 6.4–6.7) …")
    sections.append("## Active lead-through\n")
    stable = stability_map(robot)
    figure("stability.png", plot_stability_map(stable),
           f"coupled stability with a hand: k_M in {stable.stable_scales(3000.0).min():.2g}"
           "–4 keeps ζ ≥ 0.15 up to 3000 N/m")  # fmt: skip
    figure("fig6_4.png", lead_through_plots.plot_damping(damping_runs(robot, friction), 6),
           "Figs. 6.4–6.5: high and low virtual damping, joint 7")  # fmt: skip
    stops = {"thesis settings": end_stop(robot, LeadThroughParameters.thesis_unstable(), friction),
             "defaults": end_stop(robot, None, friction)}  # fmt: skip
    figure("fig6_6.png", lead_through_plots.plot_end_stop(stops), "Fig. 6.6: end-stop")
    comparison = effort_comparison(robot, friction)
    figure("fig6_7.png", lead_through_plots.plot_effort(comparison),
           "Fig. 6.7: operator effort, the same hand on the same paths")  # fmt: skip
    sections.append(comparison.table() + "\n")
    say("start-up calibration and other plants …")
    sections.append("## Start-up calibration, and the defaults on other plants\n")
    checks = calibration_checks(robot, friction)
    figure("calibration.png", lead_through_plots.plot_calibration(checks),
           "the start-up calibration against each plant's truth")  # fmt: skip
    sections.append(plants_table(checks, robustness(robot, friction)) + "\n")
    report = out / "experiments.md"
    report.write_text("# leadthrough: the thesis' experiments on the twin\n\n"
                      + "\n".join(sections), encoding="utf-8")  # fmt: skip
    return report
