"""Tests of replay (SPEC §8): planning, its refusals, and tracking on the digital twin."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.replay import (
    STOP_ACCELERATION,
    Replayer,
    ReplayParameters,
    plan_replay,
    replay_errors,
)
from leadthrough.errors import ParameterError, ReplayError
from leadthrough.experiments import replay_quality
from leadthrough.safety.supervisor import SafetySupervisor, SupervisorState
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.runner import simulate
from leadthrough.twin.simulator import DigitalTwin, TwinConfig

ROBOT = lt.robots.yumi()
N = ROBOT.n_joints
DT = 0.004
HOME = ROBOT.home()
#: The taught path's pauses (:data:`~leadthrough.experiments.replay_quality.PIECES`).
PAUSES = ((1.7, 2.2), (3.7, 4.2))  # [s]


@pytest.fixture(scope="module")
def dyn() -> lt.Dynamics:
    """The YuMi's dynamics."""
    return lt.Dynamics(ROBOT)


def taught_path() -> tuple[np.ndarray, np.ndarray]:
    """A 6 s taught path at 250 Hz: every joint moves 0.2–0.4 rad around home, two pauses.

    Minimum-jerk moves between four poses, read through the twin's encoder quantisation
    (:func:`~leadthrough.experiments.replay_quality.taught_path`).
    """
    return replay_quality.taught_path(ROBOT, DT)


def sinusoid(amplitude: float = 0.2, frequency: float = 0.2, duration: float = 6.0):
    """A slow sinusoid on every joint around home: times [s], q [rad], q̇ [rad/s]."""
    t = np.arange(round(duration / DT) + 1) * DT
    wave = np.sin(2 * np.pi * frequency * t)[:, None] * amplitude * np.ones(N)
    rate = 2 * np.pi * frequency * np.cos(2 * np.pi * frequency * t)[:, None] * amplitude
    return t, HOME + wave, rate * np.ones(N)


def test_smoothing_leaves_a_smooth_path_unchanged(dyn):
    """A slow sinusoid comes out of the zero-phase smoothing within 1e-4 rad, its speed too."""
    t, q, qd = sinusoid()
    plan = plan_replay(t, q, dyn)  # it ends moving: brought to rest after it, which the
    n = len(t) - round(0.1 / DT)  # filter blends into its last 0.1 s (0.2 mrad at the cut)
    assert np.max(np.abs(plan.q[:n] - q[:n])) < 1e-4
    assert np.max(np.abs(plan.qd[5:n] - qd[5:n])) < 1e-3


def test_smoothing_removes_step_noise(dyn):
    """A path read through a coarse 2 mrad encoder (a staircase) comes out near the true one."""
    t, q, qd = sinusoid()
    steps = np.round(q / 2e-3) * 2e-3
    plan = plan_replay(t, steps, dyn)
    raw_speed = np.gradient(steps, DT, axis=0)
    n = len(t)
    assert np.sqrt(np.mean((plan.q[:n] - q) ** 2)) < 0.25 * np.sqrt(np.mean((steps - q) ** 2))
    assert np.max(np.abs(plan.qd[:n] - qd)) < 0.05 < 0.2 < np.max(np.abs(raw_speed - qd))


def test_pauses_are_waypoints_between_motion_segments(dyn):
    """Two 0.5 s stops give two waypoints inside them and three motion segments around them."""
    t, q = taught_path()
    plan = plan_replay(t, q, dyn)
    assert len(plan.waypoints) == 2 and len(plan.segments) == 3
    for waypoint, (start, stop) in zip(plan.waypoints, PAUSES, strict=True):
        assert abs(plan.t[waypoint] - (start + stop) / 2) < 0.02
    moving = np.zeros(len(plan.t), dtype=bool)
    for a, b in plan.segments:
        moving[a:b] = True
    for start, stop in PAUSES:
        middle = (plan.t > start + 0.1) & (plan.t < stop - 0.1)
        assert not moving[middle].any()
    assert np.all(np.abs(plan.qd[~moving]).max(axis=1) < 0.01)


