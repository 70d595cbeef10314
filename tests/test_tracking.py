"""Joint tracking: model feed-forward plus a PD whose gains follow the joint inertias."""

import numpy as np

import leadthrough as lt
from leadthrough.control.tracking import JointTracker


def test_gains_follow_the_inertia_of_the_current_pose():
    """K_P = m_ii(q) ω², K_D = 2 ζ m_ii(q) ω at the pose of each call, not the first one."""
    dynamics = lt.Dynamics(lt.robots.yumi())
    tracker = JointTracker(dynamics, bandwidth=4.0, damping_ratio=0.8)
    omega = 2.0 * np.pi * 4.0
    rng = np.random.default_rng(2)
    robot = dynamics.robot
    for q in rng.uniform(robot.q_min, robot.q_max, (5, robot.n_joints)):
        error, rate_error = rng.normal(0.0, 0.01, (2, robot.n_joints))
        torque = tracker.torque(q, np.zeros(7), q + error, rate_error, np.zeros(7))
        inertia = np.diag(dynamics.mass(q))
        expected = dynamics.gravity(q) + inertia * omega**2 * error
        expected += 2.0 * 0.8 * inertia * omega * rate_error
        np.testing.assert_allclose(torque, expected, rtol=1e-12, atol=1e-12)


def test_inertia_of_the_yumi_elbow_changes_fourfold():
    """Why the gains must follow the pose: joint 3's inertia varies by 4× over the range."""
    dynamics = lt.Dynamics(lt.robots.yumi())
    robot = dynamics.robot
    poses = np.random.default_rng(0).uniform(robot.q_min, robot.q_max, (400, robot.n_joints))
    inertia = np.array([dynamics.mass(q)[2, 2] for q in poses])
    assert inertia.max() / inertia.min() > 3.0
