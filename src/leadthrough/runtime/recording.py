"""Recording of a teaching session: MCAP, written incrementally, finalised atomically (SPEC §8).

MCAP (https://mcap.dev; Foxglove opens it as is), JSON messages with JSON schemas:

- metadata ``session``: ``robot`` (TOML), ``parameters`` (JSON), ``version``, ``start_time``;
- ``/joint_state``, one message per control period: ``t`` [s], ``q`` [rad], ``qd`` [rad/s],
  ``tau``, ``tau_ext_hat``, ``tau_ext_std`` [Nm, arm side], ``mode``, ``state`` (a non-finite
  number is written ``null``, read back NaN), and when given the estimated tool wrench at
  the TCP, ``tool_wrench`` (force [N], torque [Nm], world axes) with its 6×6
  ``tool_wrench_covariance`` (row-major); log time = wall-clock start + ``t``;
- ``/event``: ``t`` [s], ``kind``, ``detail`` (supervisor and session events).

Crash safety: the recorder writes ``<path>.part``, metadata first (fsynced at open); the open
chunk is closed, flushed and fsynced as soon as it spans ``flush_period`` of session time, so a
crash or SIGKILL loses less than the last ``flush_period``. :meth:`SessionRecorder.close` writes
the summary and footer, then renames ``.part`` to ``path`` atomically. :func:`read_recording`
streams any file up to its first unreadable record (``complete=False`` if unfinished or
damaged; :attr:`Recording.recovery` then says how much was recovered, of how much when the
file's summary survived, and where reading stopped).
"""

from __future__ import annotations

import hashlib
import json
import os
import struct
import time
import tomllib
from contextlib import suppress
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from importlib.metadata import version
from pathlib import Path
from typing import Any, NamedTuple, Self

import numpy as np
import tomli_w
import zstandard
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Footer, Message, Metadata, Statistics
from mcap.stream_reader import StreamReader
from mcap.writer import MCAP0_MAGIC, CompressionType, Writer
from numpy.typing import ArrayLike

from leadthrough.errors import InputShapeError, LeadthroughError, ParameterError, RecordingError
from leadthrough.estimation.wrench import ToolWrench
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.robots.toml_format import robot_from_dict, robot_to_dict
from leadthrough.validation import real

#: Value of the ``format`` key of the session metadata.
FORMAT = "leadthrough.session/1"
_UNITS = {"q": "joint readings [rad]", "qd": "joint velocities [rad/s]",
          "tau": "measured torques, arm side [Nm]",
          "tau_ext_hat": "estimated external torques, arm side [Nm]",
          "tau_ext_std": "standard deviation of tau_ext_hat [Nm]"}  # fmt: skip
#: Arrays of a ``/joint_state`` message, in the order :meth:`SessionRecorder.record` takes them.
ARRAYS = tuple(_UNITS)
_NUMBERS = {"type": "array", "items": {"type": ["number", "null"]}}
_TIME = {"type": "number", "description": "session time [s]"}
_TEXT = {"type": "string"}


def _schema(title: str, **properties: dict[str, Any]) -> dict[str, Any]:
    return {"title": title, "type": "object", "properties": properties,
            "required": list(properties)}  # fmt: skip


JOINT_STATE_SCHEMA = _schema(
    "leadthrough.JointState",
    t=_TIME,
    **{name: _NUMBERS | {"description": unit} for name, unit in _UNITS.items()},
    mode=_TEXT | {"description": "lead-through mode"},
    state=_TEXT | {"description": "safety supervisor state"},
)
JOINT_STATE_SCHEMA["properties"] |= {  # optional: files written before have no wrench
    "tool_wrench": _NUMBERS | {"description": "tool wrench at the TCP, world axes [N, Nm]"},
    "tool_wrench_covariance": _NUMBERS
    | {"description": "its covariance, 6×6 row-major [N², N Nm, Nm²]"},
    "enabling": {"type": ["boolean", "null"],
                 "description": "the enabling device: held, released, or null without one"},
}  # fmt: skip
EVENT_SCHEMA = _schema("leadthrough.Event", t=_TIME, kind=_TEXT, detail=_TEXT)
#: What a damaged file can make the MCAP stream reader raise (the last two: a length field
#: flipped high, a huge read).
_READ_ERRORS = (McapError, ValueError, struct.error, zstandard.ZstdError, OverflowError,
                MemoryError)  # fmt: skip


