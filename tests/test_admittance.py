"""The admittance core (thesis §6.2): virtual system, dead-zone, bounds, operator weight.

And the rules of the active law around it (:class:`~leadthrough.control.active_law.ActiveLaw`:
the learned bias, the speed cap, the end-stop reaction, the limit zone, the push's average),
each on a few periods of the law alone, compiled and NumPy.
"""

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.active_law import ActiveLaw
from leadthrough.control.admittance import (
    AdmittanceState,
    admittance_step,
    braking_cap,
    damping_weight,
    dead_zone,
    keep_within,
    motion_sign,
    operator_weight,
    reanchored,
    relieved_margin,
    settled_reference,
    unwound,
    virtual_damping,
)

DT = 0.004
MASS = np.array([[2.0, 0.3], [0.3, 0.5]])  # symmetric positive definite [kg m²]


def test_undamped_step_is_newtons_law_on_the_virtual_inertia():
    """D̃ = 0: q̇_ref grows by dt (k_M M)⁻¹ τ, q_ref by dt q̇_ref⁺."""
    state = AdmittanceState(np.array([0.1, -0.2]), np.array([0.05, 0.0]))
    tau = np.array([1.0, -0.5])
    after = admittance_step(state, tau, MASS, 0.3, np.zeros((2, 2)), DT)
    expected = state.qd_ref + DT * np.linalg.solve(0.3 * MASS, tau)
    np.testing.assert_allclose(after.qd_ref, expected, rtol=1e-12)
    np.testing.assert_allclose(after.q_ref, state.q_ref + DT * expected, rtol=1e-12)


@pytest.mark.parametrize("damping", [0.5, 50.0, 5e4])
def test_constant_torque_settles_at_the_damped_speed_for_any_damping(damping):
    """Implicit in D̃: stable however stiff, converging to q̇ = D̃⁻¹ τ without overshoot."""
    state, tau = AdmittanceState(np.zeros(2), np.zeros(2)), np.array([1.0, 1.0])
    speeds = []
    for _ in range(20000):
        state = admittance_step(state, tau, MASS, 0.3, np.diag(np.full(2, damping)), DT)
        speeds.append(state.qd_ref.copy())
    np.testing.assert_allclose(state.qd_ref, tau / damping, rtol=1e-3)
    assert np.max(np.abs(speeds)) <= np.max(tau / damping) * (1 + 1e-9) + 1e-12


def test_dead_zone_removes_the_width_and_an_offset_only_widens_it():
    """sign(x)·max(|x| − w, 0); a bias widens its own side, never creates a reading."""
    x = np.array([-3.0, -1.0, 0.5, 1.0, 3.0])
    np.testing.assert_allclose(dead_zone(x, 1.0), [-2.0, 0.0, 0.0, 0.0, 2.0])
    np.testing.assert_allclose(dead_zone(x, 1.0, 1.5), [-2.0, 0.0, 0.0, 0.0, 0.5])
    assert np.all(dead_zone(np.zeros(3), 0.1, np.array([-5.0, 0.0, 5.0])) == 0.0)


def test_relieved_margin_keeps_a_reading_up_to_the_margin_drag_and_passes_a_large_push():
    """The relieved friction margin, along the motion, both signs of motion alike.

    A reading ≤ the margin keeps the whole margin (it reads as drag, so a released arm
    still stops on friction overstated by up to the margin); above it the kept part is
    margin² / a, continuous at a = margin, → 0 for a large push; a reading against the
    motion keeps the whole margin (more drag).
    """
    margin = np.array([0.2, 0.2, 0.2, 0.2, 0.2, -0.2, -0.2, -0.2, 0.0])
    reading = np.array([-0.5, 0.1, 0.2, 0.4, 20.0, -0.4, 0.5, -0.1, 0.3])
    kept = relieved_margin(reading, margin)
    np.testing.assert_allclose(kept, [0.2, 0.2, 0.2, 0.1, 0.002, -0.1, -0.2, -0.2, 0.0])
    residual = reading - kept
    assert np.all(residual[:3] <= 0.0)  # no reading up to the margin becomes a push
    assert np.all(residual[6:8] >= 0.0)  # nor with the motion the other way
    assert residual[4] == pytest.approx(20.0 - 0.002)
    just_above = relieved_margin(np.array([0.2 + 1e-9]), np.array([0.2]))
    assert just_above[0] == pytest.approx(0.2, abs=1e-8)  # no step at the margin
    a = np.linspace(0.0, 2.0, 2001)  # the drive never falls as the reading grows
    assert np.all(np.diff(a - relieved_margin(a, np.full_like(a, 0.2))) >= 0.0)


