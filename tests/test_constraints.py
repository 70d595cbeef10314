"""Virtual constraints: where they push, and that they push only where violated."""

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.constraints import Box, KeepOutSphere, Plane, constraint_torque


def test_plane_pulls_back_from_both_sides():
    """Above or below the plane, the force points back to it, proportional to the distance."""
    plane = Plane(point=(0, 0, 0.5), normal=(0, 0, 2), stiffness=1000.0, damping=0.0)
    np.testing.assert_allclose(plane.force(np.array([0.1, 0, 0.52]), np.zeros(3)), [0, 0, -20])
    np.testing.assert_allclose(plane.force(np.array([0.1, 0, 0.47]), np.zeros(3)), [0, 0, 30])


def test_box_is_free_inside_and_pushes_in_through_the_crossed_face():
    """No force inside the box; outside, a push back through each crossed face only."""
    box = Box(lower=(0, 0, 0), upper=(1, 1, 1), stiffness=100.0, damping=0.0)
    assert np.all(box.force(np.array([0.5, 0.5, 0.5]), np.zeros(3)) == 0)
    np.testing.assert_allclose(box.force(np.array([1.1, 0.5, -0.2]), np.zeros(3)), [-10, 0, 20])


def test_sphere_pushes_outwards_and_damps_only_inward_motion():
    """Inside the keep-out sphere the force is radial outwards; damping resists going deeper."""
    sphere = KeepOutSphere(center=(0, 0, 0), radius=0.1, stiffness=100.0, damping=10.0)
    at = np.array([0.05, 0.0, 0.0])
    np.testing.assert_allclose(sphere.force(at, np.zeros(3)), [5.0, 0, 0])
    assert sphere.force(at, np.array([-1.0, 0, 0]))[0] > 5.0  # moving in: more push
    assert sphere.force(at, np.array([1.0, 0, 0]))[0] == pytest.approx(5.0)  # leaving: none
    assert np.all(sphere.force(np.array([0.2, 0, 0]), np.zeros(3)) == 0)


def test_constraint_torque_is_jacobian_transpose_of_the_force():
    """The joint torque of the constraints is Jᵀ F at the flange."""
    robot = lt.robots.yumi()
    dynamics = lt.Dynamics(robot)
    q = robot.home()
    flange = dynamics.pose(q)[:3, 3]
    plane = Plane(point=flange + np.array([0.0, 0.0, 0.01]), normal=(0, 0, 1))
    torque, force = constraint_torque([plane], dynamics, q, np.zeros(7))
    np.testing.assert_allclose(torque, dynamics.jacobian(q)[:3].T @ force)
    assert force[2] > 0


def test_bad_constraint_parameters():
    """A zero normal, an empty box or a non-positive radius is refused naming the field."""
    with pytest.raises(lt.ParameterError, match="normal"):
        Plane(normal=(0, 0, 0))
    with pytest.raises(lt.ParameterError, match="upper"):
        Box(lower=(0, 0, 0), upper=(1, 0, 1))
    with pytest.raises(lt.ParameterError, match="radius"):
        KeepOutSphere(radius=0.0)
