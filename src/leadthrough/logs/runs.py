"""Which run a log holds, so that one run given twice is refused rather than fitted twice.

Identification weighs every sample it is given: a run given twice (the same log object,
or one file read twice) weighs double, in silence. :func:`run_identity` says when two
logs hold one run; :func:`refuse_repeated` refuses the second, for the Python API
(:func:`refuse_repeated_logs`) and for ``leadthrough identify``, which names runs by path
before reading them (:func:`leadthrough.runtime.readers.run_path`).
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from leadthrough.errors import ParameterError
from leadthrough.logs.log import log_item


def log_name(log: Any, index: int) -> str:
    """How an error names a log: its file, else "log <index>" (0-based).

    The file is ``JointLog.source``, or a mapping's ``"source"`` (as
    :func:`~leadthrough.friction.logs.load_logs` gives it).
    """
    source = log_item(log, "source")
    return str(source) if source else f"log {index}"


def run_identity(source: str, t: Any) -> tuple[str, float] | None:
    """What two logs that hold one run share: their source and first sample time.

    The source is resolved as a path, so that two spellings of one file are one run; a
    Panda text log's source is its folder, whether it was read from the folder or from
    one of its files. The first sample time [s] tells apart the parts of one log split
    at its gaps (:meth:`~leadthrough.logs.log.JointLog.runs`), which share its source.

    Args:
        source: Where the log came from (``JointLog.source``, a mapping's ``"source"``).
        t: The log's sample times [s].

    Returns:
        None for a log without a source or numeric samples: it is only itself.
    """
    try:
        times = np.ravel(np.asarray(t if t is not None else [], dtype=float))
    except (TypeError, ValueError):  # not numbers: the identification names that
        return None
    if not source or times.size == 0:
        return None
    return str(Path(source).resolve()), float(times[0])


def refuse_repeated(runs: Iterable[tuple[str, str, Hashable]]) -> None:
    """Refuse the first run given twice, naming it.

    Args:
        runs: (parameter, name, identity) of each run in order: the argument or option
            that gives it (``logs``, ``--log``, ``--held-out``), how the message names
            it, and what two runs given twice share.

    Raises:
        ParameterError: Naming the parameter and the run given again: ``--log: a.csv is
            given twice (each run counts once)``, or ``… is also a --log run`` when two
            parameters give it.
    """
    seen: dict[Hashable, str] = {}
    for parameter, name, identity in runs:
        if identity in seen:
            where = "given twice" if seen[identity] == parameter else f"also a {seen[identity]} run"
            raise ParameterError(parameter, f"{name} is {where} (each run counts once)")
        seen[identity] = parameter


def refuse_repeated_logs(logs: Sequence[Any]) -> None:
    """Refuse a log given twice to an identification: it would be fitted twice.

    Twice means the same object, or two logs of one run (:func:`run_identity`: two
    readings of one file, however its path is spelt). Logs are :class:`JointLog` objects or
    mappings (``source``, ``t``); one without a source is only itself.

    Raises:
        ParameterError: ``logs: run.csv is given twice (each run counts once)``.
    """

    def identity(log: Any) -> Hashable:
        source = log_item(log, "source")
        return run_identity(str(source or ""), log_item(log, "t")) or ("object", id(log))

    refuse_repeated(("logs", log_name(log, i), identity(log)) for i, log in enumerate(logs))
