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
