"""The digital twin against Pinocchio, physical laws and its own ground truth."""

import dataclasses

import mujoco
import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.feedforward import GravityCompensation
from leadthrough.twin.friction import TwinFrictionParameters
from leadthrough.twin.mjcf import Payload
from leadthrough.twin.mock import MockRobot
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.operator import Operator, TorqueProfile, ramp
from leadthrough.twin.runner import simulate
from leadthrough.twin.scenarios import SCENARIOS, scenario
from leadthrough.twin.sensors import SensorModel
from leadthrough.twin.simulator import DigitalTwin, TwinConfig, TwinError


@pytest.fixture(scope="module")
def yumi() -> lt.RobotDescription:
    """The shipped YuMi description."""
    return lt.robots.yumi()


@pytest.fixture(scope="module")
def dyn(yumi) -> lt.Dynamics:
    """Controller-side dynamics of the YuMi."""
    return lt.Dynamics(yumi)


class ConstantWrench(Operator):
    """A hand that pushes with a constant world-frame wrench at the flange."""

    def __init__(self, wrench):
        self.value = np.asarray(wrench, dtype=float)

    def wrench(self, t, flange_pose, flange_velocity):
        """The constant wrench [N, Nm]."""
        return self.value


def test_twin_mass_matrix_and_bias_equal_pinocchio(yumi, dyn):
    """MuJoCo's M(q) and bias C q̇ + G of the unperturbed twin equal Pinocchio's."""
    twin = DigitalTwin(yumi)
    rng = np.random.default_rng(0)
    full = np.zeros((7, 7))
    for _ in range(10):
        q, qd = rng.uniform(yumi.q_min, yumi.q_max), rng.uniform(-2, 2, 7)
        twin.data.qpos[:], twin.data.qvel[:] = q, qd
        mujoco.mj_forward(twin.model, twin.data)
        mujoco.mj_fullM(twin.model, twin.data, full)
        np.testing.assert_allclose(full, dyn.mass(q), atol=1e-12)
        bias = dyn.coriolis(q, qd) @ qd + dyn.gravity(q)
        np.testing.assert_allclose(twin.data.qfrc_bias, bias, atol=1e-10)
        site = twin.model.site("flange").id
        np.testing.assert_allclose(twin.data.site_xpos[site], dyn.pose(q)[:3, 3], atol=1e-12)


def _energy(dyn: lt.Dynamics, q: np.ndarray, qd: np.ndarray) -> float:
    return 0.5 * qd @ dyn.mass(q) @ qd + dyn.potential_energy(q)


def _falling_arm(yumi, friction_scale: float) -> tuple[np.ndarray, float]:
    """Total and largest kinetic energy of the arm falling from home, zero motor torque."""
    config = TwinConfig(delay_periods=0, sensors=SensorModel(torque_ripple=0.0),
                        model_error=ModelError(friction_scale=friction_scale))  # fmt: skip
    twin = DigitalTwin(yumi, config)
    dyn = lt.Dynamics(yumi)
    energy, kinetic = [], 0.0
    margin = 0.05  # stop before an end-stop, which is an (inelastic) contact
    for _ in range(200):
        q, qd = twin.truth.q, twin.truth.qd
        if np.any((q < yumi.q_min + margin) | (q > yumi.q_max - margin)):
            break
        twin.send_torque(np.zeros(7))
        energy.append(_energy(dyn, twin.truth.q, twin.truth.qd))
        kinetic = max(kinetic, 0.5 * qd @ dyn.mass(q) @ qd)
    return np.array(energy), kinetic


def test_energy_conserved_without_friction(yumi):
    """Without friction and torque, T + V stays within 1 % of the kinetic energy gained."""
    energy, kinetic = _falling_arm(yumi, friction_scale=1e-9)
    assert kinetic > 0.5  # it really fell
    assert np.ptp(energy) < 0.01 * kinetic


def test_energy_decays_with_friction(yumi):
    """With friction, T + V never grows (beyond round-off) and ends lower."""
    energy, _ = _falling_arm(yumi, friction_scale=1.0)
    assert np.all(np.diff(energy) < 1e-6)
    assert energy[-1] < energy[0] - 0.01


def _breakaway_run(yumi, dyn, joint: int, fraction: float) -> tuple[np.ndarray, DigitalTwin]:
    """Gravity-compensated arm with a torque of ``fraction`` of breakaway on one joint."""
    twin = DigitalTwin(yumi)
    params = twin.friction.params
    breakaway = params.coulomb_level(yumi.home())[joint] + (
        params.static[joint] - params.coulomb[joint]
    )
    twin.operator = TorqueProfile(joint, (ramp(0.2, 0.7, fraction * breakaway),))
    result = simulate(twin, GravityCompensation(dyn), 3.0)
    return result.q_true[:, joint], twin


