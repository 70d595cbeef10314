"""Rows of a text log: parsed one by one, the corrupted ones dropped with one warning.

Shared by the readers of text logs (UR CSV, Panda text, the excitation CSV): a row that
cannot be read is dropped, counted and named in one :class:`LogWarning`; a file with
more than half its rows dropped is a :class:`LogError` naming it.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from leadthrough.errors import LeadthroughError
from leadthrough.logs.log import FloatArray

#: More than this fraction of rows dropped: the file is not a log.
MOSTLY_GARBAGE = 0.5
#: Largest plausible |value| of a column kind: joint angle [rad], velocity [rad/s], motor
#: current [A], torque [Nm].
PLAUSIBLE = {"q": 4.0 * np.pi, "qd": 20.0, "current": 100.0, "torque": 5000.0}
#: A joint reading farther than this from the run's running median is corrupted [rad].
OFF_PATH = 0.2


class LogError(LeadthroughError, ValueError):
    """A file cannot be read as a robot log (the message names the file)."""


class LogWarning(UserWarning):
    """Rows of a log were dropped as corrupted, or a recording was read only in part."""


def numeric_rows(path: Path) -> list[list[float]]:
    """Every non-empty line as floats; an unparsable line becomes an empty row."""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as error:
        raise LogError(f"{path}: cannot read ({error})") from None
    rows = []
    for line in lines:
        if not line.strip():
            continue
        try:
            rows.append([float(value) for value in line.split(",")])
        except ValueError:
            rows.append([])
    return rows


def common_width(rows: list[list[float]]) -> int:
    """The number of columns most rows have (0 for no rows)."""
    widths = [len(row) for row in rows]
    return max(set(widths), key=widths.count) if widths else 0


def as_table(rows: list[list[float]], width: int) -> tuple[FloatArray, np.ndarray]:
    """The rows as a (N, width) table, NaN where a row has another width; which are whole."""
    whole = np.array([len(row) == width for row in rows], dtype=bool)
    table = np.full((len(rows), width), np.nan)
    for i, row in enumerate(rows):
        if whole[i]:
            table[i] = row
    return table, whole


def accept(path: Path, table: FloatArray, keep: np.ndarray) -> FloatArray:
    """The kept rows; a warning for the dropped ones, an error if they are most.

    Args:
        path: The file, named in the warning and the error.
        table: Its rows, shape (N, columns).
        keep: Which rows are sound, shape (N,).
    """
    total = len(keep)
    dropped = np.flatnonzero(~keep)
    if total == 0 or dropped.size > MOSTLY_GARBAGE * total:
        raise LogError(f"{path}: {dropped.size} of {total} rows are corrupted: not a usable log")
    if dropped.size:
        first = ", ".join(str(i + 1) for i in dropped[:5])
        more = ", …" if dropped.size > 5 else ""
        warnings.warn(f"{path}: dropped {dropped.size} of {total} rows as corrupted "
                      f"(rows {first}{more})", LogWarning, stacklevel=4)  # fmt: skip
    return table[keep]


def plausible(table: FloatArray, kinds: list[str]) -> np.ndarray:
    """Rows whose every value is finite and within its kind's physical bound."""
    bounds = np.array([PLAUSIBLE.get(kind, np.inf) for kind in kinds])
    with np.errstate(invalid="ignore"):
        return np.all(np.isfinite(table) & (np.abs(table) <= bounds), axis=1)


def on_path(q: FloatArray, candidates: np.ndarray, window: int = 9) -> np.ndarray:
    """Rows whose joint readings lie within :data:`OFF_PATH` of the running median."""
    from scipy.ndimage import median_filter  # at call time: keeps `import leadthrough` fast

    ok = candidates & np.all(np.isfinite(q), axis=1) & np.all(np.abs(q) <= PLAUSIBLE["q"], axis=1)
    result = np.zeros(len(q), dtype=bool)
    index = np.flatnonzero(ok)
    if index.size == 0:
        return result
    values = q[index]
    median = median_filter(values, size=(min(window, len(values)), 1), mode="nearest")
    result[index] = np.all(np.abs(values - median) <= OFF_PATH, axis=1)
    return result
