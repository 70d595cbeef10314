"""A released arm stops in both modes on plants whose gravity model is off (issue 13).

On the sampled plants of ``benchmarks/guiding_quality.py`` (masses ±5 %, drive gains
±10 %) the passive mode used to keep sliding after the hand let go, 0.6–1.6 rad in 10 s
on 7 of 112 cases: its Coulomb compensation (0.7 τ_C) plus the gravity model's error
exceeded the friction. Two things stop it, each tested here against the case it fixes:

- the start-up calibration's gravity error goes into the model (feed-forward, observer
  and supervisor alike), as the payload does;
- the compensation stays below the friction surely there minus the gravity error that
  may remain away from the calibration pose (``gravity_uncertainty``: masses and drive
  gains, times the change of G).
"""

import dataclasses
import functools

import numpy as np
import pytest

import leadthrough as lt
from as_found import (
    confidence_at_rest,
    constant_gravity_bias,
    constant_level_error,
    diagonal_damping,
    friction_margin_share,
    observer_readings,
    own_rest_bands,
    saturating_gravity_share,
    settled_after_moving_joints,
    six_hertz_calibration,
    slow_calibration_motion,
    thesis_compensation,
    told_measurement_delay,
    two_second_park,
    uncapped_dither,
    unchecked_drift,
    unread_torque_offset,
)
from leadthrough.control import active_law, lead_through
from leadthrough.control.active_law import ActiveLaw
from leadthrough.control.admittance import AdmittanceState
from leadthrough.control.calibration import Calibration
from leadthrough.control.calibration import run as calibration_run
from leadthrough.control.feedforward import PassiveFeedForward
from leadthrough.control.lead_through import LeadThrough
from leadthrough.estimation.tool_force import ToolForceParameters
from leadthrough.experiments.guiding import Case, default_factory, run_case, uncalibrated_factory
from leadthrough.friction.compensation import compensation_ceiling
from leadthrough.twin.plants import WIDER_RANGES, PlantRanges, sample_plant
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin

#: Two cases where the passive arm ran away: one each mechanism stops.
FAR_FROM_THE_POSE = Case("lugre", 1, "stiff", "sideways")  # G of joint 4 changes 1.9 Nm
OFF_AT_THE_POSE = Case("dry", 7, "relaxed", "upwards")  # joint 3's G 12 % off already there
UNCALIBRATED = Case("dry", 7, "stiff", "sideways")  # ran away 1.2 rad without a calibration
#: Held out (seed 12): joint 3's sliding friction is 0.74 of the model's where the arm is
#: let go (the level ±20 %, ±15 % along the travel); uncalibrated, the passive arm slid on
#: 408 mrad with its compensation at 0.8 τ_C, the model's own ±20 %.
UNIT_SPREAD = Case("dry", 12, "relaxed", "down-in")
#: Active mode coasted 0.68 s after the hand let go on the circle (drift 5.6 mrad): the
#: friction margin read as drag kept the operator weight, and so the damping, at guiding.
COASTING = Case("dry", 3, "relaxed", "circle")
#: Active mode let joint 3 of this LuGre plant creep 0.9 mrad after the release (passive
#: 0.24): friction stopped it 20 mrad short of its reference, and the PD's spring pushed it
#: (0.17 Nm) while the dither vibrated it, until the dither parked.
SPRING_HELD = Case("lugre", 1, "stiff", "down-in")
#: Uncalibrated (the model's gravity off by the drive gains and masses), joint 3 of this
#: LuGre plant creeps 0.6–0.8 mrad/s under the dither after the release, in both modes,
#: until the dither parks: 1.0 / 1.3 mrad (passive / active) parked after 2 s of rest.
DITHERED_CREEP = Case("lugre", 15, "stiff", "upwards")
#: Uncalibrated, active mode reads the friction the observer credits to joint 1's dithered
#: creep as a push, and the creep grows to 1–4 mrad/s: 2.7 mrad parked after 2 s of rest.
CREDITED_CREEP = Case("lugre", 12, "stiff", "down-in")


