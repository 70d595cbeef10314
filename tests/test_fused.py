"""Compiled active law (control/fused.py), feed-forward and friction terms equal NumPy code."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.active_law import ActiveLaw
from leadthrough.control.dither import DitherParameters
from leadthrough.control.feedforward import PassiveFeedForward
from leadthrough.control.lead_through import LeadThrough
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.estimation.observer import MomentumObserver
from test_speed_reference import CASES

PERIODS = 20000


def _state(law: ActiveLaw) -> np.ndarray:
    """Everything the active law keeps or produces, in one row."""
    references, bias = law.references, law.model_error
    return np.concatenate([law.drive, law.weight, law.feedback, law.sustained,
                           law.damping_weight, law.signed_weight,
                           bias.bias, bias.gravity_learned, bias.confidence,
                           references.q_ref, references.qd_ref])  # fmt: skip


def _law_period(law: ActiveLaw, compiled: bool, q, qd, estimate, gravity, constraint, mass):
    """One period of the law, compiled or its NumPy reference."""
    law.compiled = compiled
    law.operator_torque(estimate, q, qd, gravity)
    law.tracking(q, qd, constraint, mass)


def _law_run(robot: lt.RobotDescription, parameters: LeadThroughParameters, friction,
             compiled: bool, seed: int = 11, errors: bool = False) -> np.ndarray:  # fmt: skip
    """The law's state over seeded random periods: rest, creep, pushes, limits, jumps.

    The pose wanders (and now and then jumps, so that tracking is lost) over the whole
    range and a little beyond (the limit zones, the end-stop reaction); the estimate is
    quiet, a push, or a large one; G is random, M(q) the model's; the fusion narrows the
    Coulomb bands by random amounts (none, one period in seven). ``errors``: the friction
    levels' errors change every period (``set_friction_error``, as a level read at one
    pose has them grow with the travel).
    """
    rng = np.random.default_rng(seed)
    law = LeadThrough(robot, "active", friction=friction, parameters=parameters).law
    mass_of = lt.Dynamics(robot).mass
    n = robot.n_joints
    offset, home, rows = np.zeros(n), robot.home(), []
    for k in range(PERIODS):
        phase = (k // 500) % 4  # rest, creep, moving, fast
        qd = rng.normal(0.0, (0.0, 1e-3, 0.05, 1.0)[phase], n)
        offset = 0.998 * offset + 0.004 * qd
        if rng.random() < 0.005:  # a jump: tracking is lost
            offset = offset + rng.normal(0.0, 0.1, n)
        q = np.clip(home + offset, robot.q_min - 0.05, robot.q_max + 0.05)
        if (k // 100) % 5 == 4:  # a joint deep in a limit zone, or just beyond a limit
            joint = (k // 500) % n
            q[joint] = (robot.q_min, robot.q_max)[(k // 1000) % 2][joint] + rng.normal(0, 0.1)
        estimate = rng.normal(0.0, (0.3, 3.0, 30.0)[(k // 700) % 3], n)
        if phase == 0:  # at rest, a model error on one joint, as much as the bias may learn
            estimate = rng.normal(0.0, 0.05, n)
            estimate[(k // 2000) % n] += 8.0
        gravity = rng.normal(0.0, 20.0, n)
        constraint = rng.normal(0.0, 2.0, n) if k % 3 == 0 else np.zeros(n)
        mass = mass_of(np.clip(q, robot.q_min, robot.q_max))
        law.narrowing[:] = 1.0 if k % 7 == 0 else rng.uniform(0.0, 1.0, n)  # the fused std's
        if errors:
            law.set_friction_error(rng.uniform(parameters.stiction_margin, 0.35, n))
        _law_period(law, compiled, q, qd, estimate, gravity, constraint, mass)
        rows.append(_state(law))
    return np.array(rows)


def test_compiled_law_relieves_the_margin_as_the_numpy_reference(monkeypatch):
    """The experiment ``ActiveLaw.margin_relief`` (design log), compiled and in NumPy.

    Equal over the same random periods, and not the default law (the relief acts).
    """
    robot = lt.robots.yumi()
    friction, parameters = lt.FrictionModel.from_robot(robot), LeadThroughParameters()
    assert ActiveLaw.margin_relief is False  # the default law keeps its whole margin
    default = _law_run(robot, parameters, friction, compiled=True, errors=True)
    monkeypatch.setattr(ActiveLaw, "margin_relief", True)
    compiled = _law_run(robot, parameters, friction, compiled=True, errors=True)
    reference = _law_run(robot, parameters, friction, compiled=False, errors=True)
    np.testing.assert_allclose(compiled, reference, rtol=1e-9, atol=1e-9)
    assert np.max(np.abs(compiled - default)) > 1e-3


@pytest.mark.parametrize(
    "robot_name, changes, cable, errors",
    [
        ("yumi", {}, False, False),
        ("yumi", {}, True, False),  # a position-dependent Coulomb level
        ("yumi", {}, False, True),  # levels whose error changes every period
        ("yumi", {"bias_time": 0.02}, False, False),  # the bias learns to its bound at once
        ("yumi", {"limit_aware": False, "assist_knee": 0.0, "position_bandwidth": 0.0}, False,
         False),
        ("panda", {"rest_damping": 0.0, "mass_uncertainty": 0.0, "unwind_time": None}, False,
         False),
    ],
)  # fmt: skip
def test_compiled_law_equals_the_numpy_reference_over_random_periods(robot_name, changes, cable,
                                                                     errors):  # fmt: skip
    """20 000 periods of drive, bias, weights, references and PD torque: equal to 1e-9.

    The friction terms (a tanh) differ by one ulp between NumPy and the compiled code;
    the damping weight averages the push over ``push_time`` and feeds the references,
    which feed the next residual, so over 20 000 random periods that grows to ~1e-11
    relative. A kernel that computes anything else is off by far more (1e-6 and up).
    """
    robot = getattr(lt.robots, robot_name)()
    friction = _cable(robot) if cable else lt.FrictionModel.from_robot(robot)
    parameters = LeadThroughParameters(**changes)
    compiled = _law_run(robot, parameters, friction, compiled=True, errors=errors)
    reference = _law_run(robot, parameters, friction, compiled=False, errors=errors)
    assert np.all(np.isfinite(reference))
    weights = reference[:, robot.n_joints : 2 * robot.n_joints]
    assert 0.05 < np.mean(weights > 0.5) < 0.95 or parameters.assist_knee == 0.0  # both sides
    np.testing.assert_allclose(compiled, reference, rtol=1e-9, atol=1e-9)


def test_compiled_narrowing_equals_numpy_with_zeros_and_nans():
    """``ActiveLaw.narrow`` compiled and in NumPy: equal bit for bit, NaN where NumPy's is."""
    rng = np.random.default_rng(5)
    laws = [LeadThrough(lt.robots.yumi(), "active").law for _ in range(2)]
    laws[1].compiled = False
    for k in range(2000):
        fused, own = rng.uniform(0.0, 2.0, 7), rng.uniform(0.0, 2.0, 7)
        own[k % 7] = (0.0, 1e-12, np.inf, np.nan, 1.0, -0.0, 3.0)[k % 7]
        fused[(k + 3) % 7] = (0.0, np.nan, 5.0)[k % 3]
        for law in laws:
            law.narrow(fused, own)
        np.testing.assert_array_equal(laws[0].narrowing, laws[1].narrowing)
        assert np.all((laws[0].narrowing <= 1.0) | np.isnan(laws[0].narrowing))


