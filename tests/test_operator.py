"""Simulated operators: spring–damper laws, force limits, passivity, single-joint actions."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from leadthrough.errors import InputShapeError
from leadthrough.twin.errors import OperatorError
from leadthrough.twin.operator import (
    Hand,
    HandParameters,
    JointHand,
    NoOperator,
    Operator,
    TorqueProfile,
    TorqueSegment,
    pulse,
    ramp,
    step,
)
from leadthrough.twin.paths import JointMinimumJerk, Line, MinimumJerk

RNG_SEED = 7


def pose(position, rotation=None):
    """A 4×4 world pose of the flange (identity rotation by default)."""
    matrix = np.eye(4)
    matrix[:3, :3] = np.eye(3) if rotation is None else rotation
    matrix[:3, 3] = position
    return matrix


def reach() -> MinimumJerk:
    """A 0.4 m reach over 2 s."""
    return MinimumJerk([0.4, 0.0, 0.3], [0.4, 0.4, 0.3], 2.0)


def test_nobody_touching_applies_nothing():
    """The base operator applies a zero wrench and zero joint torques of the right size."""
    for operator in (Operator(), NoOperator()):
        np.testing.assert_array_equal(operator.wrench(1.0, np.eye(4), np.ones(6)), np.zeros(6))
        np.testing.assert_array_equal(operator.joint_torque(1.0, np.ones(7), np.ones(7)), 0.0)
        assert operator.joint_torque(0.0, np.ones(7), np.ones(7)).shape == (7,)


def test_hand_force_is_a_spring_toward_the_reference():
    """At rest with a small error the force is K·(p_ref − p): toward the reference, |f| = K|e|."""
    rng = np.random.default_rng(RNG_SEED)
    hand = Hand(reach(), stiffness=250.0)
    goal = reach().goal
    for _ in range(20):
        error = rng.normal(size=3) * 0.02
        force = hand.wrench(5.0, pose(goal - error), np.zeros(6))[:3]
        assert np.linalg.norm(force) < hand.parameters.max_force
        np.testing.assert_allclose(force, 250.0 * error, rtol=1e-12)


def test_hand_feeds_the_reference_velocity_through():
    """A flange exactly on the moving reference feels no force, and one at rest is pulled along."""
    path = reach()
    hand = Hand(path)
    on_path = hand.wrench(1.0, pose(path.position(1.0)), np.r_[path.velocity(1.0), 0, 0, 0])
    np.testing.assert_allclose(on_path, 0.0, atol=1e-12)
    at_rest = hand.wrench(1.0, pose(path.position(1.0)), np.zeros(6))[:3]
    np.testing.assert_allclose(at_rest, 20.0 * path.velocity(1.0), rtol=1e-12)


def test_hand_force_never_exceeds_max_force_and_keeps_its_direction():
    """On random seeded states |f| <= max_force, and saturation only scales the linear law."""
    rng = np.random.default_rng(RNG_SEED)
    path = reach()
    hand = Hand(path, stiffness=800.0, damping=40.0, max_force=45.0)
    for _ in range(200):
        t, position, velocity = rng.uniform(-1, 3), rng.normal(size=3), rng.normal(size=3)
        force = hand.wrench(t, pose(position), np.r_[velocity, 0, 0, 0])[:3]
        linear = 800.0 * (path.position(t) - position) + 40.0 * (path.velocity(t) - velocity)
        assert np.linalg.norm(force) <= 45.0 * (1 + 1e-12)
        np.testing.assert_allclose(np.cross(force, linear), 0.0, atol=1e-9 * np.linalg.norm(linear))
        assert force @ linear > 0.0


def test_hand_damping_dissipates_power():
    """On the reference position, damping does non-positive work on the relative motion."""
    rng = np.random.default_rng(RNG_SEED)
    path = reach()
    hand = Hand(path, stiffness=300.0, damping=25.0, max_force=30.0)
    for _ in range(200):
        t, velocity = rng.uniform(0, 2), rng.normal(size=3) * rng.uniform(0.01, 5.0)
        force = hand.wrench(t, pose(path.position(t)), np.r_[velocity, 0, 0, 0])[:3]
        assert -(velocity - path.velocity(t)) @ force >= 0.0


def test_hand_leads_a_free_mass_to_the_goal():
    """A free 2 kg point mass pulled by the hand along a line stops near the goal."""
    path = Line([0.0, 0.0, 0.0], [0.3, -0.2, 0.1], 1.5)
    hand = Hand(path)
    position, velocity, dt = np.zeros(3), np.zeros(3), 1e-3
    for k in range(4000):
        force = hand.wrench(k * dt, pose(position), np.r_[velocity, 0, 0, 0])[:3]
        velocity = velocity + dt * force / 2.0
        position = position + dt * velocity
    np.testing.assert_allclose(position, path.end, atol=1e-3)
    assert np.linalg.norm(velocity) < 1e-2


def test_hand_is_force_only_by_default():
    """With the default parameters the hand applies no moment, whatever the rotation or ω."""
    hand = Hand(reach())
    hand.wrench(0.0, pose(reach().start), np.zeros(6))
    turned = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix()
    moment = hand.wrench(0.5, pose(reach().start, turned), np.r_[0, 0, 0, 1.0, 2.0, 3.0])[3:]
    np.testing.assert_array_equal(moment, 0.0)


def test_rotational_impedance_restores_the_first_orientation():
    """A small rotation from the held orientation gives m = −K_r·δ, opposing it; ω is damped."""
    rng = np.random.default_rng(RNG_SEED)
    hand = Hand(reach(), rotational_stiffness=4.0, rotational_damping=0.5, max_moment=100.0)
    held = Rotation.random(random_state=RNG_SEED).as_matrix()
    hand.wrench(0.0, pose(reach().start, held), np.zeros(6))
    for _ in range(20):
        rotvec = rng.normal(size=3) * 0.05
        turned = Rotation.from_rotvec(rotvec).as_matrix() @ held
        moment = hand.wrench(0.1, pose(reach().start, turned), np.zeros(6))[3:]
        np.testing.assert_allclose(moment, -4.0 * rotvec, rtol=1e-9)
        omega = rng.normal(size=3)
        damped = hand.wrench(0.1, pose(reach().start, held), np.r_[0, 0, 0, omega])[3:]
        np.testing.assert_allclose(damped, -0.5 * omega, rtol=1e-9)


def test_moment_is_limited_and_reset_holds_a_new_orientation():
    """|m| <= max_moment; after reset() the hand holds the orientation of the next call."""
    hand = Hand(reach(), rotational_stiffness=50.0, max_moment=2.0)
    hand.wrench(0.0, pose(reach().start), np.zeros(6))
    turned = Rotation.from_rotvec([0.0, 0.0, 1.0]).as_matrix()
    moment = hand.wrench(0.0, pose(reach().start, turned), np.zeros(6))[3:]
    np.testing.assert_allclose(moment, [0.0, 0.0, -2.0], atol=1e-12)
    hand.reset()
    assert hand.held_orientation is None
    hand.wrench(0.0, pose(reach().start, turned), np.zeros(6))
    np.testing.assert_allclose(hand.held_orientation, turned)
    moment = hand.wrench(0.0, pose(reach().start, turned), np.zeros(6))[3:]
    np.testing.assert_allclose(moment, 0.0, atol=1e-12)


def test_hand_from_parameters_matches_keywords_and_documented_defaults():
    """Hand.from_parameters equals the keyword form; defaults are 300 N/m, 20 N s/m, 60 N."""
    parameters = HandParameters(stiffness=150.0, max_force=30.0, rotational_stiffness=2.0)
    hand = Hand.from_parameters(reach(), parameters)
    assert hand.parameters == parameters
    default = Hand(reach()).parameters
    assert (default.stiffness, default.damping, default.max_force) == (300.0, 20.0, 60.0)
    assert default.rotational_stiffness == 0.0


def test_a_trembling_hand_adds_its_tremor_through_its_own_impedance():
    """At rest on its path, the tremor's force is a (K sin + D ω cos) per axis, 120° apart.

    Its amplitude is ``a √(K² + (D ω)²)`` on each axis; without a tremor (the default) the
    force is zero there, and a tremor or a frequency out of range is a one-line error.
    """
    still = MinimumJerk([0.4, 0.0, 0.3], [0.4, 0.0, 0.3], 1.0)
    k, d, a, f = 300.0, 30.0, 3e-4, 9.0
    hand = Hand(still, stiffness=k, damping=d, tremor=a, tremor_frequency=f)
    t = np.linspace(0.0, 1.0 / f, 721)
    forces = np.array([hand.wrench(ti, pose([0.4, 0.0, 0.3]), np.zeros(6))[:3] for ti in t])
    omega = 2.0 * np.pi * f
    np.testing.assert_allclose(np.abs(forces).max(axis=0), a * np.hypot(k, d * omega), rtol=1e-4)
    phases = np.array([0.0, 2.0, 4.0]) * np.pi / 3.0
    expected = a * (k * np.sin(omega * t[:, None] + phases)
                    + d * omega * np.cos(omega * t[:, None] + phases))  # fmt: skip
    np.testing.assert_allclose(forces, expected, atol=1e-12)
    calm = Hand(still, stiffness=k, damping=d)
    np.testing.assert_array_equal(calm.wrench(0.3, pose([0.4, 0.0, 0.3]), np.zeros(6)), 0.0)
    for field, value in (("tremor", -1e-4), ("tremor_frequency", 0.0)):
        with pytest.raises(ValueError, match=field):
            HandParameters(**{field: value})


def test_joint_hand_acts_on_its_joint_only_as_a_spring_damper():
    """The joint hand gives K·(q_ref − q) + D·(q̇_ref − q̇) on one joint and zero on the others."""
    rng = np.random.default_rng(RNG_SEED)
    path = JointMinimumJerk(0.0, 0.5, 2.0)
    hand = JointHand(2, path, stiffness=20.0, damping=2.0, max_torque=5.0)
    for _ in range(50):
        t = rng.uniform(-0.5, 2.5)
        q, qd = rng.normal(size=7) * 0.05, rng.normal(size=7) * 0.1
        q[2] = path.position(t) + rng.normal() * 0.05
        tau = hand.joint_torque(t, q, qd)
        expected = 20.0 * (path.position(t) - q[2]) + 2.0 * (path.velocity(t) - qd[2])
        assert tau[2] == pytest.approx(expected, rel=1e-12)
        np.testing.assert_array_equal(np.delete(tau, 2), 0.0)


def test_joint_hand_saturates_at_max_torque():
    """Large errors give exactly ±max_torque, with the sign of the error, never more."""
    rng = np.random.default_rng(RNG_SEED)
    hand = JointHand(0, JointMinimumJerk(0.0, 1.0, 1.0), max_torque=3.0)
    for _ in range(100):
        q, qd = rng.normal(size=6) * 3.0, rng.normal(size=6) * 3.0
        assert abs(hand.joint_torque(rng.uniform(0, 2), q, qd)[0]) <= 3.0
    assert hand.joint_torque(5.0, np.r_[-10.0, np.zeros(5)], np.zeros(6))[0] == 3.0
    assert hand.joint_torque(5.0, np.r_[10.0, np.zeros(5)], np.zeros(6))[0] == -3.0


def test_step_ramp_and_pulse_values():
    """Step, ramp and pulse are zero before, right during and right after their segments."""
    at = lambda segment, t: float(segment.value(t))  # noqa: E731
    assert [at(step(1.0, 2.0), t) for t in (0.99, 1.0, 50.0)] == [0.0, 2.0, 2.0]
    assert [at(ramp(1.0, 3.0, -4.0), t) for t in (0.5, 1.0, 1.5, 3.0, 9.0)] == pytest.approx(
        [0.0, 0.0, -1.0, -4.0, -4.0]
    )
    assert [at(pulse(1.0, 2.0, 0.7), t) for t in (0.9, 1.0, 1.99, 2.0, 3.0)] == pytest.approx(
        [0.0, 0.7, 0.7, 0.0, 0.0]
    )
    ramped_pulse = TorqueSegment(start=0.0, amplitude=1.0, rise_time=1.0, stop=2.0)
    assert [at(ramped_pulse, t) for t in (0.5, 1.5, 2.5)] == pytest.approx([0.5, 1.0, 0.0])


def test_torque_profile_sums_segments_on_its_joint_only():
    """A profile applies the sum of its segments on one joint, for scalar and array times."""
    profile = TorqueProfile(3, (step(1.0, 2.0), pulse(1.5, 2.0, -0.5), ramp(3.0, 4.0, 1.0)))
    times = np.array([0.0, 1.2, 1.7, 2.5, 3.5, 5.0])
    expected = np.array([0.0, 2.0, 1.5, 2.0, 2.5, 3.0])
    np.testing.assert_allclose(profile.value(times), expected)
    for t, value in zip(times, expected, strict=True):
        tau = profile.joint_torque(float(t), np.zeros(5), np.zeros(5))
        np.testing.assert_allclose(tau, np.eye(5)[3] * value)
    assert TorqueProfile(0, step(0.0, 1.0)).segments == (step(0.0, 1.0),)


@pytest.mark.parametrize(
    ("make", "parameter"),
    [
        (lambda: Hand(reach(), stiffness=-1.0), "stiffness"),
        (lambda: Hand(reach(), damping=np.nan), "damping"),
        (lambda: Hand(reach(), max_force=0.0), "max_force"),
        (lambda: Hand(reach(), rotational_stiffness=-2.0), "rotational_stiffness"),
        (lambda: Hand(reach(), rotational_damping="1"), "rotational_damping"),
        (lambda: Hand(reach(), max_moment=-1.0), "max_moment"),
        (lambda: Hand(object()), "path"),
        (lambda: JointHand(-1, JointMinimumJerk(0, 1, 1)), "joint"),
        (lambda: JointHand(1.0, JointMinimumJerk(0, 1, 1)), "joint"),
        (lambda: JointHand(0, None), "path"),
        (lambda: JointHand(0, JointMinimumJerk(0, 1, 1), max_torque=0.0), "max_torque"),
        (lambda: JointHand(0, JointMinimumJerk(0, 1, 1), damping=-0.1), "damping"),
        (lambda: JointHand(3, JointMinimumJerk(0, 1, 1)).joint_torque(0, [0, 0], [0, 0]), "joint"),
        (lambda: TorqueProfile(0, (1.0,)), "segments"),
        (lambda: TorqueProfile(0, 5.0), "segments"),
        (lambda: TorqueProfile(2, ()).joint_torque(0.0, np.zeros(2), np.zeros(2)), "joint"),
        (lambda: ramp(2.0, 1.0, 1.0), "t1"),
        (lambda: pulse(1.0, 1.0, 1.0), "t1"),
        (lambda: step(np.inf, 1.0), "start"),
        (lambda: step(0.0, np.nan), "amplitude"),
        (lambda: TorqueSegment(0.0, 1.0, rise_time=-1.0), "rise_time"),
        (lambda: TorqueSegment(0.0, 1.0, rise_time=1.0, stop=0.5), "stop"),
    ],
)
def test_invalid_parameters_raise_one_line_error_naming_them(make, parameter):
    """Invalid operator parameters raise a one-line OperatorError (a ValueError) naming them."""
    with pytest.raises(OperatorError) as caught:
        make()
    assert isinstance(caught.value, ValueError)
    assert caught.value.parameter == parameter
    assert str(caught.value).startswith(f"{parameter}: ") and "\n" not in str(caught.value)


def test_wrong_shapes_raise_input_shape_errors():
    """A flange pose that is not 4×4, a twist not (6,), or q and q̇ of different sizes raise."""
    hand = Hand(reach())
    with pytest.raises(InputShapeError, match="flange_pose"):
        hand.wrench(0.0, np.eye(3), np.zeros(6))
    with pytest.raises(InputShapeError, match="flange_velocity"):
        hand.wrench(0.0, np.eye(4), np.zeros(3))
    with pytest.raises(InputShapeError, match="qd"):
        JointHand(0, JointMinimumJerk(0, 1, 1)).joint_torque(0.0, np.zeros(3), np.zeros(4))
