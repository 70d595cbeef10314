"""One run of joint samples as a robot logged it: the type every log reader returns."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from leadthrough.errors import InputShapeError, ParameterError

FloatArray = NDArray[np.float64]


#: The longest median sample period a robot's log may have [s], 10 Hz (the public UR10e
#: and Panda logs sample at 100 Hz and 1 kHz): a log timed in milliseconds reads 4–10 s.
MAX_PERIOD = 0.1
#: dq/dt over the time column exceeds the logged q̇ (median, where the joints move) by at
#: most this factor [–], either way; on the public UR10e and Panda logs by at most 2.3 % (a
#: time column divided by 60 or 1000: 60 or 1000; a log stretched 2×: half). As the
#: supervisor's ``rate_tolerance`` for live samples.
RATE_TOLERANCE = 1.5
#: Fewest samples (of all joints) logged faster than ``MOVING_SPEED`` for that comparison.
MIN_MOVING = 10
#: A joint moves, for that comparison, where its logged |q̇| exceeds this [rad/s].
MOVING_SPEED = 0.05
#: Samples further apart than this have rows missing between them [s]: the safety
#: supervisor's default ``max_time_gap``; the observer does not run across such a gap.
MAX_GAP = 0.25


def period_problem(period: float) -> str | None:
    """Why a log whose samples are ``period`` s apart (median) is no robot's, else None."""
    if period > MAX_PERIOD:
        return (f"samples {period:.4g} s apart (median): is its time in milliseconds? "
                f"A robot's log samples every {MAX_PERIOD:g} s or faster")  # fmt: skip
    return None


def rate_ratio(t: FloatArray, q: FloatArray, qd: FloatArray) -> float | None:
    """The median of |q̇| / |dq/dt| where the joints move: 1 for a log timed in seconds.

    A median: an angle that wraps moves it by the few samples concerned only. Samples
    whose angle did not change at all are left out: a driver that stalls (the whole
    sample repeated, q̇ held while q stays) is the supervisor's to report, not a clock's.

    Args:
        t: Sample times [s], shape (N,), increasing.
        q: Joint readings [rad], shape (N, n).
        qd: Logged joint velocities [rad/s], shape (N, n).

    Returns:
        None when fewer than :data:`MIN_MOVING` samples move faster than :data:`MOVING_SPEED`.
    """
    if len(t) < 3:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        rate = np.abs(np.gradient(q, t, axis=0))
        moving = (np.abs(qd) > MOVING_SPEED) & np.isfinite(rate) & (rate > 0.0)
        if np.count_nonzero(moving) < MIN_MOVING:
            return None
        return float(np.median(np.abs(qd[moving]) / rate[moving]))


def rate_problem(t: FloatArray, q: FloatArray, qd: FloatArray) -> str | None:
    """Why the time column ``t`` does not run in seconds by the log's q̇, else None.

    A time column divided by 60 or 1000 has a plausible sample period (a fast clock
    passes :func:`period_problem`), but its dq/dt is 60 or 1000 times the logged q̇; one
    stretched (a clock too slow, or the q̇ columns another quantity's) has a dq/dt below
    it: a free-motion log stretched 5× read two contacts, and one whose q̇ column held
    torques identified a joint without friction. Arguments as :func:`rate_ratio`'s.
    """
    ratio = rate_ratio(t, q, qd)
    if ratio is None or 1.0 / RATE_TOLERANCE <= ratio <= RATE_TOLERANCE:
        return None
    fast, factor = ratio < 1.0, max(ratio, 1.0 / ratio)
    return (f"its time column runs {factor:.0f}× too {'fast' if fast else 'slow'} for its q̇ "
            f"(dq/dt against the logged q̇ where the joints move): is it in seconds, and is "
            f"q̇ the joint velocity? A robot's agree within {RATE_TOLERANCE:g}×")  # fmt: skip


