"""The linearised coupled loop of active lead-through with a hand (experiments.stability)."""

from dataclasses import replace

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.control.tracking import loop_damping
from leadthrough.experiments.stability import (
    MARGIN,
    JointLoop,
    joint_loops,
    least_damping,
    loop_matrix,
    stability_map,
    worst_damping,
)

DT = 0.004


def test_without_control_the_loop_is_the_hand_spring_on_the_arm():
    """No PD: the arm's modes are the roots of m s² + b s + k = 0 (exactly discretised)."""
    m, k, b = 0.3, 120.0, 1.5
    parameters = LeadThroughParameters(position_bandwidth=0.0, velocity_time=1e12)
    matrix = loop_matrix(JointLoop(m, k, b, (0.3, 10.0)), parameters, DT, delay=1)
    expected = np.exp(np.roots([m, b, k]) * DT)
    eigenvalues = np.linalg.eigvals(matrix)
    for mode in expected:
        assert np.min(np.abs(eigenvalues - mode)) < 1e-9
    s = np.roots([m, b, k])
    assert least_damping(matrix, DT) <= float(-s.real[0] / abs(s[0])) + 1e-9


@pytest.fixture(scope="module")
def yumi_map():
    """The stable region of the YuMi at home, delays 1 and 2."""
    return stability_map(lt.robots.yumi(), stiffness=np.array([100.0, 300.0, 1000.0, 3000.0]),
                         inertia_scale=np.array([0.3, 1.0, 2.0]))  # fmt: skip


def test_the_defaults_keep_every_hand_up_to_3000_n_per_m_damped(yumi_map):
    """k_M = 2 keeps ζ ≥ 0.15 for hands up to 3000 N/m with one or two periods of delay."""
    assert LeadThroughParameters().inertia_scale in yumi_map.stable_scales(3000.0)
    assert np.all(yumi_map.damping[:, -1, :] >= MARGIN)


def test_an_admittance_lighter_than_the_arm_oscillates_with_a_firm_hand(yumi_map):
    """k_M = 0.3 (the previous default) has a growing oscillation with a 3000 N/m hand."""
    assert np.all(yumi_map.damping[:, 0, -1] < 0.0)
    assert 0.3 not in yumi_map.stable_scales(3000.0, margin=0.0)


def test_more_delay_never_helps():
    """Two periods of delay leave at most the damping one period leaves."""
    robot, parameters = lt.robots.yumi(), LeadThroughParameters(inertia_scale=0.5)
    for hand in (300.0, 3000.0):
        one = worst_damping(robot, parameters, hand, 1.8 * np.sqrt(hand), DT, delay=1)
        two = worst_damping(robot, parameters, hand, 1.8 * np.sqrt(hand), DT, delay=2)
        assert two <= one + 1e-9


def test_the_unwinding_counts_where_it_costs_damping():
    """Always on, the unwinding lowers the wrist loop's ζ with a firm hand, not below the margin.

    Joint 5 at home, 3000 N/m: 0.32 without, 0.19 with it always on. The map takes the
    smaller ζ of the loop with and without it (it acts only while a joint lags);
    relaxing the reference towards the joint ten times faster than the velocity loop
    would leave less than the margin.
    """
    robot, hand = lt.robots.yumi(), (3000.0, 1.8 * np.sqrt(3000.0))

    def wrist_damping(parameters):  # joint 5's loop, one period of delay
        loop = joint_loops(robot, parameters, *hand, DT)[4]
        return least_damping(loop_matrix(loop, parameters, DT, delay=1), DT)

    always, never = LeadThroughParameters(), LeadThroughParameters(unwind_time=None)
    assert MARGIN <= wrist_damping(always) < wrist_damping(never)
    fast = LeadThroughParameters(unwind_time=0.005)
    assert worst_damping(robot, fast, *hand, DT) < MARGIN


def test_a_hands_own_mass_the_model_does_not_know_keeps_the_margin():
    """The operator's hand and forearm (up to 3 kg at the tool) move with the arm.

    The model does not know that mass; the observer reads its inertial force as the
    operator's, which adds it to the virtual inertia as well as to the arm's. The defaults
    keep ζ ≥ the margin with every hand up to 3000 N/m; an admittance lighter than the arm
    (k_M = 0.3, unstable with a bare spring) gains damping from it, since the ratio of
    virtual to moved inertia comes closer to 1.
    """
    robot = lt.robots.yumi()

    def least(parameters, hand_mass):
        return min(worst_damping(robot, parameters, k, 1.8 * np.sqrt(k), DT, delay, hand_mass)
                   for k in (100.0, 300.0, 1000.0, 3000.0) for delay in (1, 2))  # fmt: skip

    assert least(LeadThroughParameters(), 3.0) >= MARGIN
    light = LeadThroughParameters(inertia_scale=0.3)
    assert least(light, 0.0) < 0.0 < least(light, 1.5) < least(light, 3.0)


@pytest.mark.filterwarnings("ignore::leadthrough.model.robots.AssumedDriveDataWarning")
def test_an_observer_slowed_by_friction_noise_costs_damping():
    """The observer's lag bound (``max_lag`` 20 ms, the defaults) buys damping.

    The UR10e's shoulder, whose friction noise would make its observer lag 52 ms, held by
    a firm hand.
    """
    ur10e, defaults = lt.robots.ur10e(), LeadThroughParameters()
    unbounded = LeadThroughParameters(
        **{**defaults.__dict__, "observer": replace(defaults.observer, max_lag=None)}
    )
    bounded, slow = (min(worst_damping(ur10e, p, 3000.0, 100.0, DT, delay) for delay in (1, 2))
                     for p in (defaults, unbounded))  # fmt: skip
    assert slow >= MARGIN  # the linear loop holds either way ...
    assert bounded > slow + 0.03  # ... but the lag costs a good share of its damping