#: Every friction level 0.8 of the model's, uniform along the travel: the edge of the 0.2 a
#: level measured on this arm may be off by.
OVERSTATED = PlantRanges(friction_scale=(0.8, 0.8), position_amplitude=0.0)
#: Dry #11 of a family wider than the benchmark's (levels 0.7–1.3, ±25 % along the travel):
#: its calibration is refused (joint 1 reads 0.52× the model's) and joint 1 turns ~0.8 rad
#: on the upward line; with the model's error alone the released arm ran on 45 mrad.
READ_LOW = Case("dry", 11, "relaxed", "upwards", WIDER_RANGES)


class _Uncorrected(LeadThrough):
    """The calibration's gravity error not put into the model (the previous defaults)."""

    def _finish_calibration(self, calibration, t):
        super()._finish_calibration(calibration, t)
        if calibration.accepted:
            gravity = self.dynamics.gravity(calibration.pose)
            self.law.model_error.calibrate(calibration.bias, gravity)
            self._gravity_offset = None


def _passive(cls=LeadThrough, calibrate=True, **changes):
    def factory(robot, mode):
        parameters = dataclasses.replace(lt.LeadThroughParameters(), **changes)
        return cls(robot, mode="passive", dt=0.004, parameters=parameters, calibrate=calibrate)

    return factory


def _runs_on_or_stops(result, runs_on: bool, beyond: float) -> None:
    """Released, the arm runs on more than ``beyond`` [rad], or stops within 0.5 s and stays."""
    if runs_on:
        assert result.drift > beyond
    else:
        assert result.stop_time <= 0.5 and result.drift < 1e-3


def _plain_payload_fit(self, gravity_error, per_kilogram, slid):
    """The previous payload: plain least squares on the joints that slid, ≥ 0."""
    fitted = np.where(slid, per_kilogram, 0.0)
    return max(float(-fitted @ gravity_error) / float(fitted @ fitted), 0.0)


def _calibration_of_the_time(monkeypatch):
    """The start-up calibration the cases below were found with.

    It slid the joints 5 mrad at 0.05 rad/s, any three paced readings each way measured a
    joint's level, and a payload was a plain least-squares fit. The calibration now slides
    faster, measures less, takes no spurious payload and reads the torque measurement's
    offset, which on these plants also hides the mechanisms the tests below show their
    rules stop.
    """
    slow_calibration_motion(monkeypatch)
    unread_torque_offset(monkeypatch)
    monkeypatch.setattr(calibration_run, "_MEASURED", 0.0)
    monkeypatch.setattr(calibration_run.CalibrationRun, "payload", _plain_payload_fit)


#: Dry #59 of the family: joint 2's drive applies 1.094× what it is told, and the shoulder
#: holds 5 Nm of gravity at the calibration pose but 0.3 Nm where the upward line takes it.
DRIVE_GAIN_BIAS = Case("dry", 59, "stiff", "upwards")


@pytest.mark.parametrize("follows", [True, False], ids=["bias-follows-G", "constant-bias"])
def test_a_gravity_error_read_as_a_relative_error_of_g_lets_the_released_arm_stop(
    follows, monkeypatch
):
    """The calibration's 0.4 Nm bias on joint 2 is mostly the drive gain's share of G.

    Taken as a relative error of G (``gravity_share``), it shrinks with G along the path
    and the released arm stops; kept constant (as before), the 0.37 Nm left over where G is
    small reads as a push along the shoulder's motion and it coasts for 0.54 s (0.67 s with
    the 6 Hz calibration of before).
    """
    if not follows:
        monkeypatch.setattr(lead_through, "gravity_share",
                            lambda bias, gravity, limit: np.zeros_like(bias))  # fmt: skip
    result = run_case(DRIVE_GAIN_BIAS, "active")
    assert result.calibrated
    if follows:
        assert result.stop_time <= 0.5 and result.drift < 1e-3
    else:
        assert result.stop_time > 0.5


#: Dry #1 of a family whose levels are 0.5–1.5 of the model's: under the calibration's own
#: feed-forward its wrist (0.52× the model's level) runs more than 60 mrad (four strokes) off the
#: motion and stops the run (under the 6 Hz loop of before: at 2.01 rad/s, too fast).
RAN_AWAY = Case("dry", 1, "relaxed", "upwards", PlantRanges(friction_scale=(0.5, 1.5)))