class SessionEvent(NamedTuple):
    """One event of a session: at ``t`` [s], of ``kind`` (e.g. ``"fault"``), ``detail``."""

    t: float
    kind: str
    detail: str


class SessionRecorder:
    """Writes a teaching session to an MCAP file, crash-safe; a context manager.

    Example:
        >>> with SessionRecorder("session.mcap", robot, {"mode": "active"}) as recorder:
        ...     recorder.record(t, q, qd, tau, lt.tau_ext_hat, lt.std, lt.mode, lt.state)

    Leaving the ``with`` block, even by an exception or Ctrl-C, finalises the file.

    Args:
        path: Final file; data goes to ``<path>.part`` until :meth:`close`.
        robot: The robot being taught, stored in the file.
        parameters: Free-form session parameters, stored as JSON (numpy values become lists,
            other non-JSON values their ``str``).
        flush_period: Longest span of session time kept only in memory [s].

    Raises:
        RecordingError: ``<path>.part`` exists (an unfinished recording, never overwritten)
            or cannot be created.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        robot: RobotDescription,
        parameters: dict[str, Any] | None = None,
        flush_period: float = 0.1,
    ) -> None:
        self.path = Path(path)
        self.part_path = self.path.with_name(self.path.name + ".part")
        self.robot = robot
        self.flush_period = real("flush_period", flush_period, minimum=0.0, strict=True,
                                 error=ParameterError)  # fmt: skip
        metadata = _session_metadata(robot, parameters or {})
        try:
            self._file = open(self.part_path, "xb")  # noqa: SIM115 (closed by close())
        except FileExistsError:
            raise RecordingError(str(self.part_path), "exists: an unfinished recording; read "
                                 "it with read_recording() or remove it") from None  # fmt: skip
        except OSError as error:
            raise RecordingError(str(self.part_path), f"cannot create: {error.strerror}") from None
        self._start_ns = time.time_ns()
        self._writer = Writer(self._file, compression=CompressionType.ZSTD)
        self._writer.start(library=f"leadthrough/{metadata['version']}")
        self._writer.add_metadata("session", metadata)
        self._joint_state = self._channel("/joint_state", JOINT_STATE_SCHEMA)
        self._event = self._channel("/event", EVENT_SCHEMA)
        self._sync()
        self._unflushed_since: float | None = None
        self._sequence = 0
        self._closed = False

    def record(
        self,
        t: float,
        q: ArrayLike,
        qd: ArrayLike,
        tau: ArrayLike,
        tau_ext_hat: ArrayLike,
        tau_ext_std: ArrayLike,
        mode: str,
        state: str,
        tool_wrench: ToolWrench | None = None,
        enabling: bool | None = None,
    ) -> None:
        """Record one control period.

        Args:
            t: Session time [s].
            q: Joint readings [rad], shape (n,).
            qd: Joint velocities [rad/s], shape (n,).
            tau: Measured joint torques, arm side [Nm], shape (n,).
            tau_ext_hat: Estimated external torques, arm side [Nm], shape (n,).
            tau_ext_std: Standard deviation of ``tau_ext_hat`` [Nm], shape (n,).
            mode: Lead-through mode, e.g. ``"active"``.
            state: Safety supervisor state, e.g. ``"teaching"``.
            tool_wrench: Estimated wrench at the TCP with its covariance
                (``LeadThrough.tool_wrench``), if any.
            enabling: The sample's enabling device (``JointState.enabling``): True
                held, False released, None for an arm without one (not written).
        """
        values = (q, qd, tau, tau_ext_hat, tau_ext_std)
        fields: dict[str, Any] = {
            name: self._numbers(name, value) for name, value in zip(ARRAYS, values, strict=True)
        }
        if tool_wrench is not None:
            fields["tool_wrench"] = _finite_or_null(tool_wrench.vector)
            fields["tool_wrench_covariance"] = _finite_or_null(tool_wrench.covariance.ravel())
        if enabling is not None:
            fields["enabling"] = bool(enabling)
        self._write(self._joint_state, t, fields | {"mode": str(mode), "state": str(state)})

    def event(self, t: float, kind: str, detail: str) -> None:
        """Record an event at session time ``t`` [s], e.g. a supervisor's SafetyEvent."""
        self._write(self._event, t, {"kind": str(kind), "detail": str(detail)})

    def close(self) -> None:
        """Write the summary and footer, fsync, and rename ``.part`` to the final path."""
        if self._closed:
            return
        self._closed = True
        try:
            self._writer.finish()
            self._file.flush()
            os.fsync(self._file.fileno())
        except OSError as error:
            with suppress(OSError):  # its own flush fails alike (a full disk): a bare OSError
                self._file.close()  # of the close hid the error naming the recording
            raise RecordingError(str(self.part_path), f"cannot write: {error.strerror}") from None
        self._file.close()
        os.replace(self.part_path, self.path)
        _fsync_directory(self.path.parent)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def _channel(self, topic: str, schema: dict[str, Any]) -> int:
        data = json.dumps(schema).encode()
        schema_id = self._writer.register_schema(schema["title"], "jsonschema", data)
        return self._writer.register_channel(topic, "json", schema_id)

    def _numbers(self, name: str, value: ArrayLike) -> list[float | None]:
        array = np.asarray(value, dtype=float)
        if array.shape != (self.robot.n_joints,):
            raise InputShapeError(name, (self.robot.n_joints,), array.shape)
        return _finite_or_null(array)

    def _write(self, channel: int, t: float, fields: dict[str, Any]) -> None:
        if self._closed:
            raise RecordingError(str(self.path), "the recorder is closed")
        t = real("t", t, error=ParameterError)
        log_time = max(0, self._start_ns + round(t * 1e9))
        data = json.dumps({"t": t} | fields, allow_nan=False).encode()
        self._writer.add_message(channel, log_time, data, log_time, self._sequence)
        self._sequence += 1
        if self._unflushed_since is None:
            self._unflushed_since = t
        if t - self._unflushed_since >= self.flush_period - 1e-9:
            self._sync()
            self._unflushed_since = None

    def _sync(self) -> None:  # close the open chunk, put everything written on disk
        try:
            self._writer.flush()
            os.fsync(self._file.fileno())
        except OSError as error:
            raise RecordingError(str(self.part_path), f"cannot write: {error.strerror}") from None


