"""The experiment factories of benchmarks/guiding_variants.py still build and run (issue 13)."""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import leadthrough as lt

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import guiding_variants

FACTORIES = ("no_unwinding", "no_weighting", "full_residual", "long_stroke", "long_stroke_trusted",
             "strong_dither", "tool_wrench_prior", "smooth_rate_guiding",
             "no_friction_margin", "half_friction_margin",
             "three_quarter_friction_margin", "joint_estimates",
             "plain_admittance", "own_rest_uncertainty", "no_credit_at_rest",
             "no_credit_at_rest_uncalibrated", "no_drive_gain_margin",
             "relieved_friction_margin", "relieved_wider_margin",
             "relieved_widest_margin", "stribeck_band", "stribeck_band_uncalibrated")  # fmt: skip


@pytest.fixture(scope="module")
def robot() -> lt.RobotDescription:
    """The YuMi."""
    return lt.robots.yumi()


@pytest.mark.parametrize("name", FACTORIES)
def test_variant_guides_and_passive_stays_default(robot, name):
    """Each variant's active controller guides a push and its passive one is the default."""
    factory = getattr(guiding_variants, name)
    assert factory(robot, "passive").parameters == lt.LeadThroughParameters(mode="passive")
    controller = _pushed(robot, factory(robot, "active"))
    assert controller.state.name == "TEACHING"
    assert controller.law.references.q_ref[3] - robot.home()[3] > 1e-4  # along the push


@pytest.mark.parametrize("name", ("full_residual", "tool_wrench_prior"))
def test_a_variant_law_is_the_one_that_runs(robot, name):
    """The variant's own law drives: its operator torque differs from the default's."""
    variant = _pushed(robot, getattr(guiding_variants, name)(robot, "active"))
    default = _pushed(robot, lt.LeadThrough(robot, mode="active"))
    assert np.max(np.abs(variant.operator_torque - default.operator_torque)) > 1e-3


def test_the_stribeck_band_is_the_observers_not_the_laws_and_nothing_counts_as_measured(robot):
    """The nominal model with a stiction excess: the observer's band holds it, the law does not.

    Passing it as ``friction=`` would count its levels as identified on this arm; the variant
    keeps them unmeasured, as the default's (their error ``unmeasured_friction_error``).
    """
    variant = guiding_variants.stribeck_band_uncalibrated(robot, "active")
    default = lt.LeadThrough(robot, mode="active")
    assert np.all(variant.observer.friction.stiction_excess == guiding_variants.STIFF_STICTION)
    assert not np.any(variant.law.friction.stiction_excess)
    np.testing.assert_array_equal(variant.law.friction_error, default.law.friction_error)


def test_without_credit_at_rest_a_creep_reads_no_push_and_the_report_stays(robot):
    """Joint 4 creeping at 3 mrad/s, the motor holding gravity only, nobody pushing.

    The default law reads the friction model at 3 mrad/s (≈ its level) as a push along
    the creep; the variant's reads none of it (what is left, 0.1 Nm, is the share of
    the other joints' readings the tool force gives it); the reported estimate is the same.
    """
    dynamics = lt.Dynamics(robot)
    default = lt.LeadThrough(robot, mode="active", dt=0.004)
    variant = guiding_variants.no_credit_at_rest_uncalibrated(robot, "active")
    q0, qd = np.array(robot.home(), dtype=float), np.zeros(robot.n_joints)
    qd[3] = 0.003
    for k in range(300):
        q = q0 + k * 0.004 * qd
        model = dynamics.snapshot(q, qd)
        for controller in (default, variant):
            controller.step(q, qd, model.gravity - model.coriolis_drift)
    np.testing.assert_array_equal(variant.tau_ext_hat, default.tau_ext_hat)
    level = default.friction.coulomb_level(q)[3]
    assert default.law.residual[3] > 0.5 * level
    assert abs(variant.law.residual[3]) < 0.2 * level  # what the tool force spreads


