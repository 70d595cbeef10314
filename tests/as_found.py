"""Defaults as they were, for tests that show cases found with them."""

import dataclasses
import math

import numpy as np

from leadthrough.control import active_law, admittance, dither, feedforward
from leadthrough.control.active_law import ActiveLaw
from leadthrough.control.bias import ModelErrorBias
from leadthrough.control.calibration import CalibrationParameters, CalibrationRun
from leadthrough.control.calibration import run as calibration_run
from leadthrough.control.dither import DitherParameters
from leadthrough.control.feedforward import PassiveFeedForward
from leadthrough.control.interface_delay import InterfaceDelay
from leadthrough.control.lead_through import LeadThrough
from leadthrough.control.ticks import TickClock
from leadthrough.friction.compensation import CoulombCompensationParameters

#: Before: 5 mrad at 0.05 rad/s, inside the plants' Stribeck range, a level refused
#: outside 1 / 1.75–1.75× the model's, and a level read known to ``friction_accuracy``
#: everywhere, its pose included.
SLOW = {"stroke": 0.005, "speed": 0.05, "max_friction_change": 0.75, "level_slope": None,
        "bandwidth": 6.0, "predict": "never"}  # fmt: skip
#: Before: a 6 Hz loop and a 10 mrad stroke at 250 Hz, a loop that grows with two periods
#: of delay (``CalibrationParameters.bandwidth``), tracking the samples (today's default
#: would predict there, ``CalibrationParameters.predict``).
SIX_HERTZ = {"stroke": 0.01, "bandwidth": 6.0, "predict": "never"}


def slow_calibration_motion(monkeypatch) -> None:
    """Every ``CalibrationParameters()`` built during the test moves as before (:data:`SLOW`).

    The default calibration of ``LeadThroughParameters`` included, so a case runs through
    the public API exactly as it did when it was found.
    """
    built_as(monkeypatch, CalibrationParameters(**SLOW))
    stamped_calibration(monkeypatch)


def stamped_calibration(monkeypatch) -> None:
    """The calibration's time is the stamps' as they come, not their ticks (``TickClock``).

    The twin's stamps are sums of periods, off their ticks by 1e-16 s; the calibration's
    triangular motion turns at whole periods, and a stamp a hair before or after a turn
    takes the quarter before or after it: the cases were found with the sums.
    """

    def stamps(clock, t):
        if clock.start is None:
            clock.start = t
        since = t - clock.start
        periods = 1 if math.isnan(clock.tick) else max(1, round((since - clock.tick) / clock.dt))
        clock.tick = since
        return periods

    monkeypatch.setattr(TickClock, "advance", stamps)


def six_hertz_calibration(monkeypatch) -> None:
    """Every ``CalibrationParameters()`` built in the test tracks as before (:data:`SIX_HERTZ`)."""
    built_as(monkeypatch, CalibrationParameters(**SIX_HERTZ))


def unchecked_push(monkeypatch) -> None:
    """Every calibration runs to its end whatever the observer reads, as before ``check_push``.

    A loop that rings reads as a push on the arm; these cases were found when only a joint
    too fast or too far off the motion stopped a run.
    """
    monkeypatch.setattr(CalibrationRun, "check_push", lambda run, estimate: None)


def unchecked_drift(monkeypatch) -> None:
    """Every calibration's readings may move between its cycles, as before ``max_drift``."""
    monkeypatch.setattr(CalibrationRun, "drift",
                        lambda run, t, plus, minus: np.full(plus.shape[1], np.nan))  # fmt: skip


def constant_gravity_bias(monkeypatch) -> None:
    """Every calibration's gravity error stays a constant, as before ``gravity_share``."""
    from leadthrough.control import lead_through

    monkeypatch.setattr(lead_through, "gravity_share",
                        lambda bias, gravity, limit: np.zeros_like(bias))  # fmt: skip