@dataclass(frozen=True, eq=False)
class Recording:
    """A teaching session read back; arrays are read-only, one row per control period.

    Attributes:
        t: Session time [s], shape (N,).
        q: Joint readings [rad], shape (N, n).
        qd: Joint velocities [rad/s], shape (N, n).
        tau: Measured joint torques, arm side [Nm], shape (N, n).
        tau_ext_hat: Estimated external torques, arm side [Nm], shape (N, n).
        tau_ext_std: Standard deviation of ``tau_ext_hat`` [Nm], shape (N, n).
        mode: Lead-through mode of each period.
        state: Safety supervisor state of each period.
        events: Events in the order recorded.
        robot: The robot description stored in the file.
        parameters: The session parameters.
        version: leadthrough version that wrote the file.
        start_time: Wall-clock start of the session, ISO 8601.
        complete: False if recovered from an unfinished, truncated or damaged file.
        tool_wrench: Estimated tool wrench at the TCP, world axes [N, Nm], shape (N, 6);
            NaN where not recorded.
        tool_wrench_covariance: Its covariance [N², N Nm, Nm²], shape (N, 6, 6); NaN where
            not recorded.
        recovery: Empty if complete; else one line saying how much was recovered (of how
            much, when the file's summary survived) and where the file stops being readable.
        enabling: The enabling device of each period: True held, False released, None
            for an arm without one (and in files written before it was recorded).
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    tau: FloatArray
    tau_ext_hat: FloatArray
    tau_ext_std: FloatArray
    mode: list[str]
    state: list[str]
    events: list[SessionEvent]
    robot: RobotDescription
    parameters: dict[str, Any]
    version: str
    start_time: str
    complete: bool
    recovery: str = ""
    tool_wrench: FloatArray = field(default_factory=lambda: np.zeros((0, 6)))
    tool_wrench_covariance: FloatArray = field(default_factory=lambda: np.zeros((0, 6, 6)))
    enabling: list[bool | None] = field(default_factory=list)


def read_recording(path: str | os.PathLike[str]) -> Recording:
    """Read a session recording, finished or not (a ``.part`` or truncated file).

    Raises:
        RecordingError: The file cannot be read, is not MCAP, or holds no readable session
            metadata; the message names the file.
    """
    path = Path(path)
    try:
        with open(path, "rb") as stream:
            if stream.read(len(MCAP0_MAGIC)) != MCAP0_MAGIC:
                raise RecordingError(str(path), "not an MCAP file (no MCAP magic bytes)")
            stream.seek(0)
            records, complete, readable = _read_records(stream)
            size = stream.seek(0, os.SEEK_END)
            expected = None if complete else _summary_statistics(stream)
    except OSError as error:
        raise RecordingError(str(path), f"cannot read: {error.strerror}") from None
    try:
        recording = _assemble(records, complete)
    except (LeadthroughError, ValueError, TypeError, KeyError) as error:
        message = " ".join(str(error).split())
        raise RecordingError(str(path), f"not a readable leadthrough session: {message}") from None
    if complete:
        return recording
    return replace(recording, recovery=_recovery(recording, records, readable, size, expected))


def _read_records(stream: Any) -> tuple[list[Any], bool, int]:
    """Records readable from the start; whether the footer was reached; bytes read cleanly."""
    size = stream.seek(0, os.SEEK_END)
    stream.seek(0)  # no record is longer than the file: a longer one is a damaged length
    reader = StreamReader(stream, validate_crcs=True, record_size_limit=min(size, 1 << 28))
    records: list[Any] = []
    readable = 0
    try:
        for record in reader.records:
            records.append(record)
            readable = stream.tell()
    except _READ_ERRORS:
        return records, False, readable
    return records, any(isinstance(record, Footer) for record in records), readable


def _summary_statistics(stream: Any) -> Statistics | None:
    """The statistics of a damaged file's summary section, if it survived (else None)."""
    try:
        stream.seek(0)
        summary = make_reader(stream).get_summary()
    except (*_READ_ERRORS, OSError, EOFError):
        return None
    return None if summary is None else summary.statistics


