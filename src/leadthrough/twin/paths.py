"""Reference paths that the simulated operator follows.

Every path starts and stops at rest with minimum-jerk timing (Flash & Hogan 1985: the
phase ``s(τ) = 10τ³ − 15τ⁴ + 6τ⁵`` of ``τ = t / duration``), the smooth, bell-shaped
speed profile of human point-to-point reaching. Before ``t = 0`` a path holds its start
and after ``duration`` its end point, with zero velocity. Positions are in the world
frame [m], velocities [m/s]. Times may be a float or an array of shape ``(N,)``; a
Cartesian path then returns shape ``(3,)`` or ``(N, 3)``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.trajectories import minimum_jerk_phase
from leadthrough.twin import _checks as check
from leadthrough.twin.errors import OperatorError

FloatArray = NDArray[np.float64]


def _set(instance: object, name: str, value: object) -> None:
    """Replace a field of a frozen dataclass with its validated value."""
    object.__setattr__(instance, name, value)


def _duration(value: object) -> float:
    """Validate a ``duration`` [s]: a finite number > 0."""
    return check.real("duration", value, minimum=0.0, strict=True)


class Path(ABC):
    """A Cartesian reference path of duration ``duration`` [s], clamped outside it."""

    duration: float

    @abstractmethod
    def position(self, t: ArrayLike) -> FloatArray:
        """Reference position [m, world] at time(s) ``t`` [s]: shape ``(3,)`` or ``(N, 3)``."""

    @abstractmethod
    def velocity(self, t: ArrayLike) -> FloatArray:
        """Reference velocity [m/s, world] at time(s) ``t`` [s]: shape ``(3,)`` or ``(N, 3)``."""

    def reference(self, t: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """:meth:`position` and :meth:`velocity` at ``t`` [s] (paths share their timing law)."""
        return self.position(t), self.velocity(t)


class _PointToPoint(Path):
    """Minimum-jerk motion along the segment between two points named by ``_ENDPOINTS``."""

    _ENDPOINTS: ClassVar[tuple[str, str]]

    def __post_init__(self) -> None:
        for name in self._ENDPOINTS:
            _set(self, name, check.vector(name, getattr(self, name)))
        _set(self, "duration", _duration(self.duration))

    @cached_property
    def _segment(self) -> tuple[FloatArray, FloatArray]:
        """Start point [m] and displacement to the end point [m]."""
        first, last = (getattr(self, name) for name in self._ENDPOINTS)
        return first, last - first

    def reference(self, t: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """:meth:`position` and :meth:`velocity` at ``t`` [s], one timing evaluation."""
        start, displacement = self._segment
        phase, rate = minimum_jerk_phase(t, self.duration)
        return start + phase[..., None] * displacement, rate[..., None] * displacement

    def position(self, t: ArrayLike) -> FloatArray:
        """Reference position [m, world] at time(s) ``t`` [s]: shape ``(3,)`` or ``(N, 3)``."""
        start, displacement = self._segment
        phase, _ = minimum_jerk_phase(t, self.duration)
        return start + phase[..., None] * displacement

    def velocity(self, t: ArrayLike) -> FloatArray:
        """Reference velocity [m/s, world] at time(s) ``t`` [s]: shape ``(3,)`` or ``(N, 3)``."""
        _, displacement = self._segment
        _, rate = minimum_jerk_phase(t, self.duration)
        return rate[..., None] * displacement


@dataclass(frozen=True, eq=False)
class MinimumJerk(_PointToPoint):
    """Point-to-point minimum-jerk reach from ``start`` to ``goal``.

    The peak speed, at ``duration / 2``, is ``1.875 · |goal − start| / duration``.

    Attributes:
        start: Start point [m, world].
        goal: End point [m, world].
        duration: Duration of the reach [s], > 0.
    """

    _ENDPOINTS: ClassVar[tuple[str, str]] = ("start", "goal")

    start: FloatArray
    goal: FloatArray
    duration: float


@dataclass(frozen=True, eq=False)
class Line(_PointToPoint):
    """Straight line from ``start`` to ``end`` with minimum-jerk timing (rest to rest).

    Attributes:
        start: Start point [m, world].
        end: End point [m, world].
        duration: Duration of the motion [s], > 0.
    """

    _ENDPOINTS: ClassVar[tuple[str, str]] = ("start", "end")

    start: FloatArray
    end: FloatArray
    duration: float


@dataclass(frozen=True, eq=False)
class Circle(Path):
    """Circle in the plane of unit ``normal``, swept with minimum-jerk timing of the angle.

    The path starts at ``center + radius · start_direction`` and turns by ``2π · turns``
    about ``normal`` (right-hand rule; a negative ``turns`` turns the other way).

    Attributes:
        center: Center of the circle [m, world].
        radius: Radius [m], > 0.
        normal: Normal of the plane [-, world]; stored normalised.
        start_direction: Direction from the center to the start point [-, world]; stored
            made orthogonal to ``normal`` and normalised.
        duration: Duration of the motion [s], > 0.
        turns: Number of turns [-].
    """

    center: FloatArray
    radius: float
    normal: FloatArray
    start_direction: FloatArray
    duration: float
    turns: float = 1.0

    def __post_init__(self) -> None:
        _set(self, "center", check.vector("center", self.center))
        _set(self, "radius", check.real("radius", self.radius, minimum=0.0, strict=True))
        normal = _unit("normal", check.vector("normal", self.normal))
        direction = check.vector("start_direction", self.start_direction)
        in_plane = direction - (direction @ normal) * normal
        if np.linalg.norm(in_plane) <= 1e-9 * max(np.linalg.norm(direction), 1e-300):
            raise OperatorError("start_direction", "must not be parallel to normal")
        _set(self, "normal", normal)
        _set(self, "start_direction", _unit("start_direction", in_plane))
        _set(self, "duration", _duration(self.duration))
        _set(self, "turns", check.real("turns", self.turns))

    def _frame(self) -> tuple[FloatArray, FloatArray]:
        """In-plane unit axes: ``start_direction`` and ``normal × start_direction``."""
        return self.start_direction, np.cross(self.normal, self.start_direction)

    def _angle(self, t: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Swept angle [rad] and its rate [rad/s] at time(s) ``t`` [s]."""
        phase, rate = minimum_jerk_phase(t, self.duration)
        sweep = 2.0 * np.pi * self.turns
        return sweep * phase[..., None], sweep * rate[..., None]

    def position(self, t: ArrayLike) -> FloatArray:
        """Reference position [m, world] at time(s) ``t`` [s]: shape ``(3,)`` or ``(N, 3)``."""
        u, w = self._frame()
        angle, _ = self._angle(t)
        return self.center + self.radius * (np.cos(angle) * u + np.sin(angle) * w)

    def velocity(self, t: ArrayLike) -> FloatArray:
        """Reference velocity [m/s, world] at time(s) ``t`` [s]: shape ``(3,)`` or ``(N, 3)``."""
        u, w = self._frame()
        angle, rate = self._angle(t)
        return self.radius * rate * (-np.sin(angle) * u + np.cos(angle) * w)

    def reference(self, t: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """:meth:`position` and :meth:`velocity` at ``t`` [s], one timing evaluation."""
        u, w = self._frame()
        angle, rate = self._angle(t)
        cos, sin = np.cos(angle), np.sin(angle)
        return (self.center + self.radius * (cos * u + sin * w),
                self.radius * rate * (-sin * u + cos * w))  # fmt: skip


def _unit(name: str, vector: FloatArray) -> FloatArray:
    """Return ``vector`` normalised (read-only); raise if it is zero."""
    norm = float(np.linalg.norm(vector))
    if norm == 0.0:
        raise OperatorError(name, "must be non-zero")
    unit = vector / norm
    unit.setflags(write=False)
    return unit


@dataclass(frozen=True, eq=False)
class JointMinimumJerk:
    """Minimum-jerk reference of one joint, from ``start`` to ``goal``.

    Attributes:
        start: Start angle [rad].
        goal: End angle [rad].
        duration: Duration of the motion [s], > 0.
    """

    start: float
    goal: float
    duration: float

    def __post_init__(self) -> None:
        _set(self, "start", check.real("start", self.start))
        _set(self, "goal", check.real("goal", self.goal))
        _set(self, "duration", _duration(self.duration))

    def position(self, t: ArrayLike) -> float | FloatArray:
        """Reference angle [rad] at time(s) ``t`` [s]: a float, or an array like ``t``."""
        phase, _ = minimum_jerk_phase(t, self.duration)
        return _scalar_if_0d(self.start + phase * (self.goal - self.start))

    def velocity(self, t: ArrayLike) -> float | FloatArray:
        """Reference rate [rad/s] at time(s) ``t`` [s]: a float, or an array like ``t``."""
        _, rate = minimum_jerk_phase(t, self.duration)
        return _scalar_if_0d(rate * (self.goal - self.start))


def _scalar_if_0d(value: FloatArray) -> float | FloatArray:
    """A Python float for a 0-d array, the array otherwise."""
    return float(value) if np.ndim(value) == 0 else value
