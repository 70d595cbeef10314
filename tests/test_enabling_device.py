"""The hand-guiding enabling device (``JointState.enabling``): the margin it replaces.

Active mode removes the friction the model may overstate from every reading along the
motion (the friction margin), and raises its damping where nothing pushes, because once the
hand has let go a friction error reads exactly as a push and would run the released arm on.
An enabling device says directly whether a hand is on the arm: held, on a calibrated model,
neither is applied (lighter); released, nothing drives the admittance and the controller
sends gravity alone (it stops). Tested against the twin, whose hand holds the device while
it holds the arm and lets go of both at once.
"""

import dataclasses

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.active_law import _REST_DAMPING, ActiveLaw
from leadthrough.control.admittance import AdmittanceState
from leadthrough.experiments.guiding import Case, run_case
from leadthrough.friction.compensation import CoulombCompensationParameters, compensation_ceiling
from leadthrough.friction.model import FrictionModel
from leadthrough.twin.operator import During, Hand, Operator
from leadthrough.twin.paths import Line
from leadthrough.twin.plants import PlantRanges
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

#: Without the friction margin and without a release read (the device read held after the
#: hand let go), this released arm ran on 788 mrad in 5.5 s.
RELEASED_ON_THE_WAY = Case("dry", 2, "stiff", "upwards", PlantRanges(enabling_device=True))
WITHOUT_A_DEVICE = dataclasses.replace(RELEASED_ON_THE_WAY, ranges=PlantRanges())


@pytest.fixture(scope="module")
def yumi():
    """The YuMi's arm."""
    return lt.robots.yumi()


def _law(robot, compiled=True):
    law = ActiveLaw(robot, lt.LeadThroughParameters(), 0.004, FrictionModel.from_robot(robot))
    law.compiled = compiled
    return law


def test_the_twin_reports_the_device_held_while_the_hand_holds(yumi):
    """Held from the grab until the hand lets go; None on an arm without a device."""
    twin = DigitalTwin(yumi, TwinConfig(enabling_device=True))
    assert twin.read_state().enabling is False  # nobody holds the arm
    start = twin.truth.flange_pose[:3, 3].copy()
    twin.operator = During(Hand(Line(start, start + np.array([0.0, 0.0, 0.1]), 2.0)), 0.0, 0.02)
    held = []
    for _ in range(10):
        held.append(twin.read_state().enabling)
        twin.send_torque(np.zeros(yumi.n_joints))
    assert held[:5] == [True] * 5 and held[5:] == [False] * 5  # let go at 20 ms
    assert DigitalTwin(yumi, TwinConfig()).read_state().enabling is None  # no device


@pytest.mark.parametrize("reading", [np.nan, "yes", 0.5, 2])
def test_a_malformed_reading_stops_the_arm(yumi, reading):
    """A device reading that is not held / released / absent: a fault naming it, the safe stop."""
    ctl = lt.LeadThrough(yumi, mode="active")
    q, qd = yumi.home(), np.zeros(yumi.n_joints)
    ctl.step(lt.JointState(0.0, q, qd, None, enabling=True))
    command = ctl.step(lt.JointState(0.004, q, qd, None, enabling=reading))
    assert ctl.state == "fault" and "enabling device reading" in ctl.supervisor.fault_reason
    assert np.all(np.isfinite(command))


@pytest.mark.parametrize("reading", [True, np.True_, 1, False, np.False_, 0])
def test_a_digital_input_reads_as_held_or_released(yumi, reading):
    """A bool, a NumPy bool or 0 / 1, as a driver's digital input gives it (held: confirmed)."""
    ctl = lt.LeadThrough(yumi, mode="active")
    for t in (0.0, 0.004):  # held is taken from its second reading on (one period at 250 Hz)
        ctl.step(lt.JointState(t, yumi.home(), np.zeros(yumi.n_joints), None, enabling=reading))
    assert ctl.state == "teaching" and ctl.enabling is bool(reading)


