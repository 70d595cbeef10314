"""The effort split by where a loaded joint sticks (guiding.effort_split, a diagnosis)."""

from __future__ import annotations

import pytest

import leadthrough as lt
from leadthrough.experiments.guiding import Case, effort_split, figures, run_case

#: Joint 1 sticks for most of this line while the hand loads it (docs/guiding_results.md,
#: *What stiction hides*): both kinds of samples occur.
CASE = Case("dry", 1, "relaxed", "sideways")


@pytest.fixture(scope="module")
def split():
    """The split of :data:`CASE` (two held runs)."""
    return effort_split(CASE)


def test_the_whole_path_is_the_benchmarks_effort(split):
    """Over the whole path the split's ratio is the benchmark's effort, computed its own way."""
    effort = figures(run_case(CASE, "passive"), run_case(CASE, "active"))["effort"]
    assert split.ratio == pytest.approx(effort, rel=1e-9)


def test_the_two_parts_make_up_the_whole(split):
    """ratio² = s · stuck² + (1 − s) · sliding², s the stuck samples' share of passive's ΣF²."""
    s = split.stuck_share
    whole = s * split.stuck_ratio**2 + (1.0 - s) * split.sliding_ratio**2
    assert split.ratio**2 == pytest.approx(whole, rel=1e-9)
    assert 0.0 < split.stuck_time < 1.0 and 0.0 < s < 1.0


def test_runs_of_different_periods_are_refused():
    """An active controller at 2 ms against the default passive one at 4 ms: one error."""

    def two_ms(robot, mode):
        return lt.LeadThrough(robot, mode=mode, dt=0.002, calibrate=True)

    with pytest.raises(ValueError, match="sampled differently"):
        effort_split(Case("dry", 1, "stiff", "upwards"), controller_factory=two_ms)
