"""Checks of the simulated operator: OperatorError for parameters, InputShapeError for shapes."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough import validation
from leadthrough.errors import InputShapeError
from leadthrough.twin.errors import OperatorError

FloatArray = NDArray[np.float64]


def real(name: str, value: object, *, minimum: float | None = None, strict: bool = False) -> float:
    """Return ``value`` as a finite float, optionally bounded below (``strict``: ``>``)."""
    return validation.real(name, value, minimum=minimum, strict=strict, error=OperatorError)


def vector(name: str, value: ArrayLike, size: int = 3) -> FloatArray:
    """Return ``value`` as a read-only finite float array of shape ``(size,)``."""
    return validation.real_array(name, value, (size,), error=OperatorError)


def index(name: str, value: object) -> int:
    """Return ``value`` as a non-negative integer index."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise OperatorError(name, f"expected a non-negative integer, got {value!r}")
    if value < 0:
        raise OperatorError(name, f"must be >= 0, got {value}")
    return int(value)


def array(name: str, value: ArrayLike, shape: tuple[int, ...]) -> FloatArray:
    """``value`` as a float array of ``shape``; raise :class:`InputShapeError` otherwise."""
    result = np.asarray(value, dtype=float)
    if result.shape != shape:
        raise InputShapeError(name, shape, result.shape)
    return result


def joint_state(q: ArrayLike, qd: ArrayLike, joint: int) -> tuple[FloatArray, FloatArray]:
    """Joint positions and velocities as (n,) arrays; raise if ``joint`` is not in them."""
    q = np.asarray(q, dtype=float)
    if q.ndim != 1:
        raise InputShapeError("q", (-1,), q.shape)
    qd = array("qd", qd, q.shape)
    if joint >= q.shape[0]:
        raise OperatorError("joint", f"index {joint} out of range for {q.shape[0]} joints")
    return q, qd


def path_like(name: str, value: object) -> None:
    """Raise unless ``value`` has the methods ``position(t)`` and ``velocity(t)``."""
    if not all(callable(getattr(value, method, None)) for method in ("position", "velocity")):
        raise OperatorError(name, f"needs position(t) and velocity(t), got {type(value).__name__}")


def after(t0: float, t1: float) -> None:
    """Raise unless ``t1 > t0`` (both finite)."""
    if real("t1", t1) <= real("t0", t0):
        raise OperatorError("t1", f"must be > t0 = {t0:g}, got {t1:g}")
