import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import tomli_w

import leadthrough as lt
from rotations import rot_x, rot_y, rot_z

Edit = Callable[[dict[str, Any]], None]


@pytest.fixture(scope="module")
def yumi() -> lt.RobotDescription:
    """The shipped YuMi left arm."""
    return lt.robots.yumi()


@pytest.fixture
def yumi_data() -> dict[str, Any]:
    """A fresh, editable copy of the shipped YuMi in the TOML layout."""
    return lt.robots.robot_to_dict(lt.robots.yumi())


# --- the shipped YuMi carries the thesis numbers -------------------------------------------

THESIS_VECTORS = [
    pytest.param("masses", [1.58, 1.22, 1.01, 0.485, 0.19, 0.359, 0.25], id="masses"),
    pytest.param("gear_ratios", [100, 100, 100, -100, 100, -101, 100], id="gear_ratios"),
    pytest.param(
        "rotor_inertias",
        np.array([8.2, 8.2, 1.97, 0.51, 0.51, 0.51, 1.97]) * 1e-6,
        id="rotor_inertias",
    ),
    pytest.param("torque_limits", [30, 30, 30, 20, 20, 10, 10], id="torque_limits"),
    pytest.param(
        "q_min", np.deg2rad([-168.5, -143.5, -168.5, -123.5, -290, -88, -229]), id="q_min"
    ),
    pytest.param("q_max", np.deg2rad([168.5, 43.5, 168.5, 80, 290, 138, 229]), id="q_max"),
    pytest.param("velocity_limits", np.deg2rad([180] * 4 + [400] * 3), id="velocity_limits"),
]


@pytest.mark.parametrize(("attribute", "expected"), THESIS_VECTORS)
def test_yumi_vector_matches_thesis(yumi, attribute, expected):
    """Each per-joint vector of the shipped YuMi equals the thesis / ABB value."""
    np.testing.assert_allclose(getattr(yumi, attribute), expected, rtol=1e-12, atol=0)


THESIS_FRICTION = [
    pytest.param("coulomb", [1.5, 1.4, 0.85, 0.7, 0.25, 0.4, 0.24], id="coulomb"),
    pytest.param("viscous", [1.1, 0.9, 0.7, 0.7, 0.05, 0.1, 0.03], id="viscous"),
    pytest.param("half_width", [2e-3, 2e-3, 2e-3, 2e-3, 3e-3, 2e-3, 2e-3], id="half_width"),
    pytest.param("slope", [5e3] * 7, id="slope"),
]


@pytest.mark.parametrize(("attribute", "expected"), THESIS_FRICTION)
def test_yumi_friction_matches_table_4_1(yumi, attribute, expected):
    """Each friction parameter of the shipped YuMi equals Table 4.1."""
    actual = [getattr(joint.friction, attribute) for joint in yumi.joints]
    np.testing.assert_allclose(actual, expected, rtol=1e-12, atol=0)


def test_yumi_tool_is_link_7(yumi):
    """Link 7 of the shipped YuMi is the 0.25 kg tool with its centre of mass at [0, 0, 0.04]."""
    tool = yumi.joints[6].link
    assert tool.mass == 0.25
    np.testing.assert_array_equal(tool.com, [0.0, 0.0, 0.04])


def test_yumi_dh_offsets(yumi):
    """The DH offsets of the shipped YuMi are [-pi -pi 0 -pi/2 pi pi 0]."""
    assert yumi.uses_dh
    offsets = [joint.dh.offset for joint in yumi.joints]
    pi = np.pi
    np.testing.assert_allclose(offsets, [-pi, -pi, 0, -pi / 2, pi, pi, 0], rtol=1e-15, atol=0)


