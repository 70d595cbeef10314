"""The joints' estimates read together as a force at the tool (estimation/tool_force.py).

Held to the posterior computed from the n × n covariances, to the torques of a known
force at the tool (a sticking joint recovers its share from the sliding ones), and to
its own std both ways: it covers the truth about as often as it says, and it is narrow
where the sliding joints determine the force.
"""

import math

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.errors import ParameterError
from leadthrough.estimation.tool_force import (
    ToolForceParameters,
    _fuse,
    fuse,
    fuse_reference,
    mixture_reference,
)
from leadthrough.experiments.guiding import Case, run_case

ROBOT = lt.robots.yumi()
DYNAMICS = lt.Dynamics(ROBOT)
#: Each joint's own std: sliding joints 1–4 read to 0.05 Nm, sticking joints 5–7 not at all.
SLIDING, STUCK = 0.05, 1.0


def _readings(rng, pose, force, other_std):
    """Torques of ``force`` at the TCP plus ε, and each joint's reading and std."""
    jacobian = DYNAMICS.tool_jacobian(pose)
    truth = jacobian[:3].T @ force + rng.normal(0.0, other_std)
    std = np.array([SLIDING] * 4 + [STUCK] * 3)
    reading = np.where(std == SLIDING, truth + rng.normal(0.0, std), 0.0)  # stuck: reads 0
    return jacobian, truth, reading, std