def test_time_scale_two_doubles_the_duration_and_halves_the_speed(dyn):
    """time_scale = 2: same path, twice the time, half the speed, a quarter the acceleration."""
    t, q = taught_path()
    normal = plan_replay(t, q, dyn)
    slow = plan_replay(t, q, dyn, parameters=ReplayParameters(time_scale=2.0))
    assert slow.duration == pytest.approx(2.0 * normal.duration)
    np.testing.assert_allclose(slow.q, normal.q)
    np.testing.assert_allclose(slow.qd, normal.qd / 2.0)
    np.testing.assert_allclose(slow.qdd, normal.qdd / 4.0)
    assert slow.waypoints == normal.waypoints and slow.segments == normal.segments
    inertial = normal.tau_required - slow.tau_required  # gravity is the same in both
    assert np.max(np.abs(inertial)) > 0.01


def test_required_torque_is_inverse_dynamics_plus_mean_friction(dyn):
    """tau_required equals RNEA + the friction mean at sampled points of the plan."""
    t, q = taught_path()
    plan = plan_replay(t, q, dyn)
    friction = lt.FrictionModel.from_robot(ROBOT)
    for k in (0, 300, 700, 1200):
        expected = dyn.inverse_dynamics(plan.q[k], plan.qd[k], plan.qdd[k])
        expected += friction.mean(plan.qd[k])
        np.testing.assert_allclose(plan.tau_required[k], expected, atol=1e-9)


def refusals() -> dict[str, tuple]:
    """Bad recordings: (t, q, parameters, words the one-line message must contain)."""
    t, q = taught_path()
    near_limit = q.copy()
    near_limit[:, 1] += ROBOT.q_max[1] - 0.01 - q[:, 1].max()  # 10 mrad from the hard limit
    nan = q.copy()
    nan[40, 3] = np.nan
    backwards = t.copy()
    backwards[9] = backwards[8] - DT  # a stamp back (a repeated one is taken: below)
    shake = np.arange(751) * DT
    fast = np.tile(HOME, (len(shake), 1))
    fast[:, 0] += 0.03 * np.sin(2 * np.pi * 4.0 * shake)  # 4 Hz, 30 mrad on joint 1
    quick = ReplayParameters(smoothing_time=0.01, time_scale=0.4)
    return {
        "outside the limits": (t, near_limit, None, ("joint 2", "position", "limit")),
        "too fast": (t, q, ReplayParameters(time_scale=0.1), ("joint 3", "speed", "time_scale")),
        "too much torque": (shake, fast, quick, ("joint 1", "torque", "time_scale")),
        "NaN": (t, nan, None, ("joint 4", "nan")),
        "short": (t[:1], q[:1], None, ("at least 2 samples",)),
        "non-increasing t": (backwards, q, None, ("not increasing", "t[9]")),
        "wrong shape": (t, q[:, :6], None, ("shape",)),
    }


@pytest.mark.parametrize("case", list(refusals()))
def test_bad_paths_are_refused_in_one_line_naming_the_joint(dyn, case):
    """Each bad recording raises a one-line ReplayError naming the joint (or what is wrong)."""
    t, q, parameters, words = refusals()[case]
    with pytest.raises(ReplayError) as caught:
        plan_replay(t, q, dyn, parameters=parameters)
    message = str(caught.value)
    assert "\n" not in message
    for word in words:
        assert word in message
    if words[0].startswith("joint"):
        assert caught.value.joint == int(words[0].split()[1])


@pytest.mark.parametrize("case", ["too fast", "too much torque"])
def test_the_suggested_time_scale_passes_and_is_close_to_the_least(dyn, case):
    """Speed/torque refusals suggest a time_scale that passes, within 10 % of one that fails."""
    t, q, parameters, _ = refusals()[case]
    with pytest.raises(ReplayError) as caught:
        plan_replay(t, q, dyn, parameters=parameters)
    scale = caught.value.suggested_time_scale
    assert scale > parameters.time_scale
    base = {"smoothing_time": parameters.smoothing_time}
    plan_replay(t, q, dyn, parameters=ReplayParameters(**base, time_scale=scale))
    with pytest.raises(ReplayError):
        plan_replay(t, q, dyn, parameters=ReplayParameters(**base, time_scale=scale / 1.1))


