"""Guiding into a stiff contact: a hand presses the tool onto a table (``--cases contact``).

The thesis promises an arm "stable also ... in contact with stiff surfaces". The contact
cases of the guiding benchmark (:data:`~leadthrough.experiments.guiding.PRESS`) measure
it on the plant family; these tests hold the table where the case says it is, and the
safety properties of one case: no chatter against the table, the hand pressing as hard
as in passive mode, and an arm let go while it presses resting there.
"""

from __future__ import annotations

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.feedforward import GravityCompensation
from leadthrough.experiments import guiding
from leadthrough.experiments.guiding import PRESS, Case, cases, run_case, vibration_windows
from leadthrough.twin.mjcf import TableSurface, tool_tip_depth
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin, TwinConfig


def test_contact_cases_press_on_every_plant_with_every_hand():
    """One press per physics, seed and hand, nothing else."""
    chosen = cases("contact", seeds=(1, 2), hands=("relaxed", "stiff"))
    assert len(chosen) == 2 * 2 * 2
    assert {case.path for case in chosen} == {PRESS}
    assert {case.hand for case in chosen} == {"relaxed", "stiff"}


@pytest.mark.parametrize(("gap", "touches"), [(0.001, False), (-0.001, True)])
def test_the_table_stands_its_gap_below_the_tools_tip(gap, touches):
    """1 mm below the tip the tool does not touch the table at home; 1 mm above it, it does.

    The tip is where :func:`tool_tip_depth` says (the capsule and its rounded end): a
    table placed from the capsule's length alone (6 cm) stands 1.5 cm into the tool.
    """
    yumi = lt.robots.yumi()
    dyn = lt.Dynamics(yumi)
    flange = dyn.pose(yumi.home())[:3, 3]
    assert tool_tip_depth() == pytest.approx(0.075)
    twin = DigitalTwin(yumi, TwinConfig(table=TableSurface.below_tool(flange, gap)))
    simulate(twin, GravityCompensation(dyn), 0.1)
    contact = twin.truth.tau_ext - twin.truth.tau_operator
    assert (np.abs(contact).max() > 1e-3) == touches


@pytest.fixture(scope="module")
def pressed() -> dict[str, guiding.CaseResult]:
    """Both modes pressing the tool onto the table with the stiff hand (LuGre plant #1)."""
    case = Case("lugre", 1, "stiff", PRESS)
    return {mode: run_case(case, mode) for mode in ("passive", "active")}


def test_active_mode_presses_as_hard_as_passive_mode(pressed):
    """The hand presses the tool as hard in both modes: the arm neither sinks nor lifts."""
    passive, active = pressed["passive"], pressed["active"]
    assert passive.residual_force > 30.0  # 1.5 cm into the table with 3000 N/m
    assert active.residual_force == pytest.approx(passive.residual_force, rel=0.05)


def test_an_arm_let_go_while_it_presses_rests_on_the_table(pressed):
    """Let go while pressing, the arm stops at once and stays (the release goals)."""
    for result in pressed.values():
        assert result.stop_time <= 0.5
        assert result.drift < 1e-3


def test_the_tool_does_not_chatter_on_the_table():
    """Held on the table, the tool is still: no contact limit cycle in active mode.

    The tool's velocity above 4 Hz over the hold (from 0.5 s after the press's path
    ends) stays below 0.5 mm/s in each 0.5 s window; a tool bouncing on a stiff table
    moves by mm/s or more.
    """
    case = Case("lugre", 1, "stiff", PRESS)
    starts, rms = vibration_windows(case, "active")
    holding = starts >= guiding.LINE_DURATION + 0.5
    assert np.count_nonzero(holding) >= 2
    assert np.all(rms[holding] < 5e-4)