def test_yumi_base_rotation(yumi):
    """The YuMi base rotation is rotx(-0.6322) roty(0.9424) rotz(-0.1793) at the origin."""
    expected = rot_x(-0.6322) @ rot_y(0.9424) @ rot_z(-0.1793)
    np.testing.assert_allclose(yumi.base.rotation, expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(yumi.base.translation, np.zeros(3))


# --- save / load round trip ------------------------------------------------------------------


def _assert_identical(a: object, b: object, where: str = "robot") -> None:
    """Assert that two descriptions agree exactly, field by field, recursively."""
    assert type(a) is type(b), where
    if dataclasses.is_dataclass(a):
        for field in dataclasses.fields(a):
            name = field.name
            _assert_identical(getattr(a, name), getattr(b, name), f"{where}.{name}")
    elif isinstance(a, tuple):
        assert len(a) == len(b), where
        for index, (x, y) in enumerate(zip(a, b, strict=True)):
            _assert_identical(x, y, f"{where}[{index}]")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype, where
        np.testing.assert_array_equal(a, b, err_msg=where, strict=True)
    else:
        assert a == b, where


ROUND_TRIP_ROBOTS = {
    "yumi": lambda robots_dir: lt.robots.yumi(),
    "panda": lambda robots_dir: lt.robots.from_urdf(
        robots_dir / "panda_description/urdf/panda.urdf", tip="panda_hand"
    ),
    "ur5": lambda robots_dir: lt.robots.from_urdf(
        robots_dir / "ur_description/urdf/ur5_robot.urdf", tip="tool0"
    ),
    "ur5-geared": lambda robots_dir: lt.robots.from_urdf(
        robots_dir / "ur_description/urdf/ur5_robot.urdf",
        tip="tool0",
        gear_ratios=[101, -100, 80, 50.5, -50, 50],
        rotor_inertias=[1e-5, 1e-5, 5e-6, 1e-6, 1e-6, 1.5e-6],
    ),
}


@pytest.mark.parametrize("name", list(ROUND_TRIP_ROBOTS))
def test_save_load_round_trip_is_exact(name, robots_dir, tmp_path):
    """save_robot then load_robot gives back identical values in every field."""
    robot = ROUND_TRIP_ROBOTS[name](robots_dir)
    path = tmp_path / f"{name}.toml"
    lt.robots.save_robot(robot, path)
    loaded = lt.robots.load_robot(path)
    _assert_identical(robot, loaded)
    again = tmp_path / f"{name}_again.toml"
    lt.robots.save_robot(loaded, again)
    assert again.read_text(encoding="utf-8") == path.read_text(encoding="utf-8")


# --- malformed files -------------------------------------------------------------------------


def _walk(data: Any, path: tuple[str | int, ...]) -> Any:
    """The container at ``path`` inside the TOML layout."""
    for key in path:
        data = data[key]
    return data


def set_(*path: str | int, value: Any) -> Edit:
    """An edit that sets the entry at ``path`` to ``value``."""

    def edit(data: dict[str, Any]) -> None:
        _walk(data, path[:-1])[path[-1]] = value

    return edit


def delete(*path: str | int) -> Edit:
    """An edit that removes the entry at ``path``."""

    def edit(data: dict[str, Any]) -> None:
        del _walk(data, path[:-1])[path[-1]]

    return edit


def dh_to_origin(index: int, axis: list[float]) -> Edit:
    """An edit that places joint ``index`` by an origin with ``axis`` instead of its DH row."""

    def edit(data: dict[str, Any]) -> None:
        joint = data["joints"][index]
        del joint["dh"]
        joint["origin"] = {"xyz": [0.0, 0.0, 0.1], "rpy": [0.0, 0.0, 0.0], "axis": axis}

    return edit


NAN = float("nan")
INDEFINITE = [[1e-3, 2e-3, 0.0], [2e-3, 1e-3, 0.0], [0.0, 0.0, 1e-3]]

BAD_FIELDS = [
    pytest.param(
        delete("joints", 3, "link", "mass"), "joints[3].link", "missing key 'mass'", id="missing"
    ),
    pytest.param(
        delete("joints", 5, "friction", "half_width"),
        "joints[5].friction",
        "missing key 'half_width'",
        id="missing-friction",
    ),
    pytest.param(
        set_("joints", 2, "friction", "damping", value=0.1),
        "joints[2].friction",
        "unknown key 'damping'",
        id="unknown",
    ),
    pytest.param(
        set_("base", "rpy_deg", value=[0.0, 0.0, 0.0]),
        "base",
        "unknown key 'rpy_deg'",
        id="unknown-in-base",
    ),
    pytest.param(
        set_("joints", 1, "link", "com", value=[0.0, 0.1]),
        "joints[1].link.com",
        "expected shape (3,), got (2,)",
        id="com-of-2",
    ),
    pytest.param(
        set_("joints", 0, "position_limits", value=[-1.0, 0.0, 1.0]),
        "joints[0].position_limits",
        "expected shape (2,), got (3,)",
        id="position-limits-of-3",
    ),
    pytest.param(
        set_("joints", 4, "link", "mass", value=NAN),
        "joints[4].link.mass",
        "must be finite",
        id="nan-mass",
    ),
    pytest.param(
        set_("joints", 2, "link", "com", 1, value=NAN),
        "joints[2].link.com",
        "must be finite",
        id="nan-com",
    ),
    pytest.param(
        set_("joints", 6, "dh", "d", value=NAN), "joints[6].dh.d", "must be finite", id="nan-dh"
    ),
    pytest.param(
        set_("joints", 3, "link", "mass", value=0.0),
        "joints[3].link.mass",
        "must be > 0",
        id="zero-mass",
    ),
    pytest.param(
        set_("joints", 3, "link", "mass", value=-0.485),
        "joints[3].link.mass",
        "must be > 0",
        id="negative-mass",
    ),
    pytest.param(
        set_("joints", 0, "link", "inertia", 0, 1, value=0.0017),
        "joints[0].link.inertia",
        "must be symmetric",
        id="inertia-not-symmetric",
    ),
    pytest.param(
        set_("joints", 0, "link", "inertia", value=INDEFINITE),
        "joints[0].link.inertia",
        "must be positive definite",
        id="inertia-indefinite",
    ),
    pytest.param(
        set_("joints", 2, "link", "inertia", 2, 2, value=-0.0016),
        "joints[2].link.inertia",
        "must be positive definite",
        id="inertia-negative-diagonal",
    ),
    pytest.param(
        set_("joints", 1, "position_limits", value=[0.75, -2.5]),
        "joints[1].position_limits",
        "must be below max",
        id="min-above-max",
    ),
    pytest.param(
        set_("joints", 5, "gear_ratio", value=0.0),
        "joints[5].gear_ratio",
        "must be non-zero",
        id="zero-gear-ratio",
    ),
    pytest.param(
        set_("joints", 2, "friction", "viscous", value=-0.7),
        "joints[2].friction.viscous",
        "must be >= 0",
        id="negative-viscous",
    ),
    pytest.param(
        dh_to_origin(0, [0.0, 0.0, 2.0]),
        "joints[0].origin.axis",
        "must be a unit vector",
        id="non-unit-axis",
    ),
    pytest.param(
        set_("base", "rpy", value=[0.0, 0.0, 0.0]),
        "base.rotation",
        "not both",
        id="rpy-and-rotation",
    ),
    pytest.param(set_("joints", value=[]), "joints", "non-empty", id="no-joints"),
    pytest.param(
        set_("joints", 4, "name", value="joint_2"), "joints", "must be unique", id="duplicate-name"
    ),
    pytest.param(dh_to_origin(3, [0.0, 0.0, 1.0]), "joints", "not a mix", id="dh-and-origin"),
]


@pytest.mark.parametrize(("edit", "field", "reason"), BAD_FIELDS)
def test_bad_field_fails_naming_file_and_field(edit, field, reason, yumi_data, tmp_path):
    """A YuMi file with one bad field fails on one line naming the file and the dotted field."""
    edit(yumi_data)
    path = tmp_path / "bad_yumi.toml"
    path.write_text(tomli_w.dumps(yumi_data), encoding="utf-8")
    with pytest.raises(lt.RobotDescriptionError) as info:
        lt.robots.load_robot(path)
    error = info.value
    message = str(error)
    assert "\n" not in message
    assert path.name in message
    assert message.startswith(f"{path}: {field}: ")
    assert (error.source, error.field) == (str(path), field)
    assert reason in error.reason


def test_unedited_yumi_data_loads(yumi_data, tmp_path):
    """The unedited YuMi layout written by tomli_w loads: the bad-file edits are the only fault."""
    path = tmp_path / "yumi.toml"
    path.write_text(tomli_w.dumps(yumi_data), encoding="utf-8")
    assert lt.robots.load_robot(path).joint_names == tuple(f"joint_{i}" for i in range(1, 8))


def _missing(path: Path) -> None:
    """Leave ``path`` absent."""


def _directory(path: Path) -> None:
    path.mkdir()


def _not_toml(path: Path) -> None:
    path.write_text("this is not = = TOML [at all\n", encoding="utf-8")


def _truncated(path: Path) -> None:
    text = tomli_w.dumps(lt.robots.robot_to_dict(lt.robots.yumi()))
    cut = text.index("rotation = [") + len("rotation = [")
    path.write_text(text[:cut], encoding="utf-8")


@pytest.mark.parametrize(
    ("make", "reason"),
    [
        pytest.param(_missing, "cannot read", id="file-not-found"),
        pytest.param(_directory, "cannot read", id="directory"),
        pytest.param(_not_toml, "not valid TOML", id="not-toml"),
        pytest.param(_truncated, "not valid TOML", id="truncated-toml"),
    ],
)
def test_unreadable_file_fails_naming_file(make, reason, tmp_path):
    """A missing or non-TOML file fails with a one-line RobotDescriptionError naming the file."""
    path = tmp_path / "robot.toml"
    make(path)
    with pytest.raises(lt.RobotDescriptionError) as info:
        lt.robots.load_robot(path)
    message = str(info.value)
    assert "\n" not in message
    assert path.name in message
    assert info.value.source == str(path)
    assert reason in message


def test_binary_file_fails_naming_file(tmp_path):
    """A binary (non-UTF-8) file fails with a RobotDescriptionError naming the file."""
    path = tmp_path / "robot.toml"
    path.write_bytes(b"\xff\xfe\x00\x01 binary")
    with pytest.raises(lt.RobotDescriptionError, match=r"robot\.toml"):
        lt.robots.load_robot(path)
