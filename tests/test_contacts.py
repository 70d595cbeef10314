"""Contact detection: the online detector, and detect_contacts over synthetic and real logs."""

import warnings

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.estimation.contacts import ContactDetector, ContactParameters
from leadthrough.estimation.log_observer import (
    LogInputError,
    ModelUncertainty,
    gravity_scale,
    observe_log,
    run_detector,
)
from realdata import REALDATA, needs_realdata


def synthetic_log(robot, push=None, duration=6.0, seed=0, current=False):
    """A log whose torque is what the model needs, minus a known external torque.

    The arm follows slow sinusoids about its home pose; time stamps jitter between 8 and
    12 ms. ``push``: (start [s], end [s], torque (n,) [Nm]) applied as τ_ext.
    """
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.008, 0.012, int(duration / 0.01)))
    n = robot.n_joints
    phase = rng.uniform(0, 2 * np.pi, n)
    omega = 2 * np.pi * rng.uniform(0.1, 0.3, n)
    q = robot.home() + 0.4 * np.sin(omega * t[:, None] + phase)
    qd = 0.4 * omega * np.cos(omega * t[:, None] + phase)
    qdd = -0.4 * omega**2 * np.sin(omega * t[:, None] + phase)
    dynamics, friction = lt.Dynamics(robot), lt.FrictionModel.from_robot(robot)
    tau = np.array([dynamics.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])
    tau += friction.mean(qd, q)
    if push is not None:
        start, end, torque = push
        tau -= np.where(((t >= start) & (t < end))[:, None], np.asarray(torque), 0.0)
    tau += rng.normal(0.0, 0.2, tau.shape)
    if current:
        return lt.JointLog(t, q, qd, current=tau / robot.torque_constants, source="synthetic")
    return lt.JointLog(t, q, qd, tau, source="synthetic")


def test_detector_finds_a_rectangular_push_with_its_timing_and_joint():
    """A 20σ step on joint 2 from 1 to 2 s: one event, dated to the sample, joint 1 only."""
    detector = ContactDetector(3)
    rng = np.random.default_rng(1)
    for t in np.arange(0.0, 3.0, 0.01):
        tau = rng.normal(0.0, 0.3, 3) + (np.array([0.0, 20.0, 0.0]) if 1.0 <= t < 2.0 else 0.0)
        detector.update(t, tau, np.ones(3))
    detector.finish()
    (event,) = detector.events
    assert event.start == pytest.approx(1.0, abs=0.015)
    assert event.end == pytest.approx(2.0, abs=0.015)
    assert event.joints == (1,)
    assert event.peak[1] == pytest.approx(20.0, abs=1.5)


def test_detector_ignores_a_short_spike_and_merges_close_events():
    """A 30 ms spike is no contact; two pushes 0.1 s apart are one event."""
    detector = ContactDetector(1, min_duration=0.1, merge_gap=0.2)
    for t in np.arange(0.0, 4.0, 0.01):
        spike = 10.0 if 0.5 <= t < 0.53 else 0.0
        pushes = 10.0 if (1.0 <= t < 1.5) or (1.6 <= t < 2.0) else 0.0
        detector.update(t, [spike + pushes], [1.0])
    detector.finish()
    assert [(round(e.start, 2), round(e.end, 2)) for e in detector.events] == [(1.0, 2.0)]


def test_detector_parameters_are_validated():
    """An off threshold above the on threshold is a one-line parameter error."""
    with pytest.raises(lt.ParameterError, match="off"):
        ContactParameters(on=2.0, off=3.0)


def test_detect_contacts_finds_an_injected_push_on_a_jittered_log(ur10e):
    """A 25 Nm push on joint 3 during motion: found within 0.1 s, on joint 3 alone."""
    log = synthetic_log(ur10e, push=(2.0, 3.0, [0, 0, 25.0, 0, 0, 0]))
    events = lt.detect_contacts(log, ur10e, None)
    assert len(events) == 1
    (event,) = events
    assert event.start == pytest.approx(2.0, abs=0.1)
    assert event.end == pytest.approx(3.0, abs=0.25)
    assert event.joints == (2,)
    assert event.peak[2] == pytest.approx(25.0, rel=0.2)


def test_a_held_arm_is_read_from_its_torque_balance(ur10e):
    """An arm held at a pose by its own controller, pushed 1 s with 3 τ_C on the shoulder.

    Its motors answer the push (τ = G − τ_ext), nothing moves: within 0.1 s the estimate
    reads the push to 10 %, and the push is one event. The Kalman observer alone took the
    friction at rest for white noise of the stiction's size: it read 7.0 Nm of this 39.8 Nm
    push after its whole second, and found no contact.
    """
    rng = np.random.default_rng(2)
    t = 0.01 * np.arange(400)
    q = np.tile(ur10e.home(), (t.size, 1)) + rng.normal(0.0, 1e-5, (t.size, ur10e.n_joints))
    push = np.zeros_like(q)
    pushed = (t >= 1.5) & (t < 2.5)
    push[pushed, 1] = 3.0 * lt.FrictionModel.from_robot(ur10e).coulomb[1]
    gravity = np.array([lt.Dynamics(ur10e).gravity(x) for x in q])
    tau = gravity - push + rng.normal(0.0, 0.2, q.shape)
    log = lt.JointLog(t, q, np.zeros_like(q), tau, source="held.csv")
    observed = observe_log(log, ur10e)
    settled = pushed & (t >= 1.6)
    np.testing.assert_allclose(observed.tau_ext[settled, 1], push[settled, 1], rtol=0.1)
    (event,) = lt.detect_contacts(log, ur10e, None)
    assert event.joints == (1,) and event.start == pytest.approx(1.5, abs=0.1)


