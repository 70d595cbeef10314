"""Offscreen pictures of the twin with MuJoCo's renderer (PNG).

Rendering needs an OpenGL context without a screen: EGL (``MUJOCO_GL=egl``, the
default here) or OSMesa. Where neither works a :class:`RenderError` says what to
install. MuJoCo reads ``MUJOCO_GL`` once, when it is first imported: a program that
renders calls :func:`prefer_offscreen_gl` before it builds a twin (the command line
does).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from leadthrough.errors import LeadthroughError

if TYPE_CHECKING:
    import mujoco


class RenderError(LeadthroughError, RuntimeError):
    """No offscreen OpenGL context is available."""


def prefer_offscreen_gl() -> None:
    """Ask MuJoCo for offscreen EGL, unless the user chose a backend (``MUJOCO_GL`` set).

    Effective only before MuJoCo's first import in the process.
    """
    os.environ.setdefault("MUJOCO_GL", "egl")


def render_arm(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    width: int = 640,
    height: int = 480,
    distance: float = 1.4,
    azimuth: float = 150.0,
    elevation: float = -20.0,
    lookat: tuple[float, float, float] = (0.2, 0.1, 0.1),
) -> np.ndarray:
    """An RGB image (height, width, 3) of the arm in its current state."""
    prefer_offscreen_gl()
    import mujoco

    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    except Exception as error:  # MuJoCo raises several types when GL is missing
        backend = os.environ.get("MUJOCO_GL", "")
        raise RenderError(
            f"no offscreen OpenGL ({backend or 'default'} backend: {error}); install EGL "
            "(Debian: apt-get install libegl1 libgl1-mesa-dri) or set MUJOCO_GL=osmesa "
            "before MuJoCo is imported"
        ) from None
    camera = mujoco.MjvCamera()
    camera.distance, camera.azimuth, camera.elevation = distance, azimuth, elevation
    camera.lookat[:] = lookat
    try:
        renderer.update_scene(data, camera)
        return renderer.render().copy()
    finally:
        renderer.close()


def save_png(image: np.ndarray, path: str | Path) -> Path:
    """Write an RGB image to ``path`` as PNG (via matplotlib, imported lazily)."""
    import matplotlib.image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    matplotlib.image.imsave(path, image)
    return path