@pytest.mark.parametrize("joint", [0, 3, 6])
def test_below_breakaway_the_joint_stays(yumi, dyn, joint):
    """Under 80 % of the breakaway torque a joint only pre-slides, then holds still."""
    angle, twin = _breakaway_run(yumi, dyn, joint, 0.8)
    presliding = twin.friction.params.static[joint] / twin.friction.params.bristle_stiffness[joint]
    assert np.abs(angle - angle[0]).max() < 2 * presliding
    quantum = twin.sensors.quantum[joint]
    settled = angle[int(1.0 / twin.dt) :]
    assert np.ptp(settled) < quantum


@pytest.mark.parametrize("joint", [0, 3, 6])
def test_above_breakaway_the_joint_moves(yumi, dyn, joint):
    """Over 130 % of the breakaway torque a joint slides away (more than 10 mrad)."""
    angle, _ = _breakaway_run(yumi, dyn, joint, 1.3)
    assert abs(angle[-1] - angle[0]) > 0.01


def test_gravity_compensated_arm_stays_put(yumi, dyn):
    """With gravity feed-forward and nobody touching it, no joint drifts over 10 s."""
    twin = DigitalTwin(yumi)
    result = simulate(twin, GravityCompensation(dyn), 10.0)
    quantum = twin.sensors.quantum
    assert np.all(np.abs(result.q_true - result.q_true[0]).max(axis=0) < 2 * quantum)
    assert np.all(np.abs(result.q - result.q[0]).max(axis=0) <= quantum * 1.0001)


def test_same_seed_same_run_other_seed_other_noise(yumi, dyn):
    """Runs with the same seed are identical; another seed changes the noise."""
    runs = []
    for seed in (3, 3, 4):
        config = TwinConfig(seed=seed, model_error=ModelError(mass_error=0.05))
        twin = scenario("line", yumi, config).twin(yumi)
        runs.append(simulate(twin, GravityCompensation(dyn), 0.5))
    np.testing.assert_array_equal(runs[0].q, runs[1].q)
    np.testing.assert_array_equal(runs[0].qd, runs[1].qd)
    assert not np.array_equal(runs[0].qd, runs[2].qd)


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_every_scenario_steps_without_mujoco_warning(yumi, dyn, name):
    """Each shipped scenario runs 2 s with no MuJoCo warning and finite signals."""
    twin = scenario(name, yumi).twin(yumi)
    result = simulate(twin, GravityCompensation(dyn), 2.0)
    assert [warning.number for warning in twin.data.warning] == [0] * len(twin.data.warning)
    assert np.all(np.isfinite(result.q_true))


def test_sensors_quantise_and_add_velocity_noise(yumi, dyn):
    """Readings are whole encoder counts; velocity noise has the configured 1e-4 rad/s std."""
    twin = DigitalTwin(yumi)
    result = simulate(twin, GravityCompensation(dyn), 2.0)
    counts = result.q / twin.sensors.quantum
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)
    noise = result.qd - result.qd_true
    assert np.std(noise) == pytest.approx(1e-4, rel=0.1)


def test_command_arrives_after_the_configured_delay(yumi):
    """A torque change reaches the measured motor torque after delay_periods periods."""
    for delay in (1, 3):
        twin = DigitalTwin(yumi, TwinConfig(delay_periods=delay, sensors=SensorModel(
            torque_noise_std=0.0, torque_ripple=0.0)))  # fmt: skip
        command = np.full(7, 0.5)
        seen = []
        for _ in range(delay + 2):
            twin.send_torque(command)
            seen.append(twin.read_state().tau_measured[0])
        assert seen[delay - 1] != pytest.approx(0.5)
        assert seen[delay] == pytest.approx(0.5)


def test_torque_saturates_at_the_limits(yumi):
    """A command beyond the limits reaches the joints clipped (ripple aside)."""
    twin = DigitalTwin(yumi, TwinConfig(delay_periods=0, sensors=SensorModel(torque_ripple=0)))
    twin.send_torque(np.full(7, 100.0))
    np.testing.assert_allclose(twin.truth.tau_motor, yumi.torque_limits)


def test_ground_truth_torque_is_jacobian_transpose_of_hand_wrench(yumi, dyn):
    """True τ_ext of a hand wrench equals Pinocchio's Jᵀ F; the wrist sensor reads Rᵀ F."""
    wrench = np.array([3.0, -2.0, 5.0, 0.1, 0.2, -0.1])
    twin = DigitalTwin(yumi, operator=ConstantWrench(wrench))
    q0 = twin.truth.q.copy()
    twin.send_torque(dyn.gravity(q0))
    np.testing.assert_allclose(twin.truth.tau_operator, dyn.jacobian(q0).T @ wrench, atol=1e-9)
    np.testing.assert_allclose(twin.truth.tau_ext, twin.truth.tau_operator, atol=1e-9)
    rotation = twin.truth.flange_pose[:3, :3]
    expected = np.concatenate([rotation.T @ wrench[:3], rotation.T @ wrench[3:]])
    np.testing.assert_allclose(twin.truth.ft_wrench, expected, atol=0.1)