@pytest.mark.parametrize("trusted", [False, True], ids=["not trusted", "model's error"])
def test_a_joint_the_calibration_ran_away_keeps_none_of_its_friction(trusted, monkeypatch):
    """Refused as run away (off its motion), that joint's friction error is 1: the arm stops.

    With the model's level and error (as before), the compensation and the estimate trust a
    level twice the wrist's: the released arm ran on 1.25 rad in active mode.
    """
    if trusted:
        monkeypatch.setattr(calibration_run.Calibration, "lowered",
                            lambda self: np.ones_like(self.friction_scale))  # fmt: skip
    result = run_case(RAN_AWAY, "active")
    assert not result.calibrated
    _runs_on_or_stops(result, trusted, beyond=0.1)


@pytest.mark.parametrize("case", [FAR_FROM_THE_POSE, OFF_AT_THE_POSE], ids=str)
def test_released_passive_arm_stops_and_stays(case):
    """The defaults: the passive arm let go at speed stops within 0.5 s, then stays."""
    result = run_case(case, "passive", _passive())
    assert result.stop_time <= 0.5 and result.drift < 1e-3


def test_without_a_calibration_the_ceiling_counts_all_of_gravity():
    """No calibration: G may be off by gravity_uncertainty · |G|; the arm still stops."""
    result = run_case(UNCALIBRATED, "passive", _passive(calibrate=False))
    assert result.stop_time <= 0.5 and result.drift < 1e-3
    thesis = _passive(calibrate=False, mass_uncertainty=0.0, drive_gain_uncertainty=0.0)
    assert run_case(UNCALIBRATED, "passive", thesis).drift > 0.1


def test_uncalibrated_the_ceiling_counts_the_unit_spread_of_the_friction_levels():
    """No level measured on this arm: its error is the spread of units (0.35), not 0.2."""
    result = run_case(UNIT_SPREAD, "passive", _passive(calibrate=False))
    assert result.stop_time <= 0.5 and result.drift < 1e-3
    model_only = _passive(calibrate=False, unmeasured_friction_error=0.0)
    assert run_case(UNIT_SPREAD, "passive", model_only).drift > 0.1


def test_without_the_ceiling_the_arm_far_from_the_calibration_pose_slides_on(monkeypatch):
    """Gravity error not counted (both uncertainties 0): the compensation keeps it going."""
    _calibration_of_the_time(monkeypatch)
    result = run_case(FAR_FROM_THE_POSE, "passive",
                      _passive(mass_uncertainty=0.0, drive_gain_uncertainty=0.0))  # fmt: skip
    assert result.drift > 0.1


def test_without_the_correction_the_arm_slides_under_the_gravity_error(monkeypatch):
    """The calibration's gravity error left out of the model: the arm slides on."""
    _calibration_of_the_time(monkeypatch)
    result = run_case(OFF_AT_THE_POSE, "passive", _passive(_Uncorrected))
    assert result.drift > 0.1


def test_the_calibrations_gravity_error_is_in_the_model_it_holds_the_arm_with():
    """Feed-forward, observer and law all use G(q) − bias from the calibration on."""
    robot = lt.robots.yumi()
    controller = LeadThrough(robot, mode="active", calibrate=True)
    simulate(DigitalTwin(robot, sample_plant(robot, 7, "dry").config), controller, 1.5)
    bias = controller.calibration.bias
    assert controller.calibration.accepted and np.max(np.abs(bias)) > 0.2  # gravity is off
    np.testing.assert_array_equal(controller.gravity_correction, -bias)
    model = controller.model
    uncorrected = controller.dynamics.gravity(model.q)
    at_pose = controller.dynamics.gravity(controller.calibration.pose)
    share = controller.gravity_share  # the part of the bias that follows G
    assert np.any(share != 0.0)
    expected = uncorrected - bias - share * (uncorrected - at_pose)
    np.testing.assert_allclose(model.gravity, expected, atol=1e-12)
    np.testing.assert_allclose(controller.last_feed_forward.gravity, model.gravity, atol=1e-12)
    assert np.max(np.abs(controller.bias)) < 0.5 * np.max(np.abs(bias))  # not removed twice