def test_the_plan_leaves_the_tracking_a_share_of_the_limits(dyn):
    """Planned within ``limit_share`` (0.85) of the speed limit, not up to the limit itself.

    At the limit the tracking's overshoot ran a UR5's joint 4 12 % over its speed limit,
    braked by the supervisor (a review). The least time scale that passes with the whole
    limit (``limit_share = 1``) is refused with the default share and passes 1/0.85 slower.
    """
    t, q, parameters, _ = refusals()["too fast"]
    with pytest.raises(ReplayError, match=r"beyond 85% of its limit .* \(the tracking needs"):
        plan_replay(t, q, dyn, parameters=parameters)
    full = ReplayParameters(time_scale=parameters.time_scale, limit_share=1.0)
    with pytest.raises(ReplayError) as caught:
        plan_replay(t, q, dyn, parameters=full)
    at_the_limit = caught.value.suggested_time_scale
    plan = plan_replay(t, q, dyn, parameters=ReplayParameters(time_scale=at_the_limit / 0.85))
    assert np.max(np.abs(plan.qd) / ROBOT.velocity_limits) <= 0.85
    with pytest.raises(ReplayError):
        plan_replay(t, q, dyn, parameters=ReplayParameters(time_scale=at_the_limit))


def test_a_pose_gravity_alone_cannot_hold_says_no_time_scale_helps():
    """An arm whose shoulder's gravity at the taught pose is beyond 85 % of its limit.

    Before, the refusal said "not even 20 times slower passes", as if slower could help
    (a review: Talos' arm at its assumed home).
    """
    weak = dataclasses.replace(ROBOT, joints=tuple(
        dataclasses.replace(joint, torque_limit=1.0) if i == 1 else joint
        for i, joint in enumerate(ROBOT.joints)))  # fmt: skip
    dynamics = lt.Dynamics(weak)
    assert abs(dynamics.gravity(HOME)[1]) > 0.85  # [Nm]: the shoulder holds more at home
    t, q = taught_path()
    with pytest.raises(ReplayError, match=r"against gravity alone takes joint 2 .* Nm: no time "
                       r"scale helps$"):  # fmt: skip
        plan_replay(t, q, dynamics)


@pytest.mark.parametrize("share", [0.0, -0.5, 1.2, np.nan])
def test_a_limit_share_outside_0_1_is_refused(share):
    """A share of the limits: in (0, 1], or a one-line error naming it."""
    with pytest.raises(lt.ParameterError, match="limit_share"):
        ReplayParameters(limit_share=share)


def test_a_repeated_stamp_keeps_its_first_sample(dyn):
    """A coarse clock repeats stamps (the supervisor takes them while teaching): planned.

    Before, one repeated stamp refused the whole recording ("time not increasing").
    """
    t, q = taught_path()
    repeated = t.copy()
    repeated[9] = repeated[8]
    plan = plan_replay(repeated, q, dyn)
    reference = plan_replay(np.delete(t, 9), np.delete(q, 9, axis=0), dyn)
    np.testing.assert_allclose(plan.q, reference.q)


def test_a_path_cut_while_moving_is_brought_to_rest(dyn):
    """A recording cut at full speed (Ctrl-C mid-motion): the plan decelerates, then ends.

    Before, its reference stopped in one period: 60 rad/s² and 12.7 Nm on joint 2 where the
    path needed 5.6. A path that ends at rest is planned as before.
    """
    t, q = taught_path()
    cut = np.searchsorted(t, 0.95)  # the middle of the first move
    moving = np.abs(np.gradient(q[:cut], t[:cut], axis=0))[-1].max()
    assert moving > 0.3  # [rad/s]
    plan = plan_replay(t[:cut], q[:cut], dyn)
    assert np.abs(plan.qd[-1]).max() < 1e-3 and plan.duration > t[cut - 1] - t[0] + 0.5
    tail = plan.t > t[cut - 1] - t[0]
    assert np.abs(plan.qdd[tail]).max() <= 2.0 * STOP_ACCELERATION  # [rad/s²]
    whole = plan_replay(t, q, dyn)
    assert whole.duration == pytest.approx(t[-1] - t[0])  # it ends at rest: no tail


def test_parameters_are_validated():
    """A non-positive time_scale or bandwidth, or a negative margin, is a ParameterError."""
    for bad in ({"time_scale": 0.0}, {"bandwidth": -1.0}, {"margin": -0.1}, {"pause_time": 0}):
        with pytest.raises(ParameterError):
            ReplayParameters(**bad)


