"""The robot registry and drive data: shipped arms, per-robot data files, stated assumptions."""

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import leadthrough as lt
from leadthrough.errors import RobotDescriptionError
from leadthrough.model.robots import AssumedDriveDataWarning

THREE_JOINT = Path(__file__).parent / "robots" / "three_joint.urdf"
REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"
DATA = Path(lt.robots.__file__).parent / "data"

#: Published numbers the drive data files must carry.
UR10E_K = [10.0, 10.6956, 8.4566, 9.0029, 9.4800, 10.1232]  # Mamedov & Mikhel 2020 [Nm/A]
GAZ_FC = [0.2450, 0.1523, 0.1827, 0.3591, 0.2669, 0.1658, 0.2109]  # Table III π_CLS [Nm]
GAZ_FV = [0.0665, 0.1987, 0.0399, 0.2257, 0.1023, -0.0132, 0.0638]  # [Nm s/rad]


def quietly(load, *args, **kwargs):
    """``load(*args, **kwargs)`` with its drive data warnings recorded, and those warnings."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load(*args, **kwargs)
    return robot, [w for w in caught if issubclass(w.category, AssumedDriveDataWarning)]


def test_registered_names():
    """names() lists the shipped arms, YuMi first."""
    assert lt.robots.names() == ["yumi", "panda", "ur5", "ur10e"]


@pytest.mark.parametrize("name", lt.robots.names())
def test_shipped_robot_loads_with_home_well_inside_its_limits(name):
    """Every shipped arm loads by name and its home pose is ≥ 5 % of each range inside."""
    robot, _ = quietly(lt.robots.load, name)
    home = robot.home()
    margin = 0.05 * (robot.q_max - robot.q_min)
    assert np.all(home >= robot.q_min + margin) and np.all(home <= robot.q_max - margin)
    assert np.all(robot.reflected_rotor_inertias > 0), "the twin needs a positive armature"


@pytest.mark.parametrize(("name", "warns"), [("yumi", 0), ("panda", 1), ("ur5", 1), ("ur10e", 1)])
def test_shipped_robot_warns_once_about_what_it_assumes(name, warns):
    """A shipped arm warns exactly once when some of its drive data are assumed, else never."""
    _, caught = quietly(lt.robots.load, name)
    assert len(caught) == warns
    assert not any("singularity" in str(warning.message) for warning in caught)


def test_ur10e_torque_constants_are_the_published_ones():
    """UR10e: τ = K·i with Mamedov & Mikhel's K per joint [Nm/A], as data."""
    robot, _ = quietly(lt.robots.ur10e)
    np.testing.assert_array_equal([joint.torque_constant for joint in robot.joints], UR10E_K)
    np.testing.assert_allclose(robot.home(), [0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0],
                               atol=1e-4)  # fmt: skip


def test_panda_friction_is_gaz_table_three():
    """Panda, sliding: our mean friction is Gaz et al.'s fc sign(q̇) + fv q̇ (fv ≥ 0, no fo)."""
    robot, _ = quietly(lt.robots.panda)
    friction = lt.FrictionModel.from_robot(robot)
    qd = np.concatenate([np.linspace(-1.0, -0.01, 20), np.linspace(0.01, 1.0, 20)])[:, None]
    gaz = np.array(GAZ_FC) * np.sign(qd) + np.maximum(GAZ_FV, 0.0) * qd
    np.testing.assert_allclose(friction.mean(qd), gaz, atol=1e-6)


def test_panda_ready_pose():
    """Panda: home is Franka's ready pose, not the zero pose clipped onto joint 4's limit."""
    robot, _ = quietly(lt.robots.panda)
    ready = [0, -np.pi / 4, 0, -3 * np.pi / 4, 0, np.pi / 2, np.pi / 4]
    np.testing.assert_allclose(robot.home(), ready, atol=1e-5)


