"""The safety supervisor's log: one event per episode, not per control period.

A joint that stays in a wall, or a tool that stays too fast, is one episode: it is
logged when it begins, and may begin again once it has ended. :class:`EventLog` keeps
the entries and which episodes are under way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class SafetyEvent:
    """One entry of the supervisor's log.

    Attributes:
        t: Time of the control period it happened in [s].
        kind: ``"fault"``, ``"tool_speed"``, ``"joint_speed"``, ``"soft_limit"``, ``"calibration"``,
            ``"overrun"``, ``"reset"``, ``"mode"`` or ``"safe_stop_failed"`` (the safe stop
            itself could not be computed or sent).
        detail: One line saying what happened, with the joint and the value.
    """

    t: float
    kind: str
    detail: str


#: The stored state of an under-way one-flag episode (see :meth:`EventLog.began`).
_UNDER_WAY = np.ones(1, dtype=bool)
_UNDER_WAY.setflags(write=False)


class EventLog:
    """Entries in the order they happened, and the episodes under way.

    Attributes:
        events: The entries.
    """

    def __init__(self) -> None:
        self.events: list[SafetyEvent] = []
        self._under_way: dict[str, NDArray[np.bool_]] = {}

    def add(self, t: float, kind: str, detail: str) -> None:
        """Append an entry at ``t`` [s]."""
        self.events.append(SafetyEvent(float(t), kind, detail))

    @property
    def episodes(self) -> list[str]:
        """The kinds of episode under way, sorted."""
        return sorted(self._under_way)

    def under_way(self, key: str) -> bool:
        """Whether episode ``key`` (of any joint) is under way."""
        return key in self._under_way

    def end(self, key: str) -> None:
        """End episode ``key`` (for every joint): the next one is logged again."""
        self._under_way.pop(key, None)

    def clear(self) -> None:
        """End every episode (after a reset)."""
        self._under_way.clear()

    def began(self, key: str, active: bool) -> bool:
        """Whether the one-flag episode ``key`` began this period (``active`` now)."""
        if not active:
            self.end(key)
            return False
        began = key not in self._under_way
        self._under_way[key] = _UNDER_WAY
        return began

    def started(self, key: str, active: NDArray[np.bool_]) -> NDArray[np.intp]:
        """Joints whose episode ``key`` began this period, of the joints ``active`` now."""
        if not active.any() and key not in self._under_way:
            return np.empty(0, dtype=np.intp)
        started = np.flatnonzero(active & ~self._under_way.get(key, np.zeros_like(active)))
        if active.any():
            self._under_way[key] = active
        else:
            del self._under_way[key]
        return started
