"""Friction identification on the twin: the fit recovers the twin's true friction."""

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.experiments.friction_study import run_friction_study
from leadthrough.friction.identification import IdentificationError, identify_friction
from leadthrough.friction.logs import LogFileError, load_logs, save_logs
from leadthrough.runtime.excitation import ExcitationRun, friction_experiment
from leadthrough.trajectories import triangular_velocity
from leadthrough.twin.friction import randomized_friction
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.simulator import DigitalTwin, TwinConfig


@pytest.fixture(scope="module")
def yumi() -> lt.RobotDescription:
    """The shipped YuMi description."""
    return lt.robots.yumi()


@pytest.fixture(scope="module")
def default_study(yumi):
    """Identification of all joints on the default twin (experiment included)."""
    return run_friction_study(yumi, progress=False)


@pytest.fixture(scope="module")
def random_study(yumi):
    """Identification on a twin whose friction is drawn at random (seeded)."""
    friction = randomized_friction(yumi, np.random.default_rng(11))
    return run_friction_study(yumi, twin_config=TwinConfig(seed=11, friction=friction))


@pytest.fixture(scope="module")
def short_logs(yumi):
    """One slow run of joint 7 on the twin."""
    twin = DigitalTwin(yumi)
    run = ExcitationRun(peak_velocity=0.3, frequency=0.25, cycles=2)
    return friction_experiment(twin, lt.Dynamics(yumi), joints=[6], runs=[run])


def _assert_recovered(study):
    coulomb_error, viscous_error = study.errors()
    assert np.all(np.abs(coulomb_error) < 0.05), coulomb_error
    assert np.all(np.abs(viscous_error) < 0.10), viscous_error


def test_default_twin_coulomb_within_5_and_viscous_within_10_percent(default_study):
    """On the default twin every joint's τ_C (mid-range) is within 5 %, c within 10 %."""
    _assert_recovered(default_study)
    assert default_study.report.joints == tuple(range(7))


def test_random_twin_coulomb_within_5_and_viscous_within_10_percent(random_study, yumi):
    """On a twin with randomly drawn friction the same tolerances hold (nothing tuned)."""
    _assert_recovered(random_study)
    nominal = lt.FrictionModel.from_robot(yumi).coulomb
    assert np.max(np.abs(random_study.truth[0] / nominal - 1.0)) > 0.1  # really different


def test_position_dependence_follows_the_cable_effect(default_study, yumi):
    """The identified τ_C(q) matches the twin's position-dependent level over the strokes."""
    twin = DigitalTwin(yumi)
    for joint in range(7):
        q, _, _ = default_study.joint_samples(joint)
        for position in np.percentile(q, [5, 95]):
            pose = 0.5 * (yumi.q_min + yumi.q_max)
            pose[joint] = position
            true = twin.friction.params.coulomb_level(pose)[joint]
            found = default_study.model.coulomb_level(pose)[joint]
            assert found == pytest.approx(true, rel=0.03)


def test_gaussian_model_is_honest_on_sliding_samples(default_study):
    """Sliding friction lies within ±3 std of the identified mean in > 97 % of samples."""
    for joint in range(7):
        q, qd, tau = default_study.joint_samples(joint)
        sliding = np.abs(qd) > 0.04
        pose = np.tile(default_study.model.position_mid, (sliding.sum(), 1))
        pose[:, joint] = q[sliding]
        speeds = np.zeros_like(pose)
        speeds[:, joint] = qd[sliding]
        mean = default_study.model.mean(speeds, pose)[:, joint]
        std = default_study.model.std(speeds, pose)[:, joint]
        assert np.mean(np.abs(tau[sliding] - mean) < 3 * std) > 0.97