def test_urdf_without_drive_data_warns_once_naming_every_assumption():
    """A bare URDF: gear ratio, rotor inertia, friction and home assumed, in one warning."""
    robot, caught = quietly(lt.robots.from_urdf, THREE_JOINT)
    assert len(caught) == 1
    message = str(caught[0].message)
    for words in ("gear ratio 100", "reflected rotor inertia", "Coulomb friction", "home"):
        assert words in message
    limits = np.array([40.0, 40.0, 20.0])
    np.testing.assert_allclose(robot.reflected_rotor_inertias, 2e-3 * limits, rtol=1e-12)
    np.testing.assert_allclose([j.friction.coulomb for j in robot.joints], 0.03 * limits)
    # zero is inside yaw's and shoulder's limits; the elbow's range [0.2, 2.6] excludes it
    np.testing.assert_allclose(robot.home(), [0.0, 0.0, 1.4])


def test_given_drive_data_are_not_assumed(tmp_path):
    """Arguments and a drive data file replace the assumptions; what they give is not named."""
    drive = tmp_path / "drive.toml"
    drive.write_text("coulomb = [1.0, 1.0, 0.5]\nhome = [0.1, 0.2, 1.0]\n")
    robot, caught = quietly(
        lt.robots.from_urdf, THREE_JOINT, gear_ratios=[50, 50, 50], drive_data=drive
    )
    message = str(caught[0].message)
    assert "gear ratio" not in message and "Coulomb" not in message and "home" not in message
    assert "rotor inertia" in message
    np.testing.assert_array_equal(robot.gear_ratios, 50.0)
    np.testing.assert_array_equal(robot.home(), [0.1, 0.2, 1.0])


def test_friction_without_its_noise_assumes_the_noise_and_says_so(tmp_path):
    """Drive data with τ_C and c but no ``noise_std``: σ is assumed, 0.05 τ_C, and named.

    It was 0, silently: no noise band on any joint. Given, it is not named.
    """
    drive = tmp_path / "drive.toml"
    drive.write_text("coulomb = [1.0, 2.0, 0.5]\nviscous = [0.5, 0.5, 0.2]\n")
    robot, caught = quietly(lt.robots.from_urdf, THREE_JOINT, drive_data=drive)
    assert [joint.friction.noise_std for joint in robot.joints] == pytest.approx([0.05, 0.1, 0.025])
    assert "friction noise σ [0.05, 0.1, 0.025] Nm (0.05 × τ_C)" in str(caught[0].message)
    drive.write_text("coulomb = [1.0, 2.0, 0.5]\nnoise_std = [0.2, 0.2, 0.2]\n")
    robot, caught = quietly(lt.robots.from_urdf, THREE_JOINT, drive_data=drive)
    assert [joint.friction.noise_std for joint in robot.joints] == [0.2, 0.2, 0.2]
    assert "noise" not in str(caught[0].message)


def test_continuous_joints_and_a_singular_home_are_stated(robots_dir, tmp_path):
    """The Kinova's continuous joints get ±2π, its assumed home points straight up: both named.

    Drive data with ``lower``, ``upper`` and a home away from the singularity silence both.
    """
    path = robots_dir / "kinova_description/robots/kinova.urdf"
    robot, caught = quietly(lt.robots.from_urdf, path, tip="j2s6s200_end_effector")
    message = str(caught[0].message)
    assert len(caught) == 1
    assert "continuous joint(s) j2s6s200_joint_1, j2s6s200_joint_4, j2s6s200_joint_6" in message
    assert "is near a singularity" in message
    drive = tmp_path / "kinova.toml"
    drive.write_text("lower = [-3.0, 0.9, 0.4, -3.0, 0.6, -3.0]\n"
                     "upper = [3.0, 5.4, 5.9, 3.0, 5.7, 3.0]\n"
                     "home = [0.0, 2.9, 1.3, -2.1, 1.4, 1.3]\n")  # fmt: skip
    robot, caught = quietly(lt.robots.from_urdf, path, tip="j2s6s200_end_effector",
                            drive_data=drive)  # fmt: skip
    message = str(caught[0].message)
    assert "continuous" not in message and "singular" not in message and "home" not in message
    np.testing.assert_allclose(robot.q_max, [3.0, 5.4, 5.9, 3.0, 5.7, 3.0])
    drive.write_text("lower = [-3.0, 0.9, 0.4, -6.283185307179586, 0.6, -3.0]\n")
    _, caught = quietly(lt.robots.from_urdf, path, tip="j2s6s200_end_effector",
                        drive_data=drive)  # fmt: skip
    message = str(caught[0].message)  # joint 4's limits are still the assumed ones
    assert "continuous joint(s) j2s6s200_joint_4;" in message


