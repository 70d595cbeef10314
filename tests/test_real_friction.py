"""Friction identification on real logs (UR10e jointwise runs, Panda excitation) and its rules."""

import warnings

import numpy as np
import pytest
from tests.realdata import REALDATA, needs_realdata

import leadthrough as lt
from leadthrough.experiments.real_friction import panda_friction, ur10e_friction
from leadthrough.friction.identification import MIN_LEVEL, FrictionSamples, fit_friction

#: Our residual may exceed the published model's by this factor at most. Ours is fitted by
#: least squares to these very samples with at least the published model's freedom (minus
#: its constant offset f_0, which is not friction), so it should not be worse; 5 % allows for
#: the missing offset and for our smooth sigmoid where the published curve jumps at q̇ = 0.
RMS_FACTOR = 1.05


@pytest.fixture(scope="module")
def real_rows():
    """Every UR10e and Panda joint identified from its real run."""
    return ur10e_friction(REALDATA) + panda_friction(REALDATA)


@needs_realdata
def test_every_real_joint_is_identified(real_rows):
    """The fit succeeds on all 6 UR10e and 7 Panda joints, with a positive level and samples."""
    assert [(r.robot, r.joint) for r in real_rows] == [("ur10e", j) for j in range(6)] + [
        ("panda", j) for j in range(7)
    ]
    for row in real_rows:
        assert row.report.samples[row.joint] >= 200
        assert row.model.coulomb[row.joint] > 0.0


@needs_realdata
def test_real_coulomb_level_is_positive_over_the_whole_joint_range(real_rows):
    """τ_C(q) > 0 over the joint range (±2π on the UR10e) and beyond."""
    for row in real_rows:
        assert row.min_level(-4.0 * np.pi, 4.0 * np.pi) > 0.0, (row.robot, row.joint)


@needs_realdata
def test_real_residual_no_worse_than_published(real_rows):
    """On the same samples our residual RMS is within RMS_FACTOR of the published model's."""
    for row in real_rows:
        assert row.rms_ours <= RMS_FACTOR * row.rms_published, (row.robot, row.joint)


def _samples(q, qd, tau, moved=None):
    """FrictionSamples of a 6-joint arm with joint 1 carrying the given arrays."""
    n = len(q)
    full = [np.zeros((n, 6)) for _ in range(3)]
    for array, column in zip(full, (q, qd, tau), strict=True):
        array[:, 0] = column
    moved = np.zeros((n, 6), dtype=bool) if moved is None else moved
    moved[:, 0] = True
    return FrictionSamples(*full, moved)


@pytest.fixture(scope="module")
def ur10e_dynamics():
    """Dynamics of the UR10e (only its joint ranges matter to the fit)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return lt.Dynamics(lt.robots.ur10e())


def _sweep(amplitude, level, seed):
    """Friction samples of joint 1 sweeping ±amplitude [rad] around 0 with τ_C(q) = level(q)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 60.0, 6000)
    q = amplitude * np.sin(0.2 * np.pi * t)
    qd = 0.2 * np.pi * amplitude * np.cos(0.2 * np.pi * t)
    tau = np.sign(qd) * level(q) + 3.0 * qd + rng.normal(0.0, 0.05, t.size)
    return _samples(q, qd, tau)


def test_a_sweep_of_a_2pi_joint_is_never_extrapolated_below_the_minimum_level(ur10e_dynamics):
    """A curved level seen over ±2 rad of a ±2π joint stays ≥ MIN_LEVEL τ_C over the range."""
    samples = _sweep(2.0, lambda q: 2.0 * (1.0 - 0.15 * q**2), 3)  # this quadratic: < 0 at 2π
    model, report = fit_friction(samples, ur10e_dynamics, joints=[0])
    pose = np.zeros((4001, 6))
    pose[:, 0] = np.linspace(-2.0 * np.pi, 2.0 * np.pi, 4001)
    level = np.broadcast_to(model.coulomb_level(pose), pose.shape)[:, 0]
    assert report.position_fitted[0]
    assert level.min() >= 0.99 * MIN_LEVEL * model.coulomb[0] > 0.0


def test_position_dependence_the_data_support_is_recovered(ur10e_dynamics):
    """A linear cable-like trend over a wide sweep of joint 3 (±π) is recovered unconstrained."""
    u = lambda q: q / np.pi  # noqa: E731 (joint 3's range is ±π)
    samples = _sweep(1.5, lambda q: 2.0 * (1.0 + 0.3 * u(q)), 4)
    samples.q[:, 2], samples.qd[:, 2], samples.tau_friction[:, 2] = (
        samples.q[:, 0], samples.qd[:, 0], samples.tau_friction[:, 0])  # fmt: skip
    samples.moved[:, 2] = True
    model, report = fit_friction(samples, ur10e_dynamics, joints=[2])
    assert report.position_fitted[2]
    pose = np.zeros((3, 6))
    pose[:, 2] = [-1.5, 0.0, 1.5]
    expected = 2.0 * (1.0 + 0.3 * u(pose[:, 2]))
    np.testing.assert_allclose(model.coulomb_level(pose)[:, 2], expected, rtol=0.03)


def test_default_joints_skip_a_joint_that_only_twitched(ur10e_dynamics):
    """With joints=None a joint that moved but slid for too few samples keeps its prior."""
    t = np.linspace(0.0, 30.0, 3000)
    qd = 0.5 * np.sin(0.5 * t)
    moved = np.zeros((t.size, 6), dtype=bool)
    moved[:, 1] = True  # joint 2 exceeded the moving speed once, slid for only 100 samples
    samples = _samples(np.cumsum(qd) * 0.01, qd, np.sign(qd) * 3.0 + 2.0 * qd, moved)
    samples.qd[:100, 1] = 0.2
    model, report = fit_friction(samples, ur10e_dynamics)
    assert report.joints == (0,)
    assert model.coulomb[1] == lt.FrictionModel.from_robot(ur10e_dynamics.robot).coulomb[1]
    with pytest.raises(lt.LeadthroughError, match="joint 2: only 100 samples"):
        fit_friction(samples, ur10e_dynamics, joints=[0, 1])


def test_coulomb_level_is_never_fitted_negative(ur10e_dynamics):
    """Data whose odd part is negative (a wrong rigid model) give τ_C = 0, not a negative level."""
    t = np.linspace(0.0, 30.0, 3000)
    qd = 0.5 * np.sin(0.5 * t)
    samples = _samples(np.zeros_like(t), qd, -np.sign(qd) * 1.0 + 2.0 * qd)
    model, _ = fit_friction(samples, ur10e_dynamics, joints=[0])
    assert model.coulomb[0] == pytest.approx(0.0, abs=1e-9)
    assert model.viscous[0] > 0.0
