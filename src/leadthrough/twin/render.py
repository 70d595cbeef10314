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
    distance: float | None = None,
    azimuth: float = 150.0,
    elevation: float = -20.0,
    lookat: tuple[float, float, float] | None = None,
) -> np.ndarray:
    """An RGB image (height, width, 3) of the arm in its current state.

    Without ``lookat`` and ``distance`` [m] the camera frames the arm's geometry in its
    current pose (:func:`_scene_box`): any arm, whatever its reach.
    """
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
    camera.azimuth, camera.elevation = azimuth, elevation
    centre, radius = _scene_box(model, data)
    fovy = np.radians(model.vis.global_.fovy)
    camera.lookat[:] = centre if lookat is None else lookat
    camera.distance = FRAME_MARGIN * radius / np.sin(fovy / 2) if distance is None else distance
    try:
        renderer.update_scene(data, camera)
        return renderer.render().copy()
    finally:
        renderer.close()


#: Distance of the camera over the one at which the arm's bounding box half-side fills
#: half the view (the box's corners may need more: a little margin).
FRAME_MARGIN = 1.25


def _scene_box(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[np.ndarray, float]:
    """Centre [m] and half the largest side [m] of a box around the arm's geoms.

    The arm: every geom on a moving body, and the world's geoms no larger than the
    largest of those (the base marker; not a table or a floor).
    """
    moving = model.geom_bodyid > 0
    if not np.any(moving):
        return np.zeros(3), 1.0
    small = model.geom_rbound <= model.geom_rbound[moving].max()
    arm = moving | (small & (model.geom_type != 0))  # type 0: a plane, infinite
    reach = model.geom_rbound[arm][:, None]
    points = data.geom_xpos[arm]
    low, high = (points - reach).min(axis=0), (points + reach).max(axis=0)
    return 0.5 * (low + high), max(0.5 * float(np.max(high - low)), 0.05)


def save_png(image: np.ndarray, path: str | Path) -> Path:
    """Write an RGB image to ``path`` as PNG (via matplotlib, imported lazily)."""
    import matplotlib.image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    matplotlib.image.imsave(path, image)
    return path
