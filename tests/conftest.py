import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before MuJoCo is first imported

import sysconfig
from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def robots_dir() -> Path:
    """Directory of the URDFs shipped by the example-robot-data package (a dev dependency)."""
    path = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share/example-robot-data/robots"
    assert path.is_dir(), f"example-robot-data is not installed: {path} is missing"
    return path


@pytest.fixture(scope="session")
def identified_friction():
    """Friction identified on the realistic twin (masses ±5 %), as a user does first."""
    import leadthrough as lt
    from leadthrough.experiments.friction_study import run_friction_study
    from leadthrough.twin.presets import REALISTIC_TWIN

    return run_friction_study(lt.robots.yumi(), twin_config=REALISTIC_TWIN).model


@pytest.fixture(scope="session")
def realistic_friction(identified_friction):
    """The identified friction without its position dependence (cable effect unmodelled)."""
    from leadthrough.experiments.observer import identified_without_position

    return identified_without_position(identified_friction)


@pytest.fixture(scope="session")
def ur10e():
    """The nominal UR10e (its assumed-drive-data warning silenced)."""
    import warnings

    import leadthrough as lt

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return lt.robots.ur10e()
