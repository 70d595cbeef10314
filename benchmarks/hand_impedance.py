"""Can the arm feel the hand? The damping a probe reads at the tool, hand against force source.

The friction margin that keeps a released arm from running on costs active mode a third of
its effort, and an enabling device that says a hand holds the tool lifts it
(docs/guiding_results.md, *Where the effort goes*). This diagnosis asks whether the motor
torques and encoders could say it instead, through the hand's impedance: a small force at the
flange, ``f_p = A sin(2π f t) u`` (the probe, added to a passive controller's command as
``J_vᵀ f_p``), moves the tool at ``f``; a hand resists that motion with its damping ``B``
[N s/m], a pure force source does not. The damping an external-torque signal ``τ`` shows over
a window is ``B̂ = −Re Σ_i T_i conj(V_i) / |J_v V|²``, with ``T`` and ``V`` the Fourier
coefficients at ``f`` of ``τ`` and of the differenced encoder velocity (Hann window) and
``J_v`` the flange's linear Jacobian: the power the external torque takes from the probe's
motion over its squared tool speed.

Each case runs twice on one plant of ``guiding_quality.py``: a hand pulls the flange along a
line, then the forces that hand applied, with the probe frequency's band taken out, drive the
same arm as a force source with no impedance. ``B̂`` is read from three signals: the twin's
true external torque (the method's check: the hand's damping, and 0), the controller's
estimate (the observer, as guiding uses it) and the momentum residual
``ṗ − Cᵀq̇ + G − τ_m`` of the measured torque, aligned with the plant's delay (no filter;
also one period off, to show what the delay is worth). Prints the median and range of
``B̂`` over the windows where the tool moves, per case, probe and signal, and draws them.
Usage::

    python benchmarks/hand_impedance.py [--periods 4] [--out docs/bench/hand_impedance.png]
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.signal import butter, filtfilt

import leadthrough as lt
from leadthrough.experiments.guiding import HANDS, case_path, tool_vibration
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.runtime.interface import JointState
from leadthrough.twin.operator import During, Hand, Operator
from leadthrough.twin.plants import Plant, sample_plant
from leadthrough.twin.runner import SimulationResult, simulate
from leadthrough.twin.simulator import DigitalTwin

#: (physics, seed, hand, line) of each case: plants of the guiding benchmark.
CASES = (("dry", 1, "relaxed", "sideways"), ("lugre", 2, "relaxed", "sideways"),
         ("dry", 3, "stiff", "sideways"), ("lugre", 4, "relaxed", "upwards"))  # fmt: skip
#: Probes (frequency [Hz], force amplitude [N]): none (the arm's own motion), about 3, 9 and
#: 25 mm/s at the YuMi's tool; passive mode's tool shakes about 2 mm/s RMS above 4 Hz.
PROBES = ((15.0, 0.0), (15.0, 0.25), (15.0, 0.75), (10.0, 0.5), (15.0, 2.0))
#: The probe's direction at the flange [world], a unit vector.
DIRECTION = np.ones(3) / np.sqrt(3.0)
#: The hand lets go here [s]; windows are read from 0.5 s to here.
RELEASE = 3.0
#: A window counts where the tool's mean speed is above this [m/s] (a stuck arm reads noise).
MOVING = 0.01
SIGNALS = ("truth", "estimate", "residual", "residual, one period off")


class ProbedController:
    """A controller whose command carries the probe ``J_vᵀ f_p(t)``; keeps its estimates."""

    def __init__(self, controller: lt.LeadThrough, probe: tuple[float, float]) -> None:
        self.controller = controller
        self.dt = controller.dt
        self.supervisor = controller.supervisor
        self.dynamics = Dynamics(controller.robot)
        self.omega, self.force = 2.0 * np.pi * probe[0], probe[1]
        self.estimates: list[FloatArray] = []
        self._start: float | None = None

    def step(self, state: JointState) -> FloatArray:
        """The controller's command [Nm] with the probe's joint torques added."""
        command = np.asarray(self.controller.step(state), dtype=float)
        self.estimates.append(np.array(self.controller.tau_ext_hat))
        t = float(state.t)
        self._start = t if self._start is None else self._start
        force = self.force * np.sin(self.omega * (t - self._start)) * DIRECTION
        return command + self.dynamics.jacobian(state.q)[:3].T @ force


class RecordedWrench(Operator):
    """A force source: the wrench history ``wrench`` [N, Nm] at times ``t`` [s], held."""

    def __init__(self, t: FloatArray, wrench: FloatArray) -> None:
        self.t, self.history = t, wrench

    def wrench(self, t: float, flange_pose: FloatArray, flange_velocity: FloatArray) -> FloatArray:
        """The wrench held since the latest recorded time at or before ``t``."""
        k = int(np.searchsorted(self.t, t + 1e-9)) - 1
        return self.history[min(max(k, 0), len(self.t) - 1)]


def run(
    robot: RobotDescription,
    plant: Plant,
    operator: Callable[[DigitalTwin], Operator],
    probe: tuple[float, float],
) -> tuple[SimulationResult, FloatArray]:
    """A passive controller with the probe on ``plant``; ``operator(twin)`` on the arm."""
    controller = ProbedController(lt.LeadThrough(robot, mode="passive", dt=0.004), probe)
    twin = DigitalTwin(robot, plant.config, q0=plant.start)
    twin.operator = operator(twin)
    sim = simulate(twin, controller, RELEASE + 0.5, progress=False)
    return sim, np.array(controller.estimates)


def hand(name: str, line: str) -> Callable[[DigitalTwin], Operator]:
    """The hand ``name`` on the twin: it pulls the flange along ``line`` from where it starts.

    It lets go at :data:`RELEASE`.
    """

    def on(twin: DigitalTwin) -> Operator:
        start = twin.truth.flange_pose[:3, 3].copy()
        grip = Hand.from_parameters(case_path(twin.robot, line, start), HANDS[name])
        return During(grip, 0.0, RELEASE)

    return on


def without_band(wrench: FloatArray, frequency: float, dt: float) -> FloatArray:
    """``wrench`` with the band ``frequency ± 3 Hz`` taken out (zero phase)."""
    nyquist = 0.5 / dt
    b, a = butter(2, [(frequency - 3.0) / nyquist, (frequency + 3.0) / nyquist], "bandstop")
    return filtfilt(b, a, wrench, axis=0)


def rigid_body_torque(dynamics: Dynamics, sim: SimulationResult) -> FloatArray:
    """``ṗ − Cᵀq̇ + G`` [Nm] from the measured angles, ``q̇`` and ``ṗ`` by central differences.

    Less the motor torque, the external torque without a filter and without friction
    (smooth at the probe's frequency on a sliding joint): :func:`momentum_residual`.
    """
    dt = float(sim.t[1] - sim.t[0])
    qd = np.gradient(sim.q, dt, axis=0)
    momentum = np.array([dynamics.momentum(q, v) for q, v in zip(sim.q, qd, strict=True)])
    coriolis = np.array([dynamics.coriolis_transpose_times_velocity(q, v)
                         for q, v in zip(sim.q, qd, strict=True)])  # fmt: skip
    gravity = np.array([dynamics.gravity(q) for q in sim.q])
    return np.gradient(momentum, dt, axis=0) - coriolis + gravity


def momentum_residual(rigid_body: FloatArray, sim: SimulationResult, shift: int) -> FloatArray:
    """``ṗ − Cᵀq̇ + G − τ_m`` [Nm], each measured torque taken ``shift`` samples later."""
    return rigid_body - np.roll(sim.tau_measured, -shift, axis=0)


def damping(
    dynamics: Dynamics, sim: SimulationResult, torque: FloatArray, frequency: float, periods: int
) -> FloatArray:
    """``B̂`` [N s/m] in half-overlapping windows of ``periods`` probe periods where the tool moves.

    Returns rows ``(B̂, tool speed amplitude at the probe's frequency [m/s])``.
    """
    t = sim.t - sim.t[0]
    dt = float(t[1] - t[0])
    qd = np.gradient(sim.q, dt, axis=0)
    speed = np.linalg.norm(np.gradient(sim.flange_position, dt, axis=0), axis=1)
    size = round(periods / frequency / dt)
    taper = np.hanning(size)[:, None]
    readings = []
    for start in range(int(0.5 / dt), int(RELEASE / dt) - size, size // 2):
        span = slice(start, start + size)
        if np.mean(speed[span]) < MOVING:
            continue
        phase = taper * np.exp(-1j * 2.0 * np.pi * frequency * t[span])[:, None]
        torque_f, velocity_f = np.sum(phase * torque[span], 0), np.sum(phase * qd[span], 0)
        tool = dynamics.jacobian(sim.q[start + size // 2])[:3] @ velocity_f
        power = -np.real(np.sum(torque_f * np.conj(velocity_f)))
        amplitude = 2.0 * np.linalg.norm(tool) / np.sum(taper)
        readings.append((power / np.sum(np.abs(tool) ** 2), amplitude))
    return np.array(readings).reshape(-1, 2)


def vibration(sim: SimulationResult) -> float:
    """RMS tool velocity above 4 Hz while the hand holds [m/s] (``guiding.tool_vibration``)."""
    dt = float(sim.t[1] - sim.t[0])
    held = sim.t - sim.t[0] < RELEASE
    return tool_vibration(np.gradient(sim.flange_position[held], dt, axis=0), dt)


@dataclass(frozen=True)
class Reading:
    """``B̂`` of one case, probe, source and signal: median and range [N s/m], windows.

    ``amplitude``: the tool's speed at the probe's frequency, median over the windows
    [m/s]; ``vibration``: the run's RMS tool velocity above 4 Hz until the release [m/s]
    (``guiding.tool_vibration``), what the probe costs.
    """

    case: str
    probe: tuple[float, float]
    source: str
    signal: str
    median: float
    low: float
    high: float
    windows: int
    amplitude: float
    vibration: float


def read_case(
    robot: RobotDescription, case: tuple[str, int, str, str], probe: tuple[float, float],
    periods: int,
) -> list[Reading]:  # fmt: skip
    """The readings of one case and probe: the hand, then its forces as a source."""
    physics, seed, hand_name, line = case
    plant = sample_plant(robot, seed, physics)
    plant = replace(plant, config=replace(plant.config, control_dt=0.004))
    dynamics = Dynamics(robot)
    held, held_estimate = run(robot, plant, hand(hand_name, line), probe)
    dt = float(held.t[1] - held.t[0])
    source = RecordedWrench(held.t - held.t[0], without_band(held.operator_wrench, probe[0], dt))
    pushed, pushed_estimate = run(robot, plant, lambda twin: source, probe)
    shift = plant.config.delay_periods - 1  # the measured torque at k acts from k − shift
    label = f"{physics}#{seed} {hand_name} {line}"
    readings = []
    for name, sim, estimate in (("hand", held, held_estimate), ("force", pushed, pushed_estimate)):
        rigid_body = rigid_body_torque(dynamics, sim)
        signals = (sim.tau_ext, estimate, momentum_residual(rigid_body, sim, shift),
                   momentum_residual(rigid_body, sim, shift + 1))  # fmt: skip
        for signal, torque in zip(SIGNALS, signals, strict=True):
            b, amplitude = damping(dynamics, sim, torque, probe[0], periods).T
            low, median, high = np.percentile(b, [0, 50, 100]) if b.size else (np.nan,) * 3
            readings.append(
                Reading(
                    label,
                    probe,
                    name,
                    signal,
                    median,
                    low,
                    high,
                    b.size,
                    float(np.median(amplitude)),
                    vibration(sim),
                )
            )
    return readings


def _probe_label(readings: list[Reading], probe: tuple[float, float]) -> str:
    """``15 Hz``, ``0.75 N`` and the hands' median tool speed at that frequency [mm/s]."""
    speeds = [r.amplitude for r in readings if r.probe == probe and r.source == "hand"]
    return f"{probe[0]:g} Hz\n{probe[1]:g} N\n{1e3 * np.median(speeds):.1f} mm/s"


def plot(readings: list[Reading], out: Path) -> None:
    """``B̂`` against the probe, hand (filled) and force source (open), one panel per signal."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(SIGNALS), figsize=(15, 4.2), sharey=True)
    probes = list(dict.fromkeys(r.probe for r in readings))
    cases = list(dict.fromkeys(r.case for r in readings))
    for ax, signal in zip(axes, SIGNALS, strict=True):
        for k, case in enumerate(cases):
            for source, fill in (("hand", None), ("force", "none")):
                key = (case, signal, source)
                rows = [r for r in readings if (r.case, r.signal, r.source) == key]
                x = [probes.index(r.probe) + 0.08 * (k - 1.5) for r in rows]
                y = [r.median for r in rows]
                err = [[r.median - r.low for r in rows], [r.high - r.median for r in rows]]
                label = f"{case}, {source}" if signal == SIGNALS[0] else None
                ax.errorbar(x, y, yerr=err, fmt="o", color=f"C{k}", mfc=fill, capsize=2,
                            label=label)  # fmt: skip
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_title(signal)
        ax.set_xticks(range(len(probes)), [_probe_label(readings, p) for p in probes], fontsize=8)
        ax.set_ylim(-60.0, 140.0)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("damping read at the tool, B̂ [N s/m]")
    fig.legend(loc="lower center", ncol=4, fontsize=7, frameon=False)
    fig.suptitle("A hand (filled; 30 N s/m relaxed, 100 stiff) against its forces replayed "
                 "(open, 0): median and range over 0.5–3 s")  # fmt: skip
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=4, help="probe periods per window")
    parser.add_argument("--out", type=Path, default=Path("docs/bench/hand_impedance.png"))
    args = parser.parse_args()
    robot = lt.robots.yumi()
    readings = []
    print(
        f"{'case':25s} {'probe':>12s} {'source':6s} {'at f':>5s} {'>4 Hz':>5s} "
        + " ".join(f"{s:>22s}" for s in SIGNALS)
        + "   [mm/s; B̂ N s/m]"
    )
    for case in CASES:
        for probe in PROBES:
            rows = read_case(robot, case, probe, args.periods)
            readings += rows
            for source in ("hand", "force"):
                own = [r for r in rows if r.source == source]
                cells = [f"{r.median:6.1f} [{r.low:5.0f},{r.high:5.0f}]" for r in own]
                print(f"{own[0].case:25s} {probe[0]:5g} Hz {probe[1]:4g} N {source:6s} "
                      f"{1e3 * own[0].amplitude:5.1f} {1e3 * own[0].vibration:5.1f} "
                      + " ".join(f"{c:>22s}" for c in cells), flush=True)  # fmt: skip
    plot(readings, args.out)
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