def saturating_gravity_share(monkeypatch) -> None:
    """Every calibration's gravity share stays at ±its limit however large the bias, as before.

    Now it fades to 0 where the bias is twice what a drive gain can make
    (``calibration.gravity_share``); the released arms of the cases found with the share
    saturated move less with it.
    """
    from leadthrough.control import lead_through

    def saturating(bias, gravity, limit):
        with np.errstate(divide="ignore", invalid="ignore"):
            share = np.where(gravity != 0.0, bias / gravity, 0.0)
        return np.clip(share, -limit, limit)

    monkeypatch.setattr(lead_through, "gravity_share", saturating)


def constant_level_error(monkeypatch) -> None:
    """Every calibration leaves a level it read its ``friction_accuracy`` at every pose.

    As before ``CalibrationParameters.level_slope``: the error did not grow from the
    readings' scatter at the pose with the travel from it (and the loop moved as it then
    did, :data:`SIX_HERTZ`).
    """
    built_as(monkeypatch, CalibrationParameters(level_slope=None, **SIX_HERTZ))


def built_as(monkeypatch, before) -> None:
    """Every instance of ``before``'s dataclass built during the test defaults to its fields."""
    defaults = tuple(getattr(before, item.name) for item in dataclasses.fields(before))
    monkeypatch.setattr(type(before).__init__, "__defaults__", defaults)


def own_rest_bands(monkeypatch) -> None:
    """Every active law keeps each joint's whole Coulomb band, as before ``ActiveLaw.narrow``."""
    monkeypatch.setattr(ActiveLaw, "narrow", lambda law, fused_std, own_std: None)


def settled_after_moving_joints(monkeypatch) -> None:
    """The NumPy law's resting reference follows a joint that moves on its own, as before.

    Before, ``settled_reference`` looked at the admittance's rest only, not the joint's.
    """

    def as_before(q_ref, q, moving, weight, rate, joint_moving=0.0):
        return admittance.settled_reference(q_ref, q, moving, weight, rate)

    monkeypatch.setattr(active_law, "settled_reference", as_before)


def friction_margin_share(monkeypatch, share: float = 1.0) -> None:
    """Every active law's friction margin removes ``share`` of the level's whole error.

    The default removes all of it (``ActiveLaw.margin_share``); 0 removes none.
    """
    monkeypatch.setattr(ActiveLaw, "margin_share", share)


def two_second_park(monkeypatch) -> None:
    """Every ``DitherParameters()`` built during the test parks after 2 s of rest only, as before.

    Parked on the creep itself (``creep``), the dither ends the creeps some of these
    cases showed.
    """
    built_as(monkeypatch, DitherParameters(park_time=2.0, creep=None))


def uncapped_dither(monkeypatch) -> None:
    """The dither not kept under the compensation's ceiling, as before (the NumPy step).

    Uncalibrated, where the ceiling is below 0.3 τ_C, the ceiling ends creeps the dither
    drove.
    """
    monkeypatch.setattr(PassiveFeedForward, "compiled", False)
    monkeypatch.setattr(feedforward, "dither_within", lambda dither, ceiling: dither)


def unread_torque_offset(monkeypatch) -> None:
    """Every calibration reads no offset of the torque measurement, as before it did.

    No ``Calibration.torque_offset``: the readings' gravity error then carries the
    measurement's offset (±0.05 Nm on the benchmark's plants), which went into the model
    and onto the arm: part of the gravity error that ran on the released arms of the
    cases found then.
    """
    monkeypatch.setattr(CalibrationRun, "torque_offset", lambda run: None)


def thesis_compensation(monkeypatch) -> None:
    """Every compensation keeps the thesis' law in active mode too, as before ``follow_push``.

    Following the push a calibrated arm's admittance reads, a joint slowed below the
    compensation's ramp keeps its compensation: the coasts and runs some of these cases
    showed then go on longer, for a reason of its own.
    """
    built_as(monkeypatch, CoulombCompensationParameters(follow_push="never"))


