"""Speed work changes no behaviour: seeded step and twin outputs against a stored reference.

``data/speed_reference.npz`` holds the outputs of :class:`LeadThrough` ``step`` over long
seeded sequences (passive and active, with and without a measured torque, calibration,
virtual constraints, a sensor fault, the two-level observer, the Panda) and of seeded twin
runs (a hand on the tool, the table, lead-through in the loop), computed at commit
2b53732, before the speed work, and regenerated since for deliberate changes of
behaviour only: the start-up calibration's gravity error put into the model and the
Coulomb compensation's ceiling (a released arm stops in either mode), then the virtual
damping weighed on the push that sustains a motion (``admittance.damping_weight``), then
the position reference of a resting joint nobody pushes drawn to where it is
(``admittance.settled_reference``), then the references braking to their bounds
(``admittance.braking_cap``) and the joints' estimates read together as a force at the
tool (``estimation.tool_force``), then a friction level nothing measured on this arm
taken as known to the spread of units only (``unmeasured_friction_error``), then lost
references re-anchored without taking up a joint's run (``admittance.reanchored``), then
the calibration reading a joint only while it slides at the motion's pace
(``calibration.run._JUMPING``), then the velocity reference of a lagging joint unwound
towards its velocity (``admittance.unwound``), then the calibration measuring a joint's
level only if it slid at pace long enough (``calibration.run._MEASURED``) and a payload only
if it stands out of the model's gravity error (``CalibrationRun.payload``), then the
calibration sliding 10 mrad at 0.1 rad/s, above the Stribeck range (``CalibrationParameters``),
then a resting joint's Coulomb band in the law narrowed by the joints read together
(``ActiveLaw.narrow``), then the observer's band taking each level's error from the law
(``LeadThrough._build``: a level nothing measured known to 0.35), then the dither parked
after 0.5 s of rest judged on either velocity (``DitherParameters.park_time``,
``Dither.slow_velocity``), then the dither parked as soon as a resting joint creeps 0.2
mrad, and otherwise after 2 s (``DitherParameters.creep``), then a level the calibration
read known to its readings' scatter at its pose, its error growing with the travel from
there (``friction.measured_level``, ``CalibrationParameters.level_slope``), then the
calibration reading the torque measurement's offset and taking it off
(``Calibration.torque_offset``), then active mode's compensation following the push once
a start-up calibration has been accepted (``CoulombCompensationParameters.follow_push``),
then the calibration reading the momentum balance over each stretch a joint slides at pace
(``calibration.sliding_readings``), then the drives' torque ripple in each joint's band, which
the joints read together weigh (``LeadThroughParameters.torque_ripple``), then the calibration
tracking at 4 Hz over 15 mrad, a loop that decays with two periods of delay, and a joint run
off its motion keeping none of its friction (``CalibrationParameters.bandwidth``,
``CalibrationRun.runaway``), then the calibration's gravity error taken as a relative error
of G as far as a drive gain explains it (``calibration.gravity_share``), then a resting
reference drawn only to a joint that rests itself (``admittance.settled_reference``), then
the dither kept under the compensation's ceiling (``feedforward.dither_within``), then
active mode's virtual damping shaped like the arm's inertia (``admittance.virtual_damping``),
its dither twice the thesis' (``dither.ACTIVE_AMPLITUDE``) and a creep parking only the
joint that crept (``DitherParameters.creep``), then the gravity the calibration measured
known to its readings' scatter in each joint's band (``LeadThrough.joint_std``; the calibrated
idle twin's outputs moved by 2e-9), then each joint's confidence in its gravity model grown
only as fast as it slides with nobody guiding, not at rest (``ModelErrorBias.update``: the
active cases without an accepted calibration moved), then the joints' estimates read as a
force at the tool or a push elsewhere, weighed by their evidence (``tool_force``, the
mixture), then the safe stop holding each joint whose reading is sound where it reads
(``SafetySupervisor._hold_sound_joints``: the sensor fault's case moved for the period of its
bad sample). A faster step must reproduce them.

Regenerate the file only for a deliberate change of behaviour (e.g. a redesigned active
mode), never to make a speed change pass::

    PYTHONPATH=src python tests/test_speed_reference.py
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.constraints import Box, KeepOutSphere, Plane
from leadthrough.control.feedforward import GravityCompensation
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.estimation.observer import ObserverParameters
from leadthrough.logs.sample import JointState
from leadthrough.twin.runner import simulate
from leadthrough.twin.scenarios import scenario

REFERENCE = Path(__file__).parent / "data" / "speed_reference.npz"
STEPS = 2000
STRIDE = 20  # every 20th period is stored (the whole sequence is computed)


def step_outputs(
    robot: lt.RobotDescription,
    seed: int,
    mode: str,
    calibrate: bool = False,
    constraints: tuple = (),
    fault_at: int | None = None,
    measured: bool = True,
    parameters: LeadThroughParameters | None = None,
) -> np.ndarray:
    """Command, τ̂_ext and the filter's std [Nm] of every period over a seeded random motion.

    The arm rests, creeps, moves and swings fast in turns of 300 periods (tool speed
    braking included); ``fault_at`` puts a NaN in one position reading.
    """
    rng = np.random.default_rng(seed)
    controller = lt.LeadThrough(robot, mode, calibrate=calibrate, constraints=constraints,
                                parameters=parameters)  # fmt: skip
    gravity = lt.Dynamics(robot).gravity
    n = robot.n_joints
    q, qd = robot.home().copy(), np.zeros(n)
    low, high = robot.q_min + 0.05, robot.q_max - 0.05
    rows = []
    for k in range(STEPS):
        scale = (0.0, 0.05, 0.5, 1.5)[(k // 300) % 4]
        qd = 0.9 * qd + 0.1 * scale * rng.standard_normal(n)
        if scale == 0.0:
            qd = 1e-4 * rng.standard_normal(n)
        q = np.clip(q + controller.dt * qd, low, high)
        tau = gravity(q) + rng.normal(0.0, 0.5, n) if measured else None
        reading = q.copy()
        if k == fault_at:
            reading[3] = np.nan
        command = controller.step(JointState(controller.dt * (k + 1), reading, qd, tau))
        rows.append(np.concatenate([command, controller.tau_ext_hat, controller.observer.std]))
    return np.array(rows)[::STRIDE]


def twin_outputs(name: str, controller_for: Callable[[lt.RobotDescription], object]) -> np.ndarray:
    """What a seeded twin run of scenario ``name`` measured, sent and truly did, 2 s."""
    robot = lt.robots.yumi()
    twin = scenario(name, robot).twin(robot)
    run = simulate(twin, controller_for(robot), 2.0, progress=False)  # type: ignore[arg-type]
    signals = (run.qd, run.tau_measured, run.tau_command, run.q_true, run.tau_ext,
               run.tau_friction, run.ft_wrench)  # fmt: skip
    return np.hstack(signals)[::STRIDE]


def _box() -> Box:
    return Box(lower=(0.0, -0.3, 0.0), upper=(0.5, 0.3, 0.5))


def _gravity_only(robot: lt.RobotDescription) -> GravityCompensation:
    return GravityCompensation(lt.Dynamics(robot))


def _yumi(seed: int, mode: str, **options: object) -> Callable[[], np.ndarray]:
    return lambda: step_outputs(lt.robots.yumi(), seed, mode, **options)  # type: ignore[arg-type]


TWO_LEVEL = LeadThroughParameters(observer=ObserverParameters(variant="two_level"))
CASES: dict[str, Callable[[], np.ndarray]] = {
    "passive": _yumi(100, "passive"),
    "active": _yumi(101, "active"),
    "active, no measured torque": _yumi(102, "active", measured=False),
    "active, calibration": _yumi(103, "active", calibrate=True),
    "passive, calibration": _yumi(104, "passive", calibrate=True),
    "active, constraints": _yumi(105, "active", constraints=(
        Plane(point=(0.3, 0.0, 0.2), normal=(0.0, 0.0, 1.0)), _box())),
    "passive, constraints": _yumi(106, "passive", constraints=(
        _box(), KeepOutSphere(center=(0.4, 0.1, 0.3), radius=0.15))),
    "active, sensor fault": _yumi(107, "active", fault_at=1200),
    "active, two-level observer": _yumi(108, "active", parameters=TWO_LEVEL),
    "panda, active": lambda: step_outputs(lt.robots.panda(), 7, "active"),
    "twin line, gravity only": lambda: twin_outputs("line", _gravity_only),
    "twin table push, gravity only": lambda: twin_outputs("table_push", _gravity_only),
    "twin line, active": lambda: twin_outputs("line", lambda r: lt.LeadThrough(r, "active")),
    "twin idle, calibrated active": lambda: twin_outputs(
        "idle", lambda r: lt.LeadThrough(r, "active", calibrate=True)),
}  # fmt: skip


@pytest.fixture(scope="module")
def reference() -> dict[str, np.ndarray]:
    """The stored outputs of commit 2b53732."""
    with np.load(REFERENCE) as stored:
        return {name: stored[name] for name in stored.files}


@pytest.mark.parametrize("case", CASES)
def test_outputs_equal_the_reference_before_the_speed_work(case, reference):
    """Every stored period agrees to 1e-9 (relative, or absolute below 1 Nm)."""
    outputs = CASES[case]()
    expected = reference[case]
    assert outputs.shape == expected.shape
    np.testing.assert_allclose(outputs, expected, rtol=1e-9, atol=1e-9, equal_nan=True)


def write_reference() -> None:
    """Compute every case with the code on the path and store it (see the module docstring)."""
    REFERENCE.parent.mkdir(exist_ok=True)
    np.savez_compressed(REFERENCE, **{name: compute() for name, compute in CASES.items()})


if __name__ == "__main__":
    write_reference()