def test_below_250_hz_the_velocity_loop_is_the_stiffest_that_keeps_the_most_damping():
    """``LeadThroughParameters.at_period`` against a scan of velocity times, per period.

    At 250 Hz and faster the settings are kept as they are. Slower, the active law's
    tracking loop, linearised (``tracking.loop_damping``), keeps the damping it has at 250
    Hz, or, where no velocity time keeps that, the most any of a fine scan keeps; no
    stiffer velocity loop keeps as much; and at 125 and 100 Hz that is clearly more than
    the 250 Hz gains leave.
    """
    p = LeadThroughParameters()
    for dt in (0.001, 0.002, 0.004):
        assert p.at_period(dt) is p

    def damping(velocity_time: float, dt: float) -> float:
        return loop_damping(p.tracking_gains(1.0 / velocity_time), dt)

    at_250_hz = damping(p.velocity_time, 0.004)
    times = np.linspace(p.velocity_time, 0.3, 501)
    for dt in (0.005, 0.008, 0.01):
        chosen = p.at_period(dt).velocity_time
        scanned = np.array([damping(t, dt) for t in times])
        target = min(at_250_hz, scanned.max())
        assert damping(chosen, dt) >= target - 2e-3
        assert np.all(scanned[times < chosen - 1e-3] < target)
        if dt >= 0.008:
            assert damping(chosen, dt) > damping(p.velocity_time, dt) + 0.05


def test_a_relaxed_hands_loop_keeps_its_250_hz_damping_at_slower_rates():
    """The coupled loop with a hand at 125 and 100 Hz, one and two periods of delay.

    With the 250 Hz gains a relaxed hand's loop (300 N/m) loses a fifth or more of the
    damping it has at 250 Hz; with the velocity loop and unwinding of :meth:`at_period`
    (what ``worst_damping`` and the controller use) it keeps it within 0.03, and the firm
    hand's loop keeps at least its 250 Hz damping (the margin either way).
    """
    robot, p = lt.robots.yumi(), LeadThroughParameters()

    def least(parameters: LeadThroughParameters, hand: float, dt: float) -> float:
        loops = joint_loops(robot, parameters, hand, 1.8 * np.sqrt(hand), dt)
        variants = (parameters, replace(parameters, unwind_time=None))
        return min(least_damping(loop_matrix(loop, variant, dt, delay), dt)
                   for loop in loops for variant in variants for delay in (1, 2))  # fmt: skip

    at_250_hz, firm_at_250_hz = least(p, 300.0, DT), least(p, 3000.0, DT)
    for dt in (0.008, 0.01):
        assert least(p, 300.0, dt) < 0.8 * at_250_hz
        assert least(p.at_period(dt), 300.0, dt) >= at_250_hz - 0.03
        assert least(p.at_period(dt), 3000.0, dt) >= firm_at_250_hz >= MARGIN
        assert min(worst_damping(robot, p, 3000.0, 100.0, dt, delay) for delay in (1, 2)) >= MARGIN


def test_the_controller_runs_the_velocity_loop_of_its_period():
    """The active law takes the softened velocity loop; the parameters given stay as given."""
    robot, p = lt.robots.yumi(), LeadThroughParameters()
    for dt in (0.004, 0.01):
        controller = lt.LeadThrough(robot, mode="active", dt=dt)
        assert controller.parameters.velocity_time == p.velocity_time
        assert controller.law.parameters.velocity_time == p.at_period(dt).velocity_time
        assert controller.law.parameters.unwind_time == p.at_period(dt).unwind_time
    assert p.at_period(0.01).velocity_time > 2.0 * p.velocity_time


def test_the_unwinding_keeps_its_ratio_to_the_velocity_loop():
    """The push the PD stores against a stuck joint, ~ unwind / velocity time, is kept.

    A lead the admittance builds against a joint that does not follow relaxes over
    ``unwind_time``, and the PD pushes it with ``K_D = m / velocity_time``: the ratio of the
    two is what a lagging joint gets. None (the thesis) stays None.
    """
    p = LeadThroughParameters(unwind_time=0.03)
    for dt in (0.005, 0.008, 0.01):
        slow = p.at_period(dt)
        assert slow.velocity_time > p.velocity_time
        assert slow.unwind_time / slow.velocity_time == pytest.approx(0.03 / 0.05, rel=1e-12)
    assert LeadThroughParameters(unwind_time=None).at_period(0.01).unwind_time is None


def test_damping_control_keeps_its_velocity_loop_at_every_rate():
    """Without position feedback there is no best velocity loop to soften to.

    Its loop's least damping ratio (finite: the resting mode at λ = 1 is left out) keeps
    rising as the loop softens, up to seconds at 50 Hz, so ``at_period`` leaves it alone.
    """
    p = LeadThroughParameters.damping_control()
    ratios = [loop_damping(p.tracking_gains(1.0 / t), 0.01) for t in (0.05, 0.2, 0.4)]
    assert np.all(np.isfinite(ratios)) and ratios[0] < ratios[1] < ratios[2]
    for dt in (0.008, 0.01, 0.02):
        assert p.at_period(dt) is p
