"""Physics checks of lt.Dynamics against laws and an independent DH chain written here."""

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

import leadthrough as lt


@pytest.fixture(scope="module")
def yumi() -> lt.RobotDescription:
    """The shipped YuMi description."""
    return lt.robots.yumi()


@pytest.fixture(scope="module")
def dyn(yumi: lt.RobotDescription) -> lt.Dynamics:
    """Dynamics of the YuMi."""
    return lt.Dynamics(yumi)


def random_states(robot: lt.RobotDescription, count: int, seed: int = 0):
    """Seeded joint positions inside the limits and velocities of a few rad/s."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q = rng.uniform(robot.q_min, robot.q_max)
        qd = rng.uniform(-2.0, 2.0, robot.n_joints)
        yield q, qd


def dh_matrix(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Thesis eq. (3.2), written out independently of the package."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def link_frames(robot: lt.RobotDescription, q: np.ndarray) -> list[np.ndarray]:
    """World poses of the DH link frames 1..n: base · A_1 · … · A_i."""
    frame = robot.base.homogeneous
    frames = []
    for joint, angle in zip(robot.joints, q, strict=True):
        dh = joint.dh
        frame = frame @ dh_matrix(angle + dh.offset, dh.d, dh.a, dh.alpha)
        frames.append(frame)
    return frames


def potential_energy(robot: lt.RobotDescription, q: np.ndarray) -> float:
    """V(q) = −Σ m_i g · c_i from the independent chain."""
    energy = 0.0
    for joint, frame in zip(robot.joints, link_frames(robot, q), strict=True):
        com_in_world = frame[:3, :3] @ joint.link.com + frame[:3, 3]
        energy -= joint.link.mass * robot.gravity @ com_in_world
    return energy


def kinetic_energy(robot: lt.RobotDescription, q: np.ndarray, qd: np.ndarray) -> float:
    """T = Σ ½ m v_c² + ½ ωᵀ I ω + ½ G²J_m q̇², velocities by central differences."""
    h = 1e-6
    before, after = link_frames(robot, q - h * qd), link_frames(robot, q + h * qd)
    energy = 0.5 * np.sum(robot.reflected_rotor_inertias * qd**2)
    for joint, frame, f0, f1 in zip(
        robot.joints, link_frames(robot, q), before, after, strict=True
    ):
        com = joint.link.com
        v_com = ((f1[:3, :3] @ com + f1[:3, 3]) - (f0[:3, :3] @ com + f0[:3, 3])) / (2 * h)
        omega_hat = (f1[:3, :3] - f0[:3, :3]) / (2 * h) @ frame[:3, :3].T
        omega = np.array([omega_hat[2, 1], omega_hat[0, 2], omega_hat[1, 0]])
        inertia_in_world = frame[:3, :3] @ joint.link.inertia @ frame[:3, :3].T
        energy += 0.5 * joint.link.mass * v_com @ v_com + 0.5 * omega @ inertia_in_world @ omega
    return energy


def test_mass_matrix_symmetric_positive_definite(yumi, dyn):
    """M(q) is symmetric positive definite on random poses."""
    for q, _ in random_states(yumi, 20):
        mass = dyn.mass(q)
        np.testing.assert_allclose(mass, mass.T, atol=1e-15)
        assert np.linalg.eigvalsh(mass).min() > 0.0


def test_mass_matrix_gives_kinetic_energy_of_independent_chain(yumi, dyn):
    """½ q̇ᵀ M q̇ equals the kinetic energy of the links and rotors computed from DH frames."""
    for q, qd in random_states(yumi, 10, seed=1):
        np.testing.assert_allclose(
            0.5 * qd @ dyn.mass(q) @ qd, kinetic_energy(yumi, q, qd), rtol=1e-7
        )


def test_rotor_inertia_on_mass_diagonal(yumi, dyn):
    """M minus the mass matrix of the arm without rotors is diag(G_r² J_m)."""
    joints = tuple(dataclasses.replace(joint, rotor_inertia=0.0) for joint in yumi.joints)
    bare = lt.Dynamics(dataclasses.replace(yumi, joints=joints))
    q = next(random_states(yumi, 1))[0]
    expected = np.diag(np.array([100, 100, 100, 100, 100, 101, 100]) ** 2 * yumi.rotor_inertias)
    np.testing.assert_allclose(dyn.mass(q) - bare.mass(q), expected, atol=1e-14)


def test_mass_derivative_is_coriolis_plus_transpose(yumi, dyn):
    """Ṁ = C + Cᵀ, with Ṁ by central finite differences along q̇."""
    h = 1e-6
    for q, qd in random_states(yumi, 10, seed=2):
        mass_dot = (dyn.mass(q + h * qd) - dyn.mass(q - h * qd)) / (2 * h)
        coriolis = dyn.coriolis(q, qd)
        np.testing.assert_allclose(mass_dot, coriolis + coriolis.T, atol=1e-8)


def test_gravity_is_gradient_of_independent_potential(yumi, dyn):
    """G(q) = ∂V/∂q, with V from the independent DH chain, by central differences."""
    h = 1e-6
    for q, _ in random_states(yumi, 10, seed=3):
        gradient = np.array(
            [
                (potential_energy(yumi, q + h * e) - potential_energy(yumi, q - h * e)) / (2 * h)
                for e in np.eye(yumi.n_joints)
            ]
        )
        np.testing.assert_allclose(dyn.gravity(q), gradient, atol=1e-7)
        assert dyn.potential_energy(q) == pytest.approx(potential_energy(yumi, q), abs=1e-12)


def test_equation_of_motion_matches_pinocchio_rnea(yumi, dyn):
    """M q̈ + C q̇ + G equals Pinocchio's recursive Newton–Euler inverse dynamics."""
    rng = np.random.default_rng(4)
    data = dyn.model.createData()
    for q, qd in random_states(yumi, 10, seed=4):
        qdd = rng.uniform(-5.0, 5.0, yumi.n_joints)
        lhs = dyn.mass(q) @ qdd + dyn.coriolis(q, qd) @ qd + dyn.gravity(q)
        np.testing.assert_allclose(lhs, pin.rnea(dyn.model, data, q, qd, qdd), atol=1e-10)
        np.testing.assert_allclose(lhs, dyn.inverse_dynamics(q, qd, qdd), atol=1e-10)


