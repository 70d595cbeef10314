"""Tests of the stiction dither (thesis §5.3, SPEC §5)."""

from __future__ import annotations

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control.dither import Dither, DitherParameters
from leadthrough.errors import ParameterError
from leadthrough.friction.model import FrictionModel

N = 7
DT = 0.004
#: The thesis' dither, never parked: the wave and each joint's rest (the park: below).
NEVER_PARKED = DitherParameters.never_parked()


@pytest.fixture(scope="module")
def friction() -> FrictionModel:
    """The YuMi's friction model (thesis Table 4.1)."""
    return FrictionModel.from_robot(lt.robots.yumi())


def ideal_wave(frequency: float, steps: int, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Square wave +1 on [m, m+½)/f, −1 on [m+½, m+1)/f at t_k = k dt; and the samples on edges."""
    half_periods = 2.0 * frequency * np.arange(steps) * dt
    on_edge = np.abs(half_periods - np.round(half_periods)) < 1e-9
    wave = np.where(np.floor(half_periods + 1e-12).astype(int) % 2 == 0, 1.0, -1.0)
    return wave, on_edge


def run_still(dither: Dither, steps: int, q=None) -> np.ndarray:
    """Dither torques (steps, n) with every joint at rest."""
    return np.array([dither.step(np.zeros(N), q) for _ in range(steps)])


@pytest.mark.parametrize("frequency", [15.0, 10.0, 7.0, 25.0])
def test_square_wave_edges_at_the_right_times(friction, frequency):
    """Over 1 s at rest, each joint follows the ±1 square wave at `frequency` (2f − 1 edges)."""
    dither = Dither(friction, DT, DitherParameters.never_parked(frequency=frequency))
    steps = round(1.0 / DT)
    torque = run_still(dither, steps)
    wave = torque / (0.3 * friction.coulomb)
    expected, on_edge = ideal_wave(frequency, steps, DT)
    np.testing.assert_allclose(np.abs(wave), 1.0, rtol=1e-14)
    np.testing.assert_array_equal(wave[~on_edge], np.repeat(expected[~on_edge, None], N, axis=1))
    edges = np.count_nonzero(np.diff(np.sign(wave[:, 0])))
    last_edge = np.floor(2.0 * frequency * (steps - 1) * DT + 1e-9)
    assert edges == last_edge
    # same wave on every joint, in phase
    np.testing.assert_array_equal(np.sign(wave), np.sign(wave[:, :1]) * np.ones((1, N)))


def test_default_wave_is_15_hz_and_zero_mean(friction):
    """The default wave changes sign 29 times in one second and averages to zero."""
    dither = Dither(friction, DT, NEVER_PARKED)
    torque = run_still(dither, round(1.0 / DT))
    assert np.count_nonzero(np.diff(np.sign(torque[:, 0]))) == 29
    assert np.all(np.abs(torque.mean(axis=0)) <= 0.02 * 0.3 * friction.coulomb)
    # 16–17 samples per period: the first half-period is 9 samples of +, then 8 of −
    np.testing.assert_array_equal(np.sign(torque[:17, 0]), [1.0] * 9 + [-1.0] * 8)


@pytest.mark.parametrize(
    ("frequency", "mean"),
    [(15.0, 0.0), (62.5, 0.0), (20.0, 1 / 25), (50.0, 1 / 5), (100.0, 1 / 5), (250 / 3, 1 / 3)],
)
def test_the_wave_averages_one_over_r_where_f_dt_is_p_over_an_odd_r(friction, frequency, mean):
    """Below Nyquist the long-run mean is 1/r for f·dt = p/r with r odd, else 0 (check_period)."""
    dither = Dither(friction, DT, DitherParameters.never_parked(frequency=frequency))
    wave = run_still(dither, 3000)[:, 0] / (0.3 * friction.coulomb[0])  # 3000: every r's multiple
    assert wave.mean() == pytest.approx(mean, abs=1e-12)


@pytest.mark.parametrize(("frequency", "dt"), [(125.0, DT), (250.0, DT), (15.0, 0.04),
                                               (15.0, 1 / 30)])  # fmt: skip
def test_a_frequency_at_or_above_nyquist_is_refused_when_built(friction, frequency, dt):
    """A frequency ≥ 1/(2 dt) is refused by the dither and the controller (at 1/dt: constant)."""
    says = rf"dither frequency: {frequency:g} Hz at dt = {dt:g} s .* Nyquist limit"
    with pytest.raises(ParameterError, match=says):
        Dither(friction, dt, DitherParameters(frequency=frequency))
    parameters = lt.LeadThroughParameters(dither=DitherParameters(frequency=frequency))
    with pytest.raises(ParameterError, match=says):
        lt.LeadThrough(lt.robots.yumi(), dt=dt, parameters=parameters)


@pytest.mark.parametrize("dt", [0.008, 0.01, 0.03])
def test_slower_controllers_keep_the_default_dither(dt):
    """125, 100 and 33 Hz controllers (the benchmarks' slower rates) build with the defaults."""
    assert lt.LeadThrough(lt.robots.yumi(), dt=dt).feed_forward.dither is not None


@pytest.mark.parametrize("amplitude", [0.3, 0.1, 0.95])
def test_amplitude_is_fraction_of_coulomb_level(friction, amplitude):
    """|dither| = amplitude · τ_C on every joint at rest."""
    dither = Dither(friction, DT, DitherParameters(amplitude=amplitude))
    torque = run_still(dither, 40)
    assert torque.shape == (40, N)
    np.testing.assert_allclose(np.abs(torque), np.tile(amplitude * friction.coulomb, (40, 1)),
                               rtol=1e-14)  # fmt: skip


def test_amplitude_follows_position_dependent_coulomb_level():
    """With a position-dependent τ_C(q), the amplitude is 0.3 τ_C(q) at the given q."""
    rng = np.random.default_rng(5)
    model = FrictionModel(
        coulomb=rng.uniform(0.2, 1.5, N),
        slope=np.full(N, 5000.0),
        half_width=np.full(N, 0.002),
        viscous=np.full(N, 0.5),
        noise_std=np.full(N, 0.05),
        position_linear=rng.uniform(-0.3, 0.3, N),
        position_quadratic=rng.uniform(0.0, 0.3, N),
        position_mid=np.zeros(N),
        position_half_range=np.full(N, 2.0),
    )
    dither = Dither(model, DT)
    q = rng.uniform(-2.0, 2.0, N)
    torque = dither.step(np.zeros(N), q)
    u = q / 2.0
    level = model.coulomb * (1.0 + model.position_linear * u + model.position_quadratic * u**2)
    np.testing.assert_allclose(np.abs(torque), 0.3 * level, rtol=1e-14)
    assert not np.allclose(np.abs(torque), 0.3 * model.coulomb)


def test_off_at_once_on_a_moving_joint_only(friction):
    """A joint above moving_velocity gets zero dither that very step; the others keep theirs."""
    dither = Dither(friction, DT)
    reference = Dither(friction, DT)
    run_still(dither, 10)
    run_still(reference, 10)
    qd = np.zeros(N)
    qd[1], qd[4] = 0.0101, -0.5  # just above the 0.01 rad/s threshold, and fast backwards
    qd[2] = 0.0099  # just below: still at rest
    torque = dither.step(qd)
    expected = reference.step(np.zeros(N))
    assert torque[1] == 0.0 and torque[4] == 0.0
    keep = [0, 2, 3, 5, 6]
    np.testing.assert_array_equal(torque[keep], expected[keep])
    np.testing.assert_array_equal(dither.active, [True, False, True, True, False, True, True])


@pytest.mark.parametrize("joint", [0, 3, 6])
def test_back_only_after_rest_time(friction, joint):
    """After motion stops, the joint's dither stays off for rest_time, then resumes in phase."""
    dither = Dither(friction, DT, NEVER_PARKED)
    reference = Dither(friction, DT, NEVER_PARKED)
    rest_steps = round(0.2 / DT)  # default rest_time 0.2 s
    moving = np.zeros(N)
    moving[joint] = 0.3
    torques, expected = [], []
    for k in range(300):
        qd = moving if 20 <= k < 60 else np.zeros(N)
        torques.append(dither.step(qd))
        expected.append(reference.step(np.zeros(N)))
    torques, expected = np.array(torques), np.array(expected)
    last_moving = 59
    off = np.arange(20, last_moving + rest_steps)  # still for fewer than rest_steps samples
    np.testing.assert_array_equal(torques[off, joint], 0.0)
    back = np.arange(last_moving + rest_steps, 300)
    np.testing.assert_array_equal(torques[back, joint], expected[back, joint])
    np.testing.assert_array_equal(torques[:20, joint], expected[:20, joint])
    others = [j for j in range(N) if j != joint]
    np.testing.assert_array_equal(torques[:, others], expected[:, others])


def test_brief_rests_do_not_restart_the_dither(friction):
    """Rests shorter than rest_time between motions keep the dither off."""
    dither = Dither(friction, DT)
    moving = np.zeros(N)
    moving[2] = -0.05
    rest_steps = round(0.2 / DT)
    pattern = ([moving] * 5 + [np.zeros(N)] * (rest_steps - 2)) * 4
    torques = np.array([dither.step(qd) for qd in pattern])
    np.testing.assert_array_equal(torques[:, 2], 0.0)
    assert np.all(torques[:, 0] != 0.0)


@pytest.mark.parametrize(
    ("dt", "rest_time"),
    [
        (0.004, 0.2),
        (0.001, 0.2),
        (0.002, 0.3),
        (0.004, 0.5),
        (0.01, 0.1),
    ],
)
def test_rest_time_counted_in_whole_periods(friction, dt, rest_time):
    """The dither returns after exactly round(rest_time / dt) still samples."""
    dither = Dither(friction, dt, DitherParameters.never_parked(rest_time=rest_time))
    moving = np.full(N, 0.5)
    dither.step(moving)
    rest_steps = round(rest_time / dt)
    active = []
    for _ in range(rest_steps + 3):
        dither.step(np.zeros(N))
        active.append(dither.active.copy())
    active = np.array(active)
    assert not active[rest_steps - 2].any()
    assert active[rest_steps - 1].all()


def test_reset_restarts_wave_and_reactivates(friction):
    """reset() restarts the wave at +amplitude and makes every joint active at once."""
    dither = Dither(friction, DT)
    first = run_still(dither, 30)
    dither.step(np.full(N, 1.0))
    assert not dither.active.any()
    dither.reset()
    assert dither.active.all()
    np.testing.assert_array_equal(run_still(dither, 30), first)


@pytest.mark.parametrize(
    "overrides",
    [
        {"amplitude": 1.0},
        {"amplitude": 1.5},
        {"amplitude": -0.1},
        {"frequency": 0.0},
        {"frequency": -15.0},
        {"frequency": float("nan")},
        {"moving_velocity": 0.0},
        {"rest_time": -0.1},
    ],
)
def test_invalid_parameters_raise(overrides):
    """Amplitude ≥ 1 or < 0, non-positive frequency and such raise ParameterError."""
    with pytest.raises(ParameterError):
        DitherParameters(**overrides)


def test_valid_edge_parameters_accepted():
    """Amplitude just below 1, zero amplitude and zero rest time are valid."""
    assert DitherParameters(amplitude=0.999).amplitude == 0.999
    assert DitherParameters(amplitude=0.0).amplitude == 0.0
    assert DitherParameters(rest_time=0.0).rest_time == 0.0


def test_each_mode_takes_its_amplitude_unless_one_is_given():
    """Passive mode the thesis' 0.3 τ_C, active mode twice it; a given amplitude in both."""
    import dataclasses

    from leadthrough.control.dither import ACTIVE_AMPLITUDE, PASSIVE_AMPLITUDE

    robot = lt.robots.yumi()
    assert (PASSIVE_AMPLITUDE, ACTIVE_AMPLITUDE) == (0.3, 0.6)
    for mode, expected in (("passive", 0.3), ("active", 0.6)):
        controller = lt.LeadThrough(robot, mode=mode, dt=DT)
        assert controller.feed_forward.dither.amplitude == expected
        given = dataclasses.replace(lt.LeadThroughParameters(mode=mode),
                                    dither=DitherParameters(amplitude=0.4))  # fmt: skip
        controller = lt.LeadThrough(robot, mode=mode, dt=DT, parameters=given)
        assert controller.feed_forward.dither.amplitude == 0.4
    assert Dither(lt.FrictionModel.from_robot(robot), DT).amplitude == 0.3  # on its own
