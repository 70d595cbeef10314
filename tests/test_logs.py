"""Reading robot logs: UR CSV, Panda text, the project's files; corrupted rows dropped loudly."""

import warnings

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.errors import InputShapeError
from leadthrough.experiments.real_logs import supervisor_verdict
from leadthrough.friction.identification import IdentificationError
from leadthrough.logs.log import rate_ratio
from leadthrough.runtime.readers import LogError, LogWarning, detect_format
from leadthrough.runtime.recording import SessionRecorder
from realdata import REALDATA, needs_realdata


def _ur_rows(n: int, width: int = 31, t0: float = 1234.5) -> np.ndarray:
    """A plausible UR log: q moving slowly, currents of a few amperes."""
    t = t0 + 0.008 * np.arange(n)
    q = 1.0 + 0.3 * np.sin(np.outer(t - t0, np.arange(1, 7) * 0.5))
    qd = np.gradient(q, t, axis=0)
    current = 0.5 + 0.1 * q
    table = [t, *q.T, *qd.T, *current.T]
    if width >= 25:
        table += [*(1.1 * current).T]
    if width == 31:
        table += [*(11.0 * current).T]
    return np.column_stack(table)


def _write(path, table, extra_lines=()):
    lines = [",".join(f"{v:.6f}" for v in row) for row in table]
    lines.extend(extra_lines)
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_clean_ur_log_reads_whole_and_currents_become_torques(tmp_path):
    """Every row kept; with the UR10e's K, tau = K·i; the 31-column targets kept by name."""
    table = _ur_rows(200)
    log = lt.read_log(_write(tmp_path / "run.csv", table), lt.robots.ur10e())
    assert log.n_samples == 200 and log.n_joints == 6 and log.dropped_rows == 0
    np.testing.assert_allclose(log.t, table[:, 0], atol=1e-6)
    np.testing.assert_allclose(log.tau, table[:, 13:19] * lt.robots.ur10e().torque_constants,
                               atol=1e-5)  # fmt: skip
    assert set(log.extra) == {"target_current", "target_torque"}
    assert lt.read_log(tmp_path / "run.csv").tau is None  # no robot: no K, no torque


@pytest.mark.parametrize("width", [19, 25])
def test_narrower_ur_logs_read(tmp_path, width):
    """19 columns (no targets) and 25 (undocumented extras) are UR logs too."""
    log = lt.read_log(_write(tmp_path / "run.csv", _ur_rows(50, width)))
    assert log.n_samples == 50 and log.current.shape == (50, 6)


def test_corrupted_rows_are_dropped_with_one_warning_that_counts_them(tmp_path):
    """253.0 rows, 1e300 rows, a row of zeros, time going back, a truncated last line."""
    table = _ur_rows(300)
    table[10, 1:4] = 253.0
    table[20, 5] = 1e300
    table[30, 1:] = 0.0
    table[40, 0] = table[39, 0] - 0.5
    path = _write(tmp_path / "bad.csv", table, ["1236.9,0.1,0.2"])
    with pytest.warns(LogWarning, match=r"dropped 5 of 301 rows as corrupted \(rows 11, 21, 31"):
        log = lt.read_log(path)
    assert log.n_samples == 296 and log.dropped_rows == 5
    assert np.all(np.diff(log.t) > 0) and np.all(np.abs(log.q - 1.0) < 0.5)


@pytest.mark.parametrize(("row", "jump"), [(0, 50.0), (30, 50.0), (250, 50.0), (30, -50.0),
                                           (299, -50.0)])  # fmt: skip
def test_a_time_stamp_that_jumped_costs_its_own_row_only(tmp_path, row, jump):
    """One row's t off by ±50 s, first, early or last: that row dropped, every other kept."""
    table = _ur_rows(300)
    table[row, 0] += jump
    with pytest.warns(LogWarning, match=rf"dropped 1 of 300 rows as corrupted \(rows {row + 1}\)"):
        log = lt.read_log(_write(tmp_path / "jump.csv", table))
    assert log.n_samples == 299 and log.dropped_rows == 1
    np.testing.assert_allclose(log.t, np.delete(table[:, 0], row), atol=1e-6)