def test_progress_and_done_follow_the_clock(dyn):
    """Progress is 0 during the approach, 1 at the path end; done 0.5 s after the end."""
    t, q = taught_path()
    plan = plan_replay(t, q, dyn)
    replayer = Replayer(plan, dyn, dt=DT)
    steps = round((2.0 + plan.duration + 0.5) / DT)
    log = []
    for _ in range(steps + 1):
        q_now, qd_now, _ = replayer.reference(replayer.time)
        replayer.step(q_now, qd_now + 1e-6 * np.random.default_rng(len(log)).normal(size=N))
        log.append((replayer.time, replayer.progress, replayer.done))
    times, progress, done = map(np.array, zip(*log, strict=True))
    assert np.all(progress[times <= 2.0] == 0.0) and progress[-1] == 1.0
    assert np.all(np.diff(progress) >= 0.0)
    assert not done[times < 2.0 + plan.duration + 0.5 - 1e-6].any() and done[-1]


def test_a_replayer_takes_the_specs_keywords_as_a_controller_does(dyn):
    """``step(q=…, qd=…, tau_measured=…)``: the same commands as the positional form."""
    t, q = taught_path()
    plan = plan_replay(t, q, dyn)
    by_position, by_keyword = Replayer(plan, dyn, dt=DT), Replayer(plan, dyn, dt=DT)
    rng = np.random.default_rng(6)
    for _ in range(50):
        q_now, qd_now, _ = by_position.reference(by_position.time)
        qd_now = qd_now + 1e-6 * rng.normal(size=N)
        expected = by_position.step(q_now, qd_now)
        np.testing.assert_array_equal(by_keyword.step(q=q_now, qd=qd_now), expected)


def test_replay_is_supervised_in_holding_mode(dyn):
    """A teaching supervisor is switched to HOLDING; a NaN reading gives the safe stop."""
    t, q = taught_path()
    supervisor = SafetySupervisor(dyn, DT)
    supervisor.teach()
    replayer = Replayer(plan_replay(t, q, dyn), dyn, dt=DT, supervisor=supervisor)
    assert supervisor.state is SupervisorState.HOLDING
    tau = replayer.step(q[0], np.zeros(N))
    np.testing.assert_allclose(tau, dyn.gravity(q[0]), atol=0.05)
    bad = q[0].copy()
    bad[2] = np.nan
    tau = replayer.step(bad, np.zeros(N))
    assert supervisor.state is SupervisorState.FAULT and "joint 3" in supervisor.fault_reason
    assert np.all(np.isfinite(tau)) and np.all(np.abs(tau) <= ROBOT.torque_limits)


def test_an_exception_in_the_replay_is_named_and_the_arm_stopped_that_period(dyn, monkeypatch):
    """An IndexError in the tracker: fault naming it and its place, the safe stop at once."""
    t, q = taught_path()
    replayer = Replayer(plan_replay(t, q, dyn), dyn, dt=DT)
    replayer.step(q[0], np.zeros(N))

    def broken(*args, **kwargs):
        raise IndexError("index 9 is out of bounds for axis 0 with size 7")

    monkeypatch.setattr(replayer.tracker, "torque", broken)
    tau = replayer.step(q[0], np.zeros(N))
    reason = replayer.supervisor.fault_reason
    assert replayer.supervisor.state is SupervisorState.FAULT
    assert reason.startswith("replay failed: IndexError: index 9 is out of bounds")
    assert "(at control/replay.py:" in reason and "in _desired)" in reason
    np.testing.assert_allclose(tau, dyn.gravity(q[0]), atol=1e-9)  # at rest: the gravity hold


def test_replay_errors_are_zero_on_the_plan_and_exact_for_an_offset(dyn):
    """The plan itself scores 0; a 1 mrad offset on one joint scores 1 mrad / √n RMS."""
    t, q = taught_path()
    plan = plan_replay(t, q, dyn)
    t_run = 2.0 + plan.t
    errors = replay_errors(plan, plan.q, t_run, dyn)
    assert errors["joint_rms"] < 1e-12 and errors["tool_rms"] < 1e-12
    offset = plan.q.copy()
    offset[:, 4] += 1e-3
    errors = replay_errors(plan, offset, t_run)
    assert errors["joint_rms"] == pytest.approx(1e-3 / np.sqrt(N))
    assert errors["joint_max"] == pytest.approx(1e-3)


