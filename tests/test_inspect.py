"""`leadthrough inspect`: report, figure and tables over a log; the false-alarm table."""

import warnings

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.cli.main import main
from leadthrough.estimation.log_observer import ObservedLog, false_alarm_table
from realdata import REALDATA, needs_realdata
from test_contacts import synthetic_log


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


def test_no_contact_spans_a_gap_in_time_and_the_report_says_where_it_is(ur10e, tmp_path, capsys):
    """Free motion with 3 s of rows missing: no contact (none is in the data), the gap named."""
    log = synthetic_log(ur10e, duration=10.0, current=True)
    kept = (log.t < 3.0) | (log.t >= 6.0)
    gapped = lt.JointLog(log.t[kept], log.q[kept], log.qd[kept], current=log.current[kept])
    assert lt.detect_contacts(gapped, ur10e, None) == []
    write_ur_csv(gapped, tmp_path / "gap.csv")
    assert main(["inspect", str(tmp_path / "gap.csv"), "--out", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    start, end = (gapped.t[k] - gapped.t[0] for k in (np.argmin(kept) - 1, np.argmin(kept)))
    where = f"1 gap(s) in time longer than 0.25 s (rows missing), at {start:.2f} … {end:.2f} s"
    assert "0 contact(s)" in printed and where in printed
    assert where in (tmp_path / "out" / "report.md").read_text()


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
    printed = capsys.readouterr()
    assert "3 contact(s)" in printed.out
    # after the summary, on stderr, as identify warns (one line: cli.arguments.one_line_warnings)
    assert "drive data assumed" not in printed.out
    assert "leadthrough: warning: ur10e: drive data assumed" in printed.err
    # the samples as logged (jittered stamps), and those the observer ran on, resampled
    report = (tmp_path / "report.md").read_text()
    assert "1896 samples over 19.7 s" in report and "median period: 1968 samples" in report


def test_inspect_says_where_the_supervisor_would_fault(ur10e, tmp_path, capsys):
    """A log whose samples repeat whole from 2 s on (a stalled driver): the fault and its time.

    The same log without the stall passes every check, and the report says so.
    """
    from leadthrough.experiments.real_logs import supervisor_verdict

    log = synthetic_log(ur10e, push=(2.0, 3.0, [0, 0, 25.0, 0, 0, 0]), current=True)
    assert supervisor_verdict(log, ur10e) is None
    stalled = [value.copy() for value in (log.q, log.qd, log.current)]
    after = log.t - log.t[0] >= 2.0
    for value in stalled:
        value[after] = value[np.argmax(after)]  # the sample at 2 s, repeated from then on
    frozen = lt.JointLog(log.t, stalled[0], stalled[1], current=stalled[2])
    time, reason = supervisor_verdict(frozen, ur10e)
    period = log.median_period
    assert time == pytest.approx(2.0 + 24 * period, abs=1.5 * period)  # the 25th repeat
    assert "frozen" in reason or "stale" in reason  # a moving joint's repeats, or the whole
    write_ur_csv(frozen, tmp_path / "stalled.csv")
    assert main(["inspect", str(tmp_path / "stalled.csv"), "--out", str(tmp_path / "out")]) == 0
    assert "supervisor would fault 2." in capsys.readouterr().out
    assert "supervisor would fault" in (tmp_path / "out" / "report.md").read_text()


@needs_realdata
def test_a_real_ur10e_log_passes_every_check_of_the_supervisor(ur10e):
    """A static hold of the real UR10e, its readings repeating exactly: no fault."""
    from leadthrough.experiments.real_logs import supervisor_verdict

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        log = lt.read_log(REALDATA / "ur10e" / "validation" / "ur-20_01_17-p1.csv", ur10e)
    assert supervisor_verdict(log, ur10e) is None