def test_ceiling_is_the_friction_surely_there_minus_the_gravity_error():
    """(1 − e_f) τ_C − gravity error, never below 0, NaN passed on."""
    coulomb = np.array([1.0, 1.0, 0.5, 0.2])
    ceiling = compensation_ceiling(coulomb, 0.2, np.array([0.0, 0.3, 0.5, np.nan]))
    np.testing.assert_allclose(ceiling, [0.8, 0.5, 0.0, np.nan])


def test_compensation_never_exceeds_its_ceiling():
    """Settled compensation of a moving joint: min(ε τ_C, ceiling) for small and large ΔG."""
    robot = lt.robots.yumi()
    feed_forward = PassiveFeedForward(lt.Dynamics(robot), dt=0.004, friction_error=0.2,
                                         gravity_uncertainty=0.15)  # fmt: skip
    q = robot.home()
    gravity = lt.Dynamics(robot).gravity(q)
    level = feed_forward.friction.coulomb_level(q)
    for reference in (gravity, gravity - 3.0, np.zeros(7)):
        feed_forward.reset()
        for _ in range(200):  # past the compensation filter's settling
            torques = feed_forward.step(q, np.full(7, 0.5), None, None, reference)
        ceiling = compensation_ceiling(level, 0.2, 0.15 * np.abs(gravity - reference))
        expected = np.minimum(0.7 * level, ceiling)
        np.testing.assert_allclose(torques.friction, expected, rtol=1e-9)


class _OperatorWeightDampingLaw(ActiveLaw):
    """The virtual damping set by the operator weight, as before the push had a direction."""

    compiled = False

    def _damping_weight(self, push, moving):
        return self.weight.copy()


class _OperatorWeightDamping(LeadThrough):
    law_class = _OperatorWeightDampingLaw


def test_released_active_arm_stops_once_nothing_sustains_its_motion():
    """The defaults: after the hand lets go on the circle, the arm stops within 0.5 s."""
    result = run_case(COASTING, "active")
    assert result.stop_time <= 0.5 and result.drift < 1e-3


def test_damping_on_the_operator_weight_lets_the_released_arm_coast(monkeypatch):
    """The drag the law reads once nobody holds the arm kept the damping low: it coasted.

    Without the unwinding of a lagging joint's reference, as when the case was found:
    that stops the coasting arm too (its references relax to the joints friction slows);
    with the dither parked after 2 s, as then: parked after 0.5 s it ends the coast; and
    with the levels read known to the calibration's 20 % everywhere, as then: known to
    their readings near the pose, it stops after 0.52 s and 0.6 mrad (0.57 s, 1.4 mrad);
    and with the thesis' compensation, the diagonal damping and the thesis' dither in
    active mode, as then (with today's damping it stops within 0.13 s).
    """
    two_second_park(monkeypatch)
    constant_level_error(monkeypatch)
    unread_torque_offset(monkeypatch)
    thesis_compensation(monkeypatch)
    diagonal_damping(monkeypatch)
    saturating_gravity_share(monkeypatch)  # as then: its fade alone stops it after 0.47 s

    def factory(robot, mode):
        parameters = lt.LeadThroughParameters(unwind_time=None)
        return _OperatorWeightDamping(robot, mode=mode, dt=0.004, parameters=parameters,
                                      calibrate=True)  # fmt: skip

    result = run_case(COASTING, "active", factory)
    assert result.stop_time > 0.5 and result.drift > 1e-3


class _NumPyLaw(ActiveLaw):
    """The readable law (its module's functions can be swapped in a test)."""

    compiled = False


class _NumPyLeadThrough(LeadThrough):
    law_class = _NumPyLaw


