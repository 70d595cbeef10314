"""A scripted teaching session for the twin: guiding, a pause, a contact, an end-stop.

Each action starts from wherever the arm is when it begins (paths are relative to the
flange position at that moment), so the script works whatever the controller did before.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.twin.mjcf import TableSurface
from leadthrough.twin.operator import Hand, JointHand, Operator
from leadthrough.twin.paths import Circle, JointMinimumJerk, Line


@dataclass(frozen=True)
class Action:
    """One action of a script.

    Attributes:
        start: Start time [s].
        stop: End time [s] (the operator lets go).
        make: Builds the operator from the flange position [m] and joint angles [rad] at
            the start.
        label: What happens.
    """

    start: float
    stop: float
    make: Callable[[FloatArray, FloatArray], Operator]
    label: str


class ScriptedOperator(Operator):
    """Plays actions one after the other; nobody touches the arm in between."""

    def __init__(self, actions: Sequence[Action]) -> None:
        self.actions = tuple(actions)
        self._current: tuple[Action, Operator] | None = None
        self._flange = np.zeros(3)
        self._q: FloatArray | None = None

    def _active(self, t: float) -> tuple[Action, Operator] | None:
        """The action under way at ``t``, built when it begins (from the latest state)."""
        action = next((a for a in self.actions if a.start <= t < a.stop), None)
        if action is None or self._q is None:
            self._current = None
        elif self._current is None or self._current[0] is not action:
            self._current = (action, action.make(self._flange.copy(), self._q.copy()))
        return self._current

    def wrench(self, t: float, flange_pose: FloatArray, flange_velocity: FloatArray) -> FloatArray:
        """Wrench of the action under way (zero between actions)."""
        self._flange = np.asarray(flange_pose)[:3, 3].copy()
        active = self._active(t)
        if active is None:
            return np.zeros(6)
        action, operator = active
        return operator.wrench(t - action.start, flange_pose, flange_velocity)

    def holds(self, t: float) -> bool:
        """Whether an action is under way at ``t`` (nobody holds the arm in between)."""
        return any(a.start <= t < a.stop for a in self.actions)

    def joint_torque(self, t: float, q: FloatArray, qd: FloatArray) -> FloatArray:
        """Joint torque of the action under way (zero between actions)."""
        self._q = np.asarray(q, dtype=float).copy()
        active = self._active(t)
        if active is None:
            return np.zeros(len(q))
        action, operator = active
        return operator.joint_torque(t - action.start, q, qd)


def _line(delta: Sequence[float], duration: float) -> Callable[[FloatArray, FloatArray], Operator]:
    return lambda p, q: Hand(Line(p, p + np.asarray(delta), duration))


def _circle(radius: float, duration: float) -> Callable[[FloatArray, FloatArray], Operator]:
    centre = np.array([0.0, radius, 0.0])
    return lambda p, q: Hand(Circle(p + centre, radius, (0, 0, 1), (0, -1, 0), duration))


def _to_end_stop(
    joint: int, robot: RobotDescription
) -> Callable[[FloatArray, FloatArray], Operator]:
    target = robot.q_max[joint] + 0.3
    return lambda p, q: JointHand(joint, JointMinimumJerk(q[joint], target, duration=2.5),
                                  stiffness=5.0, max_torque=1.0)  # fmt: skip


class TeachingSession:
    """The default 60 s session, with its table (``table(robot)``) and labels."""

    press_depth = 0.09  #: how far below the tool the hand aims when pressing [m]
    table_gap = 0.06  #: table top below the tool tip at home [m]

    def table(self, robot: RobotDescription) -> TableSurface:
        """A table a little below the tool tip at the home pose."""
        flange = Dynamics(robot).pose(robot.home())[:3, 3]
        return TableSurface(height=flange[2] - 0.06 - self.table_gap)

    def actions(self, robot: RobotDescription) -> list[Action]:
        """Guide, pause, circle, press on the table (~20 N), end-stop, guide, rest."""
        down = -(self.table_gap + self.press_depth)
        last = robot.n_joints - 1  # the wrist's last joint (joint 7 of the YuMi)
        end_stop = f"turn joint {last + 1} into its end-stop"
        return [
            # the hand takes the arm once the controller's start-up calibration (1.3 s)
            # is over: a hand on the arm before refuses it
            Action(1.5, 5.0, _line((0.0, 0.15, 0.02), 3.0), "pull the tool 15 cm"),
            Action(8.0, 15.0, _circle(0.06, 6.0), "draw a circle"),
            Action(18.0, 23.0, _line((0.0, 0.0, down), 2.0), "press the tool on the table"),
            Action(26.0, 30.0, _to_end_stop(last, robot), end_stop),
            Action(36.0, 41.0, _line((-0.05, -0.1, 0.08), 3.0), "lift the tool back"),
        ]

    def __call__(self, robot: RobotDescription) -> ScriptedOperator:
        """The session's operator for ``robot``."""
        return ScriptedOperator(self.actions(robot))


teaching_session_operator = TeachingSession()
