"""Tests of the session recording: round trip, crash safety, recovery, Ctrl-C."""

import os
import signal
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.errors import InputShapeError, RecordingError
from leadthrough.runtime.recording import ARRAYS, SessionEvent, SessionRecorder, read_recording

DT = 0.004  # control period [s], 250 Hz

# Records synthetic states in real time and prints each recorded t once record() returned.
CHILD = """
import signal, sys, time
import numpy as np
import leadthrough as lt
from leadthrough.runtime.recording import SessionRecorder

# Ctrl-C as a terminal delivers it, even when the test runs where SIGINT is ignored (a
# background job inherits SIG_IGN, and Python then installs no handler of its own)
signal.signal(signal.SIGINT, signal.default_int_handler)
dt = float(sys.argv[2])
with SessionRecorder(sys.argv[1], lt.robots.yumi(), {"dt": dt}) as recorder:
    for k in range(10**6):
        t = k * dt
        q = np.sin(t + np.arange(7))
        recorder.record(t, q, 2 * q, 3 * q, 4 * q, 5 * q, "active", "teaching")
        print(repr(t), flush=True)
        time.sleep(dt)
"""


@pytest.fixture(scope="module")
def robot() -> lt.RobotDescription:
    """The shipped YuMi arm."""
    return lt.robots.yumi()


@pytest.fixture(scope="module")
def session(robot, tmp_path_factory) -> tuple[Path, dict]:
    """A finished synthetic 3 s session at 250 Hz, and what was recorded."""
    rng = np.random.default_rng(7)
    n_samples = round(3.0 / DT)
    data = {name: rng.normal(scale=2.0, size=(n_samples, robot.n_joints)) for name in ARRAYS}
    data["t"] = np.arange(n_samples) * DT
    data["mode"] = ["active" if k < n_samples // 2 else "passive" for k in range(n_samples)]
    data["state"] = ["teaching" if k % 300 else "holding" for k in range(n_samples)]
    data["events"] = [SessionEvent(k * DT, "tool_speed", f"tool speed {k} mm/s: braking")
                      for k in range(0, n_samples, 125)]  # fmt: skip
    data["parameters"] = {"mode": "active", "dt": DT, "gains": [1.5, 2.0], "note": "λ ok"}
    path = tmp_path_factory.mktemp("session") / "session.mcap"
    with SessionRecorder(path, robot, data["parameters"]) as recorder:
        for k in range(n_samples):
            arrays = [data[name][k] for name in ARRAYS]
            recorder.record(data["t"][k], *arrays, data["mode"][k], data["state"][k])
            for event in data["events"]:
                if event.t == data["t"][k]:
                    recorder.event(*event)
    return path, data


def assert_same_robot(read: lt.RobotDescription, written: lt.RobotDescription) -> None:
    """Masses, inertials, DH rows, limits and friction are equal."""
    assert read.name == written.name
    np.testing.assert_array_equal(read.masses, written.masses)
    np.testing.assert_array_equal(read.q_min, written.q_min)
    np.testing.assert_array_equal(read.q_max, written.q_max)
    np.testing.assert_array_equal(read.velocity_limits, written.velocity_limits)
    np.testing.assert_array_equal(read.torque_limits, written.torque_limits)
    np.testing.assert_array_equal(read.gear_ratios, written.gear_ratios)
    for a, b in zip(read.joints, written.joints, strict=True):
        assert vars(a.dh) == vars(b.dh)
        np.testing.assert_array_equal(a.link.com, b.link.com)
        np.testing.assert_array_equal(a.link.inertia, b.link.inertia)
        assert vars(a.friction) == vars(b.friction)


def test_round_trip(session, robot):
    """A finished 3 s session reads back equal: arrays, strings, events, metadata, robot."""
    path, data = session
    recording = read_recording(path)
    assert recording.complete
    assert not path.with_name(path.name + ".part").exists()
    np.testing.assert_array_equal(recording.t, data["t"])
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(recording, name), data[name])
    assert recording.mode == data["mode"]
    assert recording.state == data["state"]
    assert recording.events == data["events"]
    assert recording.parameters == data["parameters"]
    assert recording.version == lt.__version__
    assert recording.start_time.endswith("+00:00")
    assert_same_robot(recording.robot, robot)


def test_non_finite_values_read_back_as_nan(robot, tmp_path):
    """A non-finite sample (a sensor fault) is recorded as null and read back as NaN."""
    q = np.arange(7.0)
    q_bad = q.copy()
    q_bad[[1, 4]] = [np.nan, np.inf]
    with SessionRecorder(tmp_path / "nan.mcap", robot) as recorder:
        recorder.record(0.0, q, q, q, q, q, "active", "teaching")
        recorder.record(DT, q_bad, q, q, q, q, "active", "fault")
    recording = read_recording(tmp_path / "nan.mcap")
    np.testing.assert_array_equal(recording.q[0], q)
    assert np.flatnonzero(np.isnan(recording.q[1])).tolist() == [1, 4]


