"""``read_log``: one robot log in, one :class:`JointLog` out, whatever wrote it.

Formats (detected from the path and the first line, or named with ``format=``):

- ``"ur_csv"``: Universal Robots logs as the RTDE scripts of other labs write them: no
  header, comma separated, absolute time; columns 1 time [s], 2–7 q [rad], 8–13 q̇
  [rad/s], 14–19 motor current [A], then 20–25 target current [A] and 26–31 target
  torque [Nm] (31 columns) or 19 columns, or 25 (20–25 undocumented, kept as
  ``extra["columns_20_25"]``).
- ``"panda_txt"``: a folder (or one of its files) with ``*_time.txt``, ``*_positions.txt``,
  ``*_velocity.txt``, ``*_torques.txt``: one value per line, the n joints of a sample on
  n consecutive lines; torques from joint torque sensors [Nm].
- ``"recording"``: the project's own teaching recordings (``.mcap``, or the ``.mcap.part``
  a crashed recorder left); a cut or damaged one is read up to where it breaks, with a
  warning saying how much was recovered.
- ``"excitation"``: the project's excitation logs (``.npz``, or ``.csv`` with a header).

Real logs have corrupted rows. A row is dropped when it has the wrong number of columns
(a truncated last line), a non-finite or physically impossible value (|q| > 4π rad,
|q̇| > 20 rad/s, |current| > 100 A, |torque| > 5000 Nm: the ``253.0`` and ``1e300``
rows of UR logs), a joint reading off the run's own path by more than 0.2 rad (a row of
zeros in a moving log), or a time out of line with the rows around it (the fewest rows
are dropped for time to increase: a time stamp that jumped costs its own row, not the
rows after it). One warning counts the dropped rows and names the first ones; a file
with more than half its rows dropped is an error naming the file. A Panda text log whose
positions and velocities are one value apart over a stretch of rows (a value missing from
one file and one added further on) is an error naming the rows (:func:`_shifted_rows`).
"""

from __future__ import annotations

import bisect
import warnings
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Literal

import numpy as np

from leadthrough.logs.log import FloatArray, JointLog, period_problem, rate_problem
from leadthrough.logs.rows import (
    LogError,
    LogWarning,
    accept,
    as_table,
    common_width,
    numeric_rows,
    on_path,
    plausible,
)
from leadthrough.model.description import RobotDescription

Format = Literal["ur_csv", "panda_txt", "recording", "excitation"]

#: Time between two runs of an excitation log read as one JointLog [s] (> MAX_GAP).
RUN_GAP = 1.0
#: UR CSV column counts that the format allows.
_UR_WIDTHS = (19, 25, 31)


def read_log(
    path: str | Path, robot: RobotDescription | None = None, format: Format | None = None
) -> JointLog:
    """Read one robot log.

    Args:
        path: The log file (or, for ``"panda_txt"``, its folder).
        robot: The arm, if known: its torque constants turn motor currents into joint
            torques (``tau = K·i``), and its joint count is checked.
        format: One of ``"ur_csv"``, ``"panda_txt"``, ``"recording"``, ``"excitation"``;
            detected when None.

    Raises:
        LogError: No such file, an unknown format (a UR-wide CSV with a header row
            included), a file that is mostly garbage, or samples further apart than
            :data:`~leadthrough.logs.log.MAX_PERIOD`, or a dq/dt over the time column more
            than :data:`~leadthrough.logs.log.RATE_TOLERANCE` times the logged q̇ (time not
            in seconds).
    """
    path = Path(path)
    if not path.exists():
        raise LogError(f"{path}: no such file")
    kind = format or detect_format(path)
    recording = partial(_read_recording, robot=robot)  # checks the robot it was made on
    readers: dict[str, Callable[[Path], JointLog]] = {
        "ur_csv": _read_ur_csv, "panda_txt": _read_panda_txt, "recording": recording,
        "excitation": _read_excitation}  # fmt: skip
    if kind not in readers:
        raise LogError(f"{path}: unknown log format {kind!r} (one of {', '.join(readers)})")
    log = _plausible_period(readers[kind](path))
    if robot is not None:
        log = _with_robot(log, robot)
    return log


