"""The guiding benchmark's command-line helpers (benchmarks/guiding_quality.py)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import numpy as np
import pytest

import guiding_quality
import leadthrough as lt


def test_seed_ranges_and_lists():
    """``5-8`` is a range, ``5,9`` a list, and both mix."""
    assert guiding_quality.parse_seeds("5-8") == [5, 6, 7, 8]
    assert guiding_quality.parse_seeds("5,9-10") == [5, 9, 10]


def test_cases_guided_without_a_calibration_are_counted_and_named():
    """A refused calibration is counted below the table, not only marked in its row."""
    results = {"dry#9 relaxed sideways": {"calibrated": 0.0},
               "dry#10 relaxed sideways": {"calibrated": 1.0}}  # fmt: skip
    line = guiding_quality.uncalibrated_line(results)
    assert line == "guided without a calibration: 1 of 2 cases (dry#9 relaxed sideways)"
    assert guiding_quality.uncalibrated_line({"x": {"calibrated": 1.0}}).endswith(": 0 of 1 cases")


def test_cases_over_a_per_case_goal_are_counted_and_named_worst_first():
    """Every case above a goal that each case must keep is named, worst first, per figure."""
    keep = {"vibration": 1.0, "speed": 0.9, "speed_passive": 0.8, "stop": 0.2, "drift": 0.3,
            "stop_passive": 0.2, "drift_passive": 0.3}  # fmt: skip
    results = {"a": keep | {"vibration": 1.6}, "b": keep | {"vibration": 2.1, "drift": 1.0},
               "c": keep | {"speed": 1.0}}  # fmt: skip
    line = guiding_quality.over_goal_line(results)
    # 1.0 of the speed bound keeps its goal (≤ 1), 1.0 mrad of drift does not (< 1)
    assert line == "over a per-case goal: vibration 2 of 3 (b 2.1, a 1.6); drift 1 of 3 (b 1)"
    assert guiding_quality.over_goal_line({"a": keep}) == "over a per-case goal: none"


def test_a_speed_over_its_bound_is_set_beside_passive_modes_on_the_same_cases():
    """The same hand and plant may throw the arm past its bound in passive mode too."""
    keep = {"vibration": 1.0, "speed": 0.9, "speed_passive": 0.8, "stop": 0.2, "drift": 0.3,
            "stop_passive": 0.2, "drift_passive": 0.3}  # fmt: skip
    results = {"a": keep | {"speed": 1.2, "speed_passive": 1.3},
               "b": keep | {"speed_passive": 1.1}, "c": keep}  # fmt: skip
    line = guiding_quality.over_goal_line(results)
    assert line == "over a per-case goal: speed 1 of 3 (a 1.2; passive mode 2 of 3)"


def test_other_hands_make_the_cases_and_an_unknown_one_is_a_one_line_error(capsys):
    """``--hands soft,firm``: 100 and 1000 N/m on the lines, the circle with the first."""
    from leadthrough.experiments.guiding import HANDS, cases

    other = cases("full", (1,), ("soft", "firm"))
    assert len(other) == 14 and {c.hand for c in other} == {"soft", "firm"}
    assert [c.hand for c in other if c.path == "circle"] == ["soft", "soft"]
    assert HANDS["soft"].stiffness == 100.0 and HANDS["firm"].stiffness == 1000.0
    with pytest.raises(SystemExit):
        guiding_quality.main(["--hands", "soft,gentle"])
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert error.endswith(
        "unknown hand(s) gentle: choose from relaxed, stiff, soft, firm, grasping, "
        "stiff-grasping, trembling, stiff-trembling"
    )


def test_a_wider_plant_family_reaches_every_case_and_a_bad_setting_is_a_one_line_error(capsys):
    """``--plants position_amplitude=0.25 friction_scale=0.7,1.3``: every case drawn wider."""
    from leadthrough.experiments.guiding import cases
    from leadthrough.model import robots
    from leadthrough.twin.plants import WIDER_RANGES, PlantRanges, sample_plant

    wide = guiding_quality.plant_ranges(["position_amplitude=0.25", "friction_scale=0.7,1.3",
                                         "delay_periods=1,3"])  # fmt: skip
    assert wide == PlantRanges(position_amplitude=0.25, friction_scale=(0.7, 1.3),
                               delay_periods=(1, 3))  # fmt: skip
    assert guiding_quality.plant_ranges(None) == PlantRanges()
    bench = ["friction_scale=0.7,1.3", "position_amplitude=0.25"]  # make bench, the README
    assert guiding_quality.plant_ranges(bench) == WIDER_RANGES
    every = cases("full", (1,), ranges=wide) + cases("quick", ranges=wide)
    assert {c.ranges for c in every} == {wide}
    yumi = robots.yumi()
    case = cases("full", (1,), ranges=wide)[0]
    friction = sample_plant(yumi, case.seed, case.physics, case.ranges).config.friction
    nominal = sample_plant(yumi, case.seed, case.physics).config.friction
    assert np.all(friction.position_amplitude == 0.25)
    assert np.all(nominal.position_amplitude == PlantRanges().position_amplitude)
    bad = (("friction_scale=1.3", "friction_scale takes LOW,HIGH, got '1.3'"),
           ("friction_scale=1.3,0.7", "friction_scale: must be > 0, LOW ≤ HIGH"),
           ("delay_periods=1,2.5", "delay_periods takes LOW,HIGH, got '1,2.5'"),
           ("position_amplitude=1", "position_amplitude: must be in [0, 1)"),
           ("friction=0.5", "unknown field 'friction', choose from mass_error"))  # fmt: skip
    for setting, says in bad:
        with pytest.raises(SystemExit):
            guiding_quality.main(["--plants", setting])
        assert says in capsys.readouterr().err.strip().splitlines()[-1]


def test_the_enabling_device_is_a_switch_not_a_range(capsys):
    """``--enabling-device`` gives the plants one; ``--plants`` takes ranges only."""
    from leadthrough.model import robots
    from leadthrough.twin.plants import PlantRanges, sample_plant

    with_device = PlantRanges(enabling_device=True)
    assert sample_plant(robots.yumi(), 1, "dry", with_device).config.enabling_device
    assert not sample_plant(robots.yumi(), 1, "dry").config.enabling_device
    with pytest.raises(SystemExit):
        guiding_quality.main(["--plants", "enabling_device=1"])
    assert "unknown field 'enabling_device'" in capsys.readouterr().err


def test_a_control_period_the_twin_cannot_run_is_a_one_line_error(capsys):
    """``--dt`` sets the plants' and controllers' period; one the twin cannot run is refused."""
    for dt, says in (("0.0013", "--dt: control_dt 0.0013 is not a multiple of physics_dt"),
                     ("-0.004", "--dt: control_dt: must be >= 0.0005, got -0.004")):  # fmt: skip
        with pytest.raises(SystemExit):
            guiding_quality.main(["--dt", dt, "--cases", "quick"])
        assert capsys.readouterr().err.strip().splitlines()[-1].endswith(says)


def test_a_compare_file_that_is_no_saved_run_is_refused_before_the_run(tmp_path, capsys):
    """``--compare`` is read first: a missing or foreign file costs no run's results.

    It was read after the run, before ``--save`` wrote anything: a typo lost both.
    """
    foreign = tmp_path / "other.json"
    foreign.write_text('{"cases": {}}')
    for path in (tmp_path / "missing.json", foreign):
        with pytest.raises(SystemExit):
            guiding_quality.main(["--cases", "quick", "--compare", str(path),
                                  "--save", str(tmp_path / "run.json")])  # fmt: skip
        assert f"--compare {path}: not a saved run" in capsys.readouterr().err
    assert not (tmp_path / "run.json").exists()


def test_identified_first_builds_the_default_controllers_only(capsys):
    """``--identified`` with a custom ``--factory`` is a one-line error.

    It gives both default modes the plant's identified friction; a custom factory's
    signature takes no friction.
    """
    with pytest.raises(SystemExit):
        guiding_quality.main(["--identified", "--factory", "guiding_variants:true_torque",
                              "--cases", "quick"])  # fmt: skip
    assert (
        capsys.readouterr()
        .err.strip()
        .splitlines()[-1]
        .endswith("--identified builds the default controllers: drop --factory")
    )


def test_cases_whose_hand_saturated_are_named():
    """A hand that could not pull the arm along its path is named below the table."""
    results = {"dry#1 stiff upwards": {"hand_saturated": 1.0},
               "dry#1 relaxed upwards": {"hand_saturated": 0.0}}  # fmt: skip
    line = guiding_quality.saturated_line(results)
    assert line.startswith("the hand saturated") and "1 of 2 cases (dry#1 stiff upwards)" in line
    assert guiding_quality.saturated_line({"x": {"hand_saturated": 0.0}}) == ""


def test_a_path_out_of_reach_saturates_the_hand(robots_dir):
    """The SO-101's upward line ends 3 cm beyond its reach: the stiff hand saturates there.

    The YuMi's, inside its reach, does not.
    """
    import warnings

    import leadthrough as lt
    from leadthrough.experiments.guiding import Case, run_case

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", lt.robots.AssumedDriveDataWarning)
        so101 = lt.robots.load(robots_dir / "so_arm_description/urdf/so101.urdf",
                               tip="gripper_frame_link")  # fmt: skip
    case = Case("dry", 1, "stiff", "upwards")
    assert run_case(case, "passive", robot=so101).hand_saturated
    assert not run_case(case, "passive").hand_saturated


def test_an_unknown_tip_is_a_one_line_error(robots_dir, capsys):
    """``--robot FILE.urdf --tip`` that names no link: the parser's one-line error."""
    urdf = robots_dir / "ur_description/urdf/ur5_robot.urdf"
    with pytest.raises(SystemExit):
        guiding_quality.main(["--robot", str(urdf), "--tip", "tool"])
    assert "did you mean 'tool0'?" in capsys.readouterr().err.strip().splitlines()[-1]