def test_a_mostly_garbage_file_is_an_error_naming_it(tmp_path):
    """More than half the rows corrupted: one error with the file's name, nothing returned."""
    table = _ur_rows(40)
    table[::2, 1] = 1e300
    table[1::4, 2] = np.nan
    with pytest.raises(LogError, match=r"garbage\.csv"):
        lt.read_log(_write(tmp_path / "garbage.csv", table))


def test_unknown_and_missing_files_fail_in_one_line(tmp_path):
    """No such file, and a file that is no known log, each name the file."""
    with pytest.raises(LogError, match="no such file"):
        lt.read_log(tmp_path / "nothing.csv")
    (tmp_path / "notes.txt").write_text("hello, world\n")
    with pytest.raises(LogError, match=r"notes\.txt: unknown log format"):
        lt.read_log(tmp_path / "notes.txt")


def test_a_folder_of_csv_logs_is_told_to_name_one(tmp_path):
    """A folder is read as a Panda text log; one holding UR CSVs says to give one file."""
    for name in ("link4.csv", "ur-static.csv"):
        (tmp_path / name).write_text("0," * 18 + "0\n")
    with pytest.raises(LogError, match=r"Panda text log.*2 other logs, e\.g\. link4\.csv: give"):
        lt.read_log(tmp_path)


def test_panda_text_log_reads_samples_on_consecutive_lines(tmp_path):
    """Each sample on n consecutive lines; irregular time stamps kept as logged."""
    t = np.array([0.0, 1.0, 2.0, 4.5, 5.5, 6.5, 7.5, 9.0, 10.0, 11.0]) * 1e-3
    q = np.linspace(0, 0.1, 70).reshape(10, 7)
    for kind, values in (("time", t), ("positions", q), ("velocity", q * 0.1),
                         ("torques", q * 10)):  # fmt: skip
        (tmp_path / f"exciting_traj_{kind}.txt").write_text("\n".join(map(str, values.ravel())))
    log = lt.read_log(tmp_path / "exciting_traj_time.txt")
    assert detect_format(tmp_path) == "panda_txt"
    np.testing.assert_allclose(log.t, t)
    np.testing.assert_allclose(log.tau, q * 10)
    assert log.n_joints == 7


def _smooth_panda_log(folder, drop=None, add=None, kind="positions"):
    """A 2 s, 1 kHz Panda text log of joints swinging at their own frequencies.

    ``drop``/``add``: the sample at which one value of ``kind`` goes missing / one is
    added (the counts stay right, the rows between are shifted by one value).
    """
    t = np.arange(2000) * 1e-3
    frequency = np.linspace(0.3, 1.5, 7)
    columns = {"time": t, "positions": 0.5 * np.sin(2 * np.pi * np.outer(t, frequency)),
               "torques": np.ones((t.size, 7))}  # fmt: skip
    columns["velocity"] = np.pi * frequency * np.cos(2 * np.pi * np.outer(t, frequency))
    for name, values in columns.items():
        lines = [repr(float(v)) for v in np.ravel(values)]
        if name == kind and drop is not None:
            del lines[7 * drop]
            lines.insert(7 * add, "0.25")
        (folder / f"exciting_traj_{name}.txt").write_text("\n".join(lines))
    return folder / "exciting_traj_time.txt"


@pytest.mark.parametrize("kind", ["positions", "velocity"])
def test_a_value_missing_and_one_added_in_a_panda_log_is_named(tmp_path, kind):
    """The counts match, so the rows between were read shifted, each joint its neighbour's.

    Before, such a log loaded whole with 900 rows misread and no word.
    """
    assert lt.read_log(_smooth_panda_log(tmp_path)).n_samples == 2000  # sound: read whole
    with pytest.raises(LogError, match=r"from about row (29|30)\d to row 1[12]\d\d each joint's "
                       r"position reads its neighbour's velocity: a value is missing and one "
                       r"added in \*_positions.txt or \*_velocity.txt"):  # fmt: skip
        lt.read_log(_smooth_panda_log(tmp_path, drop=300, add=1200, kind=kind))