@pytest.mark.parametrize("settled", [True, False], ids=["settled", "held"])
def test_a_stopped_joint_is_not_held_against_stiction_by_the_tracking_spring(settled, monkeypatch):
    """Released, the arm stays where friction stopped it; the tracking spring crept it.

    With the reference of a resting joint nobody pushes drawn to where it is, joint 3
    moves about as little as in passive mode (0.3 mrad against 0.24: the dither's creep
    under the gravity error); with the reference held, the spring's 0.17 Nm and the
    dither creep it 0.9 mrad. Each joint's own estimate, as when the case was found: read
    together as a force at the tool (the default) the held reference creeps 0.54 mrad,
    the settled one 0.34. Without the unwinding of a lagging joint's reference, as when
    the case was found: with it the held reference creeps 0.59 mrad, the settled 0.37. With
    the calibration and the dither (parked after 2 s) of the time: parked after 0.5 s,
    the dither ends the creep either way. And with the gravity error kept constant, the
    diagonal damping and the thesis' dither in active mode.
    """
    _calibration_of_the_time(monkeypatch)
    two_second_park(monkeypatch)
    constant_gravity_bias(monkeypatch)
    diagonal_damping(monkeypatch)
    if not settled:
        monkeypatch.setattr(active_law, "settled_reference", lambda q_ref, *args: q_ref)

    def factory(robot, mode):
        parameters = lt.LeadThroughParameters(tool_force=None, unwind_time=None)
        return _NumPyLeadThrough(robot, mode=mode, dt=0.004, parameters=parameters,
                                 calibrate=True)  # fmt: skip

    result = run_case(SPRING_HELD, "active", factory)
    assert result.stop_time <= 0.5
    assert (result.drift < 0.5e-3) if settled else (result.drift > 0.7e-3)


class _RawVelocityLaw(ActiveLaw):
    """The law's friction terms at the measured velocity, however slow (no rest band)."""

    def sliding_velocity(self, qd):
        return qd


class _RawVelocity(LeadThrough):
    law_class = _RawVelocityLaw


@pytest.mark.parametrize("cls, rectified", [(LeadThrough, False), (_RawVelocity, True)])
def test_a_resting_joint_twitched_by_the_dither_reads_no_push_on_average(cls, rectified):
    """A twitch below rest_velocity (here +4 / −1 mrad/s, the estimate swinging with it).

    Below ``rest_velocity`` the law sees a joint at rest in both phases: the drive
    averages to nothing. At the raw velocity the margin and the uncertainty follow the
    twitch, the weight passes one phase's drag more than the other's, and the average
    drive (up to 0.23 Nm) creeps the joint (1.2 mrad in 4 s in the sixty-second session).
    """
    robot = lt.robots.yumi()
    law = cls(robot, "active").law
    q, gravity, drives = robot.home(), np.zeros(7), []
    for k in range(400):
        up = k % 2 == 0
        law.operator_torque(np.full(7, -0.2 if up else 0.2), q, np.full(7, 0.004 if up else -0.001),
                            gravity)  # fmt: skip
        drives.append(law.drive.copy())
    mean = np.abs(np.mean(drives, axis=0))
    assert (np.max(mean) > 0.1) if rectified else (np.max(mean) < 1e-3)


#: Held out (seed 20): released, the light wrist joint 5 (τ_C ≈ 0.3 Nm) ran ahead of its
#: references into its end-stop, 1.3 rad, with the calibration reading that joint from its
#: stick-slip jumps: its gravity correction was then 0.09 Nm off and the level falls 20 %
#: along the travel, so the feed-forward pushed it.
RUNS_AHEAD = Case("dry", 20, "relaxed", "sideways")
#: The same plant's worst release once the re-anchoring was fixed: 198 mrad in 1.7 s.
JUMPS_READ = Case("dry", 20, "stiff", "sideways")
#: Held out (seed 28): the calibration read the wrist's joint 6 from 3 and 6 paced readings
#: taken between stick-slip jumps (+20 % level, gravity 0.16 Nm off): released, the passive
#: arm ran 0.9 rad into the joint's soft limit.
FEW_READINGS = Case("lugre", 28, "relaxed", "sideways")
#: Held out (seed 32): a plain least-squares fit read the drive gains' gravity errors as a
#: 0.20 kg payload; once the arm had moved sideways its torque put 0.57 Nm of error on
#: joint 4, and the released arm ran 1.3 rad in either mode.
SPURIOUS_PAYLOAD = Case("lugre", 32, "stiff", "sideways")
#: Held out (seed 29): at 5 mrad and 0.05 rad/s the calibration's readings of joint 4, which
#: stuck and jumped at 3× the pace, were its filtered velocity's edges: its level came out
#: 16 % high, and released, the passive arm slid 1.5 rad on that joint (the level falls 19 %
#: along the travel, the drive applies 9 % more than commanded).
STICK_SLIP_READ = Case("lugre", 29, "relaxed", "sideways")