def test_drives_without_a_torque_sensor_are_a_switch_and_report_none(capsys):
    """``--no-torque-sensor``: the plants' samples carry no torque; the run logs NaN there."""
    from leadthrough.model import robots
    from leadthrough.twin.plants import PlantRanges, sample_plant
    from leadthrough.twin.runner import simulate
    from leadthrough.twin.simulator import DigitalTwin

    yumi = robots.yumi()
    plant = sample_plant(yumi, 1, "lugre", PlantRanges(torque_sensor=False))
    twin = DigitalTwin(yumi, plant.config)
    assert twin.read_state().tau_measured is None
    assert sample_plant(yumi, 1, "lugre").config.sensors.torque_sensor
    run = simulate(twin, lt.LeadThrough(yumi, mode="active", dt=0.004), 0.2, progress=False)
    assert np.isnan(run.tau_measured).all() and np.isfinite(run.tau_command).all()
    with pytest.raises(SystemExit):
        guiding_quality.main(["--plants", "torque_sensor=0"])
    assert "unknown field 'torque_sensor'" in capsys.readouterr().err


def test_a_pace_stretches_every_path_and_names_its_cases(capsys):
    """``--pace 2``: every path twice as long, at half the speed; a pace ≤ 0 is refused."""
    from leadthrough.experiments.guiding import Case, case_path, cases
    from leadthrough.model import robots

    yumi = robots.yumi()
    slow = cases("full", (1,), pace=2.0)
    assert {c.pace for c in slow} == {2.0} and slow[0].name.endswith(" pace 2")
    for name in ("sideways", "circle"):
        base, stretched = case_path(yumi, name), case_path(yumi, name, pace=2.0)
        assert stretched.duration == 2.0 * base.duration
        np.testing.assert_allclose(stretched.position(2.0 * 0.3 * base.duration),
                                   base.position(0.3 * base.duration))  # fmt: skip
    assert Case("dry", 1, "relaxed", "sideways").name == "dry#1 relaxed sideways"
    with pytest.raises(SystemExit):
        guiding_quality.main(["--pace", "0"])
    assert "--pace must be a number > 0, got 0" in capsys.readouterr().err