def test_wrong_shape_is_rejected(robot, tmp_path):
    """An array of the wrong length raises InputShapeError naming it."""
    with SessionRecorder(tmp_path / "shape.mcap", robot) as recorder:
        q = np.zeros(7)
        with pytest.raises(InputShapeError, match="tau_ext_std"):
            recorder.record(0.0, q, q, q, q, np.zeros(6), "active", "teaching")


def test_part_file_holds_all_but_the_last_flush_period(robot, tmp_path):
    """While recording, the .part file on disk always holds the session but its last 0.1 s."""
    path = tmp_path / "live.mcap"
    with SessionRecorder(path, robot, flush_period=0.1) as recorder:
        assert read_recording(recorder.part_path).t.size == 0  # metadata is there at once
        for k in range(200):
            q = np.full(7, k * DT)
            recorder.record(k * DT, q, q, q, q, q, "active", "teaching")
            recovered = read_recording(recorder.part_path)
            assert not recovered.complete
            assert recovered.robot.name == robot.name
            last = recovered.t[-1] if recovered.t.size else -DT
            assert last > k * DT - 0.1 - 1e-9
    assert read_recording(path).t.size == 200


def test_unfinished_recording_is_never_overwritten(robot, tmp_path):
    """Opening a recorder whose .part exists (a crashed session) raises RecordingError."""
    path = tmp_path / "crashed.mcap"
    path.with_name("crashed.mcap.part").write_bytes(b"precious")
    with pytest.raises(RecordingError, match="unfinished recording"):
        SessionRecorder(path, robot)
    assert path.with_name("crashed.mcap.part").read_bytes() == b"precious"


def run_child_until(path: Path, t_stop: float, signal_number: int) -> tuple[float, int]:
    """Run CHILD, signal it once it reported ``t_stop``; its last reported t, its exit code."""
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(path), str(DT)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(child.stdout), daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + 120.0
        while not (lines and float(lines[-1]) >= t_stop):
            assert child.poll() is None, child.stderr.read()
            assert time.monotonic() < deadline, "the child did not record in time"
            time.sleep(0.01)
        os.kill(child.pid, signal_number)
        code = child.wait(timeout=30)
    finally:  # a child the signal did not stop must not record on after the test
        if child.poll() is None:
            child.kill()
            child.wait()
    reader.join(timeout=10)
    child.stderr.close()
    complete = [line for line in lines if line.endswith("\n")]
    return float(complete[-1]), code


def assert_synthetic_prefix(recording, n_samples: int) -> None:
    """The recording is the child's first ``n_samples`` periods, exactly."""
    assert recording.t.size == n_samples
    np.testing.assert_array_equal(recording.t, np.arange(n_samples) * DT)
    q = np.sin(recording.t[:, None] + np.arange(7))
    for factor, name in enumerate(ARRAYS, start=1):
        np.testing.assert_array_equal(getattr(recording, name), factor * q)


def test_sigkill_loses_at_most_the_flush_period(tmp_path):
    """A recorder killed (SIGKILL) mid-session leaves a .part holding all but its last 0.1 s."""
    path = tmp_path / "killed.mcap"
    reported, code = run_child_until(path, 1.0, signal.SIGKILL)
    assert code == -signal.SIGKILL
    assert not path.exists()
    recovered = read_recording(path.with_name("killed.mcap.part"))
    assert not recovered.complete
    assert recovered.robot.name == lt.robots.yumi().name
    assert recovered.parameters == {"dt": DT}
    assert recovered.t[-1] >= reported - 0.1 - DT
    assert_synthetic_prefix(recovered, recovered.t.size)


def test_sigint_finalises_the_file(tmp_path):
    """Ctrl-C (SIGINT) in a recording process leaves a finished file with every sample."""
    path = tmp_path / "interrupted.mcap"
    reported, code = run_child_until(path, 0.5, signal.SIGINT)
    assert code != 0
    assert not path.with_name("interrupted.mcap.part").exists()
    recording = read_recording(path)
    assert recording.complete
    assert recording.t[-1] >= reported
    assert_synthetic_prefix(recording, recording.t.size)


def test_keyboard_interrupt_inside_with_finalises(robot, tmp_path):
    """A KeyboardInterrupt inside ``with SessionRecorder`` still leaves a finished file."""
    path = tmp_path / "ctrl_c.mcap"
    with pytest.raises(KeyboardInterrupt), SessionRecorder(path, robot) as recorder:
        for k in range(10):
            q = np.zeros(7)
            recorder.record(k * DT, q, q, q, q, q, "active", "teaching")
        recorder.event(9 * DT, "session", "operator pressed Ctrl-C")
        raise KeyboardInterrupt
    recording = read_recording(path)
    assert recording.complete
    assert recording.t.size == 10
    assert recording.events == [SessionEvent(9 * DT, "session", "operator pressed Ctrl-C")]


def test_truncated_file_recovers_a_prefix(session, tmp_path):
    """A finished file cut at 60 % of its bytes reads back as a prefix, complete=False."""
    path, data = session
    content = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(content[: int(0.6 * len(content))])
    recovered = read_recording(cut)
    assert not recovered.complete
    n = recovered.t.size
    assert 0.3 * data["t"].size < n < data["t"].size
    np.testing.assert_array_equal(recovered.t, data["t"][:n])
    np.testing.assert_array_equal(recovered.tau_ext_hat, data["tau_ext_hat"][:n])
    assert recovered.mode == data["mode"][:n]
    assert recovered.parameters == data["parameters"]