def test_momentum_and_coriolis_transpose_term(yumi, dyn):
    """P = M q̇, and Cᵀq̇ is the transpose of the Christoffel matrix times q̇."""
    for q, qd in random_states(yumi, 5, seed=5):
        np.testing.assert_allclose(dyn.momentum(q, qd), dyn.mass(q) @ qd, atol=1e-15)
        np.testing.assert_allclose(
            dyn.coriolis_transpose_times_velocity(q, qd), dyn.coriolis(q, qd).T @ qd, atol=1e-13
        )


def test_momentum_derivative_law(yumi, dyn):
    """Along a free motion, ṗ = Cᵀq̇ − G + τ (τ = 0 here), integrated with Pinocchio's ABA."""
    data = dyn.model.createData()
    q, qd = next(random_states(yumi, 1, seed=6))
    h = 1e-6
    tau = np.zeros(yumi.n_joints)
    qdd = pin.aba(dyn.model, data, q, qd, tau)
    p_next = dyn.momentum(q + h * qd, qd + h * qdd)
    p_prev = dyn.momentum(q - h * qd, qd - h * qdd)
    p_dot = (p_next - p_prev) / (2 * h)
    expected = dyn.coriolis_transpose_times_velocity(q, qd) - dyn.gravity(q) + tau
    np.testing.assert_allclose(p_dot, expected, atol=1e-6)


def test_flange_pose_equals_independent_dh_chain(yumi, dyn):
    """The flange pose is the product of the DH homogeneous transforms of eq. (3.2)."""
    for q, _ in random_states(yumi, 10, seed=7):
        np.testing.assert_allclose(dyn.pose(q), link_frames(yumi, q)[-1], atol=1e-12)


def test_jacobian_matches_finite_differences_of_pose(yumi, dyn):
    """Jacobian rows (v, ω) in world axes equal central differences of the flange pose."""
    h = 1e-7
    for q, _ in random_states(yumi, 5, seed=8):
        jacobian = dyn.jacobian(q)
        rotation = dyn.pose(q)[:3, :3]
        for k, e in enumerate(np.eye(yumi.n_joints)):
            after, before = dyn.pose(q + h * e), dyn.pose(q - h * e)
            linear = (after[:3, 3] - before[:3, 3]) / (2 * h)
            omega_hat = (after[:3, :3] - before[:3, :3]) / (2 * h) @ rotation.T
            angular = np.array([omega_hat[2, 1], omega_hat[0, 2], omega_hat[1, 0]])
            np.testing.assert_allclose(jacobian[:3, k], linear, atol=1e-7)
            np.testing.assert_allclose(jacobian[3:, k], angular, atol=1e-7)


