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
def realistic_friction():
    """Friction identified on the realistic twin (masses ±5 %), position dependence dropped.

    What a user does on a real robot: identify, then run the observer with the result;
    the twin's cable effect stays unmodelled.
    """
    import leadthrough as lt
    from leadthrough.friction_study import run_friction_study
    from leadthrough.observer_experiments import REALISTIC_TWIN, identified_without_position

    study = run_friction_study(lt.robots.yumi(), twin_config=REALISTIC_TWIN)
    return identified_without_position(study.model)