def _recovery(recording: Recording, records: list[Any], readable: int, size: int,
              statistics: Statistics | None) -> str:  # fmt: skip
    """One line: how much of a damaged or unfinished recording was recovered, and why."""
    periods = len(recording.t)
    seconds = float(recording.t[-1] - recording.t[0]) if periods > 1 else 0.0
    channel = next((r.id for r in records if isinstance(r, Channel)
                    and r.topic == "/joint_state"), -1)  # fmt: skip
    total = 0 if statistics is None else statistics.channel_message_counts.get(channel, 0)
    if statistics is None or total <= periods:
        return (f"recovered {seconds:.1f} s ({periods} periods): the file ends at byte {size}"
                " without its summary (an unfinished or cut recording; how much is missing is "
                "unknown)")  # fmt: skip
    # the joint states' span: the summary's message times include the events too (one at
    # t = 0 before a calibration that is not recorded), so count periods at the median rate
    span = float(np.median(np.diff(recording.t))) * (total - 1) if periods > 1 else float("nan")
    return (f"recovered {seconds:.1f} s of {span:.1f} s ({periods} of {total} periods): the "
            f"file is damaged from byte {readable} of {size}")  # fmt: skip


def _assemble(records: list[Any], complete: bool) -> Recording:
    metadata = next((r.metadata for r in records if isinstance(r, Metadata)
                     and r.name == "session"), None)  # fmt: skip
    if metadata is None or metadata.get("format") != FORMAT:
        raise ValueError(f"no '{FORMAT}' session metadata")
    if "checksum" in metadata and metadata["checksum"] != _checksum(metadata):  # older: none
        raise ValueError("its session metadata (the robot, the parameters) do not match "
                         "their checksum: damaged")  # fmt: skip
    robot = robot_from_dict(tomllib.loads(metadata["robot"]))
    topics = {r.id: r.topic for r in records if isinstance(r, Channel)}
    states, events = [], []
    for record in records:
        if isinstance(record, Message):
            topic = topics.get(record.channel_id)
            if topic == "/joint_state":
                states.append(json.loads(record.data))
            elif topic == "/event":
                event = json.loads(record.data)
                events.append(SessionEvent(float(event["t"]), event["kind"], event["detail"]))
    q, qd, tau, tau_ext_hat, tau_ext_std = (
        _frozen([s[name] for s in states], (len(states), robot.n_joints)) for name in ARRAYS
    )
    return Recording(
        t=_frozen([s["t"] for s in states], (len(states),)),
        q=q,
        qd=qd,
        tau=tau,
        tau_ext_hat=tau_ext_hat,
        tau_ext_std=tau_ext_std,
        mode=[s["mode"] for s in states],
        state=[s["state"] for s in states],
        events=events,
        robot=robot,
        parameters=json.loads(metadata["parameters"]),
        version=metadata["version"],
        start_time=metadata["start_time"],
        complete=complete,
        tool_wrench=_frozen([s.get("tool_wrench", [None] * 6) for s in states], (len(states), 6)),
        tool_wrench_covariance=_frozen(
            [s.get("tool_wrench_covariance", [None] * 36) for s in states], (len(states), 6, 6)
        ),
        enabling=[s.get("enabling") for s in states],
    )