def _first_chunk_fields(content: bytes) -> dict[str, int]:
    """Byte offsets of the first chunk's length fields (MCAP: opcode u8, length u64, …)."""
    offset = 8  # the magic
    while content[offset] != 0x06:  # a Chunk record
        offset += 9 + struct.unpack_from("<Q", content, offset + 1)[0]
    body = offset + 9  # start time u64, end time u64, uncompressed size u64, crc u32
    name_length = body + 28
    records_length = name_length + 4 + struct.unpack_from("<I", content, name_length)[0]
    return {
        "record length": offset + 1,
        "uncompressed size": body + 16,
        "compression name length": name_length,
        "records length": records_length,
    }


@pytest.mark.parametrize(
    "field", ["record length", "uncompressed size", "compression name length", "records length"]
)
def test_a_flipped_length_recovers_what_comes_before(session, tmp_path, field):
    """One bit flipped high in a chunk's length field: what reads is a prefix, no traceback.

    Before, a huge declared length came out of ``replay`` and ``inspect`` as a MemoryError
    (the records' length here) or an OverflowError traceback (31 of 496 single-bit flips of
    one chunk's header, a review). A flipped uncompressed size harms nothing: the data's
    CRC still holds.
    """
    path, data = session
    content = bytearray(path.read_bytes())
    at = _first_chunk_fields(bytes(content))[field]
    content[at + (3 if field == "compression name length" else 6)] ^= 0x80
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(content))
    recovered = read_recording(damaged)
    n = recovered.t.size
    np.testing.assert_array_equal(recovered.q, data["q"][:n])
    assert recovered.complete is (n == data["t"].size)
    assert recovered.complete is (field == "uncompressed size")


def test_a_flipped_bit_in_the_robot_is_refused(session, tmp_path):
    """The session metadata carry their checksum: a robot changed by one bit is refused.

    MCAP's chunk CRCs guard the samples only: a UR10e's upper arm read 16.93 kg instead of
    12.93 from a recording read as complete, and replay and inspect ran on it.
    """
    path, _ = session
    content = path.read_bytes()
    at = content.index(b"mass = ") + len(b"mass = ")
    damaged = tmp_path / "robot.mcap"
    damaged.write_bytes(content[:at] + bytes([content[at] ^ 0x04]) + content[at + 1 :])
    with pytest.raises(RecordingError, match=r"session metadata .* do not match their checksum"):
        read_recording(damaged)


@pytest.mark.parametrize(
    "content",
    [b"", b"name = 'not a recording'\n", np.random.default_rng(3).bytes(5000)],
    ids=["empty", "text", "random"],
)
def test_not_mcap_raises_one_line_error(tmp_path, content):
    """A file that is not MCAP raises a one-line RecordingError naming the file."""
    path = tmp_path / "garbage.mcap"
    path.write_bytes(content)
    with pytest.raises(RecordingError) as error:
        read_recording(path)
    message = str(error.value)
    assert "\n" not in message
    assert str(path) in message
    assert "not an MCAP file" in message


def test_missing_file_raises_recording_error(tmp_path):
    """A missing file raises a RecordingError naming it."""
    with pytest.raises(RecordingError, match=r"missing\.mcap: cannot read"):
        read_recording(tmp_path / "missing.mcap")


def test_the_enabling_device_reads_back_and_is_absent_without_one(robot, tmp_path):
    """Held / released per period as the sample gave it; None where no device was read."""
    path = tmp_path / "device.mcap"
    n, states = robot.n_joints, [True, False, None]
    with SessionRecorder(path, robot, {}) as recorder:
        for k, enabling in enumerate(states):
            zeros = np.zeros(n)
            recorder.record(0.004 * k, zeros, zeros, zeros, zeros, zeros, "active", "teaching",
                            enabling=enabling)  # fmt: skip
    assert read_recording(path).enabling == states


def test_a_full_disk_at_the_end_names_the_recording(robot, tmp_path):
    """The summary cannot be written (a full disk): a RecordingError naming the .part file.

    Before, the file's own close, failing alike in the ``finally``, raised a bare
    ``OSError: [Errno 27] File too large`` over it, naming nothing.
    """
    recorder = SessionRecorder(tmp_path / "full.mcap", robot, {"dt": 0.004})
    q = robot.home()
    recorder.record(0.0, q, 0 * q, 0 * q, 0 * q, 0 * q, "active", "teaching")

    class Full:
        """The recorder's file on a disk that is full: flush and close fail."""

        def __init__(self, file) -> None:
            self.file = file

        def flush(self) -> None:
            raise OSError(27, "File too large")

        def fileno(self) -> int:
            return self.file.fileno()

        def close(self) -> None:
            self.file.close()
            raise OSError(27, "File too large")

    recorder._file = Full(recorder._file)
    with pytest.raises(RecordingError, match=r"full\.mcap\.part: cannot write: File too large"):
        recorder.close()