@dataclass(frozen=True, eq=False)
class JointLog:
    """A run of N samples of an n-joint arm, in the arm's own time base.

    Attributes:
        t: Sample times [s], shape (N,), strictly increasing (not necessarily uniform,
            not necessarily starting at 0).
        q: Joint readings [rad], shape (N, n).
        qd: Joint velocities [rad/s], shape (N, n), as the robot reported them.
        tau: Measured joint torque, arm side [Nm], shape (N, n): from torque sensors,
            or K·i from motor currents and the robot's torque constants; None when
            neither is known.
        current: Motor currents [A], shape (N, n), for drives that report current.
        extra: Further per-sample columns the file holds (e.g. ``target_current`` [A],
            ``target_torque`` [Nm]), each with N rows.
        source: Where the log came from (a file path, or a description).
        dropped_rows: How many rows of the source were rejected as corrupted.
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    tau: FloatArray | None = None
    current: FloatArray | None = None
    extra: Mapping[str, FloatArray] = field(default_factory=dict)
    source: str = ""
    dropped_rows: int = 0

    def __post_init__(self) -> None:
        where = self.source or "log"
        t = np.asarray(self.t, dtype=float)
        q = np.atleast_2d(np.asarray(self.q, dtype=float))
        if t.ndim != 1:
            raise InputShapeError(f"{where}: t", (q.shape[0],), t.shape)
        if q.shape[0] != t.size:
            raise InputShapeError(f"{where}: q", (t.size, q.shape[1]), q.shape)
        for name in ("qd", "tau", "current"):
            value = getattr(self, name)
            if value is None:
                continue
            value = np.asarray(value, dtype=float)
            if value.shape != q.shape:
                raise InputShapeError(f"{where}: {name}", q.shape, value.shape)
            object.__setattr__(self, name, value)
        for name, value in self.extra.items():
            if len(value) != t.size:
                raise InputShapeError(f"{where}: extra[{name!r}]", (t.size,), np.shape(value))
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "q", q)

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return int(self.q.shape[1])

    @property
    def duration(self) -> float:
        """Time from the first to the last sample [s]."""
        return float(self.t[-1] - self.t[0]) if self.t.size else 0.0

    @property
    def median_period(self) -> float:
        """Median sample period [s] (the log's nominal rate is its inverse)."""
        return float(np.median(np.diff(self.t))) if self.t.size > 1 else float("nan")

    def joint_torque(self, torque_constants: NDArray[np.float64] | None) -> FloatArray | None:
        """Arm-side joint torque [Nm], (N, n): ``tau``, else K·i from the motor currents.

        Args:
            torque_constants: The robot's K per joint [Nm/A] (``robot.torque_constants``).

        Returns:
            None when the log has neither, or only currents and no constants are given.
        """
        if self.tau is not None:
            return np.asarray(self.tau, dtype=float)
        if self.current is None or torque_constants is None:
            return None
        return np.asarray(self.current, dtype=float) * np.asarray(torque_constants, dtype=float)

    def gaps(self, max_gap: float = MAX_GAP) -> list[tuple[float, float]]:
        """(last time before, first time after) of each gap longer than ``max_gap`` [s]."""
        return [(float(self.t[k - 1]), float(self.t[k])) for k in self._after_gaps(max_gap)]

    def runs(self, max_gap: float = MAX_GAP) -> list[JointLog]:
        """The log split at its gaps longer than ``max_gap`` [s]: each run gap-free."""
        after = self._after_gaps(max_gap)
        bounds = zip([0, *after.tolist()], [*after.tolist(), self.n_samples], strict=True)
        return [self._rows(slice(start, stop)) for start, stop in bounds]

    def _after_gaps(self, max_gap: float) -> NDArray[np.intp]:
        """The first row after each gap longer than ``max_gap`` [s]."""
        return np.flatnonzero(np.diff(self.t) > max_gap) + 1

    def _rows(self, rows: slice) -> JointLog:
        def cut(values: FloatArray | None) -> FloatArray | None:
            return None if values is None else values[rows]

        extra = {name: np.asarray(value)[rows] for name, value in self.extra.items()}
        return JointLog(self.t[rows], self.q[rows], self.qd[rows], cut(self.tau),
                        cut(self.current), extra, self.source)  # fmt: skip


def as_joint_log(log: Any, index: int = 0) -> JointLog:
    """``log`` as a :class:`JointLog`: one already, a mapping or an object with its arrays.

    The forms ``lt.identify_friction`` takes (``t``, ``q``, ``qd`` and ``tau`` or
    ``current``, as keys or attributes; ``source`` if given), for every function of the
    API that reads logs: ``identify_dynamics``, ``estimate_payload`` and
    ``detect_contacts`` took a JointLog only, and a dict failed with an AttributeError.

    Raises:
        ParameterError: ``log`` has no ``t``, ``q`` or ``qd`` (one line naming it).
        InputShapeError: Its arrays do not agree in shape.
    """
    if isinstance(log, JointLog):
        return log
    if isinstance(log, str | os.PathLike):
        raise ParameterError("logs", f"{log} is a path: read it first, lt.read_log(path)")

    def get(name: str) -> Any:
        return log_item(log, name)

    missing = [name for name in ("t", "q", "qd") if get(name) is None]
    if missing:
        raise ParameterError("logs", f"log {index} ({type(log).__name__}) has no "
                             f"'{missing[0]}': give a JointLog (lt.read_log), or a mapping or "
                             "object with t, q, qd and tau")  # fmt: skip
    return JointLog(get("t"), get("q"), get("qd"), get("tau"), get("current"),
                    source=str(get("source") or ""))  # fmt: skip


def log_item(log: Any, name: str) -> Any:
    """A log's ``name``: a mapping's item or an object's attribute (None: it has none)."""
    return log.get(name) if isinstance(log, Mapping) else getattr(log, name, None)


def joint_logs(logs: Any) -> list[JointLog]:
    """One log or a list of them, each as a :class:`JointLog` (:func:`as_joint_log`)."""
    return [as_joint_log(log, index) for index, log in enumerate(one_or_many(logs))]


def one_or_many(logs: Any) -> list[Any]:
    """``[logs]`` when ``logs`` is one log, else the list of them.

    One log: a JointLog, a mapping, an object with ``t``, or a path (which
    :func:`as_joint_log` names as one).
    """
    if isinstance(logs, JointLog | Mapping | str | os.PathLike) or hasattr(logs, "t"):
        return [logs]
    try:
        return list(logs)
    except TypeError:  # one log of another kind: as_joint_log says what it lacks
        return [logs]