def run_replay(dyn, config: TwinConfig, q0: np.ndarray, parameters: ReplayParameters | None):
    """Plan the taught path, replay it on a twin started at ``q0``: plan, run, replayer."""
    t, q = taught_path()
    plan = plan_replay(t, q, dyn, parameters=parameters)
    twin = DigitalTwin(ROBOT, config, q0=q0)
    replayer = Replayer(plan, dyn, dt=twin.dt)
    run = simulate(twin, replayer, plan.parameters.approach_time + plan.duration + 0.6)
    return plan, run, replayer


def test_replay_on_the_twin_tracks_within_2_mrad_and_2_mm(dyn):
    """On the twin, started at the path start: joint RMS ≤ 2 mrad, tool-path RMS ≤ 2 mm."""
    q0 = taught_path()[1][0]
    plan, run, replayer = run_replay(dyn, TwinConfig(seed=3), q0, None)
    approach = round(2.0 / DT)
    q_run = run.q_true[approach : approach + len(plan.t)]  # the same plan times
    joint_rms = np.sqrt(np.mean((q_run - plan.q) ** 2))
    planned = np.array([dyn.pose(row)[:3, 3] for row in plan.q])
    flange = run.flange_position[approach : approach + len(plan.t)]
    tool_rms = np.sqrt(np.mean(np.sum((flange - planned) ** 2, axis=1)))
    errors = replay_errors(plan, run.q_true, run.t, dyn, run.flange_position)
    print(f"\nreplay on the twin: joint RMS {joint_rms * 1e3:.3f} mrad (max "
          f"{errors['joint_max'] * 1e3:.2f} mrad), tool RMS {tool_rms * 1e3:.3f} mm (max "
          f"{errors['tool_max'] * 1e3:.2f} mm)")  # fmt: skip
    assert joint_rms <= 2e-3 and tool_rms <= 2e-3
    assert errors["joint_rms"] == pytest.approx(joint_rms, rel=1e-6)
    assert errors["tool_rms"] == pytest.approx(tool_rms, rel=1e-6)
    assert replayer.done and replayer.supervisor.state is SupervisorState.HOLDING
    assert not replayer.supervisor.events


def test_replay_from_elsewhere_slower_on_a_perturbed_arm(dyn):
    """From 0.1 rad away, masses ±5 %, time_scale 1.5: the approach lands, RMS ≤ 2 mrad."""
    q0 = taught_path()[1][0]
    config = TwinConfig(model_error=ModelError(mass_error=0.05, com_error=0.005), seed=4)
    offset = 0.1 * (-1.0) ** np.arange(N)
    plan, run, replayer = run_replay(dyn, config, q0 + offset, ReplayParameters(time_scale=1.5))
    at_start = np.argmin(np.abs(run.t - 2.0))
    assert np.max(np.abs(run.q_true[at_start] - plan.q[0])) < 5e-3
    errors = replay_errors(plan, run.q_true, run.t, dyn, run.flange_position)
    print(f"\nslower, perturbed arm: joint RMS {errors['joint_rms'] * 1e3:.3f} mrad, "
          f"tool RMS {errors['tool_rms'] * 1e3:.3f} mm")  # fmt: skip
    assert errors["joint_rms"] <= 2e-3 and errors["tool_rms"] <= 2e-3
    assert replayer.supervisor.state is SupervisorState.HOLDING