def test_excitation_logs_read_as_one_log(tmp_path):
    """The project's excitation logs (npz) are read back unchanged."""
    from leadthrough.friction.logs import save_logs

    run = {"t": np.arange(5) * 0.004, "q": np.ones((5, 3)), "qd": np.zeros((5, 3)),
           "tau": np.full((5, 3), 0.5)}  # fmt: skip
    log = lt.read_log(save_logs([run], tmp_path / "logs.npz"))
    np.testing.assert_allclose(log.tau, run["tau"])


def test_an_excitation_csv_drops_and_counts_a_nan_row_and_a_truncated_last_line(tmp_path):
    """save_logs' CSV with a NaN row and a cut last line: those two dropped, one warning."""
    from leadthrough.friction.logs import save_logs

    t = np.arange(50) * 0.004
    run = {"t": t, "q": np.outer(t, [1.0, 2.0]), "qd": np.ones((50, 2)), "tau": np.ones((50, 2))}
    run["q"][20, 1] = np.nan
    path = save_logs([run], tmp_path / "mine.csv")
    path.write_text(path.read_text() + "0,0.2,0.1,0.2\n")  # the writer stopped mid-row
    dropped = r"mine\.csv: dropped 2 of 51 rows as corrupted \(rows 21, 51\)"
    with pytest.warns(LogWarning, match=dropped):
        log = lt.read_log(path)
    assert log.n_samples == 49 and log.dropped_rows == 2 and np.all(np.isfinite(log.q))
    np.testing.assert_allclose(log.t, np.delete(t, 20))


def test_an_excitation_npz_drops_and_counts_its_nan_rows_as_the_csv_does(tmp_path):
    """save_logs' NPZ with a NaN and an Inf row: both dropped, one warning (they passed)."""
    from leadthrough.friction.logs import load_logs, save_logs

    t = np.arange(50) * 0.004
    run = {"t": t, "q": np.outer(t, [1.0, 2.0]), "qd": np.ones((50, 2)), "tau": np.ones((50, 2))}
    run["q"][20, 1], run["tau"][30, 0] = np.nan, np.inf
    path = save_logs([run], tmp_path / "mine.npz")
    dropped = r"mine\.npz: dropped 2 of 50 rows as corrupted \(rows 21, 31\)"
    with pytest.warns(LogWarning, match=dropped):
        log = lt.read_log(path)
    assert log.n_samples == 48 and log.dropped_rows == 2 and np.all(np.isfinite(log.tau))
    np.testing.assert_allclose(log.t, np.delete(t, [20, 30]))
    with pytest.warns(LogWarning, match=dropped):
        (loaded,) = load_logs(path)
    assert loaded["dropped_rows"] == 2 and np.all(np.isfinite(loaded["q"]))


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_an_excitation_log_drops_its_implausible_rows_as_the_robot_logs_do(tmp_path, suffix):
    """A torque of 1e300, an angle of 1000 rad, one off its path: dropped, counted, warned.

    Before, only non-finite rows were: the torque ended the fit in a traceback, and the
    angle was fitted (joint 1's level 1.50 → 7.77 Nm), silently.
    """
    from leadthrough.friction.logs import load_logs, save_logs

    t = np.arange(200) * 0.004
    q = np.column_stack([np.sin(t), 0.5 * np.cos(t)])
    run = {"t": t, "q": q, "qd": np.gradient(q, t, axis=0), "tau": np.ones((200, 2))}
    run["tau"][30, 0], run["q"][60, 1], run["q"][90, 0] = 1e300, 1000.0, q[90, 0] + 0.5
    path = save_logs([run], tmp_path / f"mine{suffix}")
    with pytest.warns(LogWarning, match=r"dropped 3 of 200 rows as corrupted \(rows 31, 61, 91\)"):
        (loaded,) = load_logs(path)
    assert loaded["dropped_rows"] == 3 and np.max(np.abs(loaded["tau"])) == 1.0
    assert np.max(np.abs(loaded["q"])) <= 1.0


