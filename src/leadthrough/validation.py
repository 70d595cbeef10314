"""Checks shared by the description dataclasses: each raises a RobotDescriptionError.

The dataclasses validate their own fields and name them relative to themselves
(``mass``); :func:`within` prefixes the path of the enclosing field
(``joints[3].link.mass``) and the loaders add the file name, so that a user reads
one line that names the file and the field.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.errors import RobotDescriptionError

#: A float64 array: the type of every numeric result of leadthrough.
FloatArray = NDArray[np.float64]


@contextmanager
def within(prefix: str, source: str | None = None) -> Iterator[None]:
    """Prefix the field path (and optionally set the source) of errors raised inside."""
    try:
        yield
    except RobotDescriptionError as error:
        field = f"{prefix}.{error.field}" if prefix and error.field else prefix or error.field
        raise RobotDescriptionError(source or error.source, field, error.reason) from None


def fail(field: str, reason: str) -> RobotDescriptionError:
    """Make the error for ``field`` of a description whose source is not known yet."""
    return RobotDescriptionError("robot description", field, reason)


def short(value: object, limit: int = 60) -> str:
    """One-line, length-limited text of a value for an error message."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    text = " ".join(repr(value).split())
    return text if len(text) <= limit else text[: limit - 1] + "…"


#: Makes the exception for (field, reason); each component passes its own error class.
ErrorFactory = Callable[[str, str], Exception]


def real_array(
    field: str, value: ArrayLike, shape: tuple[int, ...], error: ErrorFactory = fail
) -> NDArray[np.float64]:
    """Return ``value`` as a read-only finite float array of ``shape``."""
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise error(field, f"expected numbers of shape {shape}, got {short(value)}") from None
    if array.shape != shape:
        raise error(field, f"expected shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise error(field, f"must be finite, got {short(value)}")
    array.setflags(write=False)
    return array


def real(
    field: str,
    value: object,
    *,
    minimum: float | None = None,
    strict: bool = False,
    error: ErrorFactory = fail,
) -> float:
    """Return ``value`` as a finite float, optionally bounded below (``strict``: ``>``)."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise error(field, f"expected a number, got {short(value)}")
    number = float(value)
    if not np.isfinite(number):
        raise error(field, f"must be finite, got {number}")
    if minimum is not None and (number <= minimum if strict else number < minimum):
        relation = ">" if strict else ">="
        raise error(field, f"must be {relation} {minimum:g}, got {number:g}")
    return number


#: The smallest eigenvalue an inertia may have, relative to its largest [–]: inertias
#: written with 6–8 significant digits (URDF files) carry rounding of that order, and an
#: identified link of the UR10e's published model has −1.1e-8 against 1.04.
INERTIA_ROUNDING = 1e-6


def symmetric_positive_definite(field: str, matrix: NDArray[np.float64]) -> None:
    """Raise unless ``matrix`` is symmetric (to 1e-12 relative) and positive definite.

    Positive definite to the rounding of its digits: an eigenvalue down to
    −:data:`INERTIA_ROUNDING` times the largest passes (a thin rod's is 0 in exact
    arithmetic).
    """
    scale = max(float(np.max(np.abs(matrix))), 1e-300)
    if np.max(np.abs(matrix - matrix.T)) > 1e-12 * scale:
        raise fail(field, "inertia must be symmetric")
    eigenvalues = np.linalg.eigvalsh(matrix)
    if eigenvalues[0] < -INERTIA_ROUNDING * max(eigenvalues[-1], 0.0) or eigenvalues[-1] <= 0.0:
        raise fail(field, "inertia must be positive definite")


def rotation_matrix(field: str, value: ArrayLike) -> NDArray[np.float64]:
    """Return ``value`` as a proper rotation matrix (orthonormal, det +1, to 1e-6)."""
    matrix = real_array(field, value, (3, 3))
    if np.max(np.abs(matrix @ matrix.T - np.eye(3))) > 1e-6 or np.linalg.det(matrix) < 0.0:
        raise fail(field, "must be a rotation matrix (orthonormal, determinant +1)")
    return matrix