def test_references_stop_at_the_bounds():
    """Clamped into [low, high]; the velocity stops only where it pushes outwards."""
    state = AdmittanceState(np.array([1.2, -1.2, 0.0]), np.array([0.3, 0.3, -0.3]))
    kept = keep_within(state, np.full(3, -1.0), np.full(3, 1.0))
    np.testing.assert_allclose(kept.q_ref, [1.0, -1.0, 0.0])
    np.testing.assert_allclose(kept.qd_ref, [0.0, 0.3, -0.3])


def test_braking_cap_stops_a_reference_at_its_bound_at_constant_deceleration():
    """Integrated at the cap, a reference brakes within ``zone`` and stops at the bound.

    The deceleration stays within 10 % (the discretisation) of cap² / (2 zone) until the
    last periods (discrete steps down from below 5 % of the cap),
    the bound is reached, and away from the bound only the cap acts.
    """
    cap, zone, dt, high = np.array([2.0]), 0.2, 0.001, np.array([1.0])
    low = np.array([-1.0])
    q, v, speeds = np.array([0.0]), np.array([0.0]), []
    for _ in range(3000):
        v = braking_cap(q, np.array([10.0]), low, high, cap, zone)  # always pushed on
        q = np.minimum(q + dt * v, high)  # the law's keep_within
        speeds.append(v[0])
    speeds = np.array(speeds)
    assert q[0] == high[0] and speeds[-1] == 0.0
    deceleration = -np.diff(speeds) / dt
    braking = speeds[:-1] > 0.05 * cap[0]  # the last periods stop from below 5 % of the cap
    assert np.max(deceleration[braking]) <= cap[0] ** 2 / (2 * zone) * 1.1
    assert speeds[0] == cap[0]  # far from the bound: only the cap
    away = braking_cap(high, np.array([-10.0]), low, high, cap, zone)
    np.testing.assert_allclose(away, -cap)  # leaving the bound is not braked


def test_operator_weight_is_smooth_monotone_and_never_amplifies():
    """The passed torque w·r is continuous, odd, monotone, slope ≤ 1.3; half passes at the knee."""
    sigma = np.full(4001, 0.5)
    residual = np.linspace(-5.0, 5.0, 4001)
    passed = residual * operator_weight(residual, sigma, 0.2)
    slope = np.diff(passed) / np.diff(residual)
    assert np.all(slope >= 0.0) and np.all(slope <= 1.3)
    np.testing.assert_allclose(passed, -passed[::-1], atol=1e-12)
    np.testing.assert_allclose(operator_weight(np.array([0.1]), np.array([0.5]), 0.2), [0.5])


def test_operator_weight_silences_what_the_model_may_read_and_passes_a_real_push():
    """Inside the model's uncertainty almost nothing passes; ten times outside almost all."""
    sigma = np.array([1.0, 1.0])
    weight = operator_weight(np.array([0.01, 1.0]), sigma, 0.1)
    assert weight[0] < 0.01 and weight[1] > 0.99
    assert np.all(operator_weight(np.array([3.0, -2.0]), sigma, 0.0) == 1.0)


def test_virtual_damping_rises_smoothly_where_nobody_pushes():
    """m_ii/T on a pushed joint, (1 + B) m_ii/T on one with weight 0, monotone in between."""
    mass = np.array([[2.0, 0.3, 0.1], [0.3, 0.5, 0.05], [0.1, 0.05, 1.0]])
    damping = virtual_damping(mass, 0.25, 5.0, np.array([1.0, 0.0, 0.5]))
    np.testing.assert_allclose(np.diag(damping), [2.0 / 0.25, 6.0 * 0.5 / 0.25, 6.0 / 3.5 / 0.25])
    np.testing.assert_allclose(damping, damping.T)  # symmetric
    assert np.all(np.linalg.eigvalsh(damping) > 0.0)  # and positive definite: it dissipates
    weights = np.linspace(0.0, 1.0, 101)
    diagonal = [virtual_damping(np.eye(1), 0.25, 5.0, np.array([w]))[0, 0] for w in weights]
    assert np.all(np.diff(diagonal) < 0.0)


