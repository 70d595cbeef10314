"""The leadthrough command line: output a user reads and one-line errors."""

import subprocess
import sys

import pytest

from leadthrough.cli.main import main


def test_info_summarises_the_yumi(capsys):
    """`leadthrough info` lists every joint, the total mass and the condition of M."""
    assert main(["info"]) == 0
    out = capsys.readouterr().out
    for k in range(1, 8):
        assert f"joint_{k}" in out
    assert "moving mass 5.094 kg" in out
    assert "condition" in out
    assert "-143.5 … 43.5" in out


def test_info_reads_a_toml_file(tmp_path, capsys):
    """`info --robot FILE.toml` loads the description written by save_robot."""
    import leadthrough as lt

    path = tmp_path / "arm.toml"
    lt.robots.save_robot(lt.robots.yumi(), path)
    assert main(["info", "--robot", str(path)]) == 0
    assert "ABB YuMi" in capsys.readouterr().out


def test_info_takes_a_urdfs_drive_data(robots_dir, tmp_path, capsys):
    """`info --robot FILE.urdf --tip LINK --drive-data FILE`: the drive data's home is used."""
    drive = tmp_path / "kinova.toml"
    drive.write_text("home = [4.80, 2.92, 1.00, 4.19, 1.44, 1.31]\n")
    urdf = robots_dir / "kinova_description/robots/kinova.urdf"
    arguments = ["info", "--robot", str(urdf), "--tip", "j2s6s200_end_effector"]
    assert main([*arguments, "--drive-data", str(drive)]) == 0
    captured = capsys.readouterr()
    assert "at q = [275. , 167.3,  57.3, 240.1,  82.5,  75.1] deg" in captured.out
    assert "continuous joint" in captured.err and "singularity" not in captured.err


def test_bad_robot_file_is_one_line_error(tmp_path, capsys):
    """A malformed description exits with code 2 and one line naming the file and field."""
    path = tmp_path / "broken.toml"
    path.write_text('name = "x"\n[[joints]]\nname = "j"\n')
    assert main(["info", "--robot", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "broken.toml" in err and "joints[0]" in err


@pytest.mark.parametrize("args", [["--help"], ["info", "--help"]])
def test_help_has_examples(args):
    """Every command answers --help through the installed entry point."""
    result = subprocess.run(
        [sys.executable, "-m", "leadthrough.cli", *args], capture_output=True, text=True
    )
    assert result.returncode == 0
    assert "usage: leadthrough" in result.stdout


def test_simulate_writes_plot_and_picture(tmp_path, capsys):
    """`leadthrough simulate` runs a scenario and writes its plot (and picture when GL works)."""
    assert (
        main(["simulate", "--scenario", "joint", "--duration", "0.5", "--out", str(tmp_path)]) == 0
    )
    out = capsys.readouterr().out
    assert "scenario joint" in out and "real time" in out
    assert (tmp_path / "joint.png").stat().st_size > 10_000


def test_identify_on_twin_then_from_saved_log(tmp_path, capsys):
    """`identify` fits joint 7 on the twin, writes TOML and figures; its log reads back alike."""
    import leadthrough as lt

    log = tmp_path / "logs.npz"
    args = ["identify", "--joints", "7", "--out", str(tmp_path / "twin"), "--save-log", str(log)]
    assert main(args) == 0
    assert "τ_C error [%]" in capsys.readouterr().out
    twin_model = lt.FrictionModel.load(tmp_path / "twin" / "friction.toml")
    assert (tmp_path / "twin" / "joint7_fig4_3_sigmoid_fit.png").stat().st_size > 10_000
    assert (
        main(["identify", "--joints", "7", "--log", str(log), "--out", str(tmp_path / "log")]) == 0
    )
    log_model = lt.FrictionModel.load(tmp_path / "log" / "friction.toml")
    assert log_model.coulomb[6] == twin_model.coulomb[6]


def test_identify_draws_a_run_that_moved_every_joint(tmp_path):
    """One excitation CSV whose run moves several joints at once: identified and drawn.

    The figures took each joint's samples from the run that excited it alone, and there
    was none: "need at least one array to concatenate" after half the files were written.
    """
    import numpy as np

    import leadthrough as lt
    from leadthrough.friction.logs import save_logs

    robot = lt.robots.yumi()
    dynamics, friction = lt.Dynamics(robot), lt.FrictionModel.from_robot(robot)
    t = np.arange(0.0, 20.0, 0.004)
    phase = 2 * np.pi * (0.2 + 0.05 * np.arange(7)) * t[:, None]
    q = robot.home() + 0.5 * np.sin(phase)
    qd = 0.5 * 2 * np.pi * (0.2 + 0.05 * np.arange(7)) * np.cos(phase)
    qdd = np.gradient(qd, t, axis=0)
    tau = np.array([dynamics.inverse_dynamics(*row) for row in zip(q, qd, qdd, strict=True)])
    path = save_logs([{"t": t, "q": q, "qd": qd, "tau": tau + friction.mean(qd)}],
                     tmp_path / "run.csv")  # fmt: skip
    assert main(["identify", "--log", str(path), "--out", str(tmp_path / "out")]) == 0
    assert (tmp_path / "out" / "friction.toml").is_file()
    assert len(list((tmp_path / "out").glob("joint*.png"))) > 4


def test_identify_rejects_bad_joint_list(capsys):
    """A joint number out of range is a one-line error, exit code 2."""
    assert main(["identify", "--joints", "9"]) == 2
    assert "joints are numbered 1 to 7" in capsys.readouterr().err


def test_identify_says_a_log_of_currents_needs_torque_constants(tmp_path, capsys):
    """A UR log of motor currents for an arm without K: one line, exit 2, before any fit.

    It failed deep in the friction fit ("'tau' has shape ()"); and the reader's warning
    about rows dropped as corrupted was silenced for the user's own logs.
    """
    import warnings

    import numpy as np

    t = 1234.5 + 0.008 * np.arange(400)
    q = 1.0 + 0.3 * np.sin(np.outer(t - t[0], np.arange(1, 7) * 0.5))
    table = np.column_stack([t, *q.T, *np.gradient(q, t, axis=0).T, *(0.5 + 0.1 * q).T])
    lines = [",".join(f"{v:.6f}" for v in row) for row in table]
    lines[100] = lines[100].replace("1.", "253.", 1)  # a corrupted row, as UR logs have
    path = tmp_path / "run.csv"
    path.write_text("\n".join(lines) + "\n")
    from leadthrough.model.robots import AssumedDriveDataWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AssumedDriveDataWarning)  # the UR5's, known
        assert main(["identify", "--robot", "ur5", "--log", str(path), "--out",
                     str(tmp_path / "out")]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert "dropped 1 of 400 rows as corrupted" in err
    assert "run.csv: the log has motor currents but ur5 has no torque constants" in err