def _finite_or_null(array: FloatArray) -> list[float | None]:
    """The numbers of ``array`` as JSON: a non-finite one is ``null``."""
    if np.isfinite(array).all():
        return array.tolist()  # type: ignore[no-any-return]
    return [x if np.isfinite(x) else None for x in array.tolist()]


def _frozen(rows: list[Any], shape: tuple[int, ...]) -> FloatArray:
    array = np.array(rows, dtype=float).reshape(shape)  # null → NaN
    array.setflags(write=False)
    return array


def _session_metadata(robot: RobotDescription, parameters: dict[str, Any]) -> dict[str, str]:
    metadata = {
        "format": FORMAT,
        "robot": tomli_w.dumps(robot_to_dict(robot)),
        "parameters": json.dumps(parameters, default=_jsonable),
        "version": version("leadthrough"),  # the package root is above the core
        "start_time": datetime.now(UTC).isoformat(timespec="milliseconds"),
    }
    return metadata | {"checksum": _checksum(metadata)}


def _checksum(metadata: dict[str, str]) -> str:
    """SHA-256 of the session metadata but its checksum (keys sorted), hex.

    MCAP's chunk CRCs guard the samples, not the metadata record: one flipped bit made a
    UR10e's upper arm 16.93 kg instead of 12.93 in a recording read as complete.
    """
    entries = {key: value for key, value in metadata.items() if key != "checksum"}
    return hashlib.sha256(json.dumps(entries, sort_keys=True).encode()).hexdigest()


def _jsonable(value: object) -> object:
    """JSON stand-in of a non-JSON parameter value."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    return str(value)


def _fsync_directory(directory: Path) -> None:
    """Make a rename in ``directory`` durable (POSIX; skipped where directories cannot open)."""
    with suppress(OSError):
        descriptor = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(descriptor)
        finally:
            os.close(descriptor)
