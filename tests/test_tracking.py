"""Joint tracking: computed torque, a PD whose gains are the inertia matrix of the pose."""

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.tracking import (
    VERIFIED_PERIOD,
    JointTracker,
    decaying_damping,
    loop_damping,
    pd_gains,
    period_bandwidth,
    predicted_state,
)


def test_gains_follow_the_inertia_of_the_current_pose():
    """K_P = M(q) ω², K_D = 2 ζ M(q) ω at the pose of each call, not the first one."""
    dynamics = lt.Dynamics(lt.robots.yumi())
    tracker = JointTracker(dynamics, bandwidth=4.0, damping_ratio=0.8)
    omega = 2.0 * np.pi * 4.0
    rng = np.random.default_rng(2)
    robot = dynamics.robot
    for q in rng.uniform(robot.q_min, robot.q_max, (5, robot.n_joints)):
        error, rate_error = rng.normal(0.0, 0.01, (2, robot.n_joints))
        torque = tracker.torque(q, np.zeros(7), q + error, rate_error, np.zeros(7))
        inertia = dynamics.mass(q)
        expected = dynamics.gravity(q) + inertia @ (omega**2 * error)
        expected += inertia @ (2.0 * 0.8 * omega * rate_error)
        np.testing.assert_allclose(torque, expected, rtol=1e-12, atol=1e-12)


def test_inertia_of_the_yumi_elbow_changes_fourfold():
    """Why the gains must follow the pose: joint 3's inertia varies by 4× over the range."""
    dynamics = lt.Dynamics(lt.robots.yumi())
    robot = dynamics.robot
    poses = np.random.default_rng(0).uniform(robot.q_min, robot.q_max, (400, robot.n_joints))
    inertia = np.array([dynamics.mass(q)[2, 2] for q in poses])
    assert inertia.max() / inertia.min() > 3.0


def test_coupled_joints_keep_the_bandwidth_where_two_axes_align():
    """Panda at q₂ = 0 (axes 1 and 3 aligned): every closed-loop mode has ω, none faster.

    The linearised loop q̈ = M⁻¹ K_P e has eigenvalues ω² (computed torque); per-joint
    gains m_ii ω² give ω² · eig(M⁻¹ diag M), which is far above ω² there.
    """
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Panda's assumed gear ratio: not what is tested
        robot = lt.robots.panda()
    dynamics = lt.Dynamics(robot)
    tracker = JointTracker(dynamics, bandwidth=4.0)
    q = robot.home()
    q[1] = 0.0
    mass = dynamics.mass(q)
    stiffness = np.column_stack([
        tracker.torque(q, np.zeros(7), q + 1e-3 * unit, np.zeros(7), np.zeros(7))
        - dynamics.gravity(q)
        for unit in np.eye(7)
    ]) / 1e-3  # fmt: skip
    loop = np.linalg.eigvals(np.linalg.solve(mass, stiffness)).real
    np.testing.assert_allclose(loop, (2.0 * np.pi * 4.0) ** 2, rtol=1e-9)
    per_joint = np.linalg.eigvals(np.linalg.solve(mass, np.diag(np.diag(mass)))).real
    assert per_joint.max() > 5.0  # what per-joint gains would have multiplied ω² by


def test_the_loop_model_has_the_damping_of_a_pd_on_a_double_integrator():
    """Without delay, filter or sampling to speak of, the loop is q̈ = −ω² q − 2ζω q̇: ζ."""
    for zeta in (0.3, 0.7):
        gains = pd_gains(zeta)(2.0 * np.pi * 4.0)
        damping = loop_damping(gains, 1e-6, delay=0, velocity_cutoff=1e7)
        assert damping == pytest.approx(zeta, rel=1e-3)


def test_a_slower_rate_leaves_the_loop_less_damping_and_the_bandwidth_keeps_it():
    """The period's bandwidth: the ceiling up to 250 Hz; slower, the largest with its margin."""
    gains = pd_gains()
    verified = loop_damping(gains(2.0 * np.pi * 6.0), VERIFIED_PERIOD)
    assert loop_damping(gains(2.0 * np.pi * 6.0), 0.008) < 0.0  # 6 Hz at 125 Hz: it grows
    assert period_bandwidth(6.0, 0.001, gains) == period_bandwidth(6.0, 0.004, gains) == 6.0
    previous = 6.0
    for dt in (0.005, 0.008, 0.01, 0.02):
        bandwidth = period_bandwidth(6.0, dt, gains)
        assert bandwidth < previous
        assert loop_damping(gains(2.0 * np.pi * bandwidth), dt) >= verified
        assert loop_damping(gains(2.0 * np.pi * 1.01 * bandwidth), dt) < verified
        previous = bandwidth
    assert period_bandwidth(6.0, 0.008, gains) == pytest.approx(3.92, abs=0.02)