class _VelocityReanchoredLaw(_NumPyLaw):
    """Lost tracking re-anchors the velocity reference to the joint's too (before)."""

    def _admittance(self, q, qd, drive, mass, push):
        references = self.references
        if references is not None:
            lost = np.abs(references.q_ref - q) > self.parameters.reanchor_error
            self.references = AdmittanceState(references.q_ref,
                                              np.where(lost, qd, references.qd_ref))  # fmt: skip
        return super()._admittance(q, qd, drive, mass, push)


class _VelocityReanchored(LeadThrough):
    law_class = _VelocityReanchoredLaw


@pytest.mark.parametrize("cls, runs", [(LeadThrough, False), (_VelocityReanchored, True)])
def test_a_joint_running_ahead_of_its_references_is_braked_not_followed(cls, runs, monkeypatch):
    """Lost tracking re-anchors the position reference only: the damping still brakes.

    Re-anchored to the joint's velocity too, the reference took up the run and the PD's
    damping, the one thing that brakes a joint the law reads no push on, went with it.
    The feed-forward error that drives the joint here is the calibration's reading of its
    jumps (counted again for this test; see the next one) through the observer, as then,
    and the references are not unwound, each joint's Coulomb band is its own, the
    compensation the thesis' and the resting reference drawn after a joint that moves (as
    when the case was found; today's reference stays, which also stops it), and the
    measurement delay as told (the plant's, read from the data, also stops it), and the
    joints read together as a force at the tool alone (with a push elsewhere weighed in,
    the re-anchored arm stops too).
    """
    monkeypatch.setattr(calibration_run, "_JUMPING", np.inf)
    _calibration_of_the_time(monkeypatch)
    observer_readings(monkeypatch)
    own_rest_bands(monkeypatch)
    thesis_compensation(monkeypatch)
    told_measurement_delay(monkeypatch)  # dry #20 has two periods of delay
    saturating_gravity_share(monkeypatch)  # as then (its fade also stops it)
    if runs:  # the resting reference of the time, which followed a joint that runs
        settled_after_moving_joints(monkeypatch)

    def factory(robot, mode):
        parameters = lt.LeadThroughParameters(
            unwind_time=None, tool_force=ToolForceParameters(tool_prior=None)
        )
        return cls(robot, mode=mode, dt=0.004, parameters=parameters, calibrate=True)

    result = run_case(RUNS_AHEAD, "active", factory)
    _runs_on_or_stops(result, runs, beyond=0.5)


@pytest.mark.parametrize("jumps_read", [False, True], ids=["paced", "jumps read"])
def test_a_calibration_that_reads_only_paced_sliding_lets_the_wrist_stop(jumps_read, monkeypatch):
    """Dry #20's joint 5 sticks and jumps at 3.5× the calibration's speed, where the observer lags.

    Read from its jumps, its gravity correction was 0.09 Nm off and the released arm ran on
    198 mrad; read only at the calibration's pace, it has too few readings, is left
    unmeasured (its friction known to the unit spread) and the arm stops. With the
    observer's readings of the time (``as_found.observer_readings``): the momentum balance
    the calibration reads now has no lag, and reads this wrist's jumps without the error.
    """
    _calibration_of_the_time(monkeypatch)
    observer_readings(monkeypatch)
    if jumps_read:
        monkeypatch.setattr(calibration_run, "_JUMPING", np.inf)
    result = run_case(JUMPS_READ, "active")
    _runs_on_or_stops(result, jumps_read, beyond=0.05)


@pytest.mark.parametrize("few_read", [False, True], ids=["measured", "a few readings read"])
def test_a_joint_the_calibration_read_only_a_few_times_keeps_its_level(few_read, monkeypatch):
    """Lugre #28's wrist slid at pace in a handful of samples only: its level is not measured.

    Measured from them (any three readings each way, as before), its level and gravity came
    out +20 % and 0.16 Nm off, and the passive feed-forward ran the released arm on; with
    the model's level and its gravity counted as not known, the arm stops. With the
    calibration motion and the observer's readings of the time (the default motion slides
    that wrist long enough; the momentum balance reads it within 5 % even from few samples).
    """
    slow_calibration_motion(monkeypatch)
    unread_torque_offset(monkeypatch)
    observer_readings(monkeypatch)
    if few_read:
        monkeypatch.setattr(calibration_run, "_MEASURED", 0.0)
    result = run_case(FEW_READINGS, "passive", _passive())
    _runs_on_or_stops(result, few_read, beyond=0.1)