@pytest.mark.parametrize("keep", [0.0, 0.5], ids=["empty", "truncated"])
def test_a_truncated_or_empty_npz_is_a_log_error_naming_it(tmp_path, keep):
    """An .npz cut short (or empty) is a one-line LogError naming the file, no traceback."""
    from leadthrough.friction.logs import save_logs

    run = {"t": np.arange(50) * 0.004, "q": np.ones((50, 3)), "qd": np.zeros((50, 3)),
           "tau": np.full((50, 3), 0.5)}  # fmt: skip
    path = save_logs([run], tmp_path / "logs.npz")
    path.write_bytes(path.read_bytes()[: int(keep * path.stat().st_size)])
    with pytest.raises(LogError, match=r"logs\.npz: cannot read logs: truncated, empty"):
        lt.read_log(path)


def test_a_cut_or_unfinished_recording_reads_with_a_warning_saying_how_much(tmp_path):
    """A crashed recorder's .mcap.part and a recording cut at 60 % read, each with a warning."""
    robot = lt.robots.yumi()
    q, z = robot.home(), np.zeros(robot.n_joints)
    path = tmp_path / "run.mcap"
    with SessionRecorder(path, robot) as recorder:
        for k in range(500):
            recorder.record(k * 0.004, q + 1e-3 * k, z, z, z, z, "active", "teaching")
        with pytest.warns(LogWarning, match=r"run\.mcap\.part: recovered \d\.\d s"):
            assert lt.read_log(recorder.part_path).n_samples > 400
    with warnings.catch_warnings():
        warnings.simplefilter("error", LogWarning)
        assert lt.read_log(path).n_samples == 500  # a finished recording: no warning
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: int(0.6 * path.stat().st_size)])
    with pytest.warns(LogWarning, match=r"cut\.mcap: recovered .* without its summary"):
        assert 0 < lt.read_log(cut).n_samples < 500
    # read with its own robot, or with another one's (taken without a word before)
    assert lt.read_log(path, robot).n_samples == 500
    with pytest.raises(LogError, match=r"run\.mcap: recorded on 'ABB YuMi.*', not 'panda'"):
        lt.read_log(path, lt.robots.panda())


@pytest.mark.parametrize(
    ("divided", "says"),
    [
        (60.0, "60× too fast"),
        (1000.0, "1000× too fast"),
        (0.2, "5× too slow"),
        (0.5, "2× too slow"),
    ],
)
def test_a_log_whose_clock_runs_too_fast_for_its_velocities_is_refused(tmp_path, divided, says):
    """Time divided by 60 or 1000 (``inspect`` read "6000 Hz"): dq/dt is 60× q̇, one line.

    Stretched 5× (``inspect`` found two contacts in a log of free motion), it is a fifth;
    stretched 2×, half (it was within the 3× allowed before).
    """
    table = _ur_rows(200, 31)
    assert lt.read_log(_write(tmp_path / "s.csv", table)).n_samples == 200  # in seconds: read
    table[:, 0] /= divided
    with pytest.raises(LogError, match=rf"fast\.csv: its time column runs {says} for its q̇"):
        lt.read_log(_write(tmp_path / "fast.csv", table))
    log = {"t": table[:, 0], "q": table[:, 1:7], "qd": table[:, 7:13], "tau": table[:, 13:19],
           "source": "fast.csv"}  # fmt: skip
    with pytest.raises(IdentificationError, match=rf"fast\.csv: its time column runs {says}"):
        lt.identify_friction(log, lt.robots.ur10e())


@needs_realdata
def test_every_real_log_has_its_velocities_within_3_percent_of_dq_dt():
    """q̇ / (dq/dt) where the joints move is 0.977–1.001 on the real logs: far inside 1.5×."""
    paths = [*sorted((REALDATA / "ur10e").glob("*/*.csv")), REALDATA / "panda_gaz2019"]
    ratios = {}
    for path in paths:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LogWarning)  # the corrupted run's dropped rows
            log = lt.read_log(path)
        ratios[path.name] = rate_ratio(log.t, log.q, log.qd)
    measured = [ratio for ratio in ratios.values() if ratio is not None]
    assert len(measured) >= 35 and all(abs(ratio - 1.0) < 0.03 for ratio in measured), ratios


