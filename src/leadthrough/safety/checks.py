"""Checks of every sensor sample and command: shape, finite, in range, not stale (SPEC §7).

Each check returns the one-line reason a reading is bad (joints numbered from 1 at the
base), or None. A good sample costs one compiled pass over its readings, which also counts
its repeats (:meth:`FrozenEncoders.count`); the reasons are only spelled out for a bad one.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from leadthrough.compiled import kernel
from leadthrough.model.description import FloatArray
from leadthrough.safety.limits import SafetyLimits


def floats(value: object) -> FloatArray:
    """A fresh float array of ``value`` (the caller may reuse its buffer)."""
    return np.array(value, dtype=float)


def as_floats(value: object) -> FloatArray:
    """``value`` as a contiguous float array, not copied if it is one (to read, not keep)."""
    array = np.asarray(value, dtype=float)
    return array if array.flags.c_contiguous else array.copy()


def in_range(readings: tuple[FloatArray, ...], low: FloatArray, high: FloatArray, n: int) -> bool:
    """Whether every reading has shape (n,) and lies within [low, high] (NaN does not).

    Args:
        readings: Vectors in their units, each expected of shape (n,).
        low: Their lower bounds, concatenated in the same order, shape (k n,) with k at
            least the number of readings.
        high: Their upper bounds, likewise.
        n: Number of joints.
    """
    shape, offset = (n,), 0
    for reading in readings:
        if reading.shape != shape or not within_bounds(reading, low, high, offset):
            return False
        offset += n
    return True


@kernel
def within_bounds(values: FloatArray, low: FloatArray, high: FloatArray, offset: int) -> bool:
    """Whether ``low[offset + i] <= values[i] <= high[offset + i]`` for all i (NaN: no).

    Compiled: ~0.2 µs against ~3 µs for the NumPy comparisons and their reduction.
    """
    for i in range(values.shape[0]):  # noqa: SIM110 (a loop numba compiles)
        if not low[offset + i] <= values[i] <= high[offset + i]:
            return False
    return True


def seconds(t: object) -> float | None:
    """A time stamp as a float [s] if it is a finite number (not a string), else None."""
    if isinstance(t, str | bytes):
        return None
    try:
        value = float(t)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def time_problem(
    t: object, previous: float | None, max_gap: float | None, value: float | None = None
) -> str | None:
    """Why a sample's time stamp cannot be used, or None.

    Args:
        t: The time stamp [s].
        previous: The latest sample's [s] (None: none since the start or a reset).
        max_gap: The longest a sample may come after the latest, or before it [s]
            (``SafetyParameters.max_time_gap``; None: any). A stamp that repeats or goes
            back by less is taken as it is (a driver's clock may be coarse): compared
            with the latest, a clock that runs backwards slowly is a fault once it is
            ``max_gap`` behind (:func:`clock_stopped` for one that stops).
        value: ``seconds(t)``, if the caller has it.
    """
    if value is None:
        value = seconds(t)
    if value is None:
        return f"time stamp {t!r} is not a finite number"
    if previous is None or max_gap is None:
        return None
    if value - previous > max_gap:
        return (f"time stamp jumped {value - previous:.4g} s, from {previous:.6f} to "
                f"{value:.6f} s (more than max_time_gap {max_gap:g} s): samples lost, or a "
                "clock not in seconds")  # fmt: skip
    if previous - value > max_gap:
        return (f"time stamp stepped back {previous - value:.4g} s, from {previous:.6f} to "
                f"{value:.6f} s (more than max_time_gap {max_gap:g} s): the robot's clock "
                "was reset")  # fmt: skip
    return None


def clock_stopped(stalled: int, dt: float, max_gap: float | None) -> str | None:
    """Why the robot's clock cannot be trusted: no later stamp for ``max_gap`` of periods.

    Args:
        stalled: Samples in a row whose stamp did not come after the latest one.
        dt: The control period [s].
        max_gap: ``SafetyParameters.max_time_gap`` [s] (None: never).

    A stamp may repeat (a coarse clock), but a clock that stops, or runs backwards, for
    ``max_gap`` leaves everything timed by it (the calibration, the dither) still: before,
    a controller fed a constant stamp calibrated for good, with no event.
    """
    if max_gap is None or stalled * dt <= max_gap:
        return None
    return (f"time stamp did not advance over {stalled} samples ({stalled * dt:.3g} s of "
            f"periods, more than max_time_gap {max_gap:g} s): the robot's clock stopped or "
            "runs backwards")  # fmt: skip


#: Seconds of stamps over which the samples' mean period is compared with ``dt`` [s]
#: (:func:`sample_rate_problem`): long enough that one gap of ``max_time_gap`` (0.25 s)
#: moves it by at most a third.
RATE_WINDOW = 1.0


def sample_rate_problem(
    span: float, samples: int, dt: float, tolerance: float | None
) -> str | None:
    """Why samples that came at this mean period cannot be taken at ``dt``, or None.

    Args:
        span: Time from the first stamp of the window to its last [s].
        samples: Samples that came after the first in that time.
        dt: The control period the controller integrates with [s].
        tolerance: ``SafetyParameters.rate_tolerance`` [–] (None: any rate).

    A controller built for one rate and fed another integrates each period's change of
    momentum over the wrong time: built for 1 kHz and fed 250 Hz samples, it read a push of
    2.5 Nm as 5.9 Nm while the arm accelerated (the dither, the admittance and the
    calibration are timed wrongly too).
    """
    if tolerance is None or samples < 1:
        return None
    period = span / samples
    if period <= tolerance * dt and period * tolerance >= dt:
        return None
    return (f"samples came every {1e3 * period:.3g} ms over the last {span:.3g} s, but the "
            f"controller runs at dt = {1e3 * dt:.3g} ms (more than {tolerance:g}× apart): "
            "was it built for another rate?")  # fmt: skip


def sample_reason(
    limits: SafetyLimits, q: FloatArray, qd: FloatArray, tau: FloatArray | None
) -> str | None:
    """The first problem of a sample, reading by reading and joint by joint, or None.

    Args:
        limits: The supervisor's bounds.
        q: Joint readings [rad].
        qd: Joint velocities [rad/s].
        tau: Measured joint torques [Nm], or None when the robot has none.
    """
    speed, torque = limits.qd_bound, limits.tau_bound
    return (
        reading_problem("position", q, limits.q_low, limits.q_high, "rad")
        or reading_problem("velocity", qd, -speed, speed, "rad/s")
        or (None if tau is None else reading_problem("torque", tau, -torque, torque, "Nm"))
    )


def reading_problem(
    kind: str, value: FloatArray, low: FloatArray, high: FloatArray, unit: str
) -> str | None:
    """Why one reading vector is invalid (shape, non-finite, outside [low, high]), or None."""
    if value.shape != low.shape:
        return f"{kind} reading has shape {value.shape}, expected {low.shape}"
    if np.all((value >= low) & (value <= high)):  # the usual case, one test (NaN fails it)
        return None
    bad = np.flatnonzero(~np.isfinite(value))
    if bad.size:
        return f"joint {bad[0] + 1} {kind} reading {value[bad[0]]}"
    bad = np.flatnonzero((value < low) | (value > high))
    if bad.size:
        i = bad[0]
        return (
            f"joint {i + 1} {kind} reading {value[i]:.4g} {unit} "
            f"outside [{low[i]:.4g}, {high[i]:.4g}] {unit}{_in_degrees(value, low, high, unit)}"
        )
    return None


def _in_degrees(value: FloatArray, low: FloatArray, high: FloatArray, unit: str) -> str:
    """A hint for velocities when every one would fit in rad/s: degrees per second?

    Not for positions: a position 2π off (a wrap) fits once divided by 57 as well.
    """
    if unit != "rad/s":
        return ""
    radians = np.deg2rad(value)
    if np.all((radians >= low) & (radians <= high)):
        return " (in degrees per second? converted, every joint's reading fits)"
    return ""


#: A joint's reading may move at most this many times its speed limit between two
#: samples [–] (a speed above the limit is braked, not impossible), plus :data:`JUMP_FLOOR`.
JUMP_SPEEDS = 2.0
#: The least step any reading may take between two samples [rad]: stamps off their
#: sample's time (the public Panda log has a joint 7 mrad on in a 1.01 ms stamp, 3× its
#: speed limit) and encoders' noise; a wrap-around is 2π.
JUMP_FLOOR = 0.05


def jump_problem(
    position: FloatArray, previous: FloatArray, speed: FloatArray, interval: float
) -> str | None:
    """Why ``position`` cannot follow ``previous`` [rad] ``interval`` [s] later, or None.

    A joint whose reading moved more than :data:`JUMP_SPEEDS` times its speed limit
    ``speed`` [rad/s] allows did not move that way: a reading that wraps around (2π on a
    joint whose range spans more), a glitch, or samples out of order. Before, such a
    reading was taken: a YuMi's joint 5 read 2π further on within its range was recorded,
    and the replay planned a full turn the hand never taught (a review).
    """
    joint = _jumped(position, previous, speed, interval, JUMP_SPEEDS, JUMP_FLOOR)
    if joint < 0:
        return None
    step = position[joint] - previous[joint]
    return (f"joint {joint + 1}'s reading jumped {step:+.3f} rad in {1e3 * interval:.3g} ms, "
            f"more than {JUMP_SPEEDS:g}× its speed limit allows: a reading that wraps "
            "around, or samples out of order?")  # fmt: skip


@kernel
def _jumped(position, previous, speed, interval, speeds, floor):  # fmt: skip
    """The first joint whose step exceeds ``speeds · speed · interval + floor``; -1 if none."""
    for j in range(position.shape[0]):
        if abs(position[j] - previous[j]) > speeds * speed[j] * interval + floor:
            return j
    return -1


#: A velocity check window closes once a joint has moved this far from its start [rad].
VELOCITY_MOVE = 0.1
#: ... or after this long without [s] (its integral restarts).
VELOCITY_WINDOW = 1.0
#: Velocity readings whose integral over a window is this many times the position's change,
#: or this much of it the other way, are not the position's rate [–]. Far apart: a filtered
#: velocity lags its position (up to ±50 % of a 0.1 rad move at 1.5 rad/s with 50 ms of lag).
VELOCITY_RATIO = (-0.5, 10.0)


class VelocityUnits:
    """Whether each joint's velocity reading is its position's rate, judged on its moves.

    Over a window that closes when the joint has moved :data:`VELOCITY_MOVE` from where
    it started, the integral of the velocity read must match the position's change within
    :data:`VELOCITY_RATIO`: a velocity in degrees per second reads 57× it, one of the other
    sign −1×. Before, degrees per second were caught only beyond twice the speed limit, and
    a Panda with a calibration went 2.9 rad to its joint limit at full torque on them, a
    reading of the other sign not at all (a review).

    Args:
        n: Number of joints.
    """

    def __init__(self, n: int) -> None:
        self._windows = np.full((3, n), np.nan)  # rows: start [rad], integral [rad], time [s]

    def clear(self) -> None:
        """Forget the windows (a reset: the next sample starts them)."""
        self._windows[:] = np.nan

    def update(self, q: FloatArray, qd: FloatArray, interval: float) -> str | None:
        """Take a sample ``interval`` [s] after the one before; why it is off, or None."""
        low, high = VELOCITY_RATIO
        joint = _velocity_off(self._windows, q, qd, interval, VELOCITY_MOVE, VELOCITY_WINDOW,
                              low, high)  # fmt: skip
        if joint < 0:
            return None
        ratio = self._windows[1, joint]  # the kernel leaves the judged window's ratio there
        self.clear()
        return (f"joint {joint + 1}'s velocity reading integrates to {ratio:+.3g}× its "
                "position's change: not in rad/s (degrees per second?), or of the other "
                "sign")  # fmt: skip


@kernel
def _velocity_off(windows, q, qd, interval, move, longest, low, high):  # fmt: skip
    """One sample of :class:`VelocityUnits`, windows in place; the first joint off, or -1.

    A joint off leaves its ratio in ``windows[1]``.
    """
    for j in range(q.shape[0]):
        if not math.isfinite(windows[0, j]) or windows[2, j] > longest:
            windows[0, j], windows[1, j], windows[2, j] = q[j], 0.0, 0.0
            continue
        windows[1, j] += qd[j] * interval
        windows[2, j] += interval
        moved = q[j] - windows[0, j]
        if abs(moved) >= move:
            ratio = windows[1, j] / moved
            if ratio < low or ratio > high:
                windows[1, j] = ratio
                return j
            windows[0, j], windows[1, j], windows[2, j] = q[j], 0.0, 0.0
    return -1


def command_problem(tau: FloatArray, n: int) -> str | None:
    """Why a controller's torque command is unusable (shape, non-finite), or None."""
    if tau.shape != (n,):
        return f"command has shape {tau.shape}, expected ({n},)"
    bad = np.flatnonzero(~np.isfinite(tau))
    return f"non-finite command on joint {bad[0] + 1}" if bad.size else None


#: :meth:`FrozenEncoders.count` of a sample with a reading out of range (or of another shape).
OUT_OF_RANGE = -2
#: The most periods a torque measurement may lag the command it holds
#: (``control.interface_delay.LONGEST``, the longest delay the controller looks for).
MEASUREMENT_LAG = 8
_NO_BOUNDS = np.zeros(0)


class FrozenEncoders:
    """Counts bit-identical readings: a stale sensor repeats itself, an arm at rest may too.

    A real arm at rest repeats its readings exactly: a UR10e standing still reports the
    same bits of (q, q̇) of a joint for up to 7.3 s and of every joint for up to 0.23 s
    (equal in value, its q̇ flipping between 0.0 and −0.0: 15 s and 1.25 s; the logs in
    ``realdata/ur10e``, 100 Hz), and a check of (q, q̇) alone faulted it after 0.25 s. So a
    repeat is stale only where it cannot be a sample of an arm at rest:

    - a joint whose q and q̇ repeat while q̇ says it moves (``|q̇| > speed``): an encoder
      that stopped, or a packet repeated while the arm moves;
    - the whole sample repeated, the measured torque of every joint included: the drives'
      torque (current) readings are noisy, and no sample of those logs repeats its
      predecessor even once.

    A torque reading without noise (a simulator's, or a driver that reports the torque it
    was sent) repeats too, wherever the arm rests and the command stops changing (a
    passive arm's dither parked). So once the controller reports the commands it sends
    (:meth:`sent`), a whole sample repeated is stale only if a command changed during the
    repeat early enough (:data:`MEASUREMENT_LAG`) to show in the torque measured since:
    live readings would have followed it. Fed samples alone, every repeat counts.

    What it cannot see, as a reading of an arm at rest: an encoder that stops while its
    joint rests, or a driver that repeats q and reports q̇ = 0, while the torques stay
    live; without a torque measurement, a stale sample of an arm whose joints all move
    slower than ``speed``; and a stale sample while every command sent is the same. The
    controller then compensates gravity at the stale pose, and the walls and the speed
    braking do not see the arm pushed away from it.

    Args:
        n: Number of joints.
        periods: Repeats that make a reading stale (0: never).
        speed: A joint whose velocity reading exceeds this moves [rad/s].
    """

    def __init__(self, n: int, periods: int, speed: float = 0.01) -> None:
        self.n = n
        self.periods = periods
        self.speed = float(speed)
        self.clear()

    def clear(self) -> None:
        """Forget the samples and commands seen so far (the counters restart)."""
        self._previous_bits: NDArray[np.uint64] | None = None
        self._runs = np.zeros(self.n + 1, dtype=np.int64)  # per joint, then the whole sample
        self._last_command: bytes | None = None
        self._changes = 0  # bit b: the command b + 1 periods back differed from its predecessor
        self._commands = 0  # commands reported since the counters restarted

    def sent(self, command: FloatArray) -> None:
        """The command sent this period [Nm], shape (n,): whether it changed is recorded."""
        bits = command.tobytes()
        changed = self._last_command is not None and bits != self._last_command
        self._last_command = bits
        window = (1 << (self.periods + MEASUREMENT_LAG)) - 1  # older changes are judged
        self._changes = ((self._changes << 1) | changed) & window
        self._commands += 1

    def _repeat_is_stale(self) -> bool:
        """Whether the whole sample's repeat is stale: see the class (commands sent).

        Bit b of the changes is the command sent b + 1 periods before this sample; one
        at least :data:`MEASUREMENT_LAG` old and sent after the repeat began shows in it.
        """
        runs = int(self._runs[self.n])
        if self._commands < runs:  # some of the repeat came with no command known
            return True
        inside = (1 << max(runs - 1 - MEASUREMENT_LAG, 0)) - 1
        return bool((self._changes >> MEASUREMENT_LAG) & inside)

    def update(self, q: FloatArray, qd: FloatArray, tau: FloatArray | None = None) -> str | None:
        """Count one sample (q [rad], q̇ [rad/s], τ [Nm] or None, shape (n,)): why stale, or None."""
        return self.reason(self.count(q, qd, tau))

    def count(
        self,
        q: FloatArray,
        qd: FloatArray,
        tau: FloatArray | None = None,
        low: FloatArray | None = None,
        high: FloatArray | None = None,
    ) -> int:
        """Count one sample if its readings are within [low, high] (as :func:`in_range`).

        Args:
            q: Joint readings [rad], shape (n,).
            qd: Joint velocities [rad/s], shape (n,).
            tau: Measured torques [Nm], shape (n,), or None.
            low: Lower bounds of (q, q̇, τ), shape (3n,); None: no range check.
            high: Upper bounds, likewise.

        Returns:
            :data:`OUT_OF_RANGE` (nothing counted), −1 (fresh), the first frozen joint, or
            ``n``: the whole sample is stale.
        """
        first = self._previous_bits is None
        if first:
            self._previous_bits = np.zeros(3 * self.n, dtype=np.uint64)
        shape = (self.n,)
        if q.shape != shape or qd.shape != shape or (tau is not None and tau.shape != shape):
            return OUT_OF_RANGE  # as in_range: a reading of another shape is not in range
        checked = 0 if low is None or high is None else (2 if tau is None else 3)
        low = _NO_BOUNDS if low is None else low
        high = _NO_BOUNDS if high is None else high
        return _count_repeats(q, qd, q if tau is None else tau, tau is not None, checked,  # type: ignore[no-any-return]
                              low, high, self._previous_bits, self._runs, first, self.periods,
                              self.speed)  # fmt: skip

    def reason(self, count: int) -> str | None:
        """Why the sample :meth:`count` returned ``count`` for is stale, else None."""
        if count < 0 or (count == self.n and not self._repeat_is_stale()):
            return None
        runs = self._runs[count]
        if count == self.n:
            return (
                f"sensor data stale: q, qd and torque of every joint identical for {runs} samples"
            )
        return (f"joint {count + 1} encoder frozen: q and qd identical for {runs} samples, "
                f"qd above {self.speed:g} rad/s")  # fmt: skip

    def frozen(self) -> NDArray[np.bool_]:
        """Joints whose readings repeated ``periods`` times, or all if the sample is stale.

        Their velocity readings are not trusted (a joint at rest loses nothing by that).
        """
        if self.periods == 0:
            return np.zeros(self.n, dtype=bool)
        repeated = self._runs >= self.periods
        return repeated[: self.n] | (repeated[self.n] and self._repeat_is_stale())


@kernel
def _count_repeats(q, qd, tau, has_tau, checked, low, high, previous_bits, runs, first,
                   periods, speed):  # fmt: skip
    """Count bit-identical readings in place; the first frozen joint, ``n`` (stale), or −1.

    First, when ``checked`` > 0, the first ``checked`` of (q, q̇, τ) must lie within
    [low, high] (NaN does not, as in :func:`in_range`): else :data:`OUT_OF_RANGE`
    and nothing is counted. ``runs[i]`` counts joint i's repeated (q, q̇), ``runs[n]`` the
    repeated whole sample (q, q̇ and τ of every joint; without τ it never repeats).
    ``previous_bits`` holds the bits of the last (q, q̇, τ) and is overwritten with these;
    ``runs[n]`` is 0 after a sample without τ, so the next one's τ is compared with nothing.
    """
    n = q.shape[0]
    for k in range(checked):
        values = q if k == 0 else (qd if k == 1 else tau)
        for i in range(n):
            if not low[k * n + i] <= values[i] <= high[k * n + i]:
                return OUT_OF_RANGE
    q_bits, qd_bits, tau_bits = q.view(np.uint64), qd.view(np.uint64), tau.view(np.uint64)
    stale = -1
    whole = has_tau and not first and runs[n] > 0  # runs[n] = 0: the last had no τ
    for i in range(n):
        same = q_bits[i] == previous_bits[i] and qd_bits[i] == previous_bits[n + i]
        whole = whole and same and tau_bits[i] == previous_bits[2 * n + i]
        runs[i] = 1 if first or not same else runs[i] + 1
        previous_bits[i], previous_bits[n + i] = q_bits[i], qd_bits[i]
        if has_tau:  # (a ternary with 0 would pass the bits through a float in numba)
            previous_bits[2 * n + i] = tau_bits[i]
        if stale < 0 and periods > 0 and runs[i] >= periods and abs(qd[i]) > speed:
            stale = i
    runs[n] = runs[n] + 1 if whole else (1 if has_tau else 0)
    if stale < 0 and periods > 0 and runs[n] >= periods:
        stale = n
    return stale


def trusted_velocity(qd: object, bound: FloatArray, frozen: NDArray[np.bool_]) -> FloatArray:
    """The velocity reading [rad/s], zero where non-finite, out of range or frozen.

    Args:
        qd: The velocity reading, anything (a bad one gives zeros).
        bound: Readings beyond ± this are not trusted [rad/s], shape (n,).
        frozen: Joints whose encoder is frozen, shape (n,).
    """
    zeros = np.zeros(bound.shape)
    try:
        values = floats(qd)
    except (TypeError, ValueError):
        return zeros
    if values.shape != bound.shape:
        return zeros
    trusted = np.isfinite(values) & (np.abs(values) <= bound) & ~frozen
    return np.where(trusted, values, 0.0)
