import dataclasses

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.model.description import rpy_to_rotation
from rotations import rot_x, rot_y, rot_z


def _friction() -> lt.JointFriction:
    return lt.JointFriction(coulomb=0.5, slope=5e3, half_width=2e-3, viscous=0.1, noise_std=0.02)


def _link() -> lt.LinkInertial:
    return lt.LinkInertial(mass=1.0, com=[0.0, 0.0, 0.1], inertia=np.diag([2e-3, 2e-3, 1e-3]))


def _joint(name: str, limits=(-1.0, 1.0), **placing) -> lt.Joint:
    if not placing:
        placing = {"dh": lt.DHParameters(d=0.1, a=0.0, alpha=0.0)}
    return lt.Joint(
        name=name,
        link=_link(),
        position_limits=limits,
        velocity_limit=2.0,
        torque_limit=10.0,
        friction=_friction(),
        **placing,
    )


def _origin(axis=(0.0, 0.0, 1.0)) -> lt.JointOrigin:
    return lt.JointOrigin(lt.Placement([0.0, 0.0, 0.1], np.eye(3)), np.array(axis))


@pytest.fixture(scope="module")
def yumi() -> lt.RobotDescription:
    """The shipped YuMi left arm."""
    return lt.robots.yumi()


# --- arrays are read-only copies -----------------------------------------------------------

ARRAYS = {
    "placement.translation": lambda robot: robot.base.translation,
    "placement.rotation": lambda robot: robot.base.rotation,
    "link.com": lambda robot: robot.joints[0].link.com,
    "link.inertia": lambda robot: robot.joints[0].link.inertia,
    "robot.gravity": lambda robot: robot.gravity,
    "robot.q_min": lambda robot: robot.q_min,
    "robot.q_max": lambda robot: robot.q_max,
    "robot.velocity_limits": lambda robot: robot.velocity_limits,
    "robot.torque_limits": lambda robot: robot.torque_limits,
    "robot.gear_ratios": lambda robot: robot.gear_ratios,
    "robot.rotor_inertias": lambda robot: robot.rotor_inertias,
    "robot.reflected_rotor_inertias": lambda robot: robot.reflected_rotor_inertias,
    "robot.masses": lambda robot: robot.masses,
}


@pytest.mark.parametrize("name", list(ARRAYS))
def test_arrays_are_read_only(yumi, name):
    """Every array a description exposes refuses writes."""
    array = ARRAYS[name](yumi)
    assert not array.flags.writeable
    with pytest.raises(ValueError, match="read-only"):
        array[...] = 0.0


def test_origin_axis_is_read_only():
    """The axis of a JointOrigin refuses writes."""
    axis = _origin().axis
    assert not axis.flags.writeable
    with pytest.raises(ValueError, match="read-only"):
        axis[0] = 1.0