def run_path(path: Path) -> Path:
    """The file or folder that holds the run ``path`` names, resolved (nothing is read).

    A Panda text log's folder, whether ``path`` is the folder or one of its files; the
    file itself otherwise. Two paths with one ``run_path`` name one run, as ``read_log``
    reads it (whose ``source`` is the folder of a Panda text log: see
    :func:`~leadthrough.logs.runs.run_identity`).
    """
    resolved = Path(path).resolve()
    return resolved.parent if _panda_file(resolved) else resolved


def _panda_file(path: Path) -> bool:
    """Whether ``path`` is one file of a Panda text log (``exciting_traj_*.txt``)."""
    return path.name.startswith("exciting_traj_") and path.suffix == ".txt" and not path.is_dir()


def detect_format(path: Path) -> Format:
    """The format of ``path`` from its name and first line (see the module docstring)."""
    if path.is_dir() or _panda_file(path):
        return "panda_txt"
    if path.suffix == ".mcap" or path.name.endswith(".mcap.part"):
        return "recording"
    if path.suffix == ".npz":
        return "excitation"
    try:
        with path.open(encoding="utf-8", errors="replace") as file:
            first = file.readline()
    except OSError as error:
        raise LogError(f"{path}: cannot read ({error})") from None
    if first.startswith("run,") or first.startswith("t,"):
        return "excitation"
    if first.count(",") + 1 in _UR_WIDTHS:
        if not _numeric(first):  # a header naming the columns: not a UR controller's file
            raise LogError(f"{path}: its first line names columns ({first.strip()[:40]}…), "
                           "and a UR CSV has no header: write your own log as an excitation "
                           "log, its header t,q1..,qd1..,tau1.. "
                           "(leadthrough identify --help)")  # fmt: skip
        return "ur_csv"
    widths = ", ".join(str(w) for w in sorted(_UR_WIDTHS))
    raise LogError(f"{path}: unknown log format: its first line is neither a UR CSV row "
                   f"({widths} columns) nor an excitation log's header (run,t,… or t,…), and "
                   "it is no Panda text log, .mcap recording or .npz")  # fmt: skip


def _numeric(line: str) -> bool:
    """Whether any value of a CSV line is a number (a corrupted row has some)."""
    for value in line.split(","):
        try:
            float(value)
        except ValueError:
            continue
        return True
    return False


def _plausible_period(log: JointLog) -> JointLog:
    """``log``, unless its sample period or its q̇ says its time is not in seconds."""
    problem = period_problem(log.median_period) if log.n_samples > 2 else None
    problem = problem or rate_problem(log.t, log.q, log.qd)
    if problem is not None:
        raise LogError(f"{log.source}: {problem}")
    return log


def _with_robot(log: JointLog, robot: RobotDescription) -> JointLog:
    if log.n_joints != robot.n_joints:
        raise LogError(f"{log.source}: {log.n_joints} joints, but {robot.name} has "
                       f"{robot.n_joints}")  # fmt: skip
    constants = robot.torque_constants
    if log.tau is not None or log.current is None or constants is None:
        return log
    return JointLog(log.t, log.q, log.qd, log.current * constants, log.current, log.extra,
                    log.source, log.dropped_rows)  # fmt: skip


# --- UR CSV ----------------------------------------------------------------------------


def _read_ur_csv(path: Path) -> JointLog:
    rows = numeric_rows(path)
    width = common_width(rows)
    if width not in _UR_WIDTHS:
        raise LogError(f"{path}: rows have {width} columns, a UR log has 19, 25 or 31")
    table, complete = as_table(rows, width)
    targets = ["current"] * 6 + ["torque"] * 6 if width == 31 else ["other"] * 6  # 25: unnamed
    kinds = ["time"] + ["q"] * 6 + ["qd"] * 6 + ["current"] * 6 + targets
    keep = complete & plausible(table, kinds[:width]) & on_path(table[:, 1:7], complete)
    keep &= _time_increases(table[:, 0], keep)
    table = accept(path, table, keep)
    extra = {}
    if width == 25:  # columns 20–25 of these files are not documented: kept, not named
        extra["columns_20_25"] = table[:, 19:25]
    if width == 31:
        extra["target_current"], extra["target_torque"] = table[:, 19:25], table[:, 25:31]
    return JointLog(table[:, 0], table[:, 1:7], table[:, 7:13], None, table[:, 13:19], extra,
                    str(path), int(len(rows) - keep.sum()))  # fmt: skip