def test_pushed_everywhere_the_damping_is_the_arms_inertia_over_its_time():
    """Every weight 1: D̃ = M / T, so a steady torque settles at q̇ = T M⁻¹ τ.

    On the YuMi at home a force at the tool then moves the tool at T J M⁻¹ Jᵀ F, the
    arm's own mobility there (a diagonal m_ii / T would give T J diag(M)⁻¹ Jᵀ F).
    """
    robot = lt.robots.yumi()
    dynamics = lt.Dynamics(robot)
    q = robot.home()
    mass, jacobian = dynamics.mass(q), dynamics.jacobian(q)[:3]
    damping = virtual_damping(mass, 0.5, 20.0, np.ones(robot.n_joints))
    np.testing.assert_allclose(damping, mass / 0.5, rtol=1e-12)
    force = np.array([0.0, 0.0, 5.0])  # [N], upwards
    state = AdmittanceState(q.copy(), np.zeros(robot.n_joints))
    for _ in range(5000):  # 20 s, 20 time constants of k_M T = 1 s
        state = admittance_step(state, jacobian.T @ force, mass, 2.0, damping, DT)
    mobility = jacobian @ np.linalg.solve(mass, jacobian.T)
    np.testing.assert_allclose(jacobian @ state.qd_ref, 0.5 * mobility @ force, rtol=1e-6)


def test_damping_weight_counts_the_push_that_starts_or_sustains_a_motion():
    """At rest the whole residual counts; moving, only its average along the motion.

    A residual against the motion (the operator braking, or friction the model
    overstates, read as drag once nobody holds the arm) weighs nothing, so the damping
    rises and the joint stops; one along it weighs as the operator weight does.
    """
    sigma, knee = np.full(3, 0.2), 0.5
    residual = np.array([0.5, 0.5, -0.5])
    moving = motion_sign(np.array([0.0, 0.3, 0.3]), 0.01)  # at rest, moving, moving
    sustained = residual * moving  # held that long: the average is the residual along it
    weight = damping_weight(residual, sustained, moving, sigma, knee)
    operator = operator_weight(residual, sigma, knee)
    np.testing.assert_allclose(weight[:2], operator[:2], rtol=1e-3)
    assert operator[2] > 0.9 and weight[2] < 0.01


def test_damping_weight_has_no_step_as_a_joint_starts_or_the_push_turns():
    """Continuous in the reference velocity and in the averaged push: nothing switches."""
    sigma, knee = np.full(2001, 0.2), 0.5
    speed = np.linspace(-0.1, 0.1, 2001)
    residual = np.full(2001, 0.4)
    moving = motion_sign(speed, 0.01)
    weight = damping_weight(residual, residual * moving, moving, sigma, knee)
    assert np.max(np.abs(np.diff(weight))) < 0.01
    sustained = np.linspace(-1.0, 1.0, 2001)
    weight = damping_weight(residual, sustained, np.ones(2001) * 0.999, sigma, knee)
    assert np.all(np.diff(weight) >= 0.0) and np.max(np.diff(weight)) < 0.01


def test_a_resting_joint_nobody_pushes_draws_its_reference_to_where_it_is():
    """Joints 10 mrad short of their reference: only the one at rest with no push follows.

    At rest with no push the error decays as (1 − rate)^k; a joint the operator pushes
    (weight → 1) or whose admittance moves keeps its reference: the spring then holds
    what the operator put in.
    """
    q = np.zeros(3)
    moving = motion_sign(np.array([0.0, 0.0, 0.3]), 0.01)  # at rest, at rest, moving
    weight = np.array([0.0, 0.99, 0.0])  # nobody pushes, pushed, nobody pushes
    rate = DT / (0.3 + DT)
    q_ref = np.full(3, 0.01)
    for _ in range(375):  # 1.5 s
        q_ref = settled_reference(q_ref, q, moving, weight, rate)
    np.testing.assert_allclose(q_ref[0], 0.01 * (1.0 - rate) ** 375, rtol=1e-12)
    assert q_ref[0] < 1e-4 and q_ref[1] > 0.0095 and q_ref[2] > 0.009


