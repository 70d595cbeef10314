"""Warm-up: every kernel compiled before the control loop's first period, nothing changed."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np

import leadthrough as lt
from leadthrough.twin.mock import MockRobot

SRC = Path(__file__).resolve().parents[1] / "src"


def _commands(controller: lt.LeadThrough, seed: int = 3) -> np.ndarray:
    """Commands over seeded samples: rest, pushes, a fast joint, a NaN reading."""
    rng = np.random.default_rng(seed)
    robot, dynamics = controller.robot, lt.Dynamics(controller.robot)
    q = np.array(robot.home(), dtype=float)
    out = []
    for k in range(400):
        qd = rng.normal(0.0, 0.05, q.size)
        q = q + 0.004 * qd
        push = rng.normal(0.0, 1.0, q.size) if k % 50 > 25 else np.zeros(q.size)
        if k == 300:
            qd[-1] = 1.2 * robot.velocity_limits[-1]
        reading = np.where(np.arange(q.size) == 0, np.nan, q) if k == 350 else q
        out.append(controller.step(reading, qd, dynamics.gravity(q) - push))
    return np.array(out)


def test_warm_up_leaves_the_controller_as_it_was():
    """A warmed-up controller commands exactly what an untouched one does."""
    robot = lt.robots.yumi()
    for mode in ("passive", "active"):
        warmed = lt.LeadThrough(robot, mode=mode, calibrate=True)
        assert warmed.warm_up() > 0.0
        untouched = lt.LeadThrough(robot, mode=mode, calibrate=True)
        np.testing.assert_array_equal(_commands(warmed), _commands(untouched))


def test_the_loop_warms_up_controllers_that_can():
    """control_loop reports the warm-up's time; a controller without one gets 0."""
    robot = lt.robots.yumi()
    mock = MockRobot(robot.n_joints, 0.004, q0=robot.home())
    report = lt.control_loop(mock, lt.LeadThrough(robot, mode="active"), duration=0.04,
                             wall_clock=False)  # fmt: skip
    assert report.warm_up > 0.0

    class Still:
        dt = 0.004

        def step(self, state):
            return np.zeros(robot.n_joints)

    assert lt.control_loop(mock, Still(), duration=0.04, wall_clock=False).warm_up == 0.0


def test_no_kernel_compiles_inside_the_loop_after_the_warm_up():
    """After warm_up nothing compiles: calibrating, guiding, braking, a fault, a replay.

    In a fresh process (nothing compiled before), on the twin, passive and active.
    """
    script = textwrap.dedent(
        """
        import numpy as np
        import leadthrough as lt
        from leadthrough import compiled
        from leadthrough.control.replay import Replayer, plan_replay
        from leadthrough.twin.runner import simulate
        from leadthrough.twin.simulator import DigitalTwin

        robot = lt.robots.yumi()
        controllers = [lt.LeadThrough(robot, mode=m, calibrate=True) for m in ("passive", "active")]
        dynamics = lt.Dynamics(robot)
        home = np.array(robot.home(), dtype=float)
        t = np.linspace(0.0, 1.0, 251)
        path = home + 0.05 * np.outer(t, np.ones(robot.n_joints))
        replayer = Replayer(plan_replay(t, path, dynamics), dynamics)
        for controller in (*controllers, replayer):
            controller.warm_up()
        before = compiled.signatures()
        for controller in controllers:
            simulate(DigitalTwin(robot), controller, 1.3, progress=False)
            qd = np.zeros(robot.n_joints)
            qd[-1] = 1.2 * robot.velocity_limits[-1]
            controller.step(home, qd, dynamics.gravity(home))
            broken = home.copy()
            broken[0] = np.nan
            controller.step(broken, np.zeros(robot.n_joints), None)
            controller.step(home, np.zeros(robot.n_joints), None)
        simulate(DigitalTwin(robot), replayer, 0.5, progress=False)
        after = compiled.signatures()
        # the controller's kernels: the twin's (the plant, not on a robot) compile as it runs
        new = {name: after[name] for name in after
               if after[name] != before[name] and not name.startswith("leadthrough.twin.")}
        assert any(before.values()), "nothing was compiled by the warm-up"
        print("NEW", new)
        """
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin",
                                 "MUJOCO_GL": "disable"}, timeout=300)  # fmt: skip
    assert result.returncode == 0, result.stderr[-2000:]
    assert "NEW {}" in result.stdout, result.stdout[-2000:]


def test_a_compiled_kernel_replaces_its_wrapper_in_the_package():
    """After its first call a kernel's module name is numba's dispatcher (no wrapper frame).

    A name held elsewhere (the registry's) still calls through the wrapper, to the same
    compiled code, and both keep the Python function as ``py_func``.
    """
    from leadthrough import compiled
    from leadthrough.estimation import tool_force

    wrapper = compiled._KERNELS["leadthrough.estimation.tool_force._fuse"]

    jacobian, estimate = np.ones((6, 3)), np.array([1.0, 2.0, 3.0])
    std, other, mean, fused_std = np.ones(3), np.ones(3), np.empty(3), np.empty(3)
    wrapper(estimate, std, jacobian, other, 1e-4, 0.0, mean, fused_std, np.zeros((3, 8)))
    bound = tool_force._fuse
    assert bound is not wrapper and type(bound).__module__.startswith("numba")
    again, again_std = np.empty(3), np.empty(3)
    bound(estimate, std, jacobian, other, 1e-4, 0.0, again, again_std, np.zeros((3, 8)))
    np.testing.assert_array_equal(again, mean)
    assert bound.py_func is wrapper.py_func


def test_a_kernel_compiles_where_numba_cannot_cache(monkeypatch):
    """No folder numba may cache in (a read-only install, no HOME): compiled all the same.

    Before, numba's "cannot cache function" ended every command, ``--help`` included.
    """
    import numba

    from leadthrough.compiled import kernel

    njit = numba.njit

    def no_cache(*args, **kwargs):
        if kwargs.get("cache"):
            raise RuntimeError("cannot cache function 'twice': no locator available")
        return njit(*args, **kwargs)

    monkeypatch.setattr(numba, "njit", no_cache)

    @kernel
    def twice(x):
        return 2.0 * x

    assert twice(1.5) == 3.0 and twice.compiled_signatures()