def test_external_wrench_maps_through_jacobian_transpose(yumi, dyn):
    """Power balance: a flange wrench F does the work Fᵀ J q̇ = (Jᵀ F)ᵀ q̇ = τ_extᵀ q̇."""
    rng = np.random.default_rng(9)
    q, qd = next(random_states(yumi, 1, seed=9))
    wrench = rng.normal(size=6)
    jacobian = dyn.jacobian(q)
    assert wrench @ (jacobian @ qd) == pytest.approx((jacobian.T @ wrench) @ qd, rel=1e-12)


def test_gravity_does_not_depend_on_base_when_base_is_rotated_with_gravity(yumi):
    """Rotating base and gravity together leaves G(q) unchanged (frame independence)."""
    angle = 0.7
    spin = np.array(
        [[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0, 0, 1]]
    )
    tilt = lt.Placement(rotation=spin.T @ yumi.base.rotation)
    turned = dataclasses.replace(yumi, base=tilt, gravity=spin.T @ yumi.gravity)
    q = next(random_states(yumi, 1, seed=10))[0]
    np.testing.assert_allclose(
        lt.Dynamics(turned).gravity(q), lt.Dynamics(yumi).gravity(q), atol=1e-12
    )


def test_outputs_are_fresh_arrays(yumi, dyn):
    """A returned array is not overwritten by the next call (no aliasing of Pinocchio data)."""
    q0, q1 = (q for q, _ in random_states(yumi, 2, seed=11))
    first = dyn.gravity(q0)
    kept = first.copy()
    dyn.gravity(q1)
    np.testing.assert_array_equal(first, kept)
    snapshot = dyn.snapshot(q0, np.ones(yumi.n_joints))
    arrays = {name: value.copy() for name, value in vars(snapshot).items()}
    dyn.snapshot(q1, -np.ones(yumi.n_joints))
    for name, value in arrays.items():
        np.testing.assert_array_equal(getattr(snapshot, name), value, err_msg=name)


@pytest.mark.parametrize("method", ["gravity", "mass", "jacobian", "pose"])
def test_wrong_shape_is_a_clear_error(dyn, method):
    """A q of the wrong length raises InputShapeError naming the argument and the shapes."""
    with pytest.raises(lt.InputShapeError, match=r"q: expected shape \(7,\), got \(6,\)"):
        getattr(dyn, method)(np.zeros(6))


def test_remembered_results_follow_q_and_cannot_be_corrupted(yumi, dyn):
    """G and M are reused only for the same q; editing a returned array changes nothing."""
    q = yumi.home()
    mass = dyn.mass(q)
    mass[:] = 0.0
    assert np.all(np.diag(dyn.mass(q)) > 0.0)
    q[0] += 0.5  # the same array, edited in place: a new pose
    fresh = lt.Dynamics(yumi)
    np.testing.assert_array_equal(dyn.mass(q), fresh.mass(q))
    np.testing.assert_array_equal(dyn.gravity(q), fresh.gravity(q))


def test_snapshot_equals_the_separate_model_calls(yumi, dyn):
    """The compiled M and Cᵀq̇ of a snapshot equal mass() and the NumPy C.T @ q̇ (1e-12)."""
    rng = np.random.default_rng(12)
    for k in range(300):
        q = rng.uniform(yumi.q_min, yumi.q_max)
        qd = rng.normal(0.0, (0.01, 1.0, 5.0)[k % 3], 7)
        snapshot = dyn.snapshot(q, qd)
        np.testing.assert_array_equal(snapshot.mass, dyn.mass(q))
        np.testing.assert_array_equal(snapshot.gravity, dyn.gravity(q))
        np.testing.assert_allclose(snapshot.coriolis_drift, dyn.coriolis(q, qd).T @ qd,
                                   rtol=1e-12, atol=1e-12)  # fmt: skip
        np.testing.assert_array_equal(snapshot.tool_jacobian, dyn.tool_jacobian(q))