def test_hands_that_grab_at_once_are_named_and_find_the_arm_calibrating():
    """``--grab-at-once``: the hand takes the arm as the run starts, while it calibrates.

    The calibrated controller (``calibrate=True``) then reads the hand and refuses its
    calibration, where a hand that waits finds it accepted.
    """
    from leadthrough.experiments.guiding import Case, _run, cases, default_factory
    from leadthrough.model import robots

    assert all(c.grab_at_once for c in cases("quick", grab_at_once=True))
    case = Case("dry", 9, "relaxed", "circle", grab_at_once=True)
    assert case.name == "dry#9 relaxed circle at once"
    yumi = robots.yumi()
    at_once, recorder = _run(yumi, case, "active", default_factory, np.inf, 1.5)
    assert at_once.t[0] == 0.0 and at_once.operator_force[: len(at_once.t) // 2].any()
    assert not recorder.controller.calibration.accepted
    assert "touched" in recorder.controller.calibration.reason
    waited = Case("dry", 9, "relaxed", "circle")
    _, recorder = _run(yumi, waited, "active", default_factory, np.inf, 0.1)
    assert recorder.controller.calibration.accepted


def test_hands_that_grab_after_a_rest_are_named_and_find_the_dither_parked(capsys):
    """``--rest S``: the arm rests S seconds, nobody touching, before the hand grabs.

    After 2 s of rest (``DitherParameters.park_time``) the dither is off on every joint:
    the hand that grabs then starts the arm without it, which a hand grabbing as the
    controller starts never does. A rest below 0, or with ``--grab-at-once``, is refused.
    """
    from leadthrough.errors import ParameterError
    from leadthrough.experiments.guiding import Case, _run, cases, uncalibrated_factory
    from leadthrough.model import robots

    assert {c.rest for c in cases("quick", rest=3.0)} == {3.0}
    case = Case("dry", 1, "stiff", "sideways", rest=2.5)
    assert case.name == "dry#1 stiff sideways after 2.5 s"
    yumi = robots.yumi()
    run, recorder = _run(yumi, case, "active", uncalibrated_factory, np.inf, 0.02)
    controller = recorder.controller
    assert run.t[0] == 0.0 and controller.time == pytest.approx(2.5 + run.t[-1], abs=1e-9)
    assert controller.feed_forward.dither.parked  # the hand finds the dither parked
    _, recorder = _run(yumi, Case("dry", 1, "stiff", "sideways"), "active",
                       uncalibrated_factory, np.inf, 0.02)  # fmt: skip
    assert not recorder.controller.feed_forward.dither.parked
    with pytest.raises(ParameterError, match="rest"):
        Case("dry", 1, "stiff", "sideways", rest=1.0, grab_at_once=True)
    for argv in (["--rest", "-1"], ["--rest", "1", "--grab-at-once"]):
        with pytest.raises(SystemExit):
            guiding_quality.main(argv)
        assert "--rest: " in capsys.readouterr().err