@pytest.mark.parametrize(("dt", "periods"), [(0.004, 1), (0.001, 5)])
def test_held_is_taken_once_confirmed_released_at_once(yumi, dt, periods):
    """Held counts after ENABLING_CONFIRMATION (5 ms: 1 period at 250 Hz, 5 at 1 kHz).

    A reading that flips every period (a loose contact) thus leaves the arm released: it
    switched the assist on and off each period, up to 4 Nm of torque chatter at 500 Hz on a
    Panda at 1 kHz. A release is taken the period it is read.
    """
    ctl = lt.LeadThrough(yumi, mode="active", dt=dt)
    q, qd = yumi.home(), np.zeros(yumi.n_joints)
    taken = []
    readings = [True] * (periods + 1) + [False] + [True, False] * 10
    for k, reading in enumerate(readings):
        ctl.step(lt.JointState(k * dt, q, qd, None, enabling=reading))
        taken.append(ctl.enabling)
    assert taken == [False] * periods + [True, False] + [False] * 20


@pytest.mark.parametrize("compiled", [True, False])
def test_held_the_friction_margin_is_not_removed(yumi, compiled):
    """Held, the margin is 0 wherever the level's error goes; released, it is back."""
    law = _law(yumi, compiled)
    whole = law.friction_error.copy()
    law.use_enabling(True)
    law.set_friction_error(whole * 1.5)  # a calibrated level's error follows the travel
    assert np.all(law.margin_error == 0.0) and np.all(law.viscous_margin_error == 0.0)
    law.use_enabling(False)  # let go: the margin is back for the next grab
    np.testing.assert_array_equal(law.margin_error, 1.5 * whole)
    np.testing.assert_array_equal(law.viscous_margin_error, whole)
    law.use_enabling(None)
    np.testing.assert_array_equal(law.margin_error, 1.5 * whole)


@pytest.mark.parametrize("compiled", [True, False])
def test_released_nothing_drives_the_admittance(yumi, compiled):
    """Released, a push reads as none: the admittance brakes the motion."""
    n, q, qd = yumi.n_joints, yumi.home(), np.full(yumi.n_joints, 0.2)
    mass = lt.Dynamics(yumi).mass(q)
    constraint = np.zeros(n)

    def after(enabling, drive):
        law = _law(yumi, compiled)
        law.use_enabling(enabling)
        law.references = AdmittanceState(q.copy(), qd.copy())
        law.drive[:], law.residual[:], law.uncertainty[:] = drive, drive, 0.1
        return law.tracking(q, qd, constraint, mass).copy(), law.references

    pushed, _ = after(None, 2.0)
    released, _ = after(False, 2.0)
    unpushed, _ = after(False, 0.0)
    np.testing.assert_array_equal(released, unpushed)  # the push reads as none
    assert released @ qd < 0.0 < pushed @ qd  # it brakes the motion (its power)


