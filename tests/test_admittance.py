"""The admittance core (thesis §6.2): virtual system, dead-zone, bounds, assisted joints."""

import numpy as np
import pytest

from leadthrough.control.admittance import (
    AdmittanceState,
    admittance_step,
    dead_zone,
    keep_within,
    operator_started,
)

DT = 0.004
MASS = np.array([[2.0, 0.3], [0.3, 0.5]])  # symmetric positive definite [kg m²]


def test_undamped_step_is_newtons_law_on_the_virtual_inertia():
    """D̃ = 0: q̇_ref grows by dt (k_M M)⁻¹ τ, q_ref by dt q̇_ref⁺."""
    state = AdmittanceState(np.array([0.1, -0.2]), np.array([0.05, 0.0]))
    tau = np.array([1.0, -0.5])
    after = admittance_step(state, tau, MASS, 0.3, np.zeros(2), DT)
    expected = state.qd_ref + DT * np.linalg.solve(0.3 * MASS, tau)
    np.testing.assert_allclose(after.qd_ref, expected, rtol=1e-12)
    np.testing.assert_allclose(after.q_ref, state.q_ref + DT * expected, rtol=1e-12)


@pytest.mark.parametrize("damping", [0.5, 50.0, 5e4])
def test_constant_torque_settles_at_the_damped_speed_for_any_damping(damping):
    """Implicit in D̃: stable however stiff, converging to q̇ = D̃⁻¹ τ without overshoot."""
    state, tau = AdmittanceState(np.zeros(2), np.zeros(2)), np.array([1.0, 1.0])
    speeds = []
    for _ in range(20000):
        state = admittance_step(state, tau, MASS, 0.3, np.full(2, damping), DT)
        speeds.append(state.qd_ref.copy())
    np.testing.assert_allclose(state.qd_ref, tau / damping, rtol=1e-3)
    assert np.max(np.abs(speeds)) <= np.max(tau / damping) * (1 + 1e-9) + 1e-12


def test_dead_zone_removes_the_width_and_an_offset_only_widens_it():
    """sign(x)·max(|x| − w, 0); a bias widens its own side, never creates a reading."""
    x = np.array([-3.0, -1.0, 0.5, 1.0, 3.0])
    np.testing.assert_allclose(dead_zone(x, 1.0), [-2.0, 0.0, 0.0, 0.0, 2.0])
    np.testing.assert_allclose(dead_zone(x, 1.0, 1.5), [-2.0, 0.0, 0.0, 0.0, 0.5])
    assert np.all(dead_zone(np.zeros(3), 0.1, np.array([-5.0, 0.0, 5.0])) == 0.0)


def test_references_stop_at_the_bounds():
    """Clamped into [low, high]; the velocity stops only where it pushes outwards."""
    state = AdmittanceState(np.array([1.2, -1.2, 0.0]), np.array([0.3, 0.3, -0.3]))
    kept = keep_within(state, np.full(3, -1.0), np.full(3, 1.0))
    np.testing.assert_allclose(kept.q_ref, [1.0, -1.0, 0.0])
    np.testing.assert_allclose(kept.qd_ref, [0.0, 0.3, -0.3])


def test_nothing_is_assisted_while_nothing_moves():
    """At rest every reading may be model error: however large, none drives the admittance."""
    drive = np.array([2.0, -1.0, 0.5])
    assert np.all(operator_started(drive, np.full(3, 1e-3), 3e-3) == 0.0)


def test_joints_at_rest_are_assisted_while_another_moves_with_the_operator():
    """Joint 1 moves with its push: it and joint 3 (at rest) are assisted, not joint 2."""
    drive = np.array([1.0, 0.8, -0.5])
    qd = np.array([0.05, -0.05, 0.0])
    np.testing.assert_allclose(operator_started(drive, qd, 3e-3), [1.0, 0.0, -0.5])


def test_a_joint_moving_against_its_reading_alone_starts_nothing():
    """The operator braking a joint (or model error against the motion) is not an assist."""
    drive = np.array([1.0, 0.0, 0.7])
    qd = np.array([-0.05, 0.0, 0.0])
    assert np.all(operator_started(drive, qd, 3e-3) == 0.0)