def _simulated_growth(gains, dt, delay, cutoff, periods=3000, predicted=False):
    """Growth rate [1/s] of the loop of :func:`loop_damping`, simulated period by period.

    The arm integrated with 50 Runge–Kutta substeps per period (not the exact
    discretisation), from a 1 mrad error; the rate is fitted to the envelope's last third.
    ``predicted``: the controller tracks the state one period ahead under the acceleration
    its previous command asked for, its integral's share left out (written out here).
    """
    stiffness, damping, integral = gains
    cutoff = 2.0 * np.pi * cutoff
    q, qd, v, accumulated, queue = 1e-3, 0.0, 0.0, 0.0, [0.0] * delay
    asked = 0.0  # the previous command's acceleration, its integral's share left out
    h = dt / 50
    peaks = []

    def derivative(x, torque):
        return np.array([x[1], torque, cutoff * (x[1] - x[2])])

    for _ in range(periods):
        tracked, velocity = q, v
        if predicted:
            tracked, velocity = q + dt * v + 0.5 * dt**2 * asked, v + dt * asked
        accumulated -= dt * tracked
        asked = -stiffness * tracked - damping * velocity
        queue.append(asked + integral * accumulated)
        torque = queue.pop(0)
        x = np.array([q, qd, v])
        for _ in range(50):
            k1 = derivative(x, torque)
            k2 = derivative(x + h / 2 * k1, torque)
            k3 = derivative(x + h / 2 * k2, torque)
            k4 = derivative(x + h * k3, torque)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q, qd, v = x
        peaks.append(abs(q))
    chunk = round(0.25 / dt)  # the envelope: the largest error of each 0.25 s
    envelope = np.array(peaks[periods // 3 :][: (periods - periods // 3) // chunk * chunk])
    envelope = envelope.reshape(-1, chunk).max(axis=1)
    return np.polyfit(np.arange(len(envelope)) * 0.25, np.log(envelope), 1)[0]


@pytest.mark.parametrize("bandwidth, dt, delay, predicted",
                         [(6.0, 0.004, 1, False), (6.0, 0.008, 1, False), (4.0, 0.008, 2, False),
                          (3.0, 0.008, 2, False), (3.95, 0.008, 2, True), (3.41, 0.01, 2, True),
                          (3.95, 0.008, 3, True)])  # fmt: skip
def test_the_loop_model_grows_or_decays_as_the_loop_simulated_in_time(
    bandwidth, dt, delay, predicted
):
    """Where the model says the loop grows (ζ < 0) the simulated loop grows, and vice versa.

    With the prediction too: 3.95 Hz at 125 Hz and 3.41 Hz at 100 Hz decay with two periods
    of delay (they grow without it, ``test_the_prediction_takes_a_period_out_of_the_loop``)
    and still grow with three.
    """
    gains = pd_gains(1.0, 0.25)(2.0 * np.pi * bandwidth)
    modelled = loop_damping(gains, dt, delay, velocity_cutoff=15.0, predicted=predicted)
    growth = _simulated_growth(gains, dt, delay, 15.0, round(3.0 / dt), predicted)
    assert np.sign(growth) == -np.sign(modelled)


def test_the_prediction_is_a_double_integrators_motion_under_a_held_acceleration():
    """``predicted_state`` against the arm integrated in time (Runge–Kutta, 100 substeps).

    A double integrator under a held acceleration, from (q, q̇): its state one period on,
    and two predictions of one period chained equal one of two periods.
    """
    q, qd = np.array([0.1, -0.2]), np.array([0.5, 0.0])
    acceleration, period = np.array([2.0, -3.0]), 0.01
    x, h = np.concatenate([q, qd]), period / 100

    def derivative(x):
        return np.concatenate([x[2:], acceleration])

    for _ in range(100):
        k1 = derivative(x)
        k2 = derivative(x + h / 2 * k1)
        k3 = derivative(x + h / 2 * k2)
        k4 = derivative(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    ahead, speed = predicted_state(q, qd, acceleration, period)
    np.testing.assert_allclose(ahead, x[:2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(speed, x[2:], rtol=0, atol=1e-12)
    twice = predicted_state(*predicted_state(q, qd, acceleration, period), acceleration, period)
    np.testing.assert_allclose(twice, predicted_state(q, qd, acceleration, 2 * period))


@pytest.mark.parametrize("dt, bandwidth", [(0.008, 3.95), (0.01, 3.41), (0.004, 4.0)])
def test_the_prediction_takes_a_period_out_of_the_loop(dt, bandwidth):
    """One period predicted: two periods of delay damp about as one did without it.

    At 125 Hz and 100 Hz the calibration's loop grows with two periods unpredicted (ζ
    −0.07, −0.08) and decays predicted (required ≥ 0.05; 0.10 and 0.11); at every rate it
    gains damping.
    """
    gains = pd_gains(1.0, 0.25)(2.0 * np.pi * bandwidth)
    for delay in (1, 2):
        assert loop_damping(gains, dt, delay, predicted=True) > loop_damping(gains, dt, delay)
    assert loop_damping(gains, dt, 2, predicted=True) > 0.05
    if dt > VERIFIED_PERIOD:
        assert loop_damping(gains, dt, 2) < 0.0


def test_a_damping_asked_for_is_kept_by_the_largest_bandwidth_up_to_the_ceiling():
    """With ``damping`` given, slower rates keep it instead of the ceiling's at 250 Hz."""
    gains = pd_gains(1.0, 0.25)
    assert period_bandwidth(4.0, 0.004, gains, damping=0.9) == 4.0  # 250 Hz: the ceiling
    assert period_bandwidth(4.0, 0.005, gains, damping=0.14) == 4.0  # it keeps 0.14 there
    for dt in (0.008, 0.01):
        bandwidth = period_bandwidth(4.0, dt, gains, damping=0.14)
        assert bandwidth > period_bandwidth(4.0, dt, gains)  # 0.14 asks less than 4 Hz's 0.36
        assert loop_damping(gains(2.0 * np.pi * bandwidth), dt) >= 0.14
        assert loop_damping(gains(2.0 * np.pi * 1.01 * bandwidth), dt) < 0.14


def test_a_loop_damped_more_at_250_hz_than_any_bandwidth_keeps_slower_gets_the_best_one():
    """A 2 Hz calibration loop is damped 0.71 at 250 Hz, more than any keeps at 125 Hz."""
    gains = pd_gains(1.0, 0.25)
    bandwidth = period_bandwidth(2.0, 0.008, gains)
    assert 0.0 < bandwidth < 2.0
    best = max(loop_damping(gains(2.0 * np.pi * f), 0.008) for f in np.linspace(0.04, 2.0, 200))
    assert loop_damping(gains(2.0 * np.pi * bandwidth), 0.008) >= best - 0.01


@pytest.mark.parametrize("dt, bandwidth", [(0.008, 3.95), (0.01, 3.41), (0.004, 4.0)])
def test_the_least_damping_that_decays_is_where_the_loop_turns(dt, bandwidth):
    """``decaying_damping``: just below it the loop grows, from it on it decays; 0 at 250 Hz.

    With two periods of delay the calibration's loop at 125 Hz and 100 Hz needs a viscous
    friction of about 7 per second per unit inertia (the YuMi's joints 4–6 have 8–14, the
    Panda's at most 0.7); at 250 Hz it decays without any.
    """
    gains = pd_gains(1.0, 0.25)(2.0 * np.pi * bandwidth)
    least = decaying_damping(gains, dt)
    if dt <= VERIFIED_PERIOD:
        assert least == 0.0 and loop_damping(gains, dt, 2) > 0.0
        return
    assert 5.0 < least < 9.0
    assert loop_damping(gains, dt, 2, viscous=least) >= 0.0
    assert loop_damping(gains, dt, 2, viscous=least - 0.01) < 0.0
    assert loop_damping(gains, dt, 2, viscous=2.0 * least) > 0.0