def test_a_resting_joint_keeps_its_whole_band_after_identification(default_study, yumi):
    """At a dithered joint's twitch (±0.4 mrad/s) the identified model still says "at rest".

    The excitation passes through zero speed in a sample or two, and its fit closed the
    band at 0.2–0.5 mrad/s: with it the observer read a resting wrist's twitch as full
    Coulomb friction, ±τ_C square waves at the dither's 15 Hz (docs/active_mode_log.md,
    *An identified model's rest band*). The prior's band is the narrowest it may be.
    """
    model, prior = default_study.model, lt.FrictionModel.from_robot(yumi)
    assert np.all(model.half_width >= prior.half_width)
    assert np.all(model.slope * model.half_width >= prior.slope * prior.half_width)
    pose = model.position_mid
    for twitch in (-4e-4, 4e-4):
        speeds = np.full(7, twitch)
        level = model.coulomb_level(pose)
        assert np.all(np.abs(model.mean(speeds, pose)) < 0.1 * level)
        assert np.all(model.std(speeds, pose) > 0.85 * level)


def test_the_fit_widens_a_rest_band_the_data_show_wider():
    """Slow samples drawn from a wider band (B = 10 mrad/s) move the fit off the prior's."""
    from leadthrough.friction.identification import _fit_sigmoids

    wide = lt.FrictionModel(coulomb=[1.0], slope=[2000.0], half_width=[0.01], viscous=[0.5],
                            noise_std=[0.02])  # fmt: skip
    rng = np.random.default_rng(3)
    qd = rng.uniform(-0.08, 0.08, 4000)[:, None]
    tau = rng.normal(wide.mean(qd), wide.std(qd))[:, 0]
    (slope, half_width), _ = _fit_sigmoids(qd[:, 0], np.ones(4000), 0.5, 0.02, tau,
                                           (5e3, 2e-3))  # fmt: skip
    assert half_width == pytest.approx(0.01, rel=0.3)
    fitted = lt.FrictionModel(coulomb=[1.0], slope=[slope], half_width=[half_width],
                              viscous=[0.5], noise_std=[0.02])  # fmt: skip
    speeds = np.array([[0.0], [0.005], [0.01], [0.02]])
    np.testing.assert_allclose(fitted.std(speeds), wide.std(speeds), atol=0.15)
    np.testing.assert_allclose(fitted.mean(speeds), wide.mean(speeds), atol=0.15)


def test_a_gravity_model_error_is_not_friction_noise(default_study, yumi):
    """Every link 10 % heavier than the model: σ stays the friction's, the levels true.

    A gravity model's error does not change sign with the motion; friction does. The fit
    takes off a torque offset and, where a joint moved alone, the first harmonic of its
    angle (the form of a gravity torque about its axis) before σ, which the controller's
    bands are made of. Fitted as friction, the 10 % error read as σ = 0.05–0.15 Nm on
    joints 1–4, 3–14× the exact twin's 0.006–0.016 Nm, and moved levels by up to 1.2 %.
    """
    heavy = run_friction_study(
        yumi, twin_config=TwinConfig(model_error=ModelError(mass_scale=1.1)), progress=False
    )
    exact = default_study.model.noise_std
    assert np.all(heavy.model.noise_std <= 1.25 * exact + 0.001), (heavy.model.noise_std, exact)
    assert np.all(np.abs(heavy.errors()[0]) < 0.005), heavy.errors()[0]


def test_a_joint_that_slid_one_way_keeps_its_whole_level(yumi):
    """One way only, an offset is the level: the fit keeps it all as friction.

    Joint 7 turns one way at 0.1–0.4 rad/s with τ_C = 0.4 Nm and c = 0.2 Nm s/rad (the
    rigid body exact). A torque offset and ``sign(q̇) τ_C`` are then the same column, and
    fitted together the level came out at 4·10⁷ Nm; the offset and the harmonic are fitted
    only for a joint that slid both ways (``BOTH_WAYS`` of its samples each).
    """
    dynamics, dt, joint = lt.Dynamics(yumi), 0.004, 6
    t = np.arange(0.0, 8.0, dt)
    speed = 0.1 + 0.3 * np.sin(np.pi * t / 4.0) ** 2
    q, qd, qdd = np.tile(yumi.home(), (t.size, 1)), np.zeros((t.size, 7)), np.zeros((t.size, 7))
    q[:, joint], qd[:, joint] = -1.5 + np.cumsum(speed) * dt, speed
    qdd[:, joint] = np.gradient(speed, dt)
    tau = np.array([dynamics.inverse_dynamics(*sample) for sample in zip(q, qd, qdd, strict=True)])
    tau[:, joint] += 0.4 + 0.2 * speed
    model, _ = identify_friction([{"t": t, "q": q, "qd": qd, "tau": tau}], dynamics, [joint])
    assert model.coulomb[joint] == pytest.approx(0.4, rel=0.02)
    assert model.viscous[joint] == pytest.approx(0.2, rel=0.02)