def test_a_nan_estimate_propagates_as_in_numpy():
    """A NaN estimate: the same NaNs, and the same numbers where NumPy keeps them."""
    robot = lt.robots.yumi()
    outputs = []
    for compiled in (True, False):
        law = LeadThrough(robot, "active").law
        q, qd, mass = robot.home(), np.zeros(7), lt.Dynamics(robot).mass(robot.home())
        for k in range(5):
            estimate = np.full(7, 2.0)
            estimate[2] = np.nan if k == 2 else 2.0
            _law_period(law, compiled, q, qd, estimate, np.ones(7), np.zeros(7), mass)
            outputs.append(_state(law))
    compiled_rows, reference_rows = np.split(np.array(outputs), 2)
    assert np.isnan(reference_rows[-1]).any()
    np.testing.assert_allclose(compiled_rows, reference_rows, rtol=1e-12, atol=1e-12,
                               equal_nan=True)  # fmt: skip


def _cable(robot: lt.RobotDescription) -> lt.FrictionModel:
    """The description's friction with a position-dependent Coulomb level."""
    n = robot.n_joints
    return replace(lt.FrictionModel.from_robot(robot), position_linear=np.full(n, 0.1),
                   position_quadratic=np.full(n, 0.05))  # fmt: skip


def _velocities(rng: np.random.Generator, k: int, n: int) -> np.ndarray:
    """Joint speeds of period ``k``: all at rest (long enough to park), some, or none."""
    phase = (k // 700) % 4
    if phase == 0:
        return rng.normal(0.0, 1e-3, n)
    moving = np.random.default_rng(k // 100).random(n) < (0.2, 0.5, 1.0)[phase - 1]  # 0.4 s
    return np.where(moving, rng.normal(0.0, 0.02, n), rng.normal(0.0, 1e-3, n))


def _feed_forward_run(parameters: DitherParameters | None, clock: bool, compiled: bool,
                      delay: int | None, capped: bool, pushed: bool = False,
                      limit_zone: float | None = None,
                      anywhere: bool = False) -> np.ndarray:  # fmt: skip
    """Parts, total and dither state over 10 000 seeded periods (NaN speeds too).

    ``capped``: a compensation ceiling, with gravity references of every size (or none).
    ``pushed``: an operator's push in [−1, 1] in two periods of three (none in the third).
    ``limit_zone``: the compensation fades within zones of this width before the limits.
    ``anywhere``: every other pose puts the joints anywhere between their limits, and a
    reading turns NaN 10 periods before the end.
    The pose changes with each phase of :func:`_velocities`; in half the phases every
    joint creeps, at up to 0.3 mrad/s (the dither's creep limit crossed or not).
    """
    robot = lt.robots.yumi()
    rng = np.random.default_rng(21)
    feed_forward = PassiveFeedForward(lt.Dynamics(robot), _cable(robot), 0.004,
        dither=parameters, measurement_delay=delay, friction_error=np.linspace(0.1, 0.3, 7),
        gravity_uncertainty=0.15 if capped else None,
        limit_zone=limit_zone)  # fmt: skip
    feed_forward.compiled = compiled
    dither, rows = feed_forward.dither, []
    for k in range(10000):
        if k % 700 == 0:
            pose = robot.home() + rng.normal(0.0, 0.5, 7)
            spread = rng.uniform(robot.q_min, robot.q_max)
            if anywhere and k % 1400:
                pose = spread
            creep = rng.choice([0.0, 3e-4]) * rng.random(7)  # [rad/s]
        q = pose + creep * 0.004 * (k % 700) + rng.normal(0.0, 1e-5, 7)
        qd = _velocities(rng, k, 7) * (1.0, 0.3)[k % 2]  # through the dead-band and the ramp
        if k % 997 == 5:
            qd[k % 7] = np.nan  # a NaN speed: moving, as in NumPy
        if anywhere and k == 9990:  # a NaN reading: NaN from there on (its gravity too)
            q[3] = np.nan
        reference = None if k % 3 == 0 else rng.normal(0.0, (1.0, 5.0)[k % 2], 7)
        if k % 1009 == 7 and reference is not None:
            reference[k % 7] = np.nan
        push = rng.uniform(-1.0, 1.0, 7) if pushed and k % 3 else None
        parts = feed_forward.step(q, qd, None, 1.7e9 + 0.004 * k if clock else None, reference,
                                  push)  # fmt: skip
        state = [] if dither is None else [dither.active, [dither.parked], dither.crept]
        if delay is not None:
            state.append(parts.dither_in_measurement)
        rows.append(np.concatenate([parts.friction, parts.dither, parts.total, *state]))
    return np.array(rows)


@pytest.mark.parametrize(
    "park_time, creep, clock, dithered, delay, capped, pushed, zoned",
    [
        (2.0, 2e-4, True, True, None, False, False, False),
        (None, 2e-4, True, True, 2, False, True, True),
        (0.5, None, False, True, 1, True, True, False),
        (None, None, True, True, None, False, False, False),
        (2.0, 2e-4, True, False, 2, True, False, True),
    ],
)
def test_compiled_feed_forward_equals_the_numpy_reference(park_time, creep, clock, dithered,
                                                          delay, capped, pushed,
                                                          zoned):  # fmt: skip
    """10 000 periods (rest, park, creep, starts, stops, a push or none, limits): same torques."""
    parameters = DitherParameters(park_time=park_time, creep=creep) if dithered else None
    zone = 0.3 if zoned else None
    compiled = _feed_forward_run(parameters, clock, True, delay, capped, pushed, zone, zoned)
    reference = _feed_forward_run(parameters, clock, False, delay, capped, pushed, zone, zoned)
    if zoned:  # the zones take some compensation away, not all
        whole = _feed_forward_run(parameters, clock, False, delay, capped, pushed, None, True)
        moving = np.abs(whole[:, :7]) > 1e-9
        lower = np.abs(reference[:, :7]) < np.abs(whole[:, :7]) - 1e-9
        assert 0.02 < np.mean(lower[moving]) < 0.5
    if capped:  # the ceiling binds in some periods, not in all
        free = _feed_forward_run(parameters, clock, False, delay, False)
        moving = np.abs(free[:, :7]) > 1e-9
        lower = np.abs(reference[:, :7]) < np.abs(free[:, :7]) - 1e-9
        assert 0.05 < np.mean(lower[moving]) < 0.95
    if dithered:
        assert 0.05 < np.mean(reference[:, 21:28]) < 0.95  # both decisions are taken
        assert reference[:, 28].any() == (park_time is not None)  # every joint parked
        assert reference[:, 29:36].any() == (creep is not None)  # a joint that crept
    compensating = np.abs(reference[:, :7]) > 1e-9
    assert 0.05 < np.mean(compensating) < 0.95  # both sides of the dead-band
    np.testing.assert_allclose(compiled, reference, rtol=1e-12, atol=1e-12, equal_nan=True)


def test_compiled_friction_terms_equal_sigmoid_terms():
    """Random (q̇, q) with NaN, beyond the span, cable and plain models: equal to 1e-12."""
    robot = lt.robots.yumi()
    rng = np.random.default_rng(23)
    for friction in (lt.FrictionModel.from_robot(robot), _cable(robot)):
        out = np.zeros((4, 7))
        for k in range(5000):
            qd = rng.normal(0.0, (1e-3, 0.05, 2.0)[k % 3], 7)
            q = rng.uniform(robot.q_min - 1.0, robot.q_max + 1.0)
            if k % 50 == 0:
                (qd if k % 100 else q)[k % 7] = np.nan
            expected = np.array(friction.sigmoid_terms(qd.copy(), q.copy()))
            np.testing.assert_allclose(friction.terms_into(qd, q, out), expected, rtol=1e-12,
                                       atol=1e-12, equal_nan=True)  # fmt: skip


@pytest.mark.parametrize("case", [name for name in CASES if not name.startswith("twin")])
def test_steps_with_the_numpy_law_equal_the_compiled_one(case, monkeypatch):
    """Whole steps (modes, calibration, constraints, a fault, the Panda): equal to 1e-12."""
    compiled = CASES[case]()
    for component in (ActiveLaw, PassiveFeedForward, MomentumObserver):
        monkeypatch.setattr(component, "compiled", False)
    np.testing.assert_allclose(compiled, CASES[case](), rtol=1e-12, atol=1e-12, equal_nan=True)