def test_detect_contacts_finds_nothing_in_free_motion(ur10e):
    """Free motion of the exact model with torque noise: no event on three seeds."""
    for seed in range(3):
        assert lt.detect_contacts(synthetic_log(ur10e, seed=seed), ur10e, None) == []


def test_currents_are_turned_into_torque_with_the_robots_constants(ur10e):
    """A current-only log gives the same estimate as the torque log it came from."""
    torque = observe_log(synthetic_log(ur10e), ur10e)
    current = observe_log(synthetic_log(ur10e, current=True), ur10e)
    np.testing.assert_allclose(current.tau_ext, torque.tau_ext, atol=1e-9)


def test_a_log_without_torque_or_current_is_a_one_line_error(ur10e):
    """No torque and no current: LogInputError naming the log."""
    log = synthetic_log(ur10e)
    bare = lt.JointLog(log.t, log.q, log.qd, source="bare.csv")
    with pytest.raises(LogInputError, match=r"bare\.csv: the log has neither"):
        lt.detect_contacts(bare, ur10e, None)


def test_seven_joints_work():
    """The Panda (7 joints): a push on joint 4 is found on joint 4."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        panda = lt.robots.panda()
    log = synthetic_log(panda, push=(1.5, 2.5, [0, 0, 0, 15.0, 0, 0, 0]), duration=4.0)
    (event,) = lt.detect_contacts(log, panda, None)
    assert event.joint == 3


def read(relative, robot):
    """A real UR10e log read with the robot (currents → torque)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return lt.read_log(REALDATA / "ur10e" / relative, robot=robot)


@needs_realdata
def test_every_push_of_the_static_run_is_found(ur10e):
    """ur-static.csv: four pushes, four events, each within 0.3 s of its push's start.

    A push starts where the torque balance of the held arm, ``G(q) − K·i``, leaves its
    resting value by 8 Nm on a joint (3.24, 11.64, 25.43 and 38.01 s; events at 3.23,
    11.68, 25.41 and 38.25 s). Before a joint at rest was read from its torque balance
    (``log_observer``), the Kalman observer alone took the last push as friction for 1.1 s
    (events at 3.5, 11.9, 25.7, 39.1 s).
    """
    log = read("pushes/ur-static.csv", ur10e)
    dynamics = lt.Dynamics(ur10e)
    balance = np.array([dynamics.gravity(q) for q in log.q])
    balance -= log.joint_torque(ur10e.torque_constants)
    pushed = np.abs(balance - balance[:50].mean(axis=0)).max(axis=1) > 8.0  # [Nm]
    onsets = log.t[1:][np.diff(pushed.astype(int)) == 1] - log.t[0]
    starts = [event.start - log.t[0] for event in lt.detect_contacts(log, ur10e, None)]
    assert len(starts) == 4
    for start in starts:
        assert np.min(np.abs(onsets - start)) < 0.3, (start, onsets)


@needs_realdata
def test_the_pushes_during_slow_motion_are_found(ur10e):
    """link4.csv: the pushes at about 3.5 s and 9.5 s and the stop at 16.6 s."""
    log = read("pushes/link4.csv", ur10e)
    starts = [event.start - log.t[0] for event in lt.detect_contacts(log, ur10e, None)]
    for push in (3.5, 9.5, 16.6):
        assert min(abs(start - push) for start in starts) < 0.3


@needs_realdata
@pytest.mark.parametrize(
    "relative",
    [
        "pushes/no_torque.csv",
        "validation/collision_free.csv",
        "validation/ur-20_01_17-ptp_10_points.csv",
    ],
)
def test_nothing_is_found_in_free_motion(ur10e, relative):
    """Free-motion runs with the nominal model: no event."""
    assert lt.detect_contacts(read(relative, ur10e), ur10e, None) == []


def test_gravity_scale_is_zero_on_a_vertical_axis_and_sets_a_std_floor(ur10e):
    """Joint 1 (vertical axis) carries no gravity; every std ≥ ε_g · G_rms of its joint."""
    scale = gravity_scale(ur10e)
    assert scale[0] == pytest.approx(0.0, abs=1e-9)
    assert scale[1] > scale[2] > scale[3] > 0.0  # shoulder, elbow, wrist 1
    observed = observe_log(synthetic_log(ur10e), ur10e, None, ModelUncertainty(gravity=0.2))
    assert np.all(observed.std_model >= 0.2 * scale - 1e-9)


def test_a_gravity_offset_where_gravity_crosses_zero_is_no_contact(ur10e):
    """Joint 2 sweeping slowly through upright (G ≈ 0) with 12 Nm of gravity model error.

    Without the ε_g floor the relative error says σ ≈ 4 Nm there and the offset reads as
    a contact; with it (default) it does not.
    """
    dynamics, friction = lt.Dynamics(ur10e), lt.FrictionModel.from_robot(ur10e)
    t = np.arange(0.0, 10.0, 0.01)
    q = np.tile([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0], (t.size, 1))
    qd = np.zeros_like(q)
    q[:, 1] += 0.05 * (t - 5.0)
    qd[:, 1] = 0.05
    tau = np.array([dynamics.gravity(x) for x in q]) + friction.mean(qd, q)
    log = lt.JointLog(t, q, qd, tau=tau + np.array([0.0, 12.0, 0.0, 0.0, 0.0, 0.0]))
    bare = observe_log(log, ur10e, None, ModelUncertainty(gravity=0.0))
    assert len(run_detector(bare)) == 1
    assert lt.detect_contacts(log, ur10e, None) == []
