"""`leadthrough inspect`: report, figure and tables over a log; the false-alarm table."""

import warnings

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.cli.main import main
from leadthrough.estimation.log_observer import ObservedLog, false_alarm_table
from realdata import REALDATA, needs_realdata
from test_contacts import synthetic_log


@pytest.fixture(scope="module")
def ur10e():
    """The nominal UR10e (its assumed-drive-data warning silenced)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return lt.robots.ur10e()


def write_ur_csv(log: lt.JointLog, path) -> None:
    """A log in the UR layout of 19 columns: time, q, q̇, motor current."""
    np.savetxt(path, np.column_stack([log.t + 1000.0, log.q, log.qd, log.current]),
               delimiter=",", fmt="%.9g")  # fmt: skip


def test_inspect_writes_a_report_with_the_injected_push(ur10e, tmp_path, capsys):
    """A UR CSV with a 25 Nm push on joint 3 from 2 to 3 s: one contact in the report."""
    log = synthetic_log(ur10e, push=(2.0, 3.0, [0, 0, 25.0, 0, 0, 0]), current=True)
    write_ur_csv(log, tmp_path / "run.csv")
    status = main(["inspect", str(tmp_path / "run.csv"), "--out", str(tmp_path / "out")])
    assert status == 0
    printed = capsys.readouterr().out
    assert "1 contact(s)" in printed and "joints 3" in printed
    report = (tmp_path / "out" / "report.md").read_text()
    assert "| 1 | " in report and "observer.png" in report
    assert "RMS τ̂/std" in report
    assert (tmp_path / "out" / "observer.png").stat().st_size > 10_000


def test_false_alarm_table_against_direct_computation():
    """RMS, peak, exceedance of 2 std and RMS of τ̂/std of known samples."""
    tau = np.array([[1.0, -4.0], [-1.0, 0.0], [3.0, 0.0], [-1.0, 2.0]])
    std = np.array([[1.0, 1.0], [1.0, 1.0], [1.0, 1.0], [1.0, 1.0]])
    zero = np.zeros_like(tau)
    observed = ObservedLog(np.arange(4.0), zero, zero, zero, tau, std, zero)
    table = false_alarm_table([observed])
    np.testing.assert_allclose(table["rms"], [np.sqrt(12 / 4), np.sqrt(20 / 4)])
    np.testing.assert_allclose(table["peak"], [3.0, 4.0])
    np.testing.assert_allclose(table["exceed"], [0.25, 0.25])
    np.testing.assert_allclose(table["z_rms"], table["rms"])


@needs_realdata
def test_inspect_the_link4_push_run(tmp_path, capsys):
    """pushes/link4.csv with the nominal UR10e: the three contacts, named joints, a report."""
    source = REALDATA / "ur10e" / "pushes" / "link4.csv"
    assert main(["inspect", str(source), "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "3 contact(s)" in printed
    assert "note: ur10e: drive data assumed" in printed
