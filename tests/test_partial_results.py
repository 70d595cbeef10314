"""Nothing partial or defaulted in silence: recovered recordings, bounded work, friction warning."""

import re
from pathlib import Path

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.cli.main import main
from leadthrough.errors import ParameterError, RecordingError
from leadthrough.experiments import teach
from leadthrough.runtime.recording import SessionRecorder, read_recording

DT = 0.004  # control period [s]
PERIODS = 1000  # 4 s


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Path:
    """A finished 4 s synthetic session, flushed every 0.1 s (about 40 chunks)."""
    robot = lt.robots.yumi()
    path = tmp_path_factory.mktemp("partial") / "session.mcap"
    with SessionRecorder(path, robot, {"dt": DT}) as recorder:
        for k in range(PERIODS):
            q = robot.home() + 0.1 * np.sin(k * DT)
            recorder.record(k * DT, q, 0 * q, 0 * q, 0 * q, 0 * q, "active", "teaching")
    return path


def test_damaged_recording_says_how_much_of_how_much(recording, tmp_path):
    """Zeroed bytes at 40 %: the prefix is read; the message gives read of total (summary)."""
    data = bytearray(recording.read_bytes())
    start = int(0.4 * len(data))
    data[start : start + 200] = bytes(200)
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    recovered = read_recording(damaged)
    periods = len(recovered.t)
    assert not recovered.complete and 0 < periods < PERIODS
    seconds = recovered.t[-1] - recovered.t[0]
    total = (PERIODS - 1) * DT  # the summary's span of message times
    assert f"recovered {seconds:.1f} s of {total:.1f} s ({periods} of {PERIODS} periods)" in (
        recovered.recovery
    )
    byte = int(recovered.recovery.split("from byte ")[1].split()[0])
    assert byte <= start, "reading stops before the damage"


def test_cut_recording_says_its_length_is_unknown(recording, tmp_path):
    """A file cut in half has no summary: what was read, where it ends, total unknown."""
    data = recording.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    recovered = read_recording(cut)
    assert not recovered.complete
    assert f"({len(recovered.t)} periods): the file ends at byte {len(data) // 2}" in (
        recovered.recovery
    )
    assert "unknown" in recovered.recovery
    assert read_recording(recording).recovery == ""


def test_replay_of_a_partial_recording_must_be_asked_for(recording, tmp_path):
    """replay_on_twin refuses a recovered recording without partial=True, naming --partial."""
    data = recording.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(RecordingError, match=r"recovered .*--partial"):
        teach.replay_on_twin(cut, tmp_path / "out")


@pytest.mark.parametrize("time_scale", [0.0, 0.01, 25.0, 1e6, float("nan")])
def test_replay_time_scale_is_bounded(recording, tmp_path, time_scale):
    """A time scale outside 0.05-20 is a ParameterError before the recording is even read."""
    with pytest.raises(ParameterError, match="time_scale"):
        teach.replay_on_twin(tmp_path / "absent.mcap", tmp_path, time_scale)


def test_replay_duration_is_bounded(recording, tmp_path, monkeypatch):
    """A replay longer than MAX_SECONDS of simulation is refused, naming the limit."""
    monkeypatch.setattr(teach, "MAX_SECONDS", 10.0)  # the 4 s recording at 3× is 12 s
    with pytest.raises(ParameterError, match="at most 10 s"):
        teach.replay_on_twin(recording, tmp_path, time_scale=3.0)


@pytest.mark.parametrize("duration", [0.0, -1.0, float("inf"), 601.0])
def test_teaching_duration_is_bounded(tmp_path, duration):
    """teach_on_twin refuses a duration outside (0, 600] s before any simulation."""
    with pytest.raises(ParameterError, match="duration"):
        teach.teach_on_twin(lt.robots.yumi(), tmp_path / "t.mcap", duration=duration)


def test_teaching_without_identified_friction_warns(tmp_path, monkeypatch):
    """No friction file: an UnidentifiedFrictionWarning naming `leadthrough identify`."""

    def stop(*args, **kwargs):
        raise RuntimeError("stop before simulating")

    monkeypatch.setattr(teach, "simulate", stop)
    with (
        pytest.warns(teach.UnidentifiedFrictionWarning, match="leadthrough identify"),
        pytest.raises(RuntimeError, match="stop before"),
    ):
        teach.teach_on_twin(lt.robots.yumi(), tmp_path / "t.mcap")