def test_a_joint_that_moves_on_its_own_keeps_its_reference():
    """Nothing drives the admittance, but the joint moves (a gravity error it cannot hold).

    Drawn after such a joint, the reference would turn a steady error into a steady drift
    (as found: a Panda's released joint 3 crept 186 mrad in 10 s at 0.02 rad/s); kept,
    the tracking spring builds until it holds the joint. Over 1 s at 0.02 rad/s the
    reference follows less than a quarter of the way; as found, more than half.
    """
    rate, speed, rest = DT / (0.3 + DT), 0.02, 0.01
    kept = found = 0.0
    for k in range(1, 251):  # 1 s
        q = np.array([speed * DT * k])
        own = motion_sign(np.array([speed]), rest)
        kept = settled_reference(np.array([kept]), q, np.zeros(1), np.zeros(1), rate, own)[0]
        found = settled_reference(np.array([found]), q, np.zeros(1), np.zeros(1), rate)[0]
    assert kept < 0.25 * q[0] and found > 0.5 * q[0]


def test_settled_reference_has_no_step_in_speed_or_weight():
    """Continuous in the reference velocity and the weight: it cannot chatter."""
    moving = motion_sign(np.linspace(-0.05, 0.05, 2001), 0.01)
    q_ref = settled_reference(np.full(2001, 0.01), np.zeros(2001), moving, np.zeros(2001), 0.04)
    assert np.max(np.abs(np.diff(q_ref))) < 1e-5
    weight = np.linspace(0.0, 1.0, 2001)
    q_ref = settled_reference(np.full(2001, 0.01), np.zeros(2001), np.zeros(2001), weight, 0.04)
    assert np.all(np.diff(q_ref) > 0.0)


def test_a_lost_reference_slows_to_a_lagging_joint_and_never_follows_one_that_runs():
    """Re-anchored: position to the joint; velocity to it only where it lags behind.

    Joints (reference velocity → joint velocity): stuck (0.2 → 0), lagging (0.2 → 0.1),
    running ahead (0.2 → 0.5), running against (−0.2 → 0.3), and one still tracked.
    """
    references = AdmittanceState(np.zeros(5), np.array([0.2, 0.2, 0.2, -0.2, 0.2]))
    q = np.array([0.1, 0.1, 0.1, 0.1, 0.01])
    qd = np.array([0.0, 0.1, 0.5, 0.3, 0.5])
    lost = np.abs(q) > 0.05
    result = reanchored(references, q, qd, lost)
    np.testing.assert_array_equal(result.q_ref, [0.1, 0.1, 0.1, 0.1, 0.0])
    np.testing.assert_array_equal(result.qd_ref, [0.0, 0.1, 0.2, -0.2, 0.2])


def test_a_lagging_joints_reference_relaxes_to_it_at_the_unwinding_rate():
    """Unwound: q̇_ref → q̇ as (1 − rate)^k where the joint lags; untouched elsewhere.

    Joints (reference velocity → joint velocity): stuck (0.2 → 0), lagging (−0.2 →
    −0.1), running ahead (0.2 → 0.5), running against (−0.2 → 0.3), at rest (0 → 0.1).
    The lagging ones never overshoot the joint's velocity nor change sign.
    """
    qd_ref = np.array([0.2, -0.2, 0.2, -0.2, 0.0])
    qd = np.array([0.0, -0.1, 0.5, 0.3, 0.1])
    rate, periods = 0.074, 40  # dt / (unwind_time + dt) with 0.004 / 0.05
    history = [qd_ref]
    for _ in range(periods):
        history.append(unwound(history[-1], qd, rate))
    decay = (1.0 - rate) ** periods
    expected = [0.2 * decay, -0.1 - 0.1 * decay, 0.2, -0.2, 0.0]
    np.testing.assert_allclose(history[-1], expected, rtol=1e-12, atol=1e-15)
    history = np.array(history)
    assert np.all(np.sign(history[:, :2]) == np.sign(qd_ref[:2]))
    assert np.all(np.abs(history[:, 1]) >= 0.1)


# --- the active law's rules, a few periods of the law alone ---------------------------------

YUMI = lt.robots.yumi()
HOME = YUMI.home()
YUMI_MASS = lt.Dynamics(YUMI).mass(HOME)
N = YUMI.n_joints


def _active_law(compiled, **changes):
    """The YuMi's active law on the nominal friction model, compiled or the NumPy reference."""
    law = ActiveLaw(YUMI, lt.LeadThroughParameters(**changes), DT,
                    lt.FrictionModel.from_robot(YUMI))  # fmt: skip
    law.compiled = compiled
    return law


def _in_the_limit_zone():
    """Home, with joint 7 half a limit zone (0.1 rad) from its upper limit [rad]."""
    q = HOME.copy()
    q[6] = YUMI.q_max[6] - 0.1
    return q


