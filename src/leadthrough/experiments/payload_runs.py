"""Twin runs of an arm carrying known payloads (tests and benchmarks of estimate_payload)."""

from dataclasses import replace

import numpy as np

from leadthrough.control.tracking import JointTracker
from leadthrough.logs.log import JointLog
from leadthrough.model.description import RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.twin.mjcf import Payload
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.sensors import SensorModel
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

HARMONICS = 5
BASE_FREQUENCY = 0.1  # [Hz]


def excitation(n: int, seed: int, amplitude: float) -> tuple[np.ndarray, ...]:
    """Amplitudes [rad], angular frequencies [rad/s] and phases of a seeded Fourier motion."""
    rng = np.random.default_rng(seed)
    order = np.arange(1, HARMONICS + 1)
    amplitudes = rng.normal(size=(n, HARMONICS)) * amplitude / order
    phases = rng.uniform(0.0, 2.0 * np.pi, (n, HARMONICS))
    return amplitudes, 2.0 * np.pi * BASE_FREQUENCY * order, phases


def record(
    robot: RobotDescription,
    payload: Payload | None,
    model_error: ModelError,
    seed: int = 0,
    motion_seed: int = 0,
    duration: float = 20.0,
    amplitude: float = 0.15,
    sensors: SensorModel | None = None,
) -> JointLog:
    """A run of the twin tracking a Fourier motion about home, with the payload on.

    The plant carries ``payload`` on top of ``model_error``; the tracker uses the nominal
    ``robot``; the log holds the twin's measured torque (what a real arm reports;
    ``sensors.torque_gain`` makes its drive gains differ from the nominal ones).
    """
    error = replace(model_error, payload=payload)
    config = TwinConfig(model_error=error, seed=seed, sensors=sensors or SensorModel())
    twin = DigitalTwin(robot, config)
    tracker = JointTracker(Dynamics(robot), bandwidth=4.0)
    home = robot.home()
    amplitudes, omega, phases = excitation(robot.n_joints, motion_seed, amplitude)
    rows: list[tuple] = []
    for k in range(int(duration / twin.dt)):
        state = twin.read_state()
        t = k * twin.dt
        ramp = min(1.0, t / 2.0)
        angle = omega * t + phases
        reference = (home + ramp * (amplitudes * np.sin(angle)).sum(1),
                     ramp * (amplitudes * omega * np.cos(angle)).sum(1),
                     -ramp * (amplitudes * omega**2 * np.sin(angle)).sum(1))  # fmt: skip
        command = tracker.torque(state.q, state.qd, *reference)
        measured = command if state.tau_measured is None else state.tau_measured
        rows.append((state.t, state.q, state.qd, measured))
        twin.send_torque(command)
    t, q, qd, tau = (np.array(column) for column in zip(*rows, strict=True))
    return JointLog(t, q, qd, tau=tau, source=f"twin payload={payload}")