def excitation_log(path: Path, moving: tuple[int, ...]) -> Path:
    """A 16 s CSV log of the YuMi at home; joints in ``moving`` swing ±0.5 rad, with friction."""
    robot, rng = lt.robots.yumi(), np.random.default_rng(0)
    dynamics, n, t = lt.Dynamics(robot), robot.n_joints, np.arange(4000) * DT
    q = np.tile(robot.home(), (len(t), 1)) + 1e-6 * rng.standard_normal((len(t), n))
    qd = 1e-4 * rng.standard_normal((len(t), n))
    for j in moving:
        q[:, j] += 0.5 * np.sin(0.4 * np.pi * t)
        qd[:, j] = 0.2 * np.pi * np.cos(0.4 * np.pi * t)
    tau = np.array([dynamics.gravity(row) for row in q]) + 0.3 * np.tanh(qd / 0.01) + 0.2 * qd
    header = ["run", "t"] + [f"{k}{i + 1}" for k in ("q", "qd", "tau") for i in range(n)]
    np.savetxt(path, np.column_stack([np.zeros(len(t)), t, q, qd, tau]), delimiter=",",
               header=",".join(header), comments="", fmt="%.9g")  # fmt: skip
    return path


def test_identify_on_a_log_where_nothing_moves_writes_nothing(tmp_path, capsys):
    """No joint moved: one-line error and exit 2; no friction file (no defaults as results)."""
    log = excitation_log(tmp_path / "still.csv", moving=())
    assert main(["identify", "--log", str(log), "--out", str(tmp_path / "id")]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("leadthrough: error: no joint moved") and "\n" not in error
    assert not (tmp_path / "id" / "friction.toml").exists()


def test_identify_with_an_unreadable_held_out_log_writes_nothing(tmp_path, capsys):
    """A held-out log that cannot be read: one line, and the output folder as it was.

    Before, the held-out logs were read after the friction figure was written: a folder
    of an earlier run then held the new figure beside the old report and models.
    """
    from tests.test_logs import _ur_rows, _write

    runs = [_write(tmp_path / f"run{k}.csv", _ur_rows(400, t0=10.0 * k)) for k in range(2)]
    _write(tmp_path / "held_out.csv", _ur_rows(400)[::-1])  # time runs back: rows corrupted
    out = tmp_path / "id"
    out.mkdir()
    (out / "report.md").write_text("an earlier run's\n")
    argv = ["identify", "--robot", "ur10e", "--log", *map(str, runs), "--held-out",
            str(tmp_path / "held_out.csv"), "--out", str(out)]  # fmt: skip
    assert main(argv) == 2
    assert "held_out.csv" in capsys.readouterr().err
    assert [path.name for path in out.iterdir()] == ["report.md"]


def test_identify_names_the_joints_it_could_not_identify(tmp_path, capsys):
    """Only joint 1 moved: it is fitted and plotted; joints 2–7 are named as not identified."""
    log = excitation_log(tmp_path / "one.csv", moving=(0,))
    out = tmp_path / "id"
    assert main(["identify", "--log", str(log), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    named = "joints 2, 3, 4, 5, 6, 7 not identified"
    assert f"leadthrough: warning: {named}" in captured.err and named in captured.out
    assert (out / "joint1_fig4_6_position_dependence.png").exists()
    friction = lt.FrictionModel.load(out / "friction.toml")
    nominal = lt.FrictionModel.from_robot(lt.robots.yumi())
    np.testing.assert_array_equal(friction.coulomb[1:], nominal.coulomb[1:])
    assert friction.coulomb[0] == pytest.approx(0.3, rel=0.1)  # the log's τ_C


def test_coulomb_level_of_a_batch_has_a_row_per_pose():
    """τ_C(q) for (m, n) poses is (m, n), with or without position dependence."""
    friction = lt.FrictionModel.from_robot(lt.robots.yumi())
    q = np.zeros((5, friction.n_joints))
    np.testing.assert_array_equal(friction.coulomb_level(q), np.tile(friction.coulomb, (5, 1)))
    assert friction.coulomb_level(q[0]) is friction.coulomb  # one pose: no copy


def test_identify_summary_has_no_nan_where_the_truth_is_zero(tmp_path, recwarn):
    """A twin joint without viscous friction: its relative error reads '–', no warning, no nan."""
    import dataclasses

    from leadthrough.cli.identify import summarise
    from leadthrough.experiments.friction_study import run_friction_study
    from leadthrough.friction.logs import load_logs

    robot = lt.robots.yumi()
    log = excitation_log(tmp_path / "one.csv", moving=(0,))
    study = run_friction_study(robot, logs=load_logs(log))
    truth = (np.full(robot.n_joints, 0.3), np.zeros(robot.n_joints))
    summary = summarise(dataclasses.replace(study, truth=truth), tmp_path)
    assert "nan" not in summary.lower() and "c error [%]:   –" in summary
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


@pytest.mark.filterwarnings("ignore::leadthrough.experiments.teach.UnidentifiedFrictionWarning")
def test_a_fault_while_teaching_is_not_silent(tmp_path, monkeypatch):
    """The supervisor stops the arm mid-session: teach warns naming when and why."""
    from leadthrough.control.lead_through import LeadThrough

    original = LeadThrough._control

    def failing(self, t, model, tau):
        if t > 1.5:  # 0.2 s after the start-up calibration's 1.3 s
            raise IndexError("injected")
        return original(self, t, model, tau)

    monkeypatch.setattr(LeadThrough, "_control", failing)
    with pytest.warns(UserWarning, match=r"stopped the arm at 1\.5\d s: .*IndexError: injected"):
        summary = teach.teach_on_twin(lt.robots.yumi(), tmp_path / "t.mcap", duration=0.8,
                                      friction_file=None)  # fmt: skip
    assert "supervisor fault" in summary
    # its replay stops where the fault began: the safe stop after it was nobody's teaching
    monkeypatch.undo()
    replayed = teach.replay_on_twin(tmp_path / "t.mcap", tmp_path / "replay")
    assert re.search(r"up to its fault at 0\.2\d s: the safe stop after it is not replayed",
                     replayed)  # fmt: skip


def test_a_session_that_records_nothing_leaves_no_file(tmp_path, monkeypatch):
    """A fault in the start-up calibration: nothing taught, the error says so, no file.

    Before, an empty recording stayed, and the next ``teach --out`` to it was refused as
    "exists (a recording)".
    """
    from leadthrough.control.calibration import CalibrationRun

    def failing(self, t, q, qd):
        raise IndexError("injected")

    monkeypatch.setattr(CalibrationRun, "command", failing)
    out = tmp_path / "t.mcap"
    with pytest.raises(RecordingError, match=r"nothing was taught or recorded.*no file written"):
        teach.teach_on_twin(lt.robots.yumi(), out, duration=0.2, friction_file=None)
    assert not out.exists() and not list(tmp_path.iterdir())


def test_damaged_recording_counts_the_taught_span_not_the_events(tmp_path):
    """Events before the first sample (a calibration) do not lengthen the 'of … s' total."""
    robot = lt.robots.yumi()
    path = tmp_path / "session.mcap"
    with SessionRecorder(path, robot, {"dt": DT}) as recorder:
        recorder.event(0.0, "calibration", "started")
        for k in range(PERIODS):
            q = robot.home() + 0.1 * np.sin(k * DT)
            recorder.record(0.9 + k * DT, q, 0 * q, 0 * q, 0 * q, 0 * q, "active", "teaching")
    data = bytearray(path.read_bytes())
    data[int(0.4 * len(data)) : int(0.4 * len(data)) + 200] = bytes(200)
    (tmp_path / "damaged.mcap").write_bytes(bytes(data))
    recovered = read_recording(tmp_path / "damaged.mcap")
    assert f"of {(PERIODS - 1) * DT:.1f} s ({len(recovered.t)} of {PERIODS}" in recovered.recovery
