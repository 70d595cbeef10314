"""Excitation logs on disk: NPZ or CSV, one file holding one or more runs.

Both formats carry the same columns: ``run`` (an integer per sample naming the run),
``t`` [s], then per joint ``q{i}`` [rad], ``qd{i}`` [rad/s], ``tau{i}`` [Nm, arm side]
(i = 1…n). In NPZ the arrays are ``run`` (N,), ``t`` (N,), ``q``, ``qd``, ``tau`` (N, n).
A row that is not finite (NPZ or CSV), or a CSV row cut short or unreadable, is dropped
with one :class:`~leadthrough.logs.rows.LogWarning` counting them, as the readers of robot
logs do.
"""

from __future__ import annotations

import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from leadthrough.errors import LeadthroughError
from leadthrough.logs.log import FloatArray
from leadthrough.logs.rows import (
    LogError,
    accept,
    as_table,
    common_width,
    numeric_rows,
    on_path,
    plausible,
)

BoolArray = NDArray[np.bool_]


class LogFileError(LeadthroughError, ValueError):
    """A log file cannot be read as excitation logs."""


def save_logs(logs: Sequence, path: str | Path) -> Path:
    """Write logs (objects or mappings with t, q, qd, tau) to ``.npz`` or ``.csv``."""
    path = Path(path)
    arrays: dict[str, Any] = _stack(logs)  # Any: numpy's stub of savez types its kwds badly
    if path.suffix == ".npz":
        np.savez_compressed(path, **arrays)
    elif path.suffix == ".csv":
        n = arrays["q"].shape[1]
        header = ["run", "t"] + [f"{k}{i + 1}" for k in ("q", "qd", "tau") for i in range(n)]
        table = np.column_stack(
            [arrays["run"], arrays["t"], arrays["q"], arrays["qd"], arrays["tau"]]
        )
        np.savetxt(path, table, delimiter=",", header=",".join(header), comments="", fmt="%.9g")
    else:
        raise LogFileError(f"{path}: unknown log format {path.suffix!r} (use .npz or .csv)")
    return path


def load_logs(path: str | Path) -> list[dict[str, Any]]:
    """Read logs written by :func:`save_logs` (or by hand in the same layout), one per run.

    Each a mapping of its arrays ``t``, ``q``, ``qd``, ``tau``, its ``source`` (the
    file, and the run where it holds several), which errors name, and ``dropped_rows``,
    the rows of the file dropped as corrupted.
    """
    path = Path(path)
    if not path.is_file():
        raise LogFileError(f"{path}: no such file")
    try:
        arrays = _read_npz(path) if path.suffix == ".npz" else _read_csv(path)
    except LogError as error:  # most rows corrupted: its message names the file already
        raise LogFileError(str(error)) from None
    except (EOFError, zipfile.BadZipFile) as error:  # numpy's words for a cut or empty file
        raise LogFileError(f"{path}: cannot read logs: truncated, empty or not an .npz "
                           f"({error})") from None  # fmt: skip
    except (OSError, ValueError, KeyError) as error:
        raise LogFileError(f"{path}: cannot read logs ({error})") from None
    runs = arrays["run"]
    numbers = np.unique(runs)
    return [{"source": str(path) if len(numbers) == 1 else f"{path} (run {run:g})",
             "dropped_rows": int(arrays["dropped_rows"]),
             **{name: arrays[name][runs == run] for name in ("t", "q", "qd", "tau")}}
            for run in numbers]  # fmt: skip


def _get(log: object, name: str) -> np.ndarray:
    return np.asarray(log[name] if isinstance(log, dict) else getattr(log, name), dtype=float)


def _stack(logs: Sequence) -> dict[str, np.ndarray]:
    names = ("t", "q", "qd", "tau")
    columns = {name: np.concatenate([_get(log, name) for log in logs]) for name in names}
    columns["run"] = np.concatenate([np.full(len(_get(log, "t")), i) for i, log in enumerate(logs)])
    return columns


def _read_npz(path: Path) -> dict[str, np.ndarray]:
    """The arrays of an excitation NPZ; a corrupted row dropped with a warning (:func:`_sound`)."""
    with path.open("rb") as file, np.load(file) as data:  # closed when not a zip too
        arrays = {name: data[name] for name in ("t", "q", "qd", "tau")}
        arrays["run"] = data["run"] if "run" in data else np.zeros(len(arrays["t"]), dtype=int)
    table = np.column_stack([arrays[name] for name in ("run", "t", "q", "qd", "tau")])
    table = table.astype(float)  # text arrays: a ValueError, which names the file
    keep = np.isfinite(table[:, 1]) & _sound(table[:, 0], *np.split(table[:, 2:], 3, axis=1))
    if not keep.all():
        accept(path, table, keep)  # the warning counting the dropped rows; mostly NaN: an error
    kept = {name: value[keep] for name, value in arrays.items()}
    return kept | {"dropped_rows": np.array(keep.size - keep.sum())}


def _read_csv(path: Path) -> dict[str, np.ndarray]:
    """The columns of an excitation CSV; a truncated or corrupted row dropped with a warning."""
    with path.open(encoding="utf-8") as file:
        header = file.readline().strip().split(",")
    if "t" not in header or "tau1" not in header:
        raise ValueError(f"its first line names {','.join(header[:4])}…, not the excitation "
                         "log's columns run,t,q1..,qd1..,tau1..")  # fmt: skip
    rows = numeric_rows(path)[1:]  # the header line read as an empty row
    if not rows:
        raise ValueError("no data rows after the header line run,t,q1..,qd1..,tau1..")
    width = common_width(rows)
    if width != len(header):
        raise ValueError(f"{width} columns but {len(header)} names in the header")
    table, whole = as_table(rows, width)
    column = {name: table[:, i] for i, name in enumerate(header)}
    n = sum(1 for name in header if name.startswith("tau"))
    joint_columns = {k: np.column_stack([column[f"{k}{i + 1}"] for i in range(n)])
                     for k in ("q", "qd", "tau")}  # fmt: skip
    run = column.get("run", np.zeros(len(table)))
    keep = whole & np.isfinite(column["t"]) & _sound(run, *joint_columns.values())
    accept(path, table, keep)
    joint_columns = {name: value[keep] for name, value in joint_columns.items()}
    column["t"], run = column["t"][keep], run[keep]
    dropped = np.array(len(keep) - keep.sum())
    return {"t": column["t"], "run": run.astype(int), "dropped_rows": dropped, **joint_columns}


def _sound(run: FloatArray, q: FloatArray, qd: FloatArray, tau: FloatArray) -> BoolArray:
    """Rows whose readings are finite, physically plausible and on their run's path.

    Within the bounds of :data:`~leadthrough.logs.rows.PLAUSIBLE` (|q| ≤ 4π rad, |q̇| ≤ 20
    rad/s, |τ| ≤ 5000 Nm) and each joint's angle within 0.2 rad of its run's running median
    (:func:`~leadthrough.logs.rows.on_path`), as the robot logs' readers ask. Before, only
    non-finite rows were dropped: one torque of 1e300 ended the fit in a traceback, and one
    angle of 1000 rad was fitted (joint 1's level 1.50 → 7.77 Nm), silently.
    """
    n = q.shape[1]
    kinds = ["q"] * n + ["qd"] * n + ["torque"] * n
    keep = plausible(np.column_stack([q, qd, tau]), kinds) & np.isfinite(run)
    for number in np.unique(run[np.isfinite(run)]):
        rows = np.flatnonzero(run == number)
        keep[rows] = on_path(q[rows], keep[rows])
    return keep
