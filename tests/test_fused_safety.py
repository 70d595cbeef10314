"""The supervisor's compiled command path and sample check equal their NumPy references."""

from __future__ import annotations

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.model.snapshot import ModelSnapshot
from leadthrough.safety.checks import OUT_OF_RANGE, FrozenEncoders, in_range
from leadthrough.safety.supervisor import SafetySupervisor, SupervisorState
from test_speed_reference import CASES

PERIODS = 20000


def _inputs(robot: lt.RobotDescription, rng: np.random.Generator, k: int):
    """(q, q̇, τ_desired, how the model is spoiled) of period ``k``: every branch in turn.

    Quiet periods, joints near and inside the walls, joints above their speed limit, a
    fast tool, huge torques (saturation), and now and then a NaN or infinite reading or
    command, or a model that makes the safety torque non-finite.
    """
    n = robot.n_joints
    phase = (k // 200) % 5  # quiet, walls, fast joints, fast tool, everything
    span = robot.q_max - robot.q_min
    q = robot.q_min + span * rng.uniform(0.2, 0.8, n)
    if phase in (1, 4):  # some joints in the soft-limit zones, or just beyond
        near = rng.random(n) < 0.4
        edge = np.where(rng.random(n) < 0.5, robot.q_min, robot.q_max)
        q = np.where(near, edge + rng.normal(0.0, 0.08, n), q)
    speed = (0.05, 0.2, 1.3, 0.6, 1.3)[phase]
    qd = rng.normal(0.0, speed, n) * robot.velocity_limits
    qd = np.clip(qd, -1.9 * robot.velocity_limits, 1.9 * robot.velocity_limits)
    tau = rng.normal(0.0, (0.3, 0.3, 0.3, 0.3, 3.0)[phase], n) * robot.torque_limits
    if k % 50 == 7:
        qd[k % n] = 0.0  # sign(0) and zero excess
    spoil = None
    if rng.random() < 0.004:
        spoil = ("q", "qd", "tau", "tau inf", "gravity", "mass", "shape")[rng.integers(7)]
    return q, qd, tau, spoil


def _model(dynamics: lt.Dynamics, robot, q, qd, spoil) -> ModelSnapshot:
    """The model at q (clipped to the range), spoiled if asked."""
    model = dynamics.snapshot(np.clip(q, robot.q_min, robot.q_max), qd)
    if spoil == "gravity":
        model.gravity[:] = np.inf
    elif spoil == "mass":
        model.mass[1, 1] = np.nan
    return model


def _run(robot: lt.RobotDescription, compiled: bool, seed: int) -> tuple[list, list]:
    """Commands, states and everything logged over seeded random periods."""
    rng = np.random.default_rng(seed)
    dynamics = lt.Dynamics(robot)
    supervisor = SafetySupervisor(dynamics, 0.004)
    supervisor.compiled = compiled
    supervisor.teach()
    rows, states = [], []
    for k in range(PERIODS):
        t = 0.004 * k
        q, qd, tau, spoil = _inputs(robot, rng, k)
        model = _model(dynamics, robot, q, qd, spoil)
        if spoil in ("q", "qd", "tau"):
            {"q": q, "qd": qd, "tau": tau}[spoil][k % robot.n_joints] = np.nan
        elif spoil == "tau inf":
            tau[0] = -np.inf
        elif spoil == "shape":
            tau = tau[:-1]
        if k % 1000 == 500:
            supervisor.hold()
        elif k % 1000 == 900:
            supervisor.teach()
        command = supervisor.command(t, q, qd, tau, model)
        rows.append(np.concatenate([command, [supervisor.max_tool_speed]]))
        last_good = supervisor._q_last_good
        states.append((supervisor.state, supervisor.fault_reason,
                       None if last_good is None else last_good.tolist(),
                       supervisor._log_book.episodes))  # fmt: skip
        if supervisor.state is SupervisorState.FAULT and rng.random() < 0.05:
            supervisor.reset()
            supervisor.teach()
    return rows, states + [(event.t, event.kind, event.detail) for event in supervisor.events]


@pytest.mark.parametrize("robot_name, seed", [("yumi", 1), ("yumi", 2), ("panda", 3)])
def test_compiled_command_path_equals_the_numpy_reference(robot_name, seed):
    """20 000 periods (saturation, walls, joint and tool braking, faults, NaN): 1e-12, same log."""
    robot = getattr(lt.robots, robot_name)()
    compiled, compiled_log = _run(robot, True, seed)
    reference, reference_log = _run(robot, False, seed)
    kinds = {entry[1] for entry in reference_log if len(entry) == 3 and isinstance(entry[0], float)}
    assert {"fault", "soft_limit", "joint_speed", "tool_speed", "mode", "reset"} <= kinds
    reasons = " ".join(str(entry[1]) for entry in reference_log if len(entry) == 4)
    assert "non-finite safety torque" in reasons and "non-finite command" in reasons
    np.testing.assert_allclose(np.array(compiled), np.array(reference), rtol=1e-12, atol=1e-12)
    assert compiled_log == reference_log


def test_the_compiled_path_brakes_saturates_and_walls_like_the_reference_each_period():
    """One period each: a fast tool, a fast joint, a joint in a wall, a huge torque."""
    robot = lt.robots.yumi()
    dynamics = lt.Dynamics(robot)
    q = robot.home()
    cases = {
        "tool": (q, np.full(7, 1.0), np.zeros(7)),
        "joint": (q, robot.velocity_limits * np.r_[1.2, np.zeros(6)], np.zeros(7)),
        "wall": (np.r_[robot.q_max[0] - 0.02, q[1:]], np.r_[0.3, np.zeros(6)], np.zeros(7)),
        "saturation": (q, np.zeros(7), 10.0 * robot.torque_limits),
    }
    for name, (position, velocity, tau) in cases.items():
        outputs = []
        for compiled in (True, False):
            supervisor = SafetySupervisor(dynamics, 0.004)
            supervisor.compiled = compiled
            supervisor.teach()
            model = dynamics.snapshot(position, velocity)
            outputs.append(supervisor.command(0.0, position, velocity, tau, model))
        assert not np.allclose(outputs[1], np.clip(tau, -robot.torque_limits, robot.torque_limits)
                               ) or name == "saturation", name  # fmt: skip
        np.testing.assert_allclose(outputs[0], outputs[1], rtol=1e-12, atol=1e-12, err_msg=name)


def test_checked_count_agrees_with_in_range_then_update():
    """Random (q, q̇[, τ]) with NaN, ±inf, bounds, wrong shapes and repeats: same verdicts."""
    rng = np.random.default_rng(6)
    low, high = -np.arange(1.0, 22.0), np.arange(1.0, 22.0)
    checked, reference = FrozenEncoders(7, 4), FrozenEncoders(7, 4)
    outcomes, previous = set(), None
    for k in range(5000):
        readings = [rng.uniform(-1.05, 1.05, 7) * high[:7] for _ in range(3)]
        if rng.random() < 0.5:  # velocities of an arm at rest: only a whole sample is stale
            readings[1] *= 1e-3
        if previous is not None and rng.random() < 0.4:  # the same sample again
            readings = [reading.copy() for reading in previous]
        for reading in readings:
            if rng.random() < 0.05:
                bad = rng.choice([np.nan, np.inf, -np.inf, 1.0, -1.0])
                reading[rng.integers(reading.size)] = bad
        if rng.random() < 0.03:
            readings[rng.integers(3)] = np.zeros(rng.choice([6, 8]))
        previous = readings
        tau = None if rng.random() < 0.3 else readings[2]
        if k % 1000 == 999:
            checked.clear()
            reference.clear()
        count = checked.count(readings[0], readings[1], tau, low, high)
        if in_range(tuple(readings[:2] if tau is None else readings), low, high, 7):
            expected = reference.update(readings[0], readings[1], tau)
            assert checked.reason(count) == expected and count != OUT_OF_RANGE
        else:
            assert count == OUT_OF_RANGE
        np.testing.assert_array_equal(checked._runs, reference._runs)
        outcomes.add(count if count < 0 else ("stale" if count == 7 else "frozen"))
    assert outcomes == {OUT_OF_RANGE, -1, "frozen", "stale"}


@pytest.mark.parametrize("case", [name for name in CASES if not name.startswith("twin")])
def test_steps_with_the_numpy_supervisor_equal_the_compiled_one(case, monkeypatch):
    """Whole steps (modes, calibration, constraints, a fault, the Panda): equal to 1e-12."""
    compiled = CASES[case]()
    monkeypatch.setattr(SafetySupervisor, "compiled", False)
    np.testing.assert_allclose(compiled, CASES[case](), rtol=1e-12, atol=1e-12, equal_nan=True)
