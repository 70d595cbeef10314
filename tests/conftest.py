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