def _track(law, q, qd, push, periods=1):
    """``periods`` of the admittance driven by ``push`` [Nm] (drive and residual alike)."""
    zeros = np.zeros(N)
    for _ in range(periods):
        law.drive[:], law.residual[:], law.uncertainty[:] = push, push, 0.1
        law.tracking(q, qd, zeros, YUMI_MASS)
    return law.references


@pytest.mark.parametrize("compiled", [True, False])
def test_the_admittance_never_asks_a_joint_for_more_than_its_share_of_the_speed_limit(compiled):
    """What the speed cap prevents: a hard push asking any speed of the references.

    A 50 Nm push on every joint, each joint following its reference, asks within 0.1 s for
    far more than ``assist_speed_fraction`` (0.3) of the joint's speed limit; the
    references stop at it.
    """
    law = _active_law(compiled)
    law.references = AdmittanceState(HOME.copy(), np.zeros(N))
    for _ in range(25):
        references = law.references
        _track(law, references.q_ref.copy(), references.qd_ref.copy(), 50.0)
    cap = 0.3 * YUMI.velocity_limits
    np.testing.assert_allclose(law.references.qd_ref, cap, rtol=1e-12)


@pytest.mark.parametrize("compiled", [True, False])
def test_near_a_limit_a_torque_away_from_it_is_the_end_stops_reaction(compiled):
    """What the end-stop reaction prevents: an arm thrown out of its stop by the stop's push.

    Joint 7 inside its limit zone reads 2 Nm away from the limit (an end-stop pushes back
    on a joint pressed into it, thesis §6.3.2): the references stay where the joint is;
    the same torque clear of the limits moves them.
    """
    q, torque, zeros = _in_the_limit_zone(), np.zeros(N), np.zeros(N)
    torque[6] = -2.0
    law = _active_law(compiled)
    law.references = AdmittanceState(q.copy(), zeros.copy())
    references = _track(law, q, zeros, torque, periods=5)
    assert references.qd_ref[6] == 0.0 and references.q_ref[6] == q[6]
    assert law.feedback[6] == 0.0
    clear = _active_law(compiled)
    clear.references = AdmittanceState(HOME.copy(), zeros.copy())
    assert _track(clear, HOME, zeros, torque, periods=5).qd_ref[6] < -0.1  # free: it moves


@pytest.mark.parametrize("compiled", [True, False])
def test_a_joint_inside_the_limit_zone_is_held_where_it_is_not_pulled_out(compiled):
    """What the bounds widened to the joint prevent: the PD pulling a joint out of the zone.

    Joint 7 rests 0.1 rad inside its limit zone (put there by the hand or the supervisor's
    wall), nothing pushes: its reference stays at the joint and the PD sends nothing.
    Clamped to the zone's edge instead, the reference would be 0.1 rad off and the PD
    would pull the joint out (keeping it out of the zone is the supervisor's soft wall).
    """
    q, zeros = _in_the_limit_zone(), np.zeros(N)
    law = _active_law(compiled)
    law.references = AdmittanceState(q.copy(), zeros.copy())
    references = _track(law, q, zeros, zeros)
    assert references.q_ref[6] == q[6] and law.feedback[6] == 0.0


