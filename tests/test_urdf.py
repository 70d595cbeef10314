import re
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import leadthrough as lt
from leadthrough.model.robots import GripperJointWarning

PANDA = "panda_description/urdf/panda.urdf"
UR5 = "ur_description/urdf/ur5_robot.urdf"

#: (URDF under the robots directory, tip, joints the reference locks at neutral).
ARMS = [
    pytest.param(PANDA, "panda_hand", ("panda_finger_joint1", "panda_finger_joint2"), id="panda"),
    pytest.param(UR5, "tool0", (), id="ur5-tool0"),
    pytest.param(UR5, None, (), id="ur5-no-tip"),
]

TOLERANCE = 1e-9

#: A URDF without drive data warns once about what it assumes (tested in test_robots.py).
pytestmark = pytest.mark.filterwarnings("ignore::leadthrough.model.robots.AssumedDriveDataWarning")


class Reference:
    """Pinocchio built straight from the URDF, independently of leadthrough."""

    def __init__(
        self, path: Path, tip: str | None, locked: tuple[str, ...], armature: np.ndarray
    ) -> None:
        model = pin.buildModelFromUrdf(str(path))
        if locked:
            ids = [model.getJointId(name) for name in locked]
            assert all(joint_id < model.njoints for joint_id in ids), locked
            model = pin.buildReducedModel(model, ids, pin.neutral(model))
        model.armature = armature  # the URDF has none: the assumed reflected rotor inertia
        self.model = model
        self.data = model.createData()
        self.tip = tip

    def gravity(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """G(q)."""
        return pin.computeGeneralizedGravity(self.model, self.data, q).copy()

    def mass(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """M(q), the upper triangle of crba symmetrized."""
        upper = np.triu(pin.crba(self.model, self.data, q))
        return upper + np.triu(upper, 1).T

    def coriolis(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """C(q, q̇)."""
        return pin.computeCoriolisMatrix(self.model, self.data, q, qd).copy()

    def pose(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """World pose of the tip frame (of the last joint frame without a tip)."""
        pin.framesForwardKinematics(self.model, self.data, q)
        if self.tip is None:
            return self.data.oMi[self.model.njoints - 1].homogeneous.copy()
        return self.data.oMf[self.model.getFrameId(self.tip)].homogeneous.copy()


QUANTITIES: dict[str, Callable[[lt.Dynamics, np.ndarray, np.ndarray], np.ndarray]] = {
    "gravity": lambda dyn, q, qd: dyn.gravity(q),
    "mass": lambda dyn, q, qd: dyn.mass(q),
    "coriolis": lambda dyn, q, qd: dyn.coriolis(q, qd),
    "pose": lambda dyn, q, qd: dyn.pose(q),
}


@pytest.mark.parametrize("quantity", list(QUANTITIES))
@pytest.mark.parametrize(("urdf", "tip", "locked"), ARMS)
def test_dynamics_match_pinocchio_from_urdf(robots_dir, urdf, tip, locked, quantity):
    """Gravity, mass, Coriolis and tip pose of a URDF arm equal Pinocchio's on the raw URDF."""
    robot = lt.robots.from_urdf(robots_dir / urdf, tip=tip)
    dyn = lt.Dynamics(robot)
    reference = Reference(robots_dir / urdf, tip, locked, robot.reflected_rotor_inertias)
    assert reference.model.nq == reference.model.nv == robot.n_joints
    rng = np.random.default_rng(0)
    for _ in range(5):
        q = rng.uniform(robot.q_min, robot.q_max)
        qd = rng.normal(size=robot.n_joints)
        actual = QUANTITIES[quantity](dyn, q, qd)
        expected = getattr(reference, quantity)(q, qd)
        np.testing.assert_allclose(actual, expected, rtol=0, atol=TOLERANCE, err_msg=str(q))


@pytest.mark.parametrize(("urdf", "tip", "locked"), ARMS)
def test_joints_and_limits_match_urdf(robots_dir, urdf, tip, locked):
    """Joint names, order and limits of a URDF arm are those of the URDF chain."""
    robot = lt.robots.from_urdf(robots_dir / urdf, tip=tip)
    model = Reference(robots_dir / urdf, tip, locked, robot.reflected_rotor_inertias).model
    assert robot.joint_names == tuple(model.names[1:])
    assert not robot.uses_dh
    np.testing.assert_array_equal(robot.q_min, model.lowerPositionLimit)
    np.testing.assert_array_equal(robot.q_max, model.upperPositionLimit)
    np.testing.assert_array_equal(robot.velocity_limits, model.velocityLimit)
    np.testing.assert_array_equal(robot.torque_limits, model.effortLimit)
    drive = lt.robots.drive
    np.testing.assert_array_equal(robot.gear_ratios, drive.ASSUMED_GEAR_RATIO)
    assumed = drive.INERTIA_PER_TORQUE_LIMIT * robot.torque_limits
    np.testing.assert_allclose(robot.reflected_rotor_inertias, assumed, rtol=1e-12)


# --- errors ----------------------------------------------------------------------------------


def _error(path: Path, **kwargs) -> lt.RobotDescriptionError:
    """The error from_urdf raises for ``path``, checked to be one line naming the file."""
    with pytest.raises(lt.RobotDescriptionError) as info:
        lt.robots.from_urdf(path, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert path.name in message
    assert info.value.source == str(path)
    return info.value


def test_panda_without_tip_is_taken_up_to_its_hand_with_a_warning(robots_dir):
    """Its two fingers branch off the hand: the arm is taken up to it, as with tip="panda_hand".

    Before, it was an error ("not a serial chain"), though example-robot-data's Panda is
    the arm a user tries first. A branch of joints not named as a gripper's still is one.
    """
    with pytest.warns(GripperJointWarning, match=r"'panda_finger_joint1', 'panda_finger_joint2' "
                      r"are a gripper's.*tip='panda_hand'"):  # fmt: skip
        robot = lt.robots.from_urdf(robots_dir / PANDA)
    given = lt.robots.from_urdf(robots_dir / PANDA, tip="panda_hand")
    assert robot.n_joints == given.n_joints == 7
    q = robot.home() + 0.2
    np.testing.assert_array_equal(lt.Dynamics(robot).pose(q), lt.Dynamics(given).pose(q))
    np.testing.assert_array_equal(lt.Dynamics(robot).mass(q), lt.Dynamics(given).mass(q))


def test_a_home_where_gravity_takes_most_of_a_joints_limit_is_named(robots_dir):
    """Talos' left arm holds 89 % of joint 1's limit at home: its load says so.

    The shipped arms hold far less and say nothing of it. Before, nothing warned, and the
    arm sank up to 1.12 rad untouched (a review).
    """
    path = robots_dir / "talos_data/robots/talos_left_arm.urdf"
    heavy = "at home joint 1 holds 89% of its torque limit against gravity"
    with pytest.warns(lt.robots.AssumedDriveDataWarning, match=heavy):
        lt.robots.from_urdf(path, tip="gripper_left_base_link")
    for name in ("yumi", "ur10e", "ur5", "panda"):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            getattr(lt.robots, name)()
        assert not any("against gravity" in str(w.message) for w in caught), name


def test_a_joint_and_a_link_of_one_name_are_a_one_line_error(robots_dir):
    """example-robot-data's SO-100 names a joint and a link "gripper": a one-line error.

    Before, Pinocchio's ``ValueError: Several frames match the filter`` reached the user
    as a traceback, with the tip its own warning suggests (a review).
    """
    path = robots_dir / "so_arm_description/urdf/so100.urdf"
    with pytest.raises(lt.RobotDescriptionError) as error:
        lt.robots.from_urdf(path, tip="gripper")
    assert "the name 'gripper' is both a joint's and a link's (rename one)" in str(error.value)
    assert "\n" not in str(error.value)


def test_a_branch_not_named_as_a_gripper_is_no_serial_chain(robots_dir, tmp_path):
    """The Panda with its finger joints renamed: the tree branches, a one-line error."""
    text = (robots_dir / PANDA).read_text(encoding="utf-8").replace("finger_joint", "slide_joint")
    path = tmp_path / "panda.urdf"
    path.write_text(text, encoding="utf-8")
    error = _error(path)
    assert "not a serial chain" in str(error) and error.field == "tip"


def test_unknown_tip_is_named(robots_dir):
    """An unknown tip fails with an error naming the tip, and the frames it may mean."""
    error = _error(robots_dir / UR5, tip="no_such_link")
    assert "'no_such_link'" in str(error)
    assert error.field == "tip"
    assert "did you mean 'tool0'" in str(_error(robots_dir / UR5, tip="tool"))


KINOVA = "kinova_description/robots/kinova.urdf"


def test_continuous_joints_load_as_one_turn_either_way(robots_dir):
    """The Kinova's continuous joints 1, 4, 6: ±2π, and the dynamics Pinocchio's own.

    The reference is Pinocchio's model of the unmodified URDF, whose continuous joints
    take (cos θ, sin θ) as their configuration.
    """
    path = robots_dir / KINOVA
    robot = lt.robots.from_urdf(path, tip="j2s6s200_end_effector")
    continuous = [0, 3, 5]
    np.testing.assert_allclose(robot.q_min[continuous], -2.0 * np.pi)
    np.testing.assert_allclose(robot.q_max[continuous], 2.0 * np.pi)
    model = pin.buildModelFromUrdf(str(path))
    locked = [i for i in range(1, model.njoints) if not model.names[i].startswith("j2s6s200_joint")]
    model = pin.buildReducedModel(model, locked, pin.neutral(model))
    model.armature = np.zeros(model.nv)
    data = model.createData()
    no_rotors = lt.robots.from_urdf(path, tip="j2s6s200_end_effector",
                                    rotor_inertias=[0.0] * 6)  # fmt: skip
    dynamics = lt.Dynamics(no_rotors)
    for q in np.random.default_rng(3).uniform(robot.q_min, robot.q_max, (5, 6)):
        configuration = np.concatenate([
            [np.cos(angle), np.sin(angle)] if joint.nq == 2 else [angle]
            for angle, joint in zip(q, model.joints[1:], strict=True)
        ])  # fmt: skip
        reference = pin.computeGeneralizedGravity(model, data, configuration)
        np.testing.assert_allclose(dynamics.gravity(q), reference, atol=1e-9)
        upper = np.triu(pin.crba(model, data, configuration))
        np.testing.assert_allclose(dynamics.mass(q), upper + np.triu(upper, 1).T, atol=1e-9)


MALFORMED = [
    pytest.param("<robot name='broken'><link name='base'>\n", id="truncated-xml"),
    pytest.param("this is not XML at all\n", id="not-xml"),
    pytest.param("", id="empty"),
]


@pytest.mark.parametrize("text", MALFORMED)
def test_malformed_urdf_names_the_file(tmp_path, text):
    """A malformed URDF file fails with a one-line error naming the file."""
    path = tmp_path / "broken_arm.urdf"
    path.write_text(text, encoding="utf-8")
    error = _error(path)
    assert "not a valid URDF" in str(error)


def test_missing_urdf_names_the_file(tmp_path):
    """A URDF path that does not exist fails naming the file."""
    error = _error(tmp_path / "absent_arm.urdf")
    assert "no such file" in str(error)


SLIDER_URDF = """<?xml version="1.0"?>
<robot name="slider">
  <link name="base"/>
  <link name="link1">
    <inertial>
      <origin xyz="0 0 0.1"/>
      <mass value="1.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>
    </inertial>
  </link>
  <link name="link2">
    <inertial>
      <origin xyz="0 0 0.1"/>
      <mass value="0.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>
    </inertial>
  </link>
  <joint name="hinge" type="revolute">
    <parent link="base"/>
    <child link="link1"/>
    <axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
  <joint name="slide" type="{second}">
    <parent link="link1"/>
    <child link="link2"/>
    <origin xyz="0 0 0.2"/>
    <axis xyz="0 0 1"/>
    <limit lower="0" upper="0.3" effort="10" velocity="1"/>
  </joint>
</robot>
"""


def test_two_revolute_links_load(tmp_path):
    """The tiny two-link URDF loads when both joints are revolute (control for the next test)."""
    path = tmp_path / "hinges.urdf"
    path.write_text(SLIDER_URDF.format(second="revolute"), encoding="utf-8")
    robot = lt.robots.from_urdf(path)
    assert robot.joint_names == ("hinge", "slide")
    np.testing.assert_array_equal(robot.masses, [1.0, 0.5])


def test_prismatic_joint_in_chain_is_named(tmp_path):
    """A chain with a prismatic joint fails naming that joint."""
    path = tmp_path / "slider.urdf"
    path.write_text(SLIDER_URDF.format(second="prismatic"), encoding="utf-8")
    error = _error(path)
    assert "slide" in error.field
    assert "hinge" not in str(error)
    assert "only revolute joints are supported, got a prismatic joint" in error.reason


def test_one_revolute_link_loads(tmp_path):
    """An arm of one joint loads (its Jacobian is (6, 1), not Pinocchio's (6,))."""
    text = SLIDER_URDF.format(second="revolute")
    link2 = text[text.index('  <link name="link2">') : text.index('  <joint name="hinge"')]
    one = text[: text.index('  <joint name="slide"')].replace(link2, "") + "</robot>\n"
    path = tmp_path / "one.urdf"
    path.write_text(one, encoding="utf-8")
    robot = lt.robots.from_urdf(path)
    assert robot.n_joints == 1
    assert lt.Dynamics(robot).jacobian(robot.home()).shape == (6, 1)


def test_a_continuous_joint_needs_its_torque_and_speed_limits(tmp_path):
    """Without ``<limit effort velocity>`` a continuous joint is one error naming it."""
    text = SLIDER_URDF.format(second="continuous")
    path = tmp_path / "unlimited.urdf"
    path.write_text(text.replace('<limit lower="0" upper="0.3" effort="10" velocity="1"/>', ""),
                    encoding="utf-8")  # fmt: skip
    error = _error(path)
    assert "'slide'" in error.field and "<limit effort velocity>" in error.reason
    path.write_text(text, encoding="utf-8")
    robot = lt.robots.from_urdf(path)
    assert robot.joints[1].position_limits == (-2.0 * np.pi, 2.0 * np.pi)
    assert robot.joints[1].torque_limit == 10.0


HINGES = SLIDER_URDF.format(second="revolute")
SLIDE_LIMIT = '<limit lower="0" upper="0.3" effort="10" velocity="1"/>'
SLIDE_AXIS = '<axis xyz="0 0 1"/>\n    ' + SLIDE_LIMIT
LINK2_MASS = '<mass value="0.5"/>'
LINK2_INERTIA = LINK2_MASS + '\n      <inertia ixx="0.01"'
SLIDE, LINK2 = "joint 'slide'", "link 'link2'"

#: (text of HINGES, its replacement, the field named, the reason given).
MALFORMED_PARTS = [
    pytest.param(SLIDE_LIMIT, SLIDE_LIMIT.replace('"10"', '"abc"'), SLIDE,
                 '<limit effort="abc"> is not a number', id="effort-not-a-number"),
    pytest.param(SLIDE_LIMIT, SLIDE_LIMIT.replace('effort="10" ', ""), SLIDE,
                 "<limit> has no effort", id="effort-missing"),
    pytest.param(SLIDE_LIMIT, SLIDE_LIMIT.replace(' velocity="1"', ""), SLIDE,
                 "<limit> has no velocity", id="velocity-missing"),
    pytest.param(SLIDE_LIMIT, SLIDE_LIMIT.replace('"0.3"', '"nan"'), SLIDE,
                 '<limit upper="nan"> is not a number', id="upper-nan"),
    pytest.param(SLIDE_LIMIT, SLIDE_LIMIT.replace('"0"', '"1e999"'), SLIDE,
                 '<limit lower="1e999"> is not finite', id="lower-overflows"),
    pytest.param(SLIDE_LIMIT, SLIDE_LIMIT.replace('"10"', '"-10"'), SLIDE,
                 '<limit effort="-10"> must not be negative', id="effort-negative"),
    pytest.param(SLIDE_LIMIT, "", SLIDE, "a revolute joint needs <limit effort velocity>: "
                 "its torque and speed limits", id="limit-missing"),
    pytest.param(SLIDE_AXIS, SLIDE_AXIS.replace('"0 0 1"', '"1 0"'), SLIDE,
                 '<axis xyz="1 0">: expected 3 numbers, got 2', id="axis-two-values"),
    pytest.param(SLIDE_AXIS, SLIDE_AXIS.replace('"0 0 1"', '"0 inf 1"'), SLIDE,
                 """<axis xyz="0 inf 1">: 'inf' is not a number""", id="axis-inf"),
    pytest.param('<origin xyz="0 0 0.2"/>', '<origin xyz="0 0 0.2" rpy="0 nan 0"/>', SLIDE,
                 """<origin rpy="0 nan 0">: 'nan' is not a number""", id="origin-nan"),
    pytest.param(SLIDE_LIMIT, SLIDE_LIMIT + '<dynamics friction="x"/>', SLIDE,
                 '<dynamics friction="x"> is not a number', id="friction-not-a-number"),
    pytest.param('<child link="link2"/>', '<child link="link9"/>', SLIDE,
                 '<child link="link9"> names no link of the file', id="child-undefined"),
    pytest.param('<parent link="link1"/>', "", SLIDE, "has no <parent link>",
                 id="parent-missing"),
    pytest.param('"slide" type="revolute"', '"slide" type="revolving"', SLIDE,
                 "type 'revolving' is not a URDF joint type (revolute, continuous, prismatic, "
                 "fixed, floating, planar)", id="type-unknown"),
    pytest.param('name="slide"', 'name="hinge"', "joint 'hinge'", "defined twice",
                 id="joint-defined-twice"),
    pytest.param(LINK2_MASS, '<mass value="-0.5"/>', LINK2,
                 '<mass value="-0.5"> must not be negative', id="mass-negative"),
    pytest.param(LINK2_MASS, '<mass value="half"/>', LINK2, '<mass value="half"> is not a number',
                 id="mass-not-a-number"),
    pytest.param(LINK2_MASS, "", LINK2, "<inertial> has no <mass>", id="mass-missing"),
    pytest.param(LINK2_INERTIA, LINK2_INERTIA.replace('"0.01"', '"nan"'), LINK2,
                 '<inertia ixx="nan"> is not a number', id="inertia-nan"),
    pytest.param('<origin xyz="0 0 0.1"/>\n      ' + LINK2_MASS,
                 '<origin xyz="0 0"/>\n      ' + LINK2_MASS, LINK2,
                 '<origin xyz="0 0">: expected 3 numbers, got 2', id="com-two-values"),
]  # fmt: skip


@pytest.mark.parametrize(("old", "new", "field", "reason"), MALFORMED_PARTS)
def test_a_malformed_joint_or_link_is_named(tmp_path, old, new, field, reason):
    """A malformed value of a joint or link: one line naming the file, it and what is wrong.

    Before, the URDF parser's reason went to stderr and the error only said "not a valid
    URDF"; a link whose mass was not a number lost its inertial and read as a mass of 0.
    """
    assert HINGES.count(old) == 1, old
    path = tmp_path / "arm.urdf"
    path.write_text(HINGES.replace(old, new), encoding="utf-8")
    error = _error(path)
    assert (error.field, error.reason) == (field, reason)
    assert str(error) == f"{path}: {field}: {reason}"


LOOPING = """  <joint name="back" type="fixed">
    <parent link="link2"/>
    <child link="link1"/>
  </joint>
</robot>"""


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        pytest.param(("</robot>", LOOPING),
                     "is the child of joints 'hinge' and 'back': a URDF is a tree, each link "
                     "has one parent", id="two-parents"),
        pytest.param(('<parent link="base"/>', '<parent link="link2"/>'),
                     "link 'link1': is on a loop of joints, not below the root link 'base'",
                     id="loop"),
        pytest.param(('<link name="base"/>', '<link name="base"/>\n  <link name="stray"/>'),
                     "the joints join the links into 2 trees, not one (root links: 'base', "
                     "'stray')", id="two-roots"),
    ],
)  # fmt: skip
def test_joints_that_do_not_make_one_tree_are_named(tmp_path, change, reason):
    """A link with two parents, a loop, a second root: one line, not Pinocchio's crash.

    Before, a link that was the child of two joints crashed the process inside Pinocchio
    (a segmentation fault, nothing printed); a loop gave urdfdom's lines on stderr and
    "not a valid URDF".
    """
    path = tmp_path / "arm.urdf"
    path.write_text(HINGES.replace(*change), encoding="utf-8")
    assert reason in str(_error(path))


def test_a_joint_of_the_arm_that_mimics_another_is_refused(robots_dir, tmp_path):
    """The shipped Panda with joint 3 mimicking joint 2: refused, naming both; a finger may.

    Before, it loaded as seven independent joints, silently.
    """
    text = (Path(lt.robots.__file__).parent / "data" / "panda.urdf").read_text(encoding="utf-8")
    joint3 = text.index('<joint name="panda_joint3"')
    end = text.index("</joint>", joint3)
    path = tmp_path / "panda.urdf"
    path.write_text(text[:end] + '<mimic joint="panda_joint2"/>' + text[end:], encoding="utf-8")
    error = _error(path, tip="panda_hand")
    assert "joint 'panda_joint3'" in str(error) and "mimics 'panda_joint2'" in str(error)
    assert "<mimic" in text  # the shipped file's finger mimics the other finger: it loads
    lt.robots.from_urdf(Path(lt.robots.__file__).parent / "data" / "panda.urdf", tip="panda_hand")


def test_a_malformed_limit_of_the_shipped_panda_names_its_joint(tmp_path):
    """The shipped Panda with joint 3's effort not a number: its joint and value named."""
    text = (Path(lt.robots.__file__).parent / "data" / "panda.urdf").read_text(encoding="utf-8")
    limit = '<limit effort="87.0" lower="-2.8973" upper="2.8973" velocity="2.175"/>'
    joint3 = text.index('<joint name="panda_joint3"')
    assert text.index(limit, joint3) < text.index("</joint>", joint3)
    path = tmp_path / "panda.urdf"
    path.write_text(text[:joint3] + text[joint3:].replace('effort="87.0"', 'effort="abc"', 1),
                    encoding="utf-8")  # fmt: skip
    error = _error(path, tip="panda_hand")
    assert str(error) == f"""{path}: joint 'panda_joint3': <limit effort="abc"> is not a number"""


def _shipped_ur5_in(tmp_path: Path, convert) -> Path:
    """The shipped UR5 with each joint's ``<limit>`` / ``<origin>`` line passed to ``convert``."""
    text = (Path(lt.robots.__file__).parent / "data" / "ur5.urdf").read_text(encoding="utf-8")
    path = tmp_path / "ur5.urdf"
    path.write_text(convert(text), encoding="utf-8")
    return path


def _in_degrees(text: str) -> str:
    def degrees(match: re.Match) -> str:
        return f'{match.group(1)}="{np.degrees(float(match.group(2))):.1f}"'

    return re.sub(r'(lower|upper)="([-0-9.e]+)"', degrees, text)


def _in_millimetres(text: str) -> str:
    def millimetres(match: re.Match) -> str:
        return 'xyz="' + " ".join(f"{1000.0 * float(v):g}" for v in match.group(1).split()) + '"'

    return re.sub(r'xyz="([^"]+)"', millimetres, text.replace("<axis xyz=", "<axis XYZ=")
                  ).replace("<axis XYZ=", "<axis xyz=")  # fmt: skip


def test_limits_in_degrees_are_refused(tmp_path):
    """A revolute joint's limits beyond two turns: radians, not degrees.

    Before, the UR5's limits of ±360 "rad" loaded and nothing limited its joints.
    """
    error = _error(_shipped_ur5_in(tmp_path, _in_degrees), tip="tool0")
    assert error.field == "joint 'shoulder_pan_joint'"
    assert error.reason == ('<limit lower="-360.0"> is more than two turns: a URDF gives '
                            "radians (was it written in degrees?)")  # fmt: skip


def test_offsets_in_millimetres_are_refused(tmp_path):
    """A moving joint 10 m or more from its parent: metres, not millimetres.

    Before, the UR5 in millimetres loaded, its shoulder holding 30 566 Nm at home.
    """
    error = _error(_shipped_ur5_in(tmp_path, _in_millimetres), tip="tool0")
    assert error.field == "joint 'shoulder_pan_joint'"
    assert "puts a joint 89.2 m from its parent's frame: a URDF gives metres" in error.reason


def test_a_centre_of_mass_in_millimetres_is_refused(tmp_path):
    """A link's centre of mass 10 m or more from its frame: one line naming the link."""
    path = tmp_path / "arm.urdf"
    path.write_text(HINGES.replace('<origin xyz="0 0 0.1"/>\n      ' + LINK2_MASS,
                                   '<origin xyz="0 0 100"/>\n      ' + LINK2_MASS),
                    encoding="utf-8")  # fmt: skip
    error = _error(path)
    assert error.field == LINK2 and "puts the centre of mass 100 m" in error.reason


def test_a_file_s_way_of_saying_no_limit_loads(tmp_path):
    """Limits of ±1e16 (example-robot-data's rotors) mean none, not degrees: they load."""
    path = tmp_path / "arm.urdf"
    path.write_text(HINGES.replace('lower="-1" upper="1"', 'lower="-1e16" upper="1e16"'),
                    encoding="utf-8")  # fmt: skip
    assert lt.robots.from_urdf(path).q_max[0] == 1e16


@pytest.mark.parametrize(
    ("keyword", "values"),
    [
        pytest.param("gear_ratios", [100.0] * 5, id="gear_ratios-short"),
        pytest.param("gear_ratios", [100.0] * 7, id="gear_ratios-long"),
        pytest.param("rotor_inertias", [1e-6] * 5, id="rotor_inertias-short"),
    ],
)
def test_per_joint_overrides_of_wrong_length_fail(robots_dir, keyword, values):
    """gear_ratios or rotor_inertias with a length other than the chain's fail naming them."""
    error = _error(robots_dir / UR5, tip="tool0", **{keyword: values})
    assert error.field == keyword
    assert "expected 6 values" in error.reason


def _link_masses(path: Path) -> dict[str, float]:
    """Each link's mass as the URDF writes it [kg]."""
    from xml.etree import ElementTree

    masses = {}
    for link in ElementTree.parse(path).getroot().iter("link"):
        mass = link.find("inertial/mass")
        masses[str(link.get("name"))] = 0.0 if mass is None else float(mass.get("value"))
    return masses


def test_a_hand_bolted_beyond_the_flange_is_not_part_of_the_arm(robots_dir):
    """A hand bolted beyond the flange is a tool: ``tip="panda_link8"`` leaves it out.

    ``tip="panda_hand"`` carries it (and its fingers) as part of the last link.

    Before, both tips gave the hand's arm (link 7 at 1.50 kg), and a Panda without the
    hand read a payload of −0.76 kg on the Gaz et al. run.
    """
    path = robots_dir / PANDA
    written = _link_masses(path)
    to_flange = lt.robots.from_urdf(path, tip="panda_link8")
    with_hand = lt.robots.from_urdf(path, tip="panda_hand")
    carried = sum(joint.link.mass for joint in with_hand.joints)
    bare = sum(joint.link.mass for joint in to_flange.joints)
    hand = written["panda_hand"] + written["panda_leftfinger"] + written["panda_rightfinger"]
    assert carried - bare == pytest.approx(hand, abs=1e-9)
    beyond = ("panda_link0", "panda_hand", "panda_leftfinger", "panda_rightfinger")  # base, hand
    arm = sum(mass for name, mass in written.items() if name not in beyond)
    assert bare == pytest.approx(arm, abs=1e-9)
    q = to_flange.home()
    flange = lt.Dynamics(to_flange).pose(q)[:3, 3]
    np.testing.assert_allclose(flange, lt.Dynamics(with_hand).pose(q)[:3, 3], atol=1e-12)