@needs_realdata
def test_every_real_ur10e_log_reads_and_the_corrupted_one_says_so():
    """All UR10e runs read; the known corrupted identification run drops its bad rows."""
    robot = lt.robots.ur10e()
    with pytest.warns(LogWarning, match="ur-19_09_27-11_32_02.csv: dropped"):
        log = lt.read_log(REALDATA / "ur10e/identification/ur-19_09_27-11_32_02.csv", robot)
    assert 0 < log.dropped_rows < 50 and np.all(np.abs(log.q) < 2 * np.pi)
    for path in sorted((REALDATA / "ur10e").glob("*/*.csv")):
        log = lt.read_log(path, robot)
        assert log.tau is not None and np.all(np.diff(log.t) > 0), path.name
        assert 0.008 < log.median_period < 0.013, path.name
        # the arm at rest repeats its readings exactly: still no stale sample for the supervisor
        assert supervisor_verdict(log, robot) is None, path.name


@needs_realdata
def test_the_panda_run_reads_at_about_one_kilohertz():
    """20,544 samples of 7 joints, median period 1 ms, torques from the sensors."""
    log = lt.read_log(REALDATA / "panda_gaz2019")
    assert log.n_samples == 20544 and log.n_joints == 7
    assert log.median_period == pytest.approx(1e-3, rel=0.05)


@pytest.mark.parametrize(
    ("columns", "named"),
    [
        ({"t": np.zeros((5, 1))}, "run.csv: t"),
        ({"q": np.zeros((4, 2))}, "run.csv: q"),
        ({"qd": np.zeros((5, 3))}, "run.csv: qd"),
        ({"extra": {"i": np.zeros(4)}}, "run.csv: extra\\['i'\\]"),
    ],
)
def test_a_log_with_disagreeing_shapes_names_the_column(columns, named):
    """Columns of the wrong shape raise InputShapeError naming the file and the column."""
    arrays = {"t": np.arange(5.0), "q": np.zeros((5, 2)), "qd": np.zeros((5, 2))} | columns
    with pytest.raises(InputShapeError, match=f"^{named}: expected shape"):
        lt.JointLog(**arrays, source="run.csv")


def test_a_ur_wide_csv_with_a_header_row_is_refused_naming_it(tmp_path):
    """Columns named in a first line: not a UR controller's file, whatever its width.

    Read as one before, its header was dropped as a corrupted row and its torque columns
    were taken for motor currents (times K): a contact of −927 Nm for the whole run.
    """
    header = ",".join(["time"] + [f"{k}{j}" for k in ("q", "dq", "tau") for j in range(1, 7)])
    path = _write(tmp_path / "mine.csv", _ur_rows(50, 19), [])
    path.write_text(header + "\n" + path.read_text())
    with pytest.raises(LogError, match=r"mine\.csv: its first line names columns \(time,q1"):
        lt.read_log(path)


def test_a_log_timed_in_milliseconds_is_refused(tmp_path):
    """Samples 8 s apart (a UR log's 8 ms, in milliseconds): one line asking about its unit.

    ``identify`` took such a log without a word (σ 6× too large), or crashed.
    """
    table = _ur_rows(50, 31)
    table[:, 0] *= 1e3
    with pytest.raises(LogError, match=r"ms\.csv: samples 8 s apart .*milliseconds"):
        lt.read_log(_write(tmp_path / "ms.csv", table))
    rows = _ur_rows(60, 19)
    log = {"t": 1e3 * rows[:, 0], "q": rows[:, 1:7], "qd": rows[:, 7:13], "tau": rows[:, 13:19]}
    with pytest.raises(IdentificationError, match="milliseconds"):
        lt.identify_friction(log, lt.robots.ur10e())