def test_report_carries_fit_quality(default_study):
    """The report gives residual RMS and parameter standard deviations per joint."""
    report = default_study.report
    assert np.all(report.residual_rms < 0.05) and np.all(report.samples > 1000)
    assert np.all(report.parameter_std["coulomb"] < 0.01)
    assert "RMS" in str(report)


def test_triangular_velocity_profile():
    """The excitation wave: stroke v/(4f), q̇ = dq/dt, |q̈| = 4 f v, back at 0 each period."""
    t = np.linspace(0.0, 20.0, 200_001)
    position, velocity, acceleration = triangular_velocity(t, 0.2, 0.1)
    assert position.max() == pytest.approx(0.5, abs=1e-9) and abs(position[-1]) < 1e-9
    np.testing.assert_allclose(np.gradient(position, t)[1:-1], velocity[1:-1], atol=1e-5)
    np.testing.assert_allclose(np.abs(acceleration), 0.08)
    assert np.max(np.abs(velocity)) == pytest.approx(0.2, abs=1e-6)


def test_mapping_logs_and_log_files_identify_the_same(short_logs, yumi, tmp_path):
    """Logs as mappings, and saved to CSV and NPZ then loaded, give the same model.

    So does a robot description given in place of its dynamics.
    """
    dynamics = lt.Dynamics(yumi)
    model, _ = identify_friction(short_logs, dynamics, joints=[6])
    from_robot, _ = identify_friction(short_logs, yumi, joints=[6])  # its model built there
    assert from_robot.coulomb[6] == model.coulomb[6]
    as_dicts = [{"t": log.t, "q": log.q, "qd": log.qd, "tau": log.tau} for log in short_logs]
    from_dicts, _ = identify_friction(as_dicts, dynamics, joints=[6])
    assert from_dicts.coulomb[6] == model.coulomb[6]
    for suffix in (".csv", ".npz"):
        loaded = load_logs(save_logs(short_logs, tmp_path / f"logs{suffix}"))
        again, _ = identify_friction(loaded, dynamics, joints=[6])
        assert again.coulomb[6] == pytest.approx(model.coulomb[6], rel=1e-6)


def _broken(log, **changes):
    data = {"t": log.t, "q": log.q, "qd": log.qd, "tau": log.tau}
    data.update(changes)
    return data


def _short(log):
    return _broken(log, t=log.t[:10], q=log.q[:10], qd=log.qd[:10], tau=log.tau[:10])


def _nan_velocity(log):
    qd = log.qd.copy()
    qd[5, 0] = np.nan
    return _broken(log, qd=qd)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (_short, "too short"),
        (lambda log: _broken(log, tau=log.tau[:-1]), r"'tau' has shape"),
        (_nan_velocity, "'qd' is not finite at sample 5, joint 1"),
        (lambda log: {"t": log.t, "q": log.q, "qd": log.qd}, "missing 'tau'"),
        (lambda log: _broken(log, t=log.t[::-1].copy()), "'t' must increase"),
    ],
)
def test_bad_logs_give_clear_errors(short_logs, yumi, make, message):
    """Malformed logs raise IdentificationError naming the log and what is wrong."""
    with pytest.raises(IdentificationError, match=message):
        identify_friction([make(short_logs[0])], lt.Dynamics(yumi), joints=[6])


def test_joint_that_never_moved_is_named(short_logs, yumi):
    """Asking for a joint absent from the logs names it."""
    with pytest.raises(IdentificationError, match="joint 2 never moved"):
        identify_friction(short_logs, lt.Dynamics(yumi), joints=[1])