@pytest.mark.parametrize("compiled", [True, False])
def test_a_stiff_hands_oscillation_does_not_modulate_the_damping(compiled):
    """What the push's average over ``push_time`` prevents: damping that swings with a hand.

    Every joint moves at 0.2 rad/s under a push of 0.8 Nm along the motion with a 5 Hz
    oscillation of ±1 Nm on top (a stiff hand: the push turns against the motion every
    other 0.1 s). Averaged over ``push_time`` the push sustains the motion throughout,
    so the damping weight stays near 1; taken sample by sample (``push_time`` → 0) it
    falls to 0 on every half-wave against the motion, and the damping rises 21-fold there.
    """
    weights = {}
    for push_time in (0.1, 1e-6):
        law, lows = _active_law(compiled, push_time=push_time), []
        for k in range(250):  # 1 s: five periods of the oscillation
            law.references = AdmittanceState(HOME.copy(), np.full(N, 0.2))
            _track(law, HOME, np.full(N, 0.2), 0.8 + (1.0 if (k // 25) % 2 == 0 else -1.0))
            lows.append(np.min(law.damping_weight))
        weights[push_time] = min(lows[100:])  # after the first 0.4 s
    assert weights[0.1] > 0.95 and weights[1e-6] < 0.01


@pytest.mark.parametrize("compiled", [True, False])
def test_the_learned_bias_never_exceeds_twice_the_plausible_model_error(compiled):
    """What the bias' bound prevents: a push held still learned as model error.

    A steady 10 Nm on every joint, learned at the full rate (as if nobody guided: the
    weights zeroed every period) for 8 learning times: the bias stops at twice the model
    error plausible there (the friction tolerance, gravity zero here), and the rest of the
    push still reads as one. Unbounded, the bias would take the whole push.
    """
    law, zeros = _active_law(compiled), np.zeros(N)
    estimate = np.full(N, 10.0)
    for _ in range(2000):
        law.weight[:] = 0.0
        law.operator_torque(estimate, HOME, zeros, zeros)
    bound = 2.0 * law._friction_tolerance
    np.testing.assert_allclose(law.model_error.bias, bound, rtol=1e-12)
    np.testing.assert_allclose(law.residual, estimate - bound, rtol=1e-12)


@pytest.mark.parametrize("compiled", [True, False])
def test_the_bias_learns_nothing_of_a_push_the_law_passes(compiled):
    """What learning only as fast as nobody guides prevents: the assist fading under a push.

    A steady push of twice the resting Coulomb band on every joint passes (weight 0.92);
    over 1 s the bias takes 1 % of it. Learned at the full rate it would take a third or
    more (up to its bound) within the second, and the assist with it.
    """
    law, zeros = _active_law(compiled), np.zeros(N)
    estimate = 2.0 * law.friction.coulomb_uncertainty(zeros, HOME)
    for _ in range(250):
        law.operator_torque(estimate, HOME, zeros, zeros)
    assert np.all(law.weight > 0.9)
    assert np.all(np.abs(law.model_error.bias) < 0.02 * estimate)


@pytest.mark.parametrize("compiled", [True, False])
def test_the_bias_learns_nothing_while_a_joint_is_in_its_limit_zone(compiled):
    """What pausing the learning near a limit prevents: a stop's reaction learned as model error.

    A small steady reading (0.3 of the friction tolerance, weight ≈ 0.05) is learned
    clear of the limits (60 % within 1 s); with joint 7 in its limit zone, where a joint
    may rest against its stop, none of it is.
    """
    zeros = np.zeros(N)
    learned = {}
    for name, q in (("clear", HOME), ("in the zone", _in_the_limit_zone())):
        law = _active_law(compiled)
        estimate = 0.3 * law._friction_tolerance
        for _ in range(250):
            law.operator_torque(estimate, q, zeros, zeros)
        learned[name] = law.model_error.bias / estimate
    assert np.all(learned["clear"] > 0.5)
    assert np.all(learned["in the zone"] == 0.0)


@pytest.mark.parametrize("compiled", [True, False])
def test_only_a_joint_that_slides_vouches_for_its_gravity_model(compiled):
    """What growing the confidence only where a joint slides prevents: a rest trusted.

    Nobody guiding for 10 s (ten learning times at rest), the bias takes what the readings
    show, but every joint's gravity tolerance stays the whole model's
    (``gravity_uncertainty · |G|``, within the 0.1 % of sliding the friction model's
    sigmoid leaves at rest): stiction may hold its error unseen there. Sliding
    unguided for as long (a released arm coasting; here joints 1–3 only), those joints'
    confidence reaches 1 and their tolerance the change of G since; the resting ones keep
    theirs. Vouched for at rest, the tolerance narrowed to the change of G on every joint.
    """
    gravity, reading = np.linspace(2.0, 8.0, N), np.full(N, 0.01)
    sliding_speed = np.where(np.arange(N) < 3, 0.05, 0.0)  # rad/s, above rest_velocity
    whole = lt.LeadThroughParameters().gravity_uncertainty * gravity
    for qd in (np.zeros(N), sliding_speed):
        law = _active_law(compiled)
        for _ in range(2500):
            law.weight[:] = 0.0  # nobody guides
            law.operator_torque(reading, HOME, qd, gravity)
        tolerance = law.model_error.tolerance(gravity)
        np.testing.assert_allclose(law.model_error.bias, reading, rtol=1e-3)
        slid = np.abs(qd) > 0.0
        np.testing.assert_allclose(tolerance[~slid], whole[~slid], rtol=0.01)
        np.testing.assert_allclose(tolerance[slid], 0.0, atol=1e-3 * whole.max())