@pytest.mark.parametrize(
    ("urdf", "joint", "flange", "n_arm"),
    [("z1_description/urdf/z1.urdf", "jointGripper", "gripperStator", 6),
     ("so_arm_description/urdf/so101.urdf", "gripper", "gripper_link", 5)],
)  # fmt: skip
def test_a_chain_that_ends_in_a_gripper_joint_is_named(robots_dir, urdf, joint, flange, n_arm):
    """Without ``tip`` the Z1's and the SO-101's jaw joint would be guided as an arm joint.

    The warning names it and the link it hangs from; that link as the tip (on the Z1 a
    joint has the same name: the link is meant) loads the arm without it, and no warning.
    """
    path = robots_dir / urdf
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lt.robots.from_urdf(path)
        robot = lt.robots.from_urdf(path, tip=flange)
    gripper = [w for w in caught if issubclass(w.category, lt.robots.GripperJointWarning)]
    assert len(gripper) == 1
    assert f"joint {joint!r}" in str(gripper[0].message)
    assert f"tip={flange!r}" in str(gripper[0].message)
    assert robot.n_joints == n_arm


@pytest.mark.filterwarnings("ignore::leadthrough.model.robots.AssumedDriveDataWarning")
def test_a_gripper_joint_named_with_a_quote_is_warned_about(tmp_path):
    """Any joint name is read as text (a quote once broke the parent link's lookup)."""
    path = tmp_path / "quoted.urdf"
    path.write_text(THREE_JOINT.read_text().replace('name="elbow"', 'name="elbow_gripper\'s"'))
    with pytest.warns(lt.robots.GripperJointWarning, match=r"tip='l2'"):
        lt.robots.from_urdf(path)