def test_table_pushes_back_on_the_tool(yumi, dyn):
    """Pressed onto the table, the tool feels an upward force whose Jᵀ F is the contact τ_ext."""
    twin = scenario("table_push", yumi).twin(yumi)
    simulate(twin, GravityCompensation(dyn), 2.0)
    contact = twin._tool_contact_wrench(twin.truth.flange_pose[:3, 3])
    assert contact[2] > 10.0
    assert np.linalg.norm(contact[:2]) < 0.5 * contact[2]
    tau_contact = twin.truth.tau_ext - twin.truth.tau_operator
    np.testing.assert_allclose(tau_contact, dyn.jacobian(twin.truth.q).T @ contact, atol=1e-6)


def test_model_error_changes_the_true_robot(yumi):
    """Seeded mass error keeps masses within ±5 %; a payload adds its weight to gravity."""
    config = TwinConfig(model_error=ModelError(mass_error=0.05, payload=Payload(0.5)), seed=7)
    twin = DigitalTwin(yumi, config)
    ratios = twin.true_robot.masses / yumi.masses
    assert np.all(np.abs(ratios - 1.0) <= 0.05) and np.ptp(ratios) > 0.01
    assert twin.model.body("flange").mass[0] == pytest.approx(0.5)
    assert DigitalTwin(yumi, config).true_robot.masses == pytest.approx(twin.true_robot.masses)


def test_friction_scale_scales_true_friction(yumi):
    """friction_scale multiplies the true Coulomb and viscous friction."""
    scaled = DigitalTwin(yumi, TwinConfig(model_error=ModelError(friction_scale=1.2)))
    nominal = TwinFrictionParameters.from_robot(yumi)
    np.testing.assert_allclose(scaled.friction.params.coulomb, 1.2 * nominal.coulomb)
    np.testing.assert_allclose(scaled.friction.params.viscous, 1.2 * nominal.viscous)


def test_mass_scale_scales_every_link(yumi):
    """mass_scale multiplies every link mass and inertia (a systematic error)."""
    heavy = DigitalTwin(yumi, TwinConfig(model_error=ModelError(mass_scale=1.05))).true_robot
    np.testing.assert_allclose(heavy.masses, 1.05 * np.array(yumi.masses), rtol=1e-12)
    for true, nominal in zip(heavy.joints, yumi.joints, strict=True):
        np.testing.assert_allclose(true.link.inertia, 1.05 * nominal.link.inertia, rtol=1e-12)


def test_bad_commands_are_refused(yumi):
    """A NaN command is a drive fault (TwinError); a wrong shape an InputShapeError."""
    twin = DigitalTwin(yumi)
    with pytest.raises(TwinError, match="non-finite"):
        twin.send_torque(np.full(7, np.nan))
    with pytest.raises(lt.InputShapeError, match="tau"):
        twin.send_torque(np.zeros(6))


def test_render_writes_a_picture(yumi, tmp_path):
    """The offscreen renderer draws the arm: a PNG with more than one colour."""
    from leadthrough.twin.render import RenderError, render_arm, save_png

    twin = DigitalTwin(yumi)
    try:
        image = render_arm(twin.model, twin.data, width=160, height=120)
    except RenderError as error:
        pytest.skip(str(error))
    path = save_png(image, tmp_path / "arm.png")
    assert path.stat().st_size > 1000
    assert image.shape == (120, 160, 3) and np.unique(image.reshape(-1, 3), axis=0).shape[0] > 10


def test_mock_robot_integrates_exactly():
    """The mock's joint follows the closed-form solution of I q̈ = τ − b q̇."""
    robot = MockRobot(2, dt=0.01, inertia=0.2, damping=0.5)
    for _ in range(100):
        robot.send_torque([1.0, -0.5])
    t, rate = 1.0, 0.5 / 0.2
    expected_v = np.array([1.0, -0.5]) / 0.5 * (1 - np.exp(-rate * t))
    np.testing.assert_allclose(robot.read_state().qd, expected_v, rtol=1e-12)
    assert len(robot.commands) == 100


def test_twin_config_rejects_bad_timing():
    """A control period that is not a multiple of the physics step, or below it, is refused."""
    with pytest.raises(TwinError, match="multiple"):
        TwinConfig(control_dt=0.0041)
    with pytest.raises(lt.ParameterError, match=r"control_dt: must be >= 0\.0005"):
        TwinConfig(control_dt=-0.004)  # named as the twin's, not a robot description's
    dataclasses.replace(TwinConfig(), control_dt=0.001)