def test_an_approach_from_far_away_is_slowed_to_a_share_of_the_speed_limits(dyn):
    """2.5 rad from the path start on joint 1: the approach takes as long as its speed needs.

    Before, it always took 2 s: 2.3 rad/s on joint 1 (4.4 rad/s from 5.2 rad away, against
    its 3.14 rad/s limit, which the supervisor only braked).
    """
    q0 = taught_path()[1][0]
    start = q0.copy()
    start[0] = q0[0] - 2.5 if q0[0] - 2.5 > ROBOT.q_min[0] + 0.2 else q0[0] + 2.5
    plan = plan_replay(*taught_path(), dyn)
    twin = DigitalTwin(ROBOT, TwinConfig(seed=3), q0=start)
    replayer = Replayer(plan, dyn, dt=twin.dt)
    approach = 1.875 * 2.5 / (0.2 * ROBOT.velocity_limits[0])
    run = simulate(twin, replayer, approach + plan.duration + 0.6)
    assert replayer.approach_time == pytest.approx(approach, rel=1e-4)  # the encoder's start
    during = run.t <= approach
    assert np.max(np.abs(run.qd_true[during, 0])) <= 0.2 * 1.1 * ROBOT.velocity_limits[0]
    assert replayer.done and replayer.supervisor.state is SupervisorState.HOLDING
    errors = replay_errors(plan, run.q_true, run.t, dyn, approach_time=replayer.approach_time)
    assert errors["joint_rms"] <= 2e-3


def test_an_arm_held_back_is_a_fault_not_a_full_torque_push(dyn):
    """The arm does not follow (held, blocked): a fault once 0.1 rad off, the safe stop.

    Before, nothing bounded the tracking error: held back by 29 Nm, joint 1 fell 0.58 rad
    behind under the full 30 Nm, and lunged back at 3.9 rad/s when let go.
    """
    t, q = taught_path()
    plan = plan_replay(t, q, dyn)
    replayer = Replayer(plan, dyn, dt=DT)
    held = plan.q[0].copy()
    for k in range(round((2.0 + plan.duration) / DT)):
        command = replayer.step(lt.JointState(k * DT, held, np.zeros(N), None))
        if replayer.supervisor.state is SupervisorState.FAULT:
            break
    reason = replayer.supervisor.fault_reason
    assert "rad off its reference, more than 0.1 rad: is the arm held or blocked?" in reason
    np.testing.assert_allclose(command, dyn.gravity(held), atol=1e-9)  # the safe stop
    off = np.abs(replayer.reference(replayer.time)[0] - held).max()
    assert 0.1 < off < 0.12  # [rad]: stopped as it passed the bound
    stopped_at, then = replayer.progress, replayer.time
    for k in range(round(plan.duration / DT)):  # the clock runs on: the replay does not
        replayer.step(lt.JointState(then + (k + 1) * DT, held, np.zeros(N), None))
    assert replayer.faulted and replayer.done and replayer.progress == stopped_at < 1.0


def test_a_reset_after_a_fault_approaches_again_from_where_the_arm_is(dyn):
    """A NaN reading mid-path, the safe stop for 1 s, reset(): a new approach, no jump.

    Before, only the supervisor could be reset while the replay clock ran on: the arm, off
    a reference that had moved on, jumped to it at 2.7 rad/s (the path's 0.5 rad/s).
    """
    t, q = taught_path()
    plan = plan_replay(t, q, dyn)
    twin = DigitalTwin(ROBOT, TwinConfig(seed=3), q0=plan.q[0])
    replayer = Replayer(plan, dyn, dt=twin.dt)
    path_speed = np.abs(plan.qd).max()
    fault_at, reset_at = round(3.5 / DT), round(4.5 / DT)
    speeds, k = [], 0
    while k <= reset_at or not replayer.done:
        assert k < reset_at + round((10.0 + plan.duration) / DT)
        state = twin.read_state()
        if k == fault_at:
            state = lt.JointState(state.t, np.full(N, np.nan), state.qd, state.tau_measured)
        if k == reset_at:
            assert replayer.supervisor.state is SupervisorState.FAULT
            replayer.reset()
        twin.send_torque(replayer.step(state))
        if k > reset_at:
            speeds.append(np.abs(twin.truth.qd).max())
        k += 1
    assert replayer.supervisor.state is SupervisorState.HOLDING
    assert max(speeds) <= 1.2 * path_speed  # [rad/s]


def test_integral_action_takes_the_friction_the_model_lacks(dyn):
    """The integral takes the friction the model lacks (stiction, cable): joint RMS −40 %."""
    q0 = taught_path()[1][0]
    runs = {}
    for integral_time in (0.1, 0.0):
        parameters = ReplayParameters(integral_time=integral_time)
        plan, run, _ = run_replay(dyn, TwinConfig(seed=3), q0, parameters)
        runs[integral_time] = replay_errors(plan, run.q_true, run.t)["joint_rms"]
    print(f"\njoint RMS with integral {runs[0.1] * 1e3:.3f} mrad, without {runs[0.0] * 1e3:.3f}")
    assert runs[0.1] < 0.6 * runs[0.0]


