"""The supervisor's log keeps one entry per episode (safety/events.py)."""

import numpy as np

from leadthrough.safety.events import EventLog


def test_a_flag_episode_is_logged_once_until_it_ends():
    """A tool too fast for many periods is one event; once slow again, the next is another."""
    log = EventLog()
    assert [log.began("tool_speed", active) for active in (True, True, False, True)] == [
        True, False, False, True]  # fmt: skip
    assert log.episodes == ["tool_speed"]
    log.end("tool_speed")
    assert not log.under_way("tool_speed") and log.began("tool_speed", True)


def test_joint_episodes_begin_per_joint():
    """A joint entering a wall is an event; another joint's entry is its own; reset clears."""
    log = EventLog()
    inside = np.array([False, True, False])
    assert log.started("soft_limit", inside).tolist() == [1]
    assert log.started("soft_limit", np.array([True, True, False])).tolist() == [0]
    assert log.started("soft_limit", np.array([True, False, False])).tolist() == []
    assert log.started("soft_limit", np.array([False, True, False])).tolist() == [1]  # again
    assert log.started("soft_limit", np.zeros(3, dtype=bool)).tolist() == []
    assert not log.under_way("soft_limit")
    log.started("soft_limit", inside)
    log.clear()
    assert log.episodes == [] and log.started("soft_limit", inside).tolist() == [1]


def test_entries_keep_their_order_and_time():
    """Entries come back in order, with their times as floats."""
    log = EventLog()
    log.add(0.5, "fault", "joint 2 reading is NaN")
    log.add(1, "reset", "supervisor reset: holding")
    assert [(e.t, e.kind) for e in log.events] == [(0.5, "fault"), (1.0, "reset")]
    assert isinstance(log.events[1].t, float)
