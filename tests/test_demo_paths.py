"""The paths the demo's hands pulled along (experiments.demo.intended_position/_velocity)."""

from __future__ import annotations

import dataclasses

import numpy as np

import leadthrough as lt
from leadthrough.experiments.demo import intended_position, intended_velocity, teaching_actions
from leadthrough.twin.runner import SimulationResult

DT = 0.004


def _run_at_rest(robot: lt.RobotDescription, duration: float) -> SimulationResult:
    """A run whose flange wanders slowly (the paths start wherever it is)."""
    t = np.arange(0.0, duration, DT)
    n, joints = len(t), robot.n_joints
    fields = {f.name: np.zeros((n, joints)) for f in dataclasses.fields(SimulationResult)}
    fields["t"] = t
    fields["operator_wrench"] = np.zeros((n, 6))
    fields["ft_wrench"] = np.zeros((n, 6))
    fields["flange_position"] = np.column_stack([0.4 + 0.01 * t, 0.3 - 0.02 * t, 0.1 + 0 * t])
    return SimulationResult(**fields)


def test_each_hands_path_starts_where_the_tool_was_and_moves_at_its_velocity():
    """Position and velocity of the same paths, from their own formulas, agree."""
    robot = lt.robots.yumi()
    actions = teaching_actions(robot)
    run = _run_at_rest(robot, actions[-1].stop + 0.5)
    position, velocity = intended_position(run, actions), intended_velocity(run, actions)
    for action in actions:
        during = np.flatnonzero((run.t >= action.start) & (run.t < action.stop))
        first = during[0]
        np.testing.assert_allclose(position[first], run.flange_position[first], atol=1e-3)
        difference = np.gradient(position[during], DT, axis=0)[1:-1]
        np.testing.assert_allclose(difference, velocity[during][1:-1], atol=2e-3)
    between = ~np.any([(run.t >= a.start) & (run.t < a.stop) for a in actions], axis=0)
    assert np.isnan(position[between]).all() and (velocity[between] == 0.0).all()
