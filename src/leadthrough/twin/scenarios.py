"""Shipped twin scenarios: a configuration, an operator and a start pose, by name.

Each scenario is a reproducible situation the controllers of later issues are
developed and measured in; all of them must step without a MuJoCo warning.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from leadthrough.errors import LeadthroughError
from leadthrough.model.description import RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.twin.mjcf import Payload, TableSurface
from leadthrough.twin.operator import Hand, JointHand, Operator, TorqueProfile, step
from leadthrough.twin.paths import Circle, JointMinimumJerk, Line, MinimumJerk
from leadthrough.twin.presets import REALISTIC_TWIN
from leadthrough.twin.simulator import DigitalTwin, TwinConfig


@dataclass(frozen=True)
class Scenario:
    """A named situation on the twin.

    Attributes:
        name: Scenario name.
        description: One line saying what happens.
        config: Twin configuration.
        operator: Who touches the arm.
        q0: Start pose [rad].
        duration: Natural length of the scenario [s].
    """

    name: str
    description: str
    config: TwinConfig
    operator: Operator
    q0: np.ndarray
    duration: float

    def twin(self, robot: RobotDescription) -> DigitalTwin:
        """A fresh twin of ``robot`` in this scenario."""
        return DigitalTwin(robot, self.config, self.operator, self.q0)


def _flange_position(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    return Dynamics(robot).pose(q)[:3, 3]


def _idle(robot: RobotDescription, config: TwinConfig) -> Scenario:
    return Scenario("idle", "nobody touches the arm", config, Operator(), robot.home(), 2.0)


def _line(robot: RobotDescription, config: TwinConfig) -> Scenario:
    start = _flange_position(robot, robot.home())
    hand = Hand(Line(start, start + np.array([0.0, 0.2, 0.0]), duration=3.0))
    return Scenario("line", "a hand pulls the tool 20 cm sideways", config, hand,
                    robot.home(), 4.0)  # fmt: skip


def _circle(robot: RobotDescription, config: TwinConfig) -> Scenario:
    start = _flange_position(robot, robot.home())
    path = Circle(start + np.array([0.0, 0.08, 0.0]), 0.08, (0.0, 0.0, 1.0),
                  (0.0, -1.0, 0.0), duration=6.0)  # fmt: skip
    return Scenario("circle", "a hand draws an 8 cm-radius circle", config, Hand(path),
                    robot.home(), 6.5)  # fmt: skip


def _point_to_point(robot: RobotDescription, config: TwinConfig) -> Scenario:
    start = _flange_position(robot, robot.home())
    path = MinimumJerk(start, start + np.array([-0.1, 0.1, 0.1]), duration=2.5)
    return Scenario("point_to_point", "a hand moves the tool to a point 17 cm away", config,
                    Hand(path), robot.home(), 3.0)  # fmt: skip


def _joint(robot: RobotDescription, config: TwinConfig) -> Scenario:
    home = robot.home()
    path = JointMinimumJerk(home[0], home[0] + 0.5, duration=3.0)
    return Scenario("joint", "a hand turns joint 1 by 0.5 rad", config,
                    JointHand(0, path), home, 4.0)  # fmt: skip


def _torque_steps(robot: RobotDescription, config: TwinConfig) -> Scenario:
    joint = min(3, robot.n_joints - 1)  # the YuMi's elbow-like joint 4, or an arm's last
    profile = TorqueProfile(joint, (step(0.5, 1.0), step(1.5, -2.0)))
    return Scenario("torque_steps", f"scripted torque steps on joint {joint + 1}", config,
                    profile, robot.home(), 2.5)  # fmt: skip


def _table_push(robot: RobotDescription, config: TwinConfig) -> Scenario:
    start = _flange_position(robot, robot.home())
    # 0.07 m below the flange: 5 mm above the tool's tip (0.075 m, mjcf.tool_tip_depth),
    # so the tool touches the table from the start (the stored reference runs keep it)
    table = TableSurface(height=start[2] - 0.07)
    pressed = MinimumJerk(start, start - np.array([0.0, 0.0, 0.08]), duration=1.0)
    return Scenario("table_push", "a hand presses the tool onto a table (~20 N)",
                    replace(config, table=table), Hand(pressed), robot.home(), 2.0)  # fmt: skip


def _payload(robot: RobotDescription, config: TwinConfig) -> Scenario:
    # the realistic plant's model error, with friction +15 % (SPEC: friction ±20 %) and a payload
    error = replace(REALISTIC_TWIN.model_error, friction_scale=1.15, payload=Payload(0.5))
    return Scenario("payload", "an unmodelled 0.5 kg payload, masses ±5 %, friction +15 %",
                    replace(config, model_error=error), Operator(), robot.home(), 2.0)  # fmt: skip


SCENARIOS: dict[str, Callable[[RobotDescription, TwinConfig], Scenario]] = {
    "idle": _idle,
    "line": _line,
    "circle": _circle,
    "point_to_point": _point_to_point,
    "joint": _joint,
    "torque_steps": _torque_steps,
    "table_push": _table_push,
    "payload": _payload,
}


def scenario(name: str, robot: RobotDescription, config: TwinConfig | None = None) -> Scenario:
    """The shipped scenario ``name`` for ``robot`` (see :data:`SCENARIOS`)."""
    if name not in SCENARIOS:
        raise LeadthroughError(f"unknown scenario {name!r}; choose from {', '.join(SCENARIOS)}")
    return SCENARIOS[name](robot, config or TwinConfig())