@pytest.mark.parametrize("plain", [False, True], ids=["weighed", "plain fit"])
def test_a_payload_the_gravity_errors_do_not_show_stays_out_of_the_model(plain, monkeypatch):
    """Lugre #32: drive gains that look like a payload at the pose are not taken for one.

    With the calibration reading no offset of the torque measurement and keeping its gravity
    error constant, as when it was found (taken as a relative error of G, the plain fit's
    arm no longer runs on 0.1 rad).
    """
    unread_torque_offset(monkeypatch)
    constant_gravity_bias(monkeypatch)
    if plain:
        monkeypatch.setattr(calibration_run.CalibrationRun, "payload", _plain_payload_fit)
    result = run_case(SPURIOUS_PAYLOAD, "passive", _passive())
    _runs_on_or_stops(result, plain, beyond=0.1)


@pytest.mark.parametrize("slow", [False, True], ids=["sliding", "stick-slip read"])
def test_a_calibration_that_slides_above_the_stribeck_range_lets_the_arm_stop(slow, monkeypatch):
    """Lugre #29: the calibration's motion, 15 mrad at 0.1 rad/s, reads joint 4 sliding.

    At 5 mrad and 0.05 rad/s (before) the joint stuck and jumped, the readings were the
    edges of its jumps and its level came out 16 % high: the passive arm ran on. With the
    observer's readings of the time, whose lag made those edges readings, and before the
    drift check (``max_drift``), which refuses those readings too: they moved between the
    motion's cycles.
    """
    observer_readings(monkeypatch)
    if slow:
        slow_calibration_motion(monkeypatch)
        unchecked_drift(monkeypatch)
    result = run_case(STICK_SLIP_READ, "passive", _passive())
    _runs_on_or_stops(result, slow, beyond=0.1)


@pytest.mark.parametrize("share, runs", [(None, False), (0.0, True)], ids=["margin", "none"])
def test_a_model_that_overstates_every_level_by_its_whole_error_stops(share, runs, monkeypatch):
    """Every level of dry #1 0.8 of a model measured on this arm to ±0.2: the arm stops.

    The margin takes the measured level's whole error (0.2 of the model's friction);
    without it the estimate reads the friction the model overstates as a push along the
    motion and the released arm runs on (320 mrad when this was written).
    """
    if share is not None:
        friction_margin_share(monkeypatch, share)

    def measured_model(robot, mode):
        model = dataclasses.replace(lt.FrictionModel.from_robot(robot),
                                    relative_error=np.full(robot.n_joints, 0.2))  # fmt: skip
        return LeadThrough(robot, mode=mode, dt=0.004, friction=model)

    result = run_case(Case("dry", 1, "relaxed", "sideways", OVERSTATED), "active", measured_model)
    _runs_on_or_stops(result, runs, beyond=0.1)


@pytest.mark.parametrize("widened, runs", [(True, False), (False, True)],
                         ids=["error-widened", "model-error-alone"])  # fmt: skip
def test_a_refused_calibration_that_read_a_level_low_still_stops_the_released_arm(
    widened, runs, monkeypatch
):
    """Refused, the run's low reading of joint 1 still widens its friction error: it stops.

    Without (the refused calibration left no trace) the model's level, about twice the
    plant's, reads as a push along the motion that the 0.35 margin does not cover (with
    the diagonal damping and the thesis' dither of the time: with today's it drifts 3.8
    mrad, past the budget still). With the
    observer's readings of the time: the momentum balance reads joint 1 at 0.64× (the
    plant's 0.65×), inside the plausible band, and the calibration is accepted. And with
    the 6 Hz loop of the time: the 4 Hz one reads joint 1 inside the band too. And with
    the measurement delay as told: read from the data, without the rule it drifts 9.95
    mrad, at the edge of this test's 10. And with the bias' confidence learned at rest
    too: learned only where a joint slides, the law passes less of the level's error, and
    without the rule the arm drifts 3.9 mrad (16.7 with the confidence of the time).
    """
    observer_readings(monkeypatch)
    six_hertz_calibration(monkeypatch)
    diagonal_damping(monkeypatch)
    told_measurement_delay(monkeypatch)  # dry #11 of the wider family has two periods
    confidence_at_rest(monkeypatch)
    if not widened:
        monkeypatch.setattr(Calibration, "lowered", lambda self: np.ones(7))
    result = run_case(READ_LOW, "active")
    assert not result.calibrated
    _runs_on_or_stops(result, runs, beyond=0.01)