def test_the_compiled_3x3_form_is_the_posterior_of_the_full_covariances():
    """Compiled and interpreted 3 × 3 form against P (P + S)⁻¹ τ̂ and P − P (P + S)⁻¹ P."""
    rng = np.random.default_rng(0)
    for _ in range(50):
        jacobian = rng.normal(0.0, 0.4, (6, 7))
        estimate, std = rng.normal(0.0, 1.0, 7), rng.uniform(0.01, 2.0, 7)
        other = rng.uniform(0.01, 0.5, 7)
        expected = fuse_reference(estimate, std, jacobian, other, 50.0)
        compiled = fuse(estimate, std, jacobian, other, 50.0, np.empty(7), np.empty(7))
        interpreted = np.empty(7), np.empty(7)
        _fuse.py_func(estimate, std, jacobian, other, 1.0 / 50.0**2, np.inf, *interpreted,
                      np.zeros((3, 8)))  # fmt: skip
        for result in (compiled, interpreted):
            np.testing.assert_allclose(result[0], expected[0], rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(result[1], expected[1], rtol=1e-9, atol=1e-12)


def test_the_compiled_mixture_is_the_one_of_the_full_covariances():
    """Evidence, weight, mean and std of the mixture: 3 × 3 form against n × n (1e-9)."""
    rng = np.random.default_rng(1)
    for _ in range(50):
        jacobian = rng.normal(0.0, 0.4, (6, 7))
        estimate, std = rng.normal(0.0, 2.0, 7), rng.uniform(0.05, 1.5, 7)
        other, prior = rng.uniform(0.05, 0.5, 7), rng.uniform(0.1, 0.9)
        mean, mixed_std, weight = mixture_reference(estimate, std, jacobian, other, 50.0, prior)
        compiled = np.empty(7), np.empty(7)
        odds = math.log(prior / (1.0 - prior))
        got = _fuse(estimate, std, jacobian, other, 1.0 / 50.0**2, odds, *compiled,
                    np.zeros((3, 8)))  # fmt: skip
        assert got == pytest.approx(weight, rel=1e-9, abs=1e-12)
        np.testing.assert_allclose(compiled[0], mean, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(compiled[1], mixed_std, rtol=1e-9, atol=1e-12)


def test_a_push_no_force_at_the_tool_makes_keeps_each_joints_own_reading():
    """One joint pushed alone: the tool's model loses, each joint keeps its own reading.

    The tool's posterior alone read a UR10e's joint 4 pushed with 8 Nm as 4.6 Nm (a
    review); a force at the tool, read by the sliding joints, keeps the tool's posterior.
    """
    ur10e = lt.robots.ur10e()
    jacobian = lt.Dynamics(ur10e).tool_jacobian(ur10e.home())
    other, std = np.full(6, 0.1), np.full(6, 0.2)
    alone = np.zeros(6)
    alone[3] = 3.0
    mean, _, weight = mixture_reference(alone, std, jacobian, other, 100.0, 0.5)
    assert weight < 1e-3 and mean[3] == pytest.approx(3.0, rel=0.01)
    # a force at the tool, the YuMi's joints 5–7 stuck: the tool's posterior fills them in
    rng = np.random.default_rng(1)
    other = np.full(7, 1e-3)
    jacobian, truth, reading, std = _readings(rng, ROBOT.home(), np.array([8.0, -5.0, 6.0]),
                                              other)  # fmt: skip
    mean, _, weight = mixture_reference(reading, std, jacobian, other, 100.0, 0.5)
    assert weight > 0.999 and np.max(np.abs(mean - truth)) < 0.1


def test_a_sticking_joint_recovers_its_share_of_the_force_the_sliding_ones_read():
    """Joints 5–7 read nothing; their torques come back from joints 1–4 with a narrow std."""
    rng = np.random.default_rng(1)
    other = np.full(7, 1e-3)
    jacobian, truth, reading, std = _readings(rng, ROBOT.home(), np.array([8.0, -5.0, 6.0]),
                                              other)  # fmt: skip
    mean, fused_std = fuse_reference(reading, std, jacobian, other, 100.0)
    stuck = std == STUCK
    assert np.all(np.abs(mean - truth)[stuck] <= 3.0 * fused_std[stuck])
    assert np.all(fused_std[stuck] < 0.2 * STUCK)
    assert np.max(np.abs(mean - truth)) < 0.1  # what a sliding joint reads to 0.05 Nm


def test_a_sliding_joint_keeps_its_own_reading():
    """Own std ≪ σ_ε: the fused value is the joint's own reading (within 1 % of σ_ε)."""
    rng = np.random.default_rng(2)
    other = np.full(7, 0.5)
    jacobian, _, reading, std = _readings(rng, ROBOT.home(), np.array([3.0, 2.0, -4.0]), other)
    mean, fused_std = fuse_reference(reading, std, jacobian, other, 100.0)
    sliding = std == SLIDING
    np.testing.assert_allclose(mean[sliding], reading[sliding], atol=0.01 * 0.5)
    assert np.all(fused_std[sliding] <= std[sliding])


def test_the_band_covers_the_truth_as_often_as_it_says_and_no_more():
    """±2 std covers 90–99 % of sampled forces and poses, and the stuck joints' band narrows."""
    rng = np.random.default_rng(3)
    other = 0.3 * lt.FrictionModel.from_robot(ROBOT).coulomb
    covered, narrowing = [], []
    for _ in range(400):
        pose = ROBOT.home() + rng.normal(0.0, 0.3, 7)
        jacobian, truth, reading, std = _readings(rng, pose, rng.normal(0.0, 10.0, 3), other)
        mean, fused_std = fuse(reading, std, jacobian, other, 100.0, np.empty(7), np.empty(7))
        covered.append(np.abs(mean - truth) <= 2.0 * fused_std)
        narrowing.append(fused_std[std == STUCK] / STUCK)
    coverage = np.mean(covered)
    assert 0.9 <= coverage <= 0.99
    assert np.median(narrowing) < 0.5


def test_parameters_are_checked_and_none_keeps_each_joints_estimate():
    """Bad priors name their field; ``tool_force=None`` reports the observer's own."""
    with pytest.raises(ParameterError, match="spread"):
        ToolForceParameters(spread=-1.0)
    with pytest.raises(ParameterError, match="force_std"):
        ToolForceParameters(force_std=0.0)
    for prior in (0.0, 1.0, 1.5, math.nan, "half"):
        with pytest.raises(ParameterError, match="tool_prior"):
            ToolForceParameters(tool_prior=prior)
    parameters = lt.LeadThroughParameters(tool_force=None)
    controller = lt.LeadThrough(ROBOT, "active", 0.004, parameters=parameters)
    q = ROBOT.home()
    controller.step(q, np.zeros(7), DYNAMICS.gravity(q))
    assert controller.fusion is None
    np.testing.assert_array_equal(controller.tau_ext_hat, controller.observer.tau_ext_hat)
    np.testing.assert_array_equal(controller.std, controller.joint_std)


def test_the_controller_reports_the_fusion_of_its_joints_estimates():
    """``tau_ext_hat`` and ``std`` are the posterior of the observer's and ``joint_std``."""
    controller = lt.LeadThrough(ROBOT, "active", 0.004)
    q = ROBOT.home()
    tau = DYNAMICS.gravity(q) + DYNAMICS.tool_jacobian(q)[:3].T @ np.array([0.0, 5.0, 0.0])
    for _ in range(50):
        controller.step(q, np.zeros(7), tau)
    prior = ToolForceParameters()
    expected = mixture_reference(controller.observer.tau_ext_hat, controller.joint_std,
                                 controller.model.tool_jacobian, controller.fusion.other_std,
                                 prior.force_std, prior.tool_prior)  # fmt: skip
    assert controller.fusion.weight == pytest.approx(expected[2], rel=1e-9)
    np.testing.assert_allclose(controller.tau_ext_hat, expected[0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(controller.std, expected[1], rtol=1e-9, atol=1e-12)
    narrowing = np.minimum(controller.std / controller.joint_std, 1.0)  # what the law uses
    np.testing.assert_allclose(controller.law.narrowing, narrowing, rtol=1e-12)
    assert np.min(narrowing) < 0.9  # at rest the joints read together narrow some bands


def test_the_fused_std_narrows_a_resting_joints_coulomb_band_in_the_law():
    """A push of half the breakaway on a resting joint: its band × fused / own std, never wider.

    Alone, the joint's friction may hold that push unseen, so the law passes less than half
    of it; read with the joints that determine it (fused std a fifth of its own), the
    Coulomb band shrinks five-fold and the law passes more than 60 % of it. A fused std
    above the joint's own widens nothing.
    """
    q, rest = ROBOT.home(), np.zeros(7)
    gravity = DYNAMICS.gravity(q)
    coulomb = lt.FrictionModel.from_robot(ROBOT).coulomb_uncertainty(rest, q)
    push = 0.5 * coulomb
    own = np.ones(7)
    laws = {}
    for name, fused in (("alone", own), ("narrowed", 0.2 * own), ("wider", 2.0 * own)):
        laws[name] = law = lt.LeadThrough(ROBOT, "active", 0.004).law
        law.narrow(fused, own)
        law.operator_torque(push, q, rest, gravity)
    alone, narrowed, wider = laws["alone"], laws["narrowed"], laws["wider"]
    np.testing.assert_allclose(alone.narrowing, 1.0)
    np.testing.assert_allclose(narrowed.uncertainty, alone.uncertainty - 0.8 * coulomb,
                               rtol=1e-12)  # fmt: skip
    np.testing.assert_array_equal(wider.uncertainty, alone.uncertainty)
    assert np.all(alone.weight < 0.5) and np.all(narrowed.weight > 0.6)
    assert np.all(alone.drive < 0.5 * push) and np.all(narrowed.drive > 0.6 * push)


def test_guiding_the_fused_estimate_is_closer_to_the_truth_than_each_joints_own():
    """Three sampled plants: the error over the motion shrinks, the band still covers ≥ 90 %.

    In every case by ≥ 5 %: 9–10 % on dry #1, dry #2 and lugre #1 (9 / 17 / 20 % with the
    6 Hz calibration loop of before, 12–15 % with the calibration reading the observer, and
    13–18 % with the thesis' compensation before that): the more joints slide under a push,
    each then read on its own, the less the others add.
    """

    def own(robot, mode):
        parameters = lt.LeadThroughParameters(tool_force=None)
        return lt.LeadThrough(robot, mode=mode, dt=0.004, parameters=parameters,
                              calibrate=True)  # fmt: skip

    ratios = []
    for physics, seed in (("dry", 1), ("dry", 2), ("lugre", 1)):
        case = Case(physics, seed, "stiff", "sideways")
        fused, alone = run_case(case, "active"), run_case(case, "active", own)
        ratios.append(fused.observer_rms / alone.observer_rms)
        assert fused.observer_coverage >= 0.9
    assert max(ratios) < 0.95, ratios


def test_a_joint_pushed_alone_on_the_twin_is_read_whole():
    """A UR10e's joint 4 pushed alone with 8 Nm: ``tau_ext_hat`` reads it, in both modes.

    The tool's posterior alone read 3.6–5.1 Nm (a review; its std 1.3–1.5 Nm) while the
    joint's own observer read 8.0, and active mode followed the push less than passive.
    """
    from leadthrough.twin.operator import TorqueProfile, pulse
    from leadthrough.twin.simulator import DigitalTwin, TwinConfig

    robot = lt.robots.ur10e()
    for mode in ("passive", "active"):
        controller = lt.LeadThrough(robot, mode, 0.004)
        twin = DigitalTwin(robot, TwinConfig(seed=2), TorqueProfile(3, (pulse(0.3, 1.5, 8.0),)))
        read = []
        for k in range(350):
            state = twin.read_state()
            twin.send_torque(controller.step(state))
            if k >= 200:  # sliding under the push
                read.append(controller.tau_ext_hat[3] - twin.truth.tau_ext[3])
        assert abs(np.mean(read)) < 1.2, mode  # 15 % of the push (36–55 % before)
