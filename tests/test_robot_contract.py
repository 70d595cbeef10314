"""Contract of every registered robot (and a 3-joint URDF arm) in the twin.

Like a model zoo's model tests: each arm steps in the twin without MuJoCo warnings,
stays still under gravity compensation with its own friction, stays still under passive
and active lead-through when nobody touches it, its start-up calibration motion stays
slow, and its friction identifies from a short excitation. Short runs: the whole file
takes well under 40 s.
"""

import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.calibration import CalibrationParameters
from leadthrough.control.lead_through import LeadThrough
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.friction.identification import fit_friction, friction_samples
from leadthrough.runtime.excitation import ExcitationRun, friction_experiment
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

THREE_JOINT = Path(__file__).parent / "robots" / "three_joint.urdf"
ROBOTS = [*lt.robots.names(), "three_joint"]

#: Still: the largest joint excursion allowed over a run [rad] (1 mrad: 1 mm at 1 m reach).
STILL = 1e-3
#: Short excitation: one triangular velocity cycle to 0.4 rad/s, 0.5 rad stroke, 5 s.
SHORT_RUN = ExcitationRun(peak_velocity=0.4, frequency=0.2, cycles=1)


def load(name: str) -> lt.RobotDescription:
    """A registered robot, or the test's 3-joint arm; drive data assumptions not warned."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", lt.robots.AssumedDriveDataWarning)
        if name == "three_joint":
            return lt.robots.from_urdf(THREE_JOINT, tip="tool")
        return lt.robots.load(name)


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request) -> lt.RobotDescription:
    """Each robot of the contract."""
    return load(request.param)


class GravityHold:
    """Commands the model's gravity torque G(q), nothing else."""

    def __init__(self, robot: lt.RobotDescription) -> None:
        self.dynamics = lt.Dynamics(robot)

    def step(self, q, qd, tau_measured):
        """G(q) [Nm]."""
        return self.dynamics.gravity(q)


def test_steps_two_seconds_without_warnings_and_gravity_compensation_holds_it(robot):
    """2 s at home under G(q) with its own friction: no MuJoCo warning, < 1 mrad moved."""
    twin = DigitalTwin(robot, TwinConfig(seed=1))
    sim = simulate(twin, GravityHold(robot), 2.0)
    warned = {mujoco.mjtWarning(i).name: int(twin.data.warning[i].number)
              for i in range(len(twin.data.warning)) if twin.data.warning[i].number}  # fmt: skip
    assert not warned, warned
    assert np.all(np.isfinite(sim.q_true))
    assert np.abs(sim.q_true - robot.home()).max() < STILL


@pytest.mark.parametrize("mode", ["passive", "active"])
def test_lead_through_keeps_it_still_when_nobody_touches_it(robot, mode):
    """Passive and active lead-through, masses 5 % off, nobody touching: < 1 mrad in 2 s."""
    config = TwinConfig(model_error=lt.twin.model_error.ModelError(mass_error=0.05), seed=2)
    controller = LeadThrough(robot, mode, parameters=LeadThroughParameters(calibration=None))
    sim = simulate(DigitalTwin(robot, config), controller, 2.0)
    moved = np.abs(sim.q_true - robot.home()).max(axis=0)
    assert moved.max() < STILL, f"joint {np.argmax(moved) + 1} moved {1e3 * moved.max():.2f} mrad"
    assert controller.state.value == "teaching"


def test_identification_recovers_the_twins_friction(robot):
    """One 0.4 rad/s cycle per joint: τ_C within 3 % + 0.01 Nm, c within 25 % + 0.05 Nm s/rad."""
    twin = DigitalTwin(robot, TwinConfig(seed=3))
    dynamics = lt.Dynamics(robot)
    logs = friction_experiment(twin, dynamics, runs=(SHORT_RUN,), progress=False)
    model, _ = fit_friction(friction_samples(logs, dynamics), dynamics)
    mid = 0.5 * (robot.q_min + robot.q_max)
    coulomb, viscous = twin.friction.params.coulomb_level(mid), twin.friction.params.viscous
    np.testing.assert_allclose(model.coulomb, coulomb, rtol=0.03, atol=0.01)
    np.testing.assert_allclose(model.viscous, viscous, rtol=0.25, atol=0.05)


def test_calibration_motion_stays_slow_and_small(robot):
    """The start-up calibration's motion: every joint below max_speed, within 2 strokes."""
    from test_calibration_safety import CalibrationOnly

    twin = DigitalTwin(robot, TwinConfig(seed=4))
    controller = CalibrationOnly(robot, twin.dt)
    sim = simulate(twin, controller, controller.run.duration)
    parameters = CalibrationParameters()
    assert np.abs(sim.qd_true).max() < parameters.max_speed
    assert np.abs(sim.q_true - robot.home()).max() < 2.0 * parameters.stroke
    assert controller.run.disturbance is None