@pytest.mark.parametrize("drive", [0.0, 0.05, 1.0])
def test_held_the_numpy_law_damps_as_the_compiled_one(yumi, drive):
    """Both read the held damping from the same place: their references agree."""
    n, q, qd = yumi.n_joints, yumi.home(), np.full(yumi.n_joints, 0.1)
    mass = lt.Dynamics(yumi).mass(q)
    laws = [_law(yumi, compiled) for compiled in (True, False)]
    for law in laws:
        law.use_enabling(True)
        for _ in range(20):
            law.drive[:], law.residual[:], law.uncertainty[:] = drive, drive, 0.1
            law.tracking(q, qd, np.zeros(n), mass)
    np.testing.assert_allclose(laws[0].references.qd_ref, laws[1].references.qd_ref,
                               rtol=1e-9, atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(laws[0].feedback, laws[1].feedback, rtol=1e-9, atol=1e-12)


def test_the_scripted_session_holds_the_device_during_its_actions_only():
    """Between the teaching session's actions nobody holds the arm, nor its device."""
    from leadthrough.twin.session_operator import Action, ScriptedOperator

    still = Action(1.0, 2.0, lambda p, q: Operator(), "hold")
    operator = ScriptedOperator([still, Action(3.0, 4.0, still.make, "again")])
    assert [operator.holds(t) for t in (0.5, 1.0, 1.99, 2.0, 2.5, 3.5, 4.0)] == [
        False, True, True, False, False, True, False]  # fmt: skip


def test_held_the_damping_does_not_rise(yumi):
    """Held, the damping stays at guiding; released or without a device it rises as before."""
    law = _law(yumi)
    rest = law.parameters.rest_damping
    for enabling, scale in ((True, 0.0), (False, rest), (None, rest), (True, 0.0)):
        law.use_enabling(enabling)
        assert law._admittance_scalars[_REST_DAMPING] == scale


@pytest.fixture(scope="module")
def released_with_the_device():
    """The case with the device, active mode."""
    return run_case(RELEASED_ON_THE_WAY, "active")


def test_a_released_arm_stops_with_no_margin_while_held(released_with_the_device):
    """Guided without the margin, let go of, the arm stops within the issue's bounds."""
    result = released_with_the_device
    assert result.stop_time <= 0.5 and result.drift < 1e-3


def test_without_the_release_it_runs_on(monkeypatch, released_with_the_device):
    """As found: a device that still reads held after the hand let go.

    Nothing then stops the arm: the margin is what stops it when nothing says the hand is gone.
    """
    monkeypatch.setattr(During, "holds", lambda operator, t: operator.start <= t)
    result = run_case(RELEASED_ON_THE_WAY, "active")
    assert result.drift > 0.01 > released_with_the_device.drift


def test_held_it_guides_lighter(released_with_the_device):
    """The margin's cost: the same hand on the same plant pulls harder without a device."""
    without = run_case(WITHOUT_A_DEVICE, "active")
    assert released_with_the_device.rms_force <= 0.9 * without.rms_force


def test_held_the_rising_damping_costs_effort(monkeypatch):
    """As found: the damping that rises where no push sustains a joint, kept while held."""
    case = Case("dry", 3, "relaxed", "sideways", PlantRanges(enabling_device=True))
    flat = run_case(case, "active").rms_force
    use = ActiveLaw.use_enabling

    def rising(law, enabling):
        use(law, enabling)
        law._admittance_scalars[_REST_DAMPING] = law.parameters.rest_damping

    monkeypatch.setattr(ActiveLaw, "use_enabling", rising)
    assert flat <= 0.9 * run_case(case, "active").rms_force


def test_held_without_a_calibration_the_law_keeps_its_margin(yumi):
    """Unmeasured, the levels may be off by far more than stated: held counts as no device."""
    ctl = lt.LeadThrough(yumi, mode="active")  # no start-up calibration
    q, qd = yumi.home(), np.zeros(yumi.n_joints)
    for t in (0.0, 0.004):  # held, confirmed at its second reading
        ctl.step(lt.JointState(t, q, qd, None, enabling=True))
    assert ctl.law.enabling is None and np.all(ctl.law.margin_error > 0.0)
    ctl.step(lt.JointState(0.008, q, qd, None, enabling=False))
    assert ctl.law.enabling is False  # released counts, calibrated or not


def _sliding_compensation(robot, mode, enabling, held_fraction=1.0, periods=50):
    """Coulomb compensation [Nm] of every joint sliding at home, and its ceiling [Nm].

    The controller is taken as calibrated, so that a held device counts, on levels known to
    5 % and an exact gravity model: the ceiling, 0.95 τ_C, is above the thesis' 0.7 τ_C.
    """
    parameters = lt.LeadThroughParameters(mode=mode, mass_uncertainty=0.0,
                                          drive_gain_uncertainty=0.0)  # fmt: skip
    compensation = dataclasses.replace(parameters.compensation, held_fraction=held_fraction)
    parameters = dataclasses.replace(parameters, compensation=compensation)
    nominal = FrictionModel.from_robot(robot)
    known = dataclasses.replace(nominal, relative_error=np.full(robot.n_joints, 0.05))
    ctl = lt.LeadThrough(robot, friction=known, parameters=parameters)
    q, qd = robot.home(), np.full(robot.n_joints, 0.05)
    for k in range(periods):
        ctl.step(lt.JointState(0.004 * k, q, qd, None, enabling=enabling))
    level = ctl.friction.coulomb_level(q)
    gravity_error = ctl.parameters.gravity_uncertainty * np.abs(ctl.model.gravity)
    ceiling = compensation_ceiling(level, ctl.feed_forward.friction_error, gravity_error)
    return ctl.last_feed_forward.friction, level, ceiling


@pytest.fixture
def taken_as_calibrated(monkeypatch):
    """Every controller of the test counts as calibrated (a held device then counts)."""
    monkeypatch.setattr(lt.LeadThrough, "_calibrated", property(lambda ctl: True))


def test_held_active_mode_compensates_the_friction_surely_there(yumi, taken_as_calibrated):
    """``held_fraction = 1``, held: τ_C under the ceiling; else the thesis' ε = 0.7."""
    held, level, ceiling = _sliding_compensation(yumi, "active", True)
    np.testing.assert_allclose(held, np.minimum(level, ceiling), rtol=1e-4, atol=1e-9)
    for enabling in (None, False):  # no device; released (the controller sends gravity alone)
        other, _, _ = _sliding_compensation(yumi, "active", enabling)
        np.testing.assert_allclose(other, np.minimum(0.7 * level, ceiling), rtol=1e-4,
                                   atol=1e-9)  # fmt: skip
    assert np.all(held > 0.9 * level)  # the case is one where it differs


def test_held_passive_mode_keeps_the_thesis_law(yumi, taken_as_calibrated):
    """Passive mode is the thesis' law (the benchmark's reference), device or not."""
    held, level, ceiling = _sliding_compensation(yumi, "passive", True)
    np.testing.assert_allclose(held, np.minimum(0.7 * level, ceiling), rtol=1e-4, atol=1e-9)


def test_by_default_held_keeps_the_thesis_fraction(yumi, taken_as_calibrated):
    """``held_fraction = None`` (the default): ε is ``fraction`` whatever the device says."""
    assert CoulombCompensationParameters().held_fraction is None
    held, _, _ = _sliding_compensation(yumi, "active", True, held_fraction=None)
    thesis, _, _ = _sliding_compensation(yumi, "active", None)
    np.testing.assert_allclose(held, thesis, atol=1e-12)


def test_the_settings_follow_the_device_each_time_it_changes(yumi, taken_as_calibrated):
    """The law and the compensation are set when the device changes, not every period.

    Held, released, none, held again, then a reset (new law parts) while held: each
    period's damping, margin and ε are those of the device read that period.
    """
    parameters = lt.LeadThroughParameters(mode="active")
    parameters = dataclasses.replace(parameters, compensation=dataclasses.replace(
        parameters.compensation, held_fraction=1.0))  # fmt: skip
    ctl = lt.LeadThrough(yumi, parameters=parameters)
    q, qd = yumi.home(), np.zeros(yumi.n_joints)
    rest_damping, thesis = parameters.rest_damping, parameters.compensation.fraction
    t = 0.0
    for readings in ((True, True, False, False, None, True, True), (True, True)):
        for k, reading in enumerate(readings):
            ctl.step(lt.JointState(t, q, qd, None, enabling=reading))
            t += 0.004
            # held is taken from its second reading in a row on (one period at 250 Hz)
            enabling = False if reading and (k == 0 or not readings[k - 1]) else reading
            assert ctl.law.enabling is enabling
            held = enabling is True
            assert ctl.law._admittance_scalars[_REST_DAMPING] == (0.0 if held else rest_damping)
            assert bool(np.all(ctl.law.margin_error == 0.0)) is held
            assert ctl.feed_forward.compensation.fraction == (1.0 if held else thesis)
        ctl.reset()  # new feed-forward: set again, though the device did not change


@pytest.mark.parametrize("value", [-0.1, 1.2, np.nan, "all"])
def test_a_held_fraction_outside_0_1_is_refused(value):
    """A fraction of τ_C: a number in [0, 1], or a one-line error naming the field."""
    with pytest.raises(lt.ParameterError, match="held_fraction"):
        CoulombCompensationParameters(held_fraction=value)


def test_held_at_the_ceiling_it_guides_lighter_and_stops(released_with_the_device):
    """``held_fraction = 1``: the same hand pulls at most 0.9 of ε = 0.7's; the release stops."""
    parameters = lt.LeadThroughParameters()
    ceiling = dataclasses.replace(parameters, compensation=dataclasses.replace(
        parameters.compensation, held_fraction=1.0))  # fmt: skip

    def factory(robot, mode):
        return lt.LeadThrough(robot, mode=mode, parameters=ceiling, calibrate=True)

    held = run_case(RELEASED_ON_THE_WAY, "active", factory)
    assert held.rms_force <= 0.9 * released_with_the_device.rms_force
    assert held.stop_time <= 0.5 and held.drift < 1e-3


@pytest.mark.parametrize("mode", ["passive", "active"])
def test_released_the_feed_forward_is_gravity_alone(yumi, mode):
    """No Coulomb compensation and no dither while nobody guides; both with no device."""
    q, qd = yumi.home(), np.full(yumi.n_joints, 0.05)  # every joint sliding: compensated

    def command(enabling):
        ctl = lt.LeadThrough(yumi, mode=mode)
        ctl.step(lt.JointState(0.0, q, qd, None, enabling=enabling))
        return ctl.step(lt.JointState(0.004, q, qd, None, enabling=enabling)), ctl

    released, ctl = command(False)
    if mode == "passive":
        np.testing.assert_allclose(released, ctl.model.gravity, atol=1e-12)
    compensated, _ = command(None)
    assert np.all((compensated - released) * qd > 0.0)  # the compensation is gone


def test_released_the_compensation_does_not_carry_the_arm_on(monkeypatch):
    """As found: the Coulomb compensation kept after the device was let go.

    Uncalibrated (refused: levels 0.5–1.5 of the model's), this LuGre plant's compensation
    of levels the model overstates carried the released circle on for 0.46 s.
    """
    wide = PlantRanges(friction_scale=(0.5, 1.5), enabling_device=True)
    case = Case("lugre", 3, "relaxed", "circle", wide)
    stopped = run_case(case, "active").stop_time
    monkeypatch.setattr(lt.LeadThrough, "_for_the_hand", lambda ctl, ff: (ff.total, ff.dither))
    assert stopped <= 0.3 < run_case(case, "active").stop_time


def test_held_while_the_arm_calibrates_refuses_the_calibration(yumi):
    """A hand on the arm while it calibrates: refused at once, held against gravity, guided.

    The calibration reads the arm alone; a held device says a hand is on it, whether or not
    its push shows in the motion yet. Released all along, the same samples keep it running;
    held from the sample that ends the run, it is the hand taking the arm handed over.
    """
    q, qd = yumi.home(), np.zeros(yumi.n_joints)

    def run(held_at, periods=50):
        ctl = lt.LeadThrough(yumi, mode="active", calibrate=True)
        for k in range(periods):
            command = ctl.step(lt.JointState(0.004 * k, q, qd, None, enabling=k >= held_at))
            if not ctl.calibrating:
                return ctl, command
        return ctl, command

    alone, _ = run(held_at=50)
    assert alone.calibrating  # released all along: the run goes on
    touched, command = run(held_at=30)
    assert not touched.calibrating and not touched.calibration.accepted
    assert "enabling device was held" in touched.calibration.reason
    assert "\n" not in touched.calibration.reason
    np.testing.assert_allclose(command, touched.model.gravity, atol=1e-12)
    assert touched.state == "teaching"  # guiding goes on, with the model as given
    # grabbed on the sample that ends the run (the hand takes the arm as it is handed over)
    end = round(alone.calibration_time / 0.004)
    handed_over, _ = run(held_at=end, periods=end + 2)
    assert not handed_over.calibrating and "enabling" not in handed_over.calibration.reason