@pytest.mark.parametrize(
    "name, scale",
    [
        ("no_friction_margin", 0.0),
        ("half_friction_margin", 0.5),
        ("three_quarter_friction_margin", 0.75),
    ],
)
def test_scaled_margin_is_that_share_of_the_default(robot, name, scale):
    """The margin variants remove ``scale`` times the default's margin, compiled or not."""
    q, qd = np.array(robot.home(), dtype=float), np.linspace(-0.3, 0.3, robot.n_joints)
    measured = np.arange(robot.n_joints) % 2 == 0  # measured or not: the whole error
    law = lt.LeadThrough(robot, mode="active").law
    variant = getattr(guiding_variants, name)(robot, "active").law
    for each in (law, variant):
        each.use_friction(each.friction, measured)
    np.testing.assert_array_equal(law.margin_error, law.friction_error)
    default = law._friction_margin(q, qd)
    assert np.max(np.abs(default)) > 0.01
    np.testing.assert_allclose(variant._friction_margin(q, qd), scale * default, rtol=1e-12,
                               atol=1e-15)  # fmt: skip
    sliding = law.sliding_velocity(qd).copy()  # the speed the law's friction sees
    expected = (1.0 - scale) * law._friction_margin(q, sliding)
    compiled = _residual(variant, q, qd) - _residual(law, q, qd)  # the margins' difference
    np.testing.assert_allclose(compiled, expected, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(
    "name, scale",
    [("relieved_friction_margin", 1.0), ("relieved_wider_margin", 1.3),
     ("relieved_widest_margin", 1.6)],
)  # fmt: skip
def test_relieved_margins_relieve_that_share_of_the_default(robot, name, scale):
    """The relieved variants set the relief (compiled law too) and their margin's share."""
    law = getattr(guiding_variants, name)(robot, "active").law
    assert law.margin_relief and law._drive_scalars[-1] == 1.0
    assert law.margin_share == scale
    assert lt.LeadThrough(robot, mode="active").law._drive_scalars[-1] == 0.0


def test_without_the_drive_gain_term_the_tracking_torque_reads_as_nothing(robot):
    """The default removes 10 % of the last tracking torque from the residual, the variant none.

    It keeps the gravity tolerance, which ``drive_gain_uncertainty`` also sets.
    """
    q, qd = np.array(robot.home(), dtype=float), np.zeros(robot.n_joints)
    law = lt.LeadThrough(robot, mode="active").law
    variant = guiding_variants.no_drive_gain_margin(robot, "active").law
    assert variant.parameters.gravity_uncertainty == law.parameters.gravity_uncertainty
    tracking = np.linspace(-1.0, 1.0, robot.n_joints)
    for each in (law, variant):
        each.reset()
        each.feedback[:] = tracking
        each.operator_torque(np.zeros(each.n), q, qd, np.zeros(each.n))
    np.testing.assert_allclose(law.residual, -0.1 * tracking, atol=1e-12)
    np.testing.assert_array_equal(variant.residual, np.zeros(robot.n_joints))
    np.testing.assert_array_equal(variant.feedback, tracking)  # the law's state is kept


def _residual(law, q, qd):
    """The compiled law's residual for a zero estimate at (q, q̇), gravity zero [Nm]."""
    law.reset()
    law.operator_torque(np.zeros(law.n), q, qd, np.zeros(law.n))
    return law.residual.copy()


@pytest.mark.parametrize("name", ("true_torque", "true_torque_plain", "true_torque_no_margin"))
def test_an_oracle_guides_on_the_truth_it_is_handed(robot, name):
    """Handed a twin whose operator pushes joint 4, the oracle follows that push, not the motors."""
    push = np.zeros(robot.n_joints)
    push[3] = 2.0
    twin = SimpleNamespace(truth=SimpleNamespace(tau_operator=push))
    controller = getattr(guiding_variants, name)(robot, "active")
    controller.observe_truth(twin)
    controller = _pushed(robot, controller, measured_push=0.0)
    assert controller.law.references.q_ref[3] - robot.home()[3] > 1e-4  # along the truth


def test_guiding_hands_the_twin_to_an_oracle(robot):
    """``guiding._run`` hands the simulated robot to a controller that asks for it."""
    from leadthrough.experiments import guiding
    from leadthrough.twin.simulator import DigitalTwin

    seen = []

    def factory(robot: lt.RobotDescription, mode: str) -> lt.LeadThrough:
        controller = lt.LeadThrough(robot, mode=mode, dt=0.004)
        controller.observe_truth = seen.append  # type: ignore[attr-defined]
        return controller

    guiding._run(robot, guiding.Case("dry", 1, "relaxed", "sideways"), "passive", factory,
                 np.inf, 0.1)  # fmt: skip
    assert len(seen) == 1 and isinstance(seen[0], DigitalTwin)


def _pushed(
    robot: lt.RobotDescription, controller: lt.LeadThrough, measured_push: float = 2.0
) -> lt.LeadThrough:
    """``controller`` (calibration skipped) after 200 periods of a push on joint 4 [Nm]."""
    controller.calibrate = False
    controller.reset()
    dynamics = lt.Dynamics(robot)
    q = np.array(robot.home(), dtype=float)
    push = np.zeros(robot.n_joints)
    push[3] = measured_push  # 2 Nm: far above any margin
    rng = np.random.default_rng(0)
    for _ in range(200):  # the arm held still, its encoders alive (a frozen one faults)
        noisy = q + rng.normal(0.0, 1e-6, q.size)
        command = controller.step(noisy, np.zeros(robot.n_joints), dynamics.gravity(q) - push)
        assert np.all(np.isfinite(command))
    return controller