def test_arrays_are_copies_of_the_inputs():
    """Mutating the arrays a description was built from does not change the description."""
    translation, rotation = np.array([1.0, 2.0, 3.0]), np.eye(3)
    com, inertia = np.array([0.0, 0.0, 0.1]), np.diag([2e-3, 2e-3, 1e-3])
    axis = np.array([0.0, 1.0, 0.0])
    placement = lt.Placement(translation, rotation)
    link = lt.LinkInertial(1.0, com, inertia)
    origin = lt.JointOrigin(placement, axis)
    for array in (translation, rotation, com, inertia, axis):
        array[...] = 7.0
    np.testing.assert_array_equal(placement.translation, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(placement.rotation, np.eye(3))
    np.testing.assert_array_equal(link.com, [0.0, 0.0, 0.1])
    np.testing.assert_array_equal(link.inertia, np.diag([2e-3, 2e-3, 1e-3]))
    np.testing.assert_array_equal(origin.axis, [0.0, 1.0, 0.0])


def test_dataclasses_are_frozen(yumi):
    """Description fields cannot be reassigned."""
    with pytest.raises(dataclasses.FrozenInstanceError):
        yumi.name = "other"  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        yumi.joints[0].gear_ratio = 1.0  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        yumi.joints[0].link.mass = 1.0  # type: ignore[misc]


# --- derived quantities ----------------------------------------------------------------------


@pytest.mark.parametrize(("gear", "rotor"), [(100.0, 8.2e-6), (-101.0, 0.51e-6), (1.0, 0.0)])
def test_reflected_rotor_inertia_is_gear_squared_times_rotor(gear, rotor):
    """Joint.reflected_rotor_inertia is G_r² J_m, whatever the sign of the gear ratio."""
    joint = lt.Joint(
        name="j",
        link=_link(),
        position_limits=(-1.0, 1.0),
        velocity_limit=2.0,
        torque_limit=10.0,
        friction=_friction(),
        gear_ratio=gear,
        rotor_inertia=rotor,
        dh=lt.DHParameters(d=0.0, a=0.0, alpha=0.0),
    )
    assert joint.reflected_rotor_inertia == pytest.approx(gear * gear * rotor, rel=1e-15)


def test_robot_reflected_rotor_inertias_are_gear_squared_times_rotor(yumi):
    """RobotDescription.reflected_rotor_inertias is G_r² J_m per joint (YuMi: 0.082 on joint 1)."""
    expected = yumi.gear_ratios**2 * yumi.rotor_inertias
    np.testing.assert_allclose(yumi.reflected_rotor_inertias, expected, rtol=1e-15, atol=0)
    assert yumi.reflected_rotor_inertias[0] == pytest.approx(100.0**2 * 8.2e-6, rel=1e-15)
    assert yumi.reflected_rotor_inertias[5] == pytest.approx(101.0**2 * 0.51e-6, rel=1e-15)


def test_rpy_to_rotation_is_rz_ry_rx():
    """rpy_to_rotation(r, p, y) equals Rz(y) Ry(p) Rx(r) and is a proper rotation."""
    rng = np.random.default_rng(0)
    for roll, pitch, yaw in rng.uniform(-np.pi, np.pi, size=(50, 3)):
        rotation = rpy_to_rotation([roll, pitch, yaw])
        expected = rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)
        np.testing.assert_allclose(rotation, expected, rtol=0, atol=1e-15)
        np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), rtol=0, atol=1e-14)
        assert np.linalg.det(rotation) == pytest.approx(1.0, abs=1e-14)


def test_rpy_to_rotation_single_axes_are_right_handed():
    """A quarter turn of yaw, pitch or roll alone maps the axes as a right-handed rotation."""
    ex, ey, ez = np.eye(3)
    quarter = np.pi / 2
    np.testing.assert_allclose(rpy_to_rotation([0, 0, quarter]) @ ex, ey, atol=1e-15)
    np.testing.assert_allclose(rpy_to_rotation([0, quarter, 0]) @ ez, ex, atol=1e-15)
    np.testing.assert_allclose(rpy_to_rotation([quarter, 0, 0]) @ ey, ez, atol=1e-15)


def test_placement_homogeneous():
    """Placement.homogeneous is [[R, t], [0, 1]] and maps points as R p + t."""
    rng = np.random.default_rng(0)
    np.testing.assert_array_equal(lt.Placement().homogeneous, np.eye(4))
    for _ in range(10):
        rotation = rpy_to_rotation(rng.uniform(-np.pi, np.pi, size=3))
        translation = rng.normal(size=3)
        matrix = lt.Placement(translation, rotation).homogeneous
        assert matrix.shape == (4, 4)
        np.testing.assert_array_equal(matrix[:3, :3], rotation)
        np.testing.assert_array_equal(matrix[:3, 3], translation)
        np.testing.assert_array_equal(matrix[3], [0.0, 0.0, 0.0, 1.0])
        point = rng.normal(size=3)
        mapped = matrix @ np.append(point, 1.0)
        np.testing.assert_allclose(mapped[:3], rotation @ point + translation, atol=1e-15)