def _uncalibrated(**dither):
    """Uncalibrated controllers, their dither's settings changed by ``dither``."""
    parameters = lt.LeadThroughParameters()
    parameters = dataclasses.replace(
        parameters, dither=dataclasses.replace(parameters.dither, **dither)
    )
    return lambda robot, mode: LeadThrough(robot, mode=mode, dt=0.004, parameters=parameters)


@pytest.mark.parametrize("case, mode", [(DITHERED_CREEP, "passive"), (DITHERED_CREEP, "active"),
                                        (CREDITED_CREEP, "active")], ids=str)  # fmt: skip
def test_the_dither_parks_on_a_creep_within_the_drift_budget(case, mode):
    """Released, uncalibrated: the dither parks as the joint creeps, within 1 mrad."""
    result = run_case(case, mode, _uncalibrated())
    assert result.stop_time <= 0.5 and result.drift < 1e-3


@pytest.mark.parametrize("case", [DITHERED_CREEP, CREDITED_CREEP], ids=str)
def test_parked_after_two_seconds_alone_the_dithered_creep_leaves_the_drift_budget(
    case, monkeypatch
):
    """Parked only after 2 s of rest, not on the creep: the same creeps run past 1 mrad.

    With the dither not kept under the compensation's ceiling, as when they were found
    (under the ceiling they creep 0.6 mrad even so).
    """
    uncapped_dither(monkeypatch)
    assert run_case(case, "active", _uncalibrated(creep=None)).drift > 1e-3


@pytest.mark.parametrize("case", [DITHERED_CREEP, CREDITED_CREEP], ids=str)
def test_under_the_ceiling_the_dither_alone_leaves_no_creep_past_the_budget(case):
    """The same creeps, parked after 2 s alone, stay within 1 mrad under the dither's ceiling.

    What the ceiling prevents: uncalibrated, a level known to 35 % and a gravity error leave
    less than the dither's amplitude of friction surely there on the creeping joint (0.6 mrad
    here).
    """
    result = run_case(case, "active", _uncalibrated(creep=None))
    assert result.stop_time <= 0.5 and result.drift < 1e-3


def test_at_a_kilohertz_the_released_active_arm_stops_as_at_250_hz():
    """A 1 kHz arm: the twin runs at the controller's period, the released arm still stops.

    Nothing in the defaults is counted in periods of 4 ms (filters, times and noise
    intensities are in seconds), so a controller built with ``dt=0.001`` on a plant
    sampled at 1 kHz keeps the release goals (the control loop refuses a controller whose
    period differs from the twin's, so the run itself shows the twin ran at 1 ms).
    """
    result = run_case(COASTING, "active", functools.partial(default_factory, dt=0.001))
    assert result.stop_time <= 0.5 and result.drift < 1e-3


#: Uncalibrated, masses 10 % and drive gains 20 % off (beyond the family), the arm resting
#: 5 s before the hand takes it: stiction held the shoulder's gravity error unseen there.
RESTED_FIRST = Case("dry", 3, "stiff", "upwards", PlantRanges(mass_error=0.1, com_error=0.01,
                    torque_gain=(0.8, 1.2)), rest=5.0)  # fmt: skip


def test_a_rest_does_not_vouch_for_the_gravity_model(monkeypatch):
    """What growing the bias' confidence only where a joint slides prevents (``ModelErrorBias``).

    Uncalibrated, the gravity tolerance is the whole model's until a joint slides with
    nobody guiding. Vouched for by the rest before the grab, it narrowed to the change of
    G since, and the released arm ran on the error stiction had hidden: 0.34 rad over 10 s.
    """
    result = run_case(RESTED_FIRST, "active", uncalibrated_factory)
    assert result.stop_time <= 0.5 and result.drift < 1e-3
    confidence_at_rest(monkeypatch)
    assert run_case(RESTED_FIRST, "active", uncalibrated_factory).drift > 0.1
