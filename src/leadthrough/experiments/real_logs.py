"""Inspect a recorded log: the observer at the log's rate, contacts, false-alarm table.

And the safety supervisor's sample checks over the log as recorded (:func:`supervisor_verdict`):
a driver whose samples the supervisor would refuse (stale, out of range, non-finite) is
found on a log, before the arm is guided.

Used by ``leadthrough inspect`` and by ``benchmarks/real_observer.py``: the observer runs
over the log with the robot model given (nominal or identified) and its model
uncertainty, the online contact detector runs on the result, and a report (Markdown
with a figure of τ̂_ext ± 2 std per joint and the contacts) is written.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from leadthrough.estimation.contacts import ContactEvent, ContactParameters
from leadthrough.estimation.log_observer import (
    ModelUncertainty,
    ObservedLog,
    events_of,
    false_alarm_table,
    joined,
    measured_torque,
    observe_runs,
)
from leadthrough.friction.model import FrictionModel
from leadthrough.logs.log import MAX_GAP, JointLog
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.safety.limits import SafetyParameters
from leadthrough.safety.supervisor import SafetySupervisor


@dataclass(frozen=True, eq=False)
class Inspection:
    """The observer's run over one log and what it found.

    Attributes:
        observed: τ̂_ext and its std on the observer's grid.
        events: Detected contacts (log time base).
        table: The false-alarm table of the whole log (:func:`false_alarm_table`).
        robot: Name of the model used.
        fault: Where the supervisor would fault over the log as recorded: (time from its
            start [s], the reason), or None (:func:`supervisor_verdict`).
        logged: Samples in the log as recorded (``observed`` is resampled onto a uniform
            grid at its median period); 0: not known.
        gaps: (last time before, first time after) of each gap in the log longer than
            :data:`~leadthrough.logs.log.MAX_GAP` [s], log time base: rows missing, not
            observed across.
    """

    observed: ObservedLog
    events: list[ContactEvent]
    table: dict[str, FloatArray]
    robot: str
    fault: tuple[float, str] | None = None
    logged: int = 0
    gaps: list[tuple[float, float]] = field(default_factory=list)


def supervisor_verdict(log: JointLog, robot: RobotDescription) -> tuple[float, str] | None:
    """The safety supervisor's checks of every sample of ``log``, at its median period.

    Returns:
        (time from the log's start [s], the one-line reason) of the first sample it
        would fault on (a reading out of range, non-finite, or stale), or None. Its gaps
        in time are not judged, nor the rate they slow: they are where the reader dropped
        corrupted rows (0.46 s in a second of one public UR10e log), which a live
        supervisor would have faulted on themselves.
    """
    torque = measured_torque(log, robot)
    every_gap = SafetyParameters(max_time_gap=None, rate_tolerance=None)
    supervisor = SafetySupervisor(Dynamics(robot), log.median_period, every_gap)
    for k in range(log.n_samples):
        if not supervisor.check(float(log.t[k]), log.q[k], log.qd[k], torque[k]):
            return float(log.t[k] - log.t[0]), str(supervisor.fault_reason)
    return None


def inspect_log(
    log: JointLog,
    robot: RobotDescription,
    friction: FrictionModel | None = None,
    uncertainty: ModelUncertainty | None = None,
    parameters: ContactParameters | None = None,
) -> Inspection:
    """The observer over ``log`` at its own rate, the contacts and the false-alarm table.

    Each gap-free run is observed on its own (:func:`observe_runs`): no contact spans a gap.
    """
    runs = observe_runs(log, robot, friction, uncertainty)
    events = events_of(runs, parameters)
    return Inspection(joined(runs), events, false_alarm_table(runs), robot.name,
                      supervisor_verdict(log, robot), int(log.t.size), log.gaps())  # fmt: skip


def false_alarm_markdown(table: dict[str, FloatArray], label: str = "") -> str:
    """The false-alarm table as Markdown: one row per joint."""
    lines = [f"| joint | RMS τ̂_ext [Nm] | peak [Nm] | median std [Nm] | "
             f"\\|τ̂\\| > 2 std [%] | RMS τ̂/std [–] |{' run |' if label else ''}",
             "|---:|---:|---:|---:|---:|---:|" + ("---|" if label else "")]  # fmt: skip
    for j in range(table["rms"].size):
        lines.append(f"| {j + 1} | {table['rms'][j]:.2f} | {table['peak'][j]:.2f} | "
                     f"{table['median_std'][j]:.2f} | {100 * table['exceed'][j]:.1f} | "
                     f"{table['z_rms'][j]:.2f} |{f' {label} |' if label else ''}")  # fmt: skip
    return "\n".join(lines)


def supervisor_markdown(fault: tuple[float, str] | None) -> str:
    """One line: every sample passes the supervisor's checks, or where it would fault."""
    if fault is None:
        return ("Every sample of the log, as recorded, passes the supervisor's checks: none is "
                "out of range, non-finite or stale.")  # fmt: skip
    return f"The supervisor would fault {fault[0]:.2f} s into the log: {fault[1]}."


def gaps_markdown(gaps: Sequence[tuple[float, float]], t0: float) -> str:
    """One line: where the log has rows missing (gaps from its start [s]), or that it has none."""
    if not gaps:
        return f"No gap in time longer than {MAX_GAP:g} s."
    where = ", ".join(f"{start - t0:.2f} … {end - t0:.2f} s" for start, end in gaps[:5])
    more = f" and {len(gaps) - 5} more" if len(gaps) > 5 else ""
    return (f"{len(gaps)} gap(s) in time longer than {MAX_GAP:g} s (rows missing), at {where}"
            f"{more}: the observer starts afresh after each, no contact spans one.")  # fmt: skip


def events_markdown(events: Sequence[ContactEvent], t0: float) -> str:
    """The contacts as Markdown: start and end from the log's start, joints, peak torque."""
    if not events:
        return "No contact detected."
    lines = ["| # | start [s] | end [s] | joints | peak τ̂_ext per joint [Nm] |",
             "|---:|---:|---:|---|---|"]  # fmt: skip
    for k, event in enumerate(events, 1):
        joints = ", ".join(str(j + 1) for j in event.joints)
        peak = ", ".join(f"{value:+.1f}" for value in event.peak)
        lines.append(f"| {k} | {event.start - t0:.2f} | {event.end - t0:.2f} | {joints} | "
                     f"{peak} |")  # fmt: skip
    return "\n".join(lines)


def write_inspection(inspection: Inspection, source: str, out: Path) -> Path:
    """Write ``report.md`` and ``observer.png`` into ``out``; returns the report's path."""
    from leadthrough.plots.observed_log import plot_observed_log

    out.mkdir(parents=True, exist_ok=True)
    observed = inspection.observed
    figure = plot_observed_log(observed, inspection.events, title=Path(source).name)
    figure.savefig(out / "observer.png", dpi=110)
    figure.clf()
    text = [
        f"# Inspection of {source}",
        "",
        f"Model: {inspection.robot}. {inspection.logged or observed.t.size} samples over "
        f"{observed.t[-1] - observed.t[0]:.1f} s, observer at {1 / observed.dt:.0f} Hz (the "
        f"log's median period: {observed.t.size} samples). The std is the observer's and the "
        "model uncertainty combined.",
        "",
        "## Safety supervisor",
        "",
        supervisor_markdown(inspection.fault),
        "",
        "## Contacts",
        "",
        gaps_markdown(inspection.gaps, float(observed.t[0])),
        "",
        events_markdown(inspection.events, float(observed.t[0])),
        "",
        "![τ̂_ext ± 2 std per joint, contacts shaded](observer.png)",
        "",
        "## Estimated external torque over the whole log",
        "",
        "Where nothing touches the arm these are the false-alarm level: small RMS and peak, "
        "|τ̂_ext| rarely above 2 std, RMS of τ̂/std near 1 (≪ 1: the std is wider than the "
        "errors it covers).",
        "",
        false_alarm_markdown(inspection.table),
        "",
    ]
    report = out / "report.md"
    report.write_text("\n".join(text), encoding="utf-8")
    return report
