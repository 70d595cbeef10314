"""``leadthrough identify --log ... --held-out ...`` on real UR10e runs: report, figures, TOML."""

import warnings

import numpy as np
from tests.realdata import REALDATA, needs_realdata

import leadthrough as lt
from leadthrough.cli.main import main


@needs_realdata
def test_identify_real_logs_writes_report_figures_and_a_loadable_description(tmp_path, capsys):
    """One excitation run fitted, one held out: report.md, PNGs, and a TOML that loads."""
    runs = [REALDATA / "ur10e" / "identification" / "ur-20_02_05-20sec_8harm.csv"]
    held_out = REALDATA / "ur10e" / "validation" / "collision_free.csv"
    out = tmp_path / "out"
    argv = ["identify", "--robot", "ur10e", "--log", *map(str, runs), "--held-out",
            str(held_out), "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    report = (out / "report.md").read_text()
    assert "| ours |" in report and "| nominal |" in report
    for name in ("friction.png", "held_out_1.png"):
        assert (out / name).stat().st_size > 10_000
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        nominal = lt.robots.ur10e()
    identified = lt.robots.load(str(out / "identified.toml"))
    assert identified.torque_constants is not None
    q = nominal.home()
    assert not np.allclose(lt.Dynamics(identified).gravity(q), lt.Dynamics(nominal).gravity(q))
    lt.FrictionModel.load(out / "friction.toml")
    assert "Identified description" in capsys.readouterr().out


@needs_realdata
def test_joints_a_real_run_did_not_identify_are_named(tmp_path, capsys):
    """One joint's run: the others are named in a warning and the report, and keep nominal."""
    run = REALDATA / "ur10e" / "jointwise" / "ur-20_01_22-joint_4.csv"
    out = tmp_path / "out"
    assert main(["identify", "--robot", "ur10e", "--log", str(run), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "joints 1, 2, 3, 5, 6 not identified" in err
    report = (out / "report.md").read_text()
    assert "joints 1, 2, 3, 5, 6 not identified" in report
    assert "| 4 |" in report and "| 1 |" not in report.split("Dynamics fit:")[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        nominal = lt.FrictionModel.from_robot(lt.robots.ur10e())
    written = lt.FrictionModel.load(out / "friction.toml")
    np.testing.assert_allclose(written.coulomb[[0, 1, 2, 4, 5]], nominal.coulomb[[0, 1, 2, 4, 5]])
    assert "(never moved fast enough: nominal)" in report