def _time_increases(t: FloatArray, keep: np.ndarray) -> np.ndarray:
    """``keep`` without the fewest rows that leave time [s] increasing along the rest.

    The longest run of kept rows whose time increases: a row whose time stamp jumped
    (forward or back) is dropped, not the good rows after it. Built from the last row
    back, so that of two equally long runs (or two equal times) the earlier rows stay.
    """
    heads: list[float] = []  # heads[k]: the latest first time of a run of k + 1 rows
    starts: list[int] = []  # starts[k]: the row that starts that run
    following = np.full(len(t), -1)
    for i in np.flatnonzero(keep)[::-1]:
        k = bisect.bisect_left(heads, -t[i])  # heads kept negated: ascending for bisect
        following[i] = starts[k - 1] if k else -1
        if k == len(heads):
            heads.append(-t[i])
            starts.append(int(i))
        else:
            heads[k], starts[k] = -t[i], int(i)
    result = np.zeros(len(t), dtype=bool)
    row = starts[-1] if starts else -1
    while row >= 0:
        result[row], row = True, following[row]
    return result


# --- Panda text ------------------------------------------------------------------------


def _read_panda_txt(path: Path) -> JointLog:
    folder = path if path.is_dir() else path.parent
    files = {kind: sorted(folder.glob(f"*_{kind}.txt")) for kind in
             ("time", "positions", "velocity", "torques")}  # fmt: skip
    missing = [kind for kind, found in files.items() if len(found) != 1]
    if missing:
        others = sorted(p.name for p in folder.iterdir() if p.suffix in (".csv", ".mcap"))
        hint = (f" (it holds {len(others)} other logs, e.g. {others[0]}: give one file)"
                if others else "")  # fmt: skip
        raise LogError(f"{folder}: a folder is read as a Panda text log, which needs one "
                       f"*_{missing[0]}.txt file{hint}")  # fmt: skip
    columns = {kind: _one_per_line(found[0]) for kind, found in files.items()}
    t = columns["time"]
    n = columns["positions"].size // max(t.size, 1)
    if n < 1 or any(columns[kind].size != n * t.size for kind in ("positions", "velocity",
                                                                  "torques")):  # fmt: skip
        raise LogError(f"{folder}: {t.size} times do not match {columns['positions'].size} "
                       "positions, velocities or torques")  # fmt: skip
    shifted = _shifted_rows(t, columns["positions"], columns["velocity"], n)
    if shifted is not None:
        raise LogError(f"{folder}: from about row {shifted[0]} to row {shifted[1]} each joint's "
                       "position reads its neighbour's velocity: a value is missing and one "
                       "added in *_positions.txt or *_velocity.txt")  # fmt: skip
    q, qd, tau = (columns[kind].reshape(t.size, n) for kind in ("positions", "velocity", "torques"))
    table = np.column_stack([t, q, qd, tau])
    kinds = ["time"] + ["q"] * n + ["qd"] * n + ["torque"] * n
    keep = plausible(table, kinds)
    keep = _time_increases(t, keep & on_path(q, keep))
    table = accept(folder, table, keep)
    return JointLog(table[:, 0], table[:, 1:1 + n], table[:, 1 + n:1 + 2 * n],
                    table[:, 1 + 2 * n:], source=str(folder),
                    dropped_rows=int(t.size - keep.sum()))  # fmt: skip


#: Samples over which positions are compared with the velocities' integral (_shifted_rows).
_ALIGNMENT_WINDOW = 20
#: Smallest disagreement read as evidence [rad]: below it, a joint at rest or quantisation.
_ALIGNMENT_FLOOR = 1e-3