VECTORS = {
    "q_min": lambda joint: joint.position_limits[0],
    "q_max": lambda joint: joint.position_limits[1],
    "velocity_limits": lambda joint: joint.velocity_limit,
    "torque_limits": lambda joint: joint.torque_limit,
    "gear_ratios": lambda joint: joint.gear_ratio,
    "rotor_inertias": lambda joint: joint.rotor_inertia,
    "reflected_rotor_inertias": lambda joint: joint.reflected_rotor_inertia,
    "masses": lambda joint: joint.link.mass,
}


@pytest.mark.parametrize("name", list(VECTORS))
def test_vector_property_matches_joints(yumi, name):
    """Each RobotDescription vector property stacks the per-joint values in joint order."""
    vector = getattr(yumi, name)
    assert vector.shape == (yumi.n_joints,)
    assert vector.dtype == np.float64
    np.testing.assert_array_equal(vector, [VECTORS[name](joint) for joint in yumi.joints])


def test_scalar_properties_match_joints(yumi):
    """n_joints, joint_names, total_mass and uses_dh agree with the joints."""
    assert yumi.n_joints == len(yumi.joints) == 7
    assert yumi.joint_names == tuple(joint.name for joint in yumi.joints)
    assert yumi.total_mass == pytest.approx(sum(joint.link.mass for joint in yumi.joints))
    assert yumi.uses_dh
    chain = lt.RobotDescription("chain", (_joint("a", origin=_origin()),))
    assert not chain.uses_dh


def test_home_is_inside_the_limits(yumi):
    """home() is the described home pose, else zero clipped into the limits."""
    home = yumi.home()
    assert np.all(yumi.q_min <= home) and np.all(home <= yumi.q_max)
    np.testing.assert_array_equal(home, [-1.001, -0.869, 1.491, 0.072, 1.535, 0.668, 0.0])
    home[0] = 9.0
    assert yumi.home()[0] == -1.001
    limits = [(0.5, 1.0), (-2.0, -1.0), (-1.0, 1.0)]
    robot = lt.RobotDescription(
        "offset limits", tuple(_joint(f"j{i}", lim) for i, lim in enumerate(limits))
    )
    np.testing.assert_array_equal(robot.home(), [0.5, -1.0, 0.0])
    assert np.all(robot.q_min <= robot.home()) and np.all(robot.home() <= robot.q_max)


# --- construction errors ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "placing",
    [
        pytest.param({}, id="neither"),
        pytest.param(
            {"dh": lt.DHParameters(d=0.1, a=0.0, alpha=0.0), "origin": _origin()}, id="both"
        ),
    ],
)
def test_joint_needs_exactly_one_of_dh_and_origin(placing):
    """A Joint with neither or both of dh and origin is rejected."""
    with pytest.raises(lt.RobotDescriptionError, match="exactly one of 'dh' and 'origin'"):
        lt.Joint(
            name="j",
            link=_link(),
            position_limits=(-1.0, 1.0),
            velocity_limit=2.0,
            torque_limit=10.0,
            friction=_friction(),
            **placing,
        )


def test_dataclass_error_names_the_field():
    """A bad dataclass field raises a RobotDescriptionError naming that field."""
    with pytest.raises(lt.RobotDescriptionError) as info:
        lt.LinkInertial(mass=-1.0, com=[0.0, 0.0, 0.0], inertia=np.eye(3))
    assert info.value.field == "mass"
    assert "must be > 0" in str(info.value)


def test_nan_array_error_is_one_line():
    """A NaN in a 3×3 numpy inertia gives a one-line error message."""
    with pytest.raises(lt.RobotDescriptionError) as info:
        lt.LinkInertial(mass=1.0, com=[0.0, 0.0, 0.0], inertia=np.diag([1.0, np.nan, 1.0]))
    assert "\n" not in str(info.value)


def test_home_outside_limits_is_rejected(yumi):
    """A home pose outside the joint limits raises an error naming the joint."""
    with pytest.raises(lt.RobotDescriptionError, match="home: joint_2 at 1 rad is outside"):
        dataclasses.replace(yumi, home_position=[0.0, 1.0, 0, 0, 0, 0, 0])
