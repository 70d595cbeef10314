"""The admittance does not wind up against a joint that stiction holds (issue 13).

On a LuGre plant with a relaxed hand pulling sideways, joint 3 sticks while the hand loads
it. Without the unwinding of a lagging joint's velocity reference (``unwind_time`` None,
the previous default) the admittance ran on at the speed the push asked for; at breakaway
the PD's stored push added to the hand's and the joint slipped, the estimate read the
slip's drag, the reference braked and the joint stuck again: stick-slip that shook the
tool 1.43× as much as passive mode (1.15× with it; the benchmark's goal is ≤ 1.5×), with
the calibration motion and the law's Coulomb bands of the time. With today's defaults
(the calibration slides faster, the joints read together narrow a resting joint's band):
1.47× wound up, 1.29× unwound.
"""

import numpy as np
import pytest

import leadthrough as lt
from as_found import (
    observer_readings,
    own_rest_bands,
    saturating_gravity_share,
    slow_calibration_motion,
    two_second_park,
    unread_torque_offset,
)
from leadthrough.experiments.guiding import Case, run_case, vibration_windows

STICK_SLIP = Case("lugre", 1, "relaxed", "sideways")


def _active(unwind_time):
    def factory(robot, mode):
        parameters = lt.LeadThroughParameters(unwind_time=unwind_time)
        return lt.LeadThrough(robot, mode=mode, dt=0.004, parameters=parameters, calibrate=True)

    return factory


def _vibration_ratios(*unwind_times):
    """Active / passive vibration of the case, the admittance unwound after each time."""
    passive = run_case(STICK_SLIP, "passive").vibration
    return [run_case(STICK_SLIP, "active", _active(t)).vibration / passive for t in unwind_times]


def test_a_joint_held_by_stiction_shakes_the_tool_no_more_than_the_goal():
    """The defaults: the tool shakes ≤ 1.5× passive mode's (the benchmark's goal)."""
    (unwound,) = _vibration_ratios(0.05)
    assert unwound <= 1.5


def test_a_joint_held_by_stiction_does_not_wind_the_admittance_up(monkeypatch):
    """Unwound, the tool shakes ≥ 15 % less than wound up.

    With the calibration motion the case was found with (5 mrad at 0.05 rad/s) and each
    joint's own Coulomb band in the law: 1.15× against 1.43×. With the defaults, 1.29×
    against 1.47×. And with the dither parked after 2 s, as then (parked after 0.5 s it
    stops twitching both arms in the hold, whose 2 s count in the vibration), and no
    offset of the torque measurement read by the calibration, and the calibration reading
    the observer, as then.
    """
    slow_calibration_motion(monkeypatch)
    observer_readings(monkeypatch)
    unread_torque_offset(monkeypatch)
    own_rest_bands(monkeypatch)
    two_second_park(monkeypatch)
    saturating_gravity_share(monkeypatch)  # as then
    unwound, wound_up = _vibration_ratios(0.05, None)
    assert unwound <= 0.85 * wound_up


def test_vibration_windows_split_the_cases_vibration():
    """Equal windows over the held run: their mean square is the case's vibration squared.

    To 0.1 %: a window's edge on the sampled time may move a sample from one to the next.
    """
    starts, rms = vibration_windows(STICK_SLIP, "passive")
    assert np.allclose(np.diff(starts), 0.5) and rms.size == 12  # 4 s path + 2 s hold
    whole = run_case(STICK_SLIP, "passive").vibration
    assert np.sqrt(np.mean(rms**2)) == pytest.approx(whole, rel=1e-3)
