"""Close the loop: a controller against the twin, every signal logged as arrays."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.model.description import FloatArray
from leadthrough.progress import Progress
from leadthrough.runtime.interface import Controller, JointState, RobotInterface
from leadthrough.runtime.loop import control_loop
from leadthrough.twin.simulator import DigitalTwin, Truth

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Signals of a closed-loop run, one row per control period (N rows).

    What the controller saw: ``t``, ``q``, ``qd``, ``tau_measured``; what it sent:
    ``tau_command``. Ground truth: everything else (see :class:`~.simulator.Truth`).

    Attributes:
        t: Sample times [s], (N,).
        q: Joint readings [rad], (N, n).
        qd: Reported joint velocities [rad/s], (N, n).
        tau_measured: Measured motor torque [Nm], (N, n); NaN where the drives report none.
        tau_command: Commanded torque [Nm], (N, n).
        q_true: True joint angles [rad], (N, n).
        qd_true: True joint velocities [rad/s], (N, n).
        tau_ext: True external joint torque [Nm], (N, n).
        tau_operator: Operator's joint torque [Nm], (N, n).
        operator_wrench: Hand wrench at the flange, world axes [N, Nm], (N, 6).
        ft_wrench: Wrist sensor reading in the flange frame [N, Nm], (N, 6).
        tau_motor: Motor torque that reached the joints [Nm], (N, n).
        tau_friction: Friction torque [Nm], (N, n).
        flange_position: Flange position in the world [m], (N, 3).
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    tau_measured: FloatArray
    tau_command: FloatArray
    q_true: FloatArray
    qd_true: FloatArray
    tau_ext: FloatArray
    tau_operator: FloatArray
    operator_wrench: FloatArray
    ft_wrench: FloatArray
    tau_motor: FloatArray
    tau_friction: FloatArray
    flange_position: FloatArray

    @property
    def operator_force(self) -> FloatArray:
        """Norm of the hand force [N], (N,)."""
        return np.linalg.norm(self.operator_wrench[:, :3], axis=1)

    def after(self, start: float, restart_clock: bool = True) -> SimulationResult:
        """The rows from ``start`` [s] on, with time counted from ``start`` (or as it was)."""
        keep = self.t >= start - 1e-9
        rows = {field.name: getattr(self, field.name)[keep] for field in fields(self)}
        if restart_clock:
            rows["t"] = rows["t"] - start
        return SimulationResult(**rows)

    def plot(self, joints: list[int] | None = None) -> Figure:
        """Figure of joint angles, torques and the operator force (see ``twin.plots``)."""
        from leadthrough.plots.simulation import plot_simulation

        return plot_simulation(self, joints)


def simulate(
    twin: DigitalTwin, controller: Controller, duration: float, progress: bool | None = None
) -> SimulationResult:
    """Run ``controller`` against ``twin`` for ``duration`` seconds of simulated time.

    Through :func:`~leadthrough.runtime.loop.control_loop`, the loop that runs on hardware,
    with the twin as a driver without a wall clock: each period the controller gets the
    twin's sample (its clock included), its command is sent, the twin simulates the
    period; compute time is measured but not held against the period. An error brings
    the controller's safe stop and is raised again, and so does Ctrl-C (after the safe
    stop: a partial run is no result). ``progress`` shows a bar (default:
    when stderr is a terminal and the run is longer than 10 s).
    """
    log: dict[str, list] = {field.name: [] for field in fields(SimulationResult)}
    bar = Progress(duration, "simulating", enabled=progress if progress is not None else None)
    bar.enabled = bar.enabled and (progress is True or duration > 10.0)
    observed = _Observed(twin)
    start = twin.time

    def record(state: JointState, command: FloatArray) -> None:
        _record(log, state, command, observed.truth)
        bar.update(state.t - start)

    try:
        report = control_loop(observed, controller, duration, after_period=record,
                              wall_clock=False, hold_at_end=False)  # fmt: skip
    finally:
        bar.close()
    if report.interrupted:  # the arm was stopped safely; a partial run is no result
        simulated = report.periods * report.period
        raise KeyboardInterrupt(f"the simulation stopped at {simulated:.2f} s of {duration:g} s")
    return SimulationResult(**{name: np.array(values) for name, values in log.items()})


class _Observed(RobotInterface):
    """The twin as a driver, keeping the ground truth of the latest sample read."""

    def __init__(self, twin: DigitalTwin) -> None:
        self.twin, self.dt, self.n_joints = twin, twin.dt, twin.n_joints
        self.truth = twin.truth

    def read_state(self) -> JointState:
        state = self.twin.read_state()
        self.truth = self.twin.truth
        return state

    def send_torque(self, tau: ArrayLike) -> None:
        self.twin.send_torque(tau)

    def close(self) -> None:
        self.twin.close()


def _record(log: dict[str, list], state: JointState, command: FloatArray, truth: Truth) -> None:
    log["t"].append(state.t)
    log["q"].append(state.q)
    log["qd"].append(state.qd)
    measured = state.tau_measured  # NaN where the drives report none
    log["tau_measured"].append(np.full(len(state.q), np.nan) if measured is None else measured)
    log["tau_command"].append(np.array(command, dtype=float))
    log["q_true"].append(truth.q)
    log["qd_true"].append(truth.qd)
    log["tau_ext"].append(truth.tau_ext)
    log["tau_operator"].append(truth.tau_operator)
    log["operator_wrench"].append(truth.operator_wrench)
    log["ft_wrench"].append(truth.ft_wrench)
    log["tau_motor"].append(truth.tau_motor)
    log["tau_friction"].append(truth.tau_friction)
    log["flange_position"].append(truth.flange_pose[:3, 3])