def test_no_joints_to_identify_is_refused(short_logs, yumi):
    """``joints=[]`` is an error: the prior came back as if it had been identified."""
    with pytest.raises(lt.ParameterError, match=r"joints: is empty"):
        identify_friction(short_logs, lt.Dynamics(yumi), joints=[])


@pytest.mark.parametrize("joints", [[7], [-1], [1.5], [True]], ids=str)
def test_a_joint_out_of_range_is_refused_naming_the_range(short_logs, yumi, joints):
    """``joints`` are 0-based: 7 of the 7-joint YuMi, −1 or 1.5 name the valid range.

    They read "joint 8 never moved", "joint 0 never moved", and 1.5 was truncated to 1.
    """
    with pytest.raises(lt.ParameterError, match=r"numbered 0 to 6 here \(0-based; the command "
                                                r"line's --joints counts 1 to 7\)"):  # fmt: skip
        identify_friction(short_logs, lt.Dynamics(yumi), joints=joints)


def test_friction_pulled_below_zero_is_held_at_0_with_a_warning(yumi):
    """A joint whose torque sign is flipped: τ_C and c held at 0, with a warning naming it.

    The warning says the likely cause; they were held at 0 silently.
    """
    dynamics, dt, joint = lt.Dynamics(yumi), 0.004, 6
    t = np.arange(0.0, 8.0, dt)
    q, qd, qdd = np.tile(yumi.home(), (t.size, 1)), np.zeros((t.size, 7)), np.zeros((t.size, 7))
    q[:, joint] += 0.5 * np.sin(np.pi * t / 2.0)
    qd[:, joint] = 0.5 * np.pi / 2.0 * np.cos(np.pi * t / 2.0)
    qdd[:, joint] = -0.5 * (np.pi / 2.0) ** 2 * np.sin(np.pi * t / 2.0)
    tau = np.array([dynamics.inverse_dynamics(*sample) for sample in zip(q, qd, qdd, strict=True)])
    tau[:, joint] -= 0.4 * np.sign(qd[:, joint]) + 0.2 * qd[:, joint]  # friction, sign flipped
    log = {"t": t, "q": q, "qd": qd, "tau": tau}
    with pytest.warns(UserWarning, match=r"joint 7: fitted Coulomb level and viscous "
                                         r"coefficient held at 0 .* sign flipped"):  # fmt: skip
        model, _ = identify_friction([log], dynamics, [joint])
    assert model.coulomb[joint] < 1e-9 and model.viscous[joint] < 1e-9


def test_unreadable_log_file(tmp_path):
    """A missing or garbled log file raises LogFileError naming the file."""
    with pytest.raises(LogFileError, match="no such file"):
        load_logs(tmp_path / "nothing.csv")
    garbled = tmp_path / "garbled.csv"
    garbled.write_text("run,t,q1\n0,0.0\n")
    with pytest.raises(LogFileError, match=r"garbled\.csv"):
        load_logs(garbled)
    other = tmp_path / "other.csv"  # a CSV of another layout: its columns named, not NumPy's
    other.write_text("time,x,y\n0.0,1.0,2.0\n")
    with pytest.raises(LogFileError, match=r"other\.csv: .*time,x,y.*not the excitation log"):
        load_logs(other)


def test_a_bad_log_is_named_by_its_file(yumi):
    """A log read from a file is named by it in the errors, not by its place in the list."""
    n, t = yumi.n_joints, np.arange(12) * 0.004
    short = lt.JointLog(t, np.zeros((12, n)), np.zeros((12, n)), np.zeros((12, n)),
                        source="runs/short.csv")  # fmt: skip
    with pytest.raises(IdentificationError, match=r"runs/short\.csv: too short \(12 samples"):
        identify_friction([short], lt.Dynamics(yumi))


