"""Exceptions of leadthrough: one root, subclasses that carry their diagnostics."""

from __future__ import annotations


class LeadthroughError(Exception):
    """Root of every error raised by leadthrough."""


class RobotDescriptionError(LeadthroughError, ValueError):
    """A robot description (TOML file, URDF or dataclass) is malformed.

    Attributes:
        source: File or object the description came from.
        field: Dotted path of the offending field, e.g. ``joints[3].link.mass``.
        reason: What is wrong with it.
    """

    def __init__(self, source: str, field: str, reason: str) -> None:
        self.source = source
        self.field = field
        self.reason = reason
        where = f"{source}: {field}" if field else source
        super().__init__(f"{where}: {reason}")


class InputShapeError(LeadthroughError, ValueError):
    """An array passed to a model function has the wrong shape."""

    def __init__(self, name: str, expected: tuple[int, ...], got: tuple[int, ...]) -> None:
        self.name = name
        self.expected = expected
        self.got = got
        super().__init__(f"{name}: expected shape {expected}, got {got}")


class InputValueError(LeadthroughError, ValueError):
    """An array passed to an estimator is missing or not finite (NaN, Inf).

    Attributes:
        name: The argument.
        reason: What is wrong with it.
    """

    def __init__(self, name: str, reason: str) -> None:
        self.name = name
        self.reason = reason
        super().__init__(f"{name}: {reason}")


class ParameterError(LeadthroughError, ValueError):
    """A parameter of a component (simulator, operator, controller) is invalid.

    Attributes:
        parameter: Name of the offending parameter, with the joint index when it is per
            joint, e.g. ``static[3]``.
        reason: What is wrong with it.
    """

    def __init__(self, parameter: str, reason: str) -> None:
        self.parameter = parameter
        self.reason = reason
        super().__init__(f"{parameter}: {reason}")


class RecordingError(LeadthroughError):
    """A session recording cannot be written or read.

    Attributes:
        path: The recording file.
        reason: What went wrong.
    """

    def __init__(self, path: str, reason: str) -> None:
        self.path = path
        self.reason = reason
        super().__init__(f"{path}: {reason}")


class ReplayError(LeadthroughError, ValueError):
    """A taught path cannot be replayed: a malformed recording, or it breaks a limit.

    Attributes:
        reason: One line saying what is wrong (joint, time, value and limit when it is a
            limit).
        joint: The offending joint, numbered from 1 at the base, or None.
        suggested_time_scale: A ``time_scale`` that passes the speed and torque checks,
            when slowing down helps, else None.
    """

    def __init__(
        self, reason: str, joint: int | None = None, suggested_time_scale: float | None = None
    ) -> None:
        self.reason = reason
        self.joint = joint
        self.suggested_time_scale = suggested_time_scale
        super().__init__(reason)


def failure(stage: str, error: BaseException) -> str:
    """One line for a fault: the stage that failed, the exception, where in the package.

    ``"observer failed: IndexError: … (at estimation/observer.py:120 in update)"``: the
    innermost frame of the traceback inside this package names the place.
    """
    import traceback
    from pathlib import Path

    package = Path(__file__).resolve().parent
    inside = [frame for frame in traceback.extract_tb(error.__traceback__)
              if Path(frame.filename).resolve().is_relative_to(package)]  # fmt: skip
    where = ""
    if inside:
        frame = inside[-1]
        module = Path(frame.filename).resolve().relative_to(package).as_posix()
        where = f" (at {module}:{frame.lineno} in {frame.name})"
    return f"{stage} failed: {type(error).__name__}: {error}{where}"