def observer_readings(monkeypatch) -> None:
    """Every calibration reads the observer at each sample at pace, as before the momentum balance.

    The readings of the time: the Kalman observer's estimate, fed the robot's filtered
    velocity (15–40 Hz, with its lag), taken at each sample whose *filtered* velocity was
    between a quarter and twice the motion's speed. The inertial torque of the motion
    and of the tracking's ringing passed into those readings (up to ±2 Nm on a Panda).
    The run keeps, next to each sample it records, that velocity and estimate. The band
    took the gravity they gave as exact then (:func:`exact_calibrated_gravity`).
    """
    exact_calibrated_gravity(monkeypatch)
    calibrate, record = LeadThrough._calibrate, CalibrationRun.record
    current = {}  # the controller calibrating and the velocity of its sample

    def observed(controller, t, model, tau_measured):
        current.update(controller=controller, velocity=model.qd.copy())
        return calibrate(controller, t, model, tau_measured)

    def recorded(run, t, q, tau, discrepancy=None):
        samples = len(run._balance)
        record(run, t, q, tau, discrepancy)
        if len(run._balance) > samples:
            estimate = current["controller"].observer.tau_ext_hat.copy()
            run.__dict__.setdefault("observed", []).append((current["velocity"], estimate))

    def readings(run):
        observed = run.__dict__.get("observed", [])
        t = run._balance.arrays()[0]
        velocity = np.array([sample[0] for sample in observed]).reshape(len(t), -1)
        estimate = np.array([sample[1] for sample in observed]).reshape(len(t), -1)
        speed, pace = np.abs(velocity), run.parameters.speed
        sliding, jumping = calibration_run._SLIDING * pace, calibration_run._JUMPING * pace
        paced = (speed > sliding) & (speed <= jumping)
        paced = (speed > sliding) & (speed <= jumping)
        return t, velocity, np.where(paced, estimate, np.nan)

    monkeypatch.setattr(LeadThrough, "_calibrate", observed)
    monkeypatch.setattr(CalibrationRun, "record", recorded)
    monkeypatch.setattr(CalibrationRun, "readings", readings)


def exact_calibrated_gravity(monkeypatch) -> None:
    """The band takes the gravity a calibration measured as exact, as before.

    ``LeadThrough.joint_std`` now counts the readings' scatter as that gravity's error
    (the scatter of the observer's readings of the time was large): it widens the band
    the joints are read together with, which alone stops some of the runs found then.
    """
    finish = LeadThrough._finish_calibration

    def exact(controller, result, t):
        finish(controller, result, t)
        controller._gravity_reading_std[:] = 0.0

    monkeypatch.setattr(LeadThrough, "_finish_calibration", exact)


def diagonal_damping(monkeypatch) -> None:
    """Active mode as it was before its damping was shaped like the arm (the NumPy law).

    ``D̃`` diagonal, ``m_ii / T`` weighed per joint, and the thesis' 0.3 τ_C dither in
    active mode too (the creep park stays per joint): the cases found with them ran further
    or shook more than they do now.
    """
    monkeypatch.setattr(ActiveLaw, "compiled", False)
    shaped = admittance.virtual_damping
    monkeypatch.setattr(active_law, "virtual_damping",
                        lambda mass, *args: np.diag(np.diag(shaped(mass, *args))))  # fmt: skip
    monkeypatch.setattr(dither, "ACTIVE_AMPLITUDE", 0.3)


def told_measurement_delay(monkeypatch) -> None:
    """Every controller keeps the ``measurement_delay`` it is told, as before it read it."""
    monkeypatch.setattr(InterfaceDelay, "update", lambda estimate, tau_measured: estimate.delay)


def confidence_at_rest(monkeypatch) -> None:
    """Every law's bias vouches for the gravity model at rest too, as before (the NumPy law).

    Each joint's confidence grew as fast as nobody guided, sliding or not: a rest of a few
    seconds narrowed the gravity tolerance to the change of G since, though stiction had
    held the model's error unseen there.
    """
    monkeypatch.setattr(ActiveLaw, "compiled", False)
    update = ModelErrorBias.update

    def as_if_sliding(self, estimate, gravity, dt, bound, sliding, unguided=1.0):
        return update(self, estimate, gravity, dt, bound, np.ones_like(sliding), unguided)

    monkeypatch.setattr(ModelErrorBias, "update", as_if_sliding)