@pytest.mark.parametrize("integral_time", [0.1, 0.05, 0.0])
def test_the_gains_are_the_bandwidths_at_250_hz_and_softer_at_125_hz(dyn, integral_time):
    """K_I = K_P / integral_time at 250 Hz; at 125 Hz lower gains, the integral's share kept."""
    plan = plan_replay(
        *taught_path(), dyn, parameters=ReplayParameters(integral_time=integral_time)
    )
    fast, slow = Replayer(plan, dyn, dt=0.004), Replayer(plan, dyn, dt=0.008)
    omega = 2.0 * np.pi * plan.parameters.bandwidth
    np.testing.assert_allclose(fast.tracker.kp, np.diag(dyn.mass(plan.q[0])) * omega**2)
    expected = fast.tracker.kp / integral_time if integral_time else np.zeros(N)
    np.testing.assert_allclose(fast.ki, expected)
    assert np.all(slow.tracker.kp > 0.0) and np.all(slow.tracker.kp < 0.6 * fast.tracker.kp)
    # K_I / (K_P ω) is the loop's shape: the same at both rates
    slow_omega = omega * np.sqrt(slow.tracker.kp[0] / fast.tracker.kp[0])
    np.testing.assert_allclose(slow.ki / (slow.tracker.kp * slow_omega),
                               fast.ki / (fast.tracker.kp * omega))  # fmt: skip


def test_the_replay_holds_on_a_plant_with_two_periods_of_delay():
    """Lugre #3 of the guiding benchmark at 250 Hz (2 periods of delay, ~15 Hz velocity filter).

    What the 4 Hz default prevents: at 6 Hz (the default before) the tracking loop of its
    wrist grows until the supervisor faults (the loop model: damping ratio −0.02).
    """
    replayed = replay_quality.replay_on_plant(ROBOT, 3, "lugre")
    assert replayed.delay == 2 and not replayed.faulted
    assert replayed.joint_rms < 5e-3 and replayed.tool_rms < 1e-3
    six_hertz = ReplayParameters(bandwidth=6.0)
    assert replay_quality.replay_on_plant(ROBOT, 3, "lugre", parameters=six_hertz).faulted


def test_at_125_hz_the_replay_tracks_with_the_bandwidth_its_delay_allows(monkeypatch):
    """Lugre #2 at 125 Hz: the period's bandwidth (2.8 Hz) replays; 4 Hz there faults."""
    from leadthrough.control import replay

    replayed = replay_quality.replay_on_plant(ROBOT, 2, "lugre", dt=0.008)
    assert not replayed.faulted and replayed.joint_rms < 10e-3 and replayed.tool_rms < 2e-3
    monkeypatch.setattr(replay, "period_bandwidth", lambda ceiling, dt, gains: ceiling)
    assert replay_quality.replay_on_plant(ROBOT, 2, "lugre", dt=0.008).faulted


def test_the_replay_summary_says_what_the_supervisor_did(dyn):
    """Its events and the largest torque used go into the replay's line, not only the errors.

    Before, a replay the supervisor braked printed "joint RMS 4.07 mrad" alone.
    """
    from types import SimpleNamespace

    from leadthrough.experiments.teach import _safety

    t, q = taught_path()
    replayer = Replayer(plan_replay(t, q, dyn), dyn, None, DT)
    command = np.zeros((3, ROBOT.n_joints))
    command[1, 3] = 0.5 * ROBOT.torque_limits[3]
    sim = SimpleNamespace(tau_command=command)
    quiet = "safety: no event, largest torque 50% of joint 4's limit"
    assert _safety(replayer, sim, ROBOT) == quiet
    replayer.supervisor.log("joint_speed", "joint 4 speed 3.2 rad/s above 3.1 rad/s: braking")
    assert _safety(replayer, sim, ROBOT) == (
        "safety: 1 event (joint_speed; first: joint 4 speed 3.2 rad/s above 3.1 rad/s: "
        "braking), largest torque 50% of joint 4's limit"
    )