def test_an_arm_chain_raises_no_gripper_warning(robots_dir):
    """A chain without ``tip`` whose last joint is the arm's (a UR5's wrist) is not a gripper's."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = lt.robots.from_urdf(robots_dir / "ur_description/urdf/ur5_robot.urdf")
        lt.robots.from_urdf(THREE_JOINT)
    assert robot.n_joints == 6
    assert not [w for w in caught if issubclass(w.category, lt.robots.GripperJointWarning)]


def test_an_unknown_tip_suggests_each_name_once(robots_dir):
    """The Z1 has a joint and a link called gripperStator: suggested once."""
    with pytest.raises(
        RobotDescriptionError, match=r"did you mean 'gripperStator', 'gripperMover'"
    ):
        lt.robots.from_urdf(robots_dir / "z1_description/urdf/z1.urdf", tip="gripperStato")


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ("coulomb = [1.0, 2.0]\n", "coulomb"),
        ("gear = [1.0, 2.0, 3.0]\n", "gear"),
        ("home = [0.0, 0.0, 'x']\n", "home"),
        ("assumed = 'everything'\n", "assumed"),
    ],
)
def test_bad_drive_data_names_the_file_and_key(tmp_path, text, key):
    """A wrong drive data file is one error naming the file and the key."""
    drive = tmp_path / "bad.toml"
    drive.write_text(text)
    with pytest.raises(RobotDescriptionError, match=rf"bad\.toml.*{key}"):
        lt.robots.from_urdf(THREE_JOINT, drive_data=drive)


def test_a_toml_description_takes_no_tip_or_drive_data():
    """A TOML file carries its flange and drive data: a tip given with it is an error."""
    with pytest.raises(RobotDescriptionError, match="takes no tip or drive data"):
        lt.robots.load(DATA / "yumi_left.toml", tip="flange")


def test_unknown_robot_name_lists_the_shipped_ones():
    """An unknown name is an error that lists the shipped robots."""
    with pytest.raises(RobotDescriptionError, match="yumi, panda, ur5, ur10e"):
        lt.robots.load("pandas")


def test_panda_with_identified_inertials_and_the_shipped_drive_data():
    """Gaz et al.'s identified Panda URDF + the Panda drive data: Gaz's masses and friction."""
    urdf = REALDATA / "panda_gaz2019" / "panda_identified.urdf"
    if not urdf.is_file():
        pytest.skip(f"real data absent: {urdf}")
    robot, _ = quietly(lt.robots.from_urdf, urdf, drive_data=DATA / "panda_drive.toml")
    shipped, _ = quietly(lt.robots.panda)
    assert robot.n_joints == 7
    np.testing.assert_allclose(robot.joints[0].link.mass, 4.970684)
    coulomb = [joint.friction.coulomb for joint in robot.joints]
    assert coulomb == [joint.friction.coulomb for joint in shipped.joints]
    np.testing.assert_allclose(robot.home(), shipped.home())


def test_a_published_urdf_with_an_inertia_rounded_below_zero_loads():
    """A published URDF whose inertia rounds below zero loads, as Pinocchio loads it.

    The UR10e's published identification writes wrist 1's inertia with an eigenvalue of
    −1.1e-8 against 1.04: rounding of its printed digits.
    """
    urdf = REALDATA / "ur10e" / "description" / "ur10e_published_identification.urdf"
    if not urdf.is_file():
        pytest.skip(f"real data absent: {urdf}")
    robot, _ = quietly(lt.robots.from_urdf, urdf, tip="tool0")
    reference = pin.buildModelFromUrdf(str(urdf))
    q = np.linspace(-1.0, 1.0, robot.n_joints)
    np.testing.assert_allclose(lt.Dynamics(robot).gravity(q),
                               pin.computeGeneralizedGravity(reference, reference.createData(), q),
                               atol=1e-9)  # fmt: skip


def test_an_inertia_off_by_more_than_rounding_is_refused():
    """Rounding passes (−1e-8 of 1); an eigenvalue of −1e-4 of 1 is an error, naming it."""
    from leadthrough.validation import symmetric_positive_definite

    rounded = np.diag([1.04, 0.5, -1.1e-8])
    symmetric_positive_definite("inertia", rounded)
    with pytest.raises(RobotDescriptionError, match="inertia: inertia must be positive definite"):
        symmetric_positive_definite("inertia", np.diag([1.0, 0.5, -1e-4]))


@pytest.mark.parametrize("name", lt.robots.names())
def test_info_command_summarises_every_shipped_robot(name, capsys):
    """`leadthrough info --robot NAME` prints the robot's joints and exits 0."""
    from leadthrough.cli.main import main

    robot, _ = quietly(lt.robots.load, name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AssumedDriveDataWarning)
        assert main(["info", "--robot", name]) == 0
    printed = capsys.readouterr().out
    assert all(joint in printed for joint in robot.joint_names)


def test_friction_given_without_its_coulomb_level_is_kept(tmp_path):
    """Drive data with c (and σ) but no τ_C: τ_C assumed and named, the file's c and σ kept.

    Before, the assumed friction replaced the whole of it: the file's c and σ were lost,
    and the warning named an assumed viscous coefficient the file had given.
    """
    drive = tmp_path / "drive.toml"
    drive.write_text("viscous = [0.5, 0.4, 0.3]\nnoise_std = [0.2, 0.2, 0.2]\n")
    robot, caught = quietly(lt.robots.from_urdf, THREE_JOINT, drive_data=drive)
    assert [joint.friction.viscous for joint in robot.joints] == [0.5, 0.4, 0.3]
    assert [joint.friction.noise_std for joint in robot.joints] == [0.2, 0.2, 0.2]
    assert all(joint.friction.coulomb > 0.0 for joint in robot.joints)
    message = str(caught[0].message)
    assert "Coulomb friction" in message and "viscous" not in message