def _shifted_rows(
    t: FloatArray, positions: FloatArray, velocities: FloatArray, n: int
) -> tuple[int, int] | None:
    """The first and last rows (1-based) whose positions sit one value off the velocities.

    One value per line, a value missing from one file and one added further on keep the
    counts right and shift every joint of the rows between onto its neighbour's. Over
    each window of :data:`_ALIGNMENT_WINDOW` samples the change of each position is
    compared with the integral of its velocity; a window is shifted where the positions
    moved one value either way agree at least four times better and the disagreement is
    above :data:`_ALIGNMENT_FLOOR`. None: no more shifted windows than one window's worth
    (a real Panda log: none of its 20 544). A shift in the torques is not seen.
    """
    rows, window = t.size, _ALIGNMENT_WINDOW
    if rows <= window:
        return None
    velocity = velocities.reshape(rows, n)
    steps = 0.5 * (velocity[1:] + velocity[:-1]) * np.median(np.diff(t))
    integral = np.vstack([np.zeros((1, n)), np.cumsum(steps, axis=0)])
    travel = integral[window:] - integral[:-window]

    def disagreement(flat: FloatArray) -> FloatArray:
        q = flat.reshape(rows, n)
        with np.errstate(invalid="ignore"):
            return np.max(np.abs(q[window:] - q[:-window] - travel), axis=1)

    none = np.array([np.nan])
    as_read = disagreement(positions)
    moved = np.fmin(disagreement(np.concatenate([positions[1:], none])),
                    disagreement(np.concatenate([none, positions[:-1]])))  # fmt: skip
    with np.errstate(invalid="ignore"):
        shifted = np.flatnonzero((moved < 0.25 * as_read) & (as_read > _ALIGNMENT_FLOOR))
    if shifted.size <= window:
        return None
    return int(shifted[0]) + 1, int(shifted[-1]) + window + 1


def _one_per_line(path: Path) -> FloatArray:
    values = []
    for line in path.read_text(encoding="utf-8", errors="replace").split():
        try:
            values.append(float(line))
        except ValueError:
            values.append(np.nan)
    return np.array(values)


# --- the project's own files -----------------------------------------------------------


def _read_recording(path: Path, robot: RobotDescription | None = None) -> JointLog:
    """A recording's samples; refused if ``robot`` is not the one it was recorded on.

    A UR10e's recording read with a UR5 was taken without a word (``inspect`` refused it
    already: a YuMi's read as a Panda's showed 42.7 Nm of "contacts").
    """
    from leadthrough.errors import RecordingError
    from leadthrough.runtime.recording import read_recording

    try:
        recording = read_recording(path)
    except RecordingError as error:
        raise LogError(str(error)) from None
    if robot is not None and recording.robot.name != robot.name:
        raise LogError(f"{path}: recorded on {recording.robot.name!r}, not {robot.name!r}")
    if not recording.complete:  # a cut, damaged or unfinished file: the user is told how much
        warnings.warn(f"{path}: {recording.recovery}", LogWarning, stacklevel=3)
    extra = {"tau_ext_hat": recording.tau_ext_hat, "tau_ext_std": recording.tau_ext_std}
    return JointLog(recording.t, recording.q, recording.qd, recording.tau, None, extra,
                    str(path))  # fmt: skip


def _read_excitation(path: Path) -> JointLog:
    """An excitation log; one of several runs (``identify --save-log``) as one JointLog.

    The runs are put one after the other with :data:`RUN_GAP` between them, a gap longer
    than :data:`~leadthrough.logs.log.MAX_GAP`: ``log.runs()`` gives them back, and the
    observer and the contact detector start afresh after it. Before, a log of several runs
    was an error pointing to a function outside the API.
    """
    from leadthrough.friction.logs import LogFileError, load_logs

    try:
        runs = load_logs(path)
    except LogFileError as error:
        raise LogError(str(error)) from None
    times, start = [], 0.0
    for run in runs:
        t = np.asarray(run["t"], dtype=float)
        shift = start - (t[0] if t.size else 0.0)
        times.append(t + shift)
        start = (times[-1][-1] if t.size else start) + RUN_GAP
    joined = {name: np.concatenate([run[name] for run in runs]) for name in ("q", "qd", "tau")}
    return JointLog(np.concatenate(times), joined["q"], joined["qd"], joined["tau"],
                    source=str(path),
                    dropped_rows=sum(int(run["dropped_rows"]) for run in runs))  # fmt: skip