def test_a_run_given_twice_is_refused(yumi, tmp_path):
    """The same log twice, or one file read twice however spelt: one error naming the run.

    Both were fitted, the run weighing double. The parts of one log split at its gap are
    two runs: not refused (the fit then finds that nothing moved).
    """
    n, t = yumi.n_joints, np.arange(60) * 0.004
    log = lt.JointLog(t, np.zeros((60, n)), np.zeros((60, n)), np.zeros((60, n)))
    with pytest.raises(lt.ParameterError) as error:
        identify_friction([log, log], yumi)
    assert str(error.value) == "logs: log 1 is given twice (each run counts once)"
    path = save_logs([log], tmp_path / "run.csv")
    (tmp_path / "sub").mkdir()
    spelt_otherwise = tmp_path / "sub" / ".." / "run.csv"
    with pytest.raises(lt.ParameterError) as error:
        identify_friction([lt.read_log(path), lt.read_log(spelt_otherwise)], yumi)
    assert str(error.value) == f"logs: {spelt_otherwise} is given twice (each run counts once)"
    gapped = lt.JointLog(np.concatenate([t, t + 10.0]), np.zeros((120, n)), np.zeros((120, n)),
                         np.zeros((120, n)), source=str(path))  # fmt: skip
    with pytest.raises(IdentificationError, match="no joint moved"):
        identify_friction(gapped.runs(), yumi)


def test_an_excitation_file_is_named_in_the_errors_with_its_joint_count(short_logs, tmp_path):
    """Logs loaded from a file carry it: a NaN or another arm's joint count names it.

    They were "log 0", and another joint count "'q' has shape (…, 6), expected (…, 7)".
    """
    log = short_logs[0]
    good = {"t": log.t, "q": log.q, "qd": log.qd, "tau": log.tau}
    (loaded,) = load_logs(save_logs([good], tmp_path / "mine.npz"))  # the reader drops NaN rows
    loaded["qd"] = np.where(np.arange(len(log.t))[:, None] == 3, np.nan, loaded["qd"])
    with pytest.raises(IdentificationError, match=r"mine\.npz: 'qd' is not finite at sample 3"):
        identify_friction([loaded], lt.Dynamics(lt.robots.yumi()))
    with pytest.raises(IdentificationError, match=r"mine\.npz: 7 joints, but ur10e has 6"):
        identify_friction([loaded], lt.Dynamics(lt.robots.ur10e()))


def test_the_joints_identified_are_saved_and_the_others_count_as_unmeasured(
    short_logs, yumi, tmp_path
):
    """Joint 7 alone identified: the file says so, and the controller widens the others.

    Before, a file with one joint fitted made ``LeadThrough`` take every joint's level as
    measured on this arm (0.2 of error where nobody measured it, instead of 0.35); a file
    that does not say (written before) still counts whole.
    """
    model, _ = identify_friction(short_logs, lt.Dynamics(yumi), joints=[6])
    assert model.identified.tolist() == [False] * 6 + [True]
    model.save(tmp_path / "friction.toml")
    loaded = lt.FrictionModel.load(tmp_path / "friction.toml")
    assert loaded.identified.tolist() == model.identified.tolist()
    parameters = lt.LeadThroughParameters()
    error = lt.LeadThrough(yumi, "active", friction=loaded).law.friction_error
    np.testing.assert_allclose(error[:6], parameters.unmeasured_friction_error)
    assert error[6] < 0.1  # its own, measured along the stroke
    unstated = lt.FrictionModel(**{**loaded.to_dict(), "identified": None})
    whole = lt.LeadThrough(yumi, "active", friction=unstated).law.friction_error
    assert np.all(whole[:6] < parameters.unmeasured_friction_error)


def test_identified_flags_of_another_length_are_refused_naming_the_file(yumi, tmp_path):
    """``identified`` must hold one boolean per joint: a file that does not is one line."""
    path = tmp_path / "friction.toml"
    lt.FrictionModel.from_robot(yumi).save(path)
    path.write_text(path.read_text() + "identified = [true, false]\n")
    with pytest.raises(lt.RobotDescriptionError, match=r"friction\.identified.*7 booleans"):
        lt.FrictionModel.load(path)
