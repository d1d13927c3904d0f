"""`Recorder`: the bus observer that writes a session to an aeroexec MCAP file.

    recorder = Recorder("flight.mcap", drone="drone1", metadata={...},
                        attachments={"catalog.yaml": text, "mission.py": script},
                        records={"behaviors": {...}})
    executive = Executive(catalog, library=..., observers=[recorder])
    ...
    recorder.close()            # or: with Recorder(...) as recorder: ...

The file (see docs/recording.md): profile `aeroexec`, JSON messages with one JSON Schema
per channel, channels `/<drone>/<service>` (one per service, the completed call) and
`/<drone>/<topic>` (behavior_event, list_of_active_behaviors, list_of_active_capabilities,
process_state, beliefs, mission/command, vehicle/state, log as `foxglove.Log`) plus what
Foxglove's panels need (foxglove.py `PanelFeed`): `vehicle/transform`
(`foxglove.FrameTransform`, with each vehicle/state whose pose changed), `scene/static` and
`scene` (`foxglove.SceneUpdate`: the world's still entities; the vehicle's body and the
moving object), `call_log` (`foxglove.Log`, one line per top-level call) and
`capability_state` (each capability's reference count when it changes). Given the
vehicle's `start_pose`, the scene and the first transform are written at the session's
first log time, before its first message.
Channels are created when first used, so their ids follow first-use order. Log time and
publish time are the record's clock time; the MCAP sequence number counts messages from 0.

**Deterministic.** Nothing depends on the wall clock, the host or chance: attachments
carry log/create time 0, the header names only the aeroexec and mcap-python versions, chunks
are cut at the flush bound (a function of the message stream only) and compressed with
LZ4 frames (no timestamps or random ids; same input, same bytes; and some 8x cheaper than
zstd on the small chunks the flush bound makes). Same inputs, same file, byte for byte.

**Crash-safe.** FLUSH BOUND: after a message is written, the current chunk is closed and
handed to the operating system when it holds `flush_messages` (default 100) messages or
`flush_bytes` (default 4 MiB) of message data, whichever comes first; a live session
(`fly`, whose log time is the wall clock) also gives `flush_interval_ns` (0.5 s), and
then a chunk is closed as soon as its messages span that much log time. A process killed
with SIGKILL therefore loses at most the last 99 messages (and, live, never a message
older than 0.5 s of wall-clock time before the last one written); everything before is in
complete chunks that `aeroexec recover` (or the reader) reads from a file with no footer.
A simulated session has no time bound: 0.5 s of simulated time passes in well under a
millisecond, so it protects nothing, and a deterministic run that a crash cut short can
be made again exactly. The header, the metadata and the attachments are on disk before
the first message. `close()` (also at normal interpreter exit, if the owner forgot)
flushes and writes the summary and footer. The data reaches the kernel, not necessarily
the disk: a power cut is not covered (no fsync per chunk).

**Encoded once, handed over in bursts.** Each message is encoded once, straight from the
bus record, and kept as the very arguments of mcap's `Writer.add_message` until the
flush bound closes the chunk; then the chunk's messages go to the writer in one tight
loop and the chunk is flushed. A message is on disk no sooner and no later than if it
had been handed over at once (a chunk becomes durable only when it is closed), the
writer sees the same calls in the same order (a new channel first hands over what came
before it), so the file is the same, byte for byte; but mcap's per-message work runs
hot in cache instead of between the executive's, about a third cheaper.
"""

from __future__ import annotations

import atexit
import contextlib
import json
import math
import os
import stat
from collections.abc import Callable, Mapping
from dataclasses import asdict, is_dataclass
from enum import Enum
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, NoReturn

import orjson
from mcap.writer import CompressionType, Writer
from mcap.writer import __version__ as MCAP_VERSION

from aeroexec import __version__, interrupts
from aeroexec.errors import Mark, OutputLost, RecordingError
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.recording.foxglove import PanelFeed, Pose
from aeroexec.recording.schemas import (
    LOG_LEVELS,
    MESSAGE_ENCODING,
    PROFILE,
    SCHEMA_ENCODING,
    SERVICE_CALL,
    schema_for,
    schema_name_for_topic,
)
from aeroexec.recording.tap import RecordTap, reading_of

if TYPE_CHECKING:
    from aeroexec.vehicles.world import World

# A signal's watchdog never raises inside this module (or the mcap writer it calls):
# a record is written whole or not at all.
interrupts.critical_file(__file__)

#: Flush bound, in messages (see the module docstring).
FLUSH_MESSAGES = 100
#: Flush bound, in bytes of message data (mcap's own chunk size, see the module docstring).
FLUSH_BYTES = 4 * 1024 * 1024
#: Flush bound of a live session, in log-time (there: wall-clock) nanoseconds.
FLUSH_INTERVAL_NS = 500_000_000
#: The metadata record's name.
METADATA_NAME = "aeroexec"
#: The metadata record written when a session ends (`Recorder.end_session`).
END_METADATA_NAME = "aeroexec_end"
LIBRARY = f"aeroexec/{__version__} mcap-python/{MCAP_VERSION}"

_COMPRESSIONS = {
    "zstd": CompressionType.ZSTD,
    "lz4": CompressionType.LZ4,
    "none": CompressionType.NONE,
}
_MEDIA_TYPES = {
    ".yaml": "application/yaml",
    ".yml": "application/yaml",
    ".py": "text/x-python",
    ".json": "application/json",
    ".txt": "text/plain",
}
_NS = 1_000_000_000


def _default(value: Any) -> Any:
    """JSON fallback for values the core may put in a payload."""
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, (set, frozenset)):
        return sorted(value, key=repr)
    if is_dataclass(value) and not isinstance(value, type):
        return asdict(value)
    if isinstance(value, bytes):
        return value.hex()
    return str(value)


def _plain(value: Any) -> Any:
    """A JSON-safe copy: string keys, non-finite floats as null (JSON has no NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (str, int, bool)) or value is None:
        return value
    return _plain(_default(value))


def _make_encoder() -> Callable[[Any], str]:
    """Compact, ASCII, NaN-refusing JSON with the standard library (the fallback of
    `encode_json`). The C encoder is built once: `json.dumps` rebuilds it on every call,
    which is most of its cost for small messages."""
    slow = json.JSONEncoder(separators=(",", ":"), allow_nan=False, default=_default).encode
    make = getattr(json.encoder, "c_make_encoder", None)
    if make is None:
        return slow
    try:
        chunks = make(
            None,
            _default,
            json.encoder.encode_basestring_ascii,
            None,
            ":",
            ",",
            False,
            False,
            False,
        )

        def fast(value: Any) -> str:
            return "".join(chunks(value, 0))

        sample = {"a": [1, 2.5, None, True, "é"], "b": {"c": ""}}
        if fast(sample) != slow(sample):
            return slow
    except Exception:
        return slow
    return fast


_ENCODE = _make_encoder()
_ORJSON = orjson.dumps
_ORJSON_ERROR = orjson.JSONEncodeError


def encode_json(value: Any) -> bytes:
    """Compact UTF-8 JSON bytes, once per message; never NaN/Infinity (invalid JSON:
    written as null).

    orjson writes it (a tenth of the standard library's time per message; its output is
    a pure function of the value, so recordings stay byte-identical). What orjson
    refuses (integers beyond 64 bits, non-string keys, nesting deeper than 254) goes
    through the standard library as before."""
    try:
        return _ORJSON(value, default=_default)
    except _ORJSON_ERROR:
        pass
    try:
        return _ENCODE(value).encode()
    except (ValueError, TypeError, RecursionError):
        try:
            return _ENCODE(_plain(value)).encode()
        except RecursionError:
            return _ENCODE({"unencodable": repr(value)[:1000]}).encode()


def _stamp(log_time_ns: int) -> dict[str, int]:
    sec, nsec = divmod(max(log_time_ns, 0), _NS)
    return {"sec": sec, "nsec": nsec}


def log_message(data: Mapping[str, Any], log_time_ns: int) -> dict[str, Any]:
    """The executive's `log` payload as a `foxglove.Log` message."""
    level = data.get("level", "INFO")
    if not isinstance(level, int):
        level = LOG_LEVELS.get(str(level).upper(), 0)
    line = data.get("line", 0)
    return {
        "timestamp": _stamp(log_time_ns),
        "level": level,
        "message": str(data.get("message", "")),
        "name": str(data.get("name", "")),
        "file": str(data.get("file", "")),
        "line": line if isinstance(line, int) and line >= 0 else 0,
    }


def call_message(record: ServiceCallRecord) -> dict[str, Any]:
    """A completed call as recorded: `parent_seq` only for a call made inside another."""
    data = {
        "seq": record.seq,
        "caller": record.caller,
        "service": record.service,
        "request": record.request,
        "response": record.response,
    }
    if record.parent_seq is not None:
        data["parent_seq"] = record.parent_seq
    return data


def without_nulls(data: Mapping[str, Any]) -> dict[str, Any]:
    """The payload without its absent (None) fields: the schemas leave such keys out."""
    return {k: v for k, v in data.items() if v is not None}


def _media_type(name: str) -> str:
    return _MEDIA_TYPES.get(Path(name).suffix.lower(), "application/octet-stream")


class Recorder:
    """A `BusObserver` writing the aeroexec MCAP profile (see the module docstring for
    the channels, determinism and the flush bound: 100 messages or 4 MiB; live sessions
    also give `flush_interval_ns`, 0.5 s of wall-clock log time).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        drone: str = "drone1",
        metadata: Mapping[str, object] | None = None,
        attachments: Mapping[str, str | bytes] | None = None,
        *,
        records: Mapping[str, Mapping[str, str]] | None = None,
        flush_messages: int = FLUSH_MESSAGES,
        flush_bytes: int = FLUSH_BYTES,
        flush_interval_ns: int | None = None,
        compression: str = "lz4",
        world: World | None = None,
        start_pose: Pose | None = None,
        tap: RecordTap | None = None,
    ) -> None:
        if flush_messages < 1 or flush_bytes < 1 or (flush_interval_ns or 0) < 0:
            raise ValueError("flush bounds must be positive")
        if compression not in _COMPRESSIONS:
            raise ValueError(f"compression must be one of {sorted(_COMPRESSIONS)}")
        self.path = Path(path)
        self.drone = drone.strip("/")
        self._prefix = f"/{self.drone}/"
        self.flush_messages = flush_messages
        self.flush_bytes = flush_bytes
        self.flush_interval_ns = flush_interval_ns
        try:
            # `-o out/flight.mcap` should just work, as an output path does in make.
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._stream: IO[bytes] = open(self.path, "wb")  # noqa: SIM115 (closed by close())
        except OSError as exc:
            raise RecordingError(f"cannot write: {exc.strerror or exc}", Mark(str(path))) from None
        #: What is safely in the file: the offset after the last flush, and the messages
        #: and clock time up to it. A failed write truncates the file back to it.
        self._lost = False
        self._good_offset = 0
        self._good_messages = 0
        self._good_until_ns: int | None = None
        self._last_ns: int | None = None
        self._writer = Writer(
            self._stream,
            chunk_size=FLUSH_BYTES,
            compression=_COMPRESSIONS[compression],
        )
        self._add = self._writer.add_message
        #: The messages of the chunk in progress, as `add_message`'s arguments
        #: (channel, log time, data, publish time, sequence), not yet handed to the writer.
        self._pending: list[tuple[int, int, bytes, int, int]] = []
        self._keep = self._pending.append
        #: Until the flush bound closes the chunk (a new channel hands the pending
        #: messages over earlier, but closes nothing): how many more messages, how many
        #: more bytes; and the log time of the first message since the last flush.
        self._room = flush_messages
        self._room_bytes = flush_bytes
        self._unflushed_since: int | None = None
        self._schemas: dict[str, int] = {}
        #: service -> channel id, topic (inside the namespace) -> channel id
        self._services: dict[str, int] = {}
        self._topics: dict[str, int] = {}
        #: The messages for Foxglove's panels. With the start pose known, their start
        #: comes before the session's first message; without, with the first state.
        self._panels = PanelFeed(self.drone, self._derived, world, start_pose)
        #: What the panels derive from, by topic.
        self._panel_inputs: dict[str, Callable[[Mapping[str, Any], int], None]] = {
            "vehicle/state": self._panels.vehicle_state,
            "list_of_active_capabilities": self._panels.capabilities,
        }
        #: topic -> (channel, what the panels derive from it): the topics written as
        #: published (not `log` or `mission/command`), once their channel exists.
        self._routes: dict[str, tuple[int, Callable[[Mapping[str, Any], int], None] | None]] = {}
        self._await_start = start_pose is not None
        self._count = 0
        self._flushed = 0
        self._closed = False
        self._forget_finisher: Callable[[], None] = lambda: None
        #: Sees every channel and message as written (the live view): a tee, not a copy.
        self._tap = tap
        if tap is not None or flush_interval_ns is not None:
            # A live view or a time bound: the general path. A simulated session's
            # messages take the plain `_write`, which checks neither.
            self._write = self._write_watched  # type: ignore[method-assign]
        try:
            self._guard(
                self._start, dict(metadata or {}), dict(attachments or {}), dict(records or {})
            )
        except OutputLost as lost:
            raise lost.error from None  # nothing written yet: a plain "cannot write"
        except BaseException:
            self._closed = True
            self._stream.close()
            raise
        atexit.register(self.close)
        self._forget_finisher = interrupts.at_forced_exit(self._finish_abruptly)

    # -- BusObserver ---------------------------------------------------------------------
    def on_service_call(self, record: ServiceCallRecord) -> None:
        if self._await_start:
            self._begin_panels(record.log_time_ns)
        service = record.service
        channel = self._services.get(service)
        if channel is None:
            channel = self._services[service] = self._channel(self._prefix + service, SERVICE_CALL)
        data = call_message(record)
        log_time_ns = record.log_time_ns
        try:
            encoded = _ORJSON(data, default=_default)
        except _ORJSON_ERROR:
            encoded = encode_json(data)
        self._write(channel, log_time_ns, encoded)
        if record.parent_seq is None:
            self._panels.call(data, log_time_ns)

    def on_topic(self, record: TopicRecord) -> None:
        # Most of a session's messages take this path (vehicle states, beliefs): a topic
        # already seen, written as published, is encoded and written right here.
        topic = record.topic
        route = self._routes.get(topic)
        if route is None:
            self.write_topic(topic, record.data, record.log_time_ns)
            return
        channel, then = route
        data = record.data
        log_time_ns = record.log_time_ns
        try:
            encoded = _ORJSON(data, default=_default)
        except _ORJSON_ERROR:
            encoded = encode_json(data)
        self._write(channel, log_time_ns, encoded)
        if then is not None:
            then(data, log_time_ns)

    # -- public --------------------------------------------------------------------------
    def write_topic(self, topic: str, data: Mapping[str, Any], log_time_ns: int) -> None:
        """Record `data` on `/<drone>/<topic>` (what `on_topic` does for the bus)."""
        if self._await_start:
            self._begin_panels(log_time_ns)
        channel = self._topics.get(topic)
        if channel is None:
            channel = self._topics[topic] = self._channel(
                self._prefix + topic, schema_name_for_topic(topic)
            )
        if topic == "log":
            data = log_message(data, log_time_ns)
        elif topic == "mission/command":
            data = without_nulls(data)
        elif topic not in self._routes:
            self._routes[topic] = (channel, self._panel_inputs.get(topic))
        self._write(channel, log_time_ns, encode_json(data))
        if topic == "vehicle/state":
            self._panels.vehicle_state(data, log_time_ns)
        elif topic == "list_of_active_capabilities":
            self._panels.capabilities(data, log_time_ns)

    @property
    def messages_written(self) -> int:
        """Messages written so far (in the file once flushed)."""
        return self._count

    @property
    def messages_flushed(self) -> int:
        """Messages already handed to the operating system (survive a SIGKILL)."""
        return self._flushed

    @property
    def closed(self) -> bool:
        return self._closed

    def flush(self) -> None:
        """Close the current chunk and hand everything written so far to the OS."""
        self._check_open()
        self._guard(self._flush)
        self._flushed = self._count
        self._mark_good()

    def end_session(self, reason: str, detail: str = "", **facts: str) -> None:
        """Record why the session ended: the metadata record `aeroexec_end`
        (`reason`, `detail`, the clock time of the last message and any `facts`),
        written after every message so far. A file killed before its end has none."""
        self.flush()
        values = {
            "reason": reason,
            "detail": detail,
            "time_ns": str(self._last_ns or 0),
            **{k: str(v) for k, v in facts.items()},
        }
        self._guard(self._writer.add_metadata, END_METADATA_NAME, values)
        self._mark_good()

    def close(self) -> None:
        """Flush, write the summary and footer, close the file. Idempotent.

        On a write error (a full disk) the file is cut back to its last flush, which
        stays readable without a footer, and `OutputLost` says so."""
        if self._closed:
            return
        try:
            self._guard(self._finish)
        finally:
            self._closed = True
            atexit.unregister(self.close)
            self._forget_finisher()
            self._stream.close()
            self._flushed = self._count
            if self._tap is not None:
                self._tap.recording_closed()

    def finalized_note(self) -> str:
        """What a stopped command says about this (closed) recording."""
        return f"recording finalized: {self.path} ({self.messages_written} messages, complete)"

    def _finish_abruptly(self, reason: str, detail: str) -> str | None:
        """Before a forced exit (the user's code never let go of a signal): the end
        record and the footer, written from the signal handler — never while a record is
        being written (the handler waits until this module is left)."""
        if self._closed:
            return None
        self.end_session(reason, detail)
        self.close()
        return self.finalized_note()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- internals -----------------------------------------------------------------------
    def _derived(self, topic: str, log_time_ns: int, data: Mapping[str, Any]) -> None:
        """A message derived from what was recorded (not itself published on the bus)."""
        channel = self._topics.get(topic)
        if channel is None:
            channel = self._topics[topic] = self._channel(
                self._prefix + topic, schema_name_for_topic(topic)
            )
        try:
            encoded = _ORJSON(data, default=_default)
        except _ORJSON_ERROR:
            encoded = encode_json(data)
        self._write(channel, log_time_ns, encoded)

    def _begin_panels(self, log_time_ns: int) -> None:
        """The panels' start, at the session's first log time."""
        self._await_start = False
        self._panels.begin(log_time_ns)

    def _start(
        self,
        metadata: dict[str, object],
        attachments: dict[str, str | bytes],
        records: dict[str, Mapping[str, str]],
    ) -> None:
        self._writer.start(profile=PROFILE, library=LIBRARY)
        values = {str(k): str(v) for k, v in metadata.items()}
        values.setdefault("aeroexec_version", __version__)
        values.setdefault("drone", self.drone)
        self._writer.add_metadata(METADATA_NAME, values)
        # Further records (`behaviors`: which code implemented each behavior).
        for name, record in records.items():
            self._writer.add_metadata(name, {str(k): str(v) for k, v in record.items()})
        attached: dict[str, bytes] = {}
        for name, content in attachments.items():
            data = attached[name] = content.encode() if isinstance(content, str) else bytes(content)
            self._writer.add_attachment(
                create_time=0, log_time=0, name=name, media_type=_media_type(name), data=data
            )
        self._stream.flush()
        if self._tap is not None:
            self._tap.recording_started(values, attached)
        self._mark_good()

    def _channel(self, topic: str, schema_name: str) -> int:
        if self._lost:
            return 0
        self._check_open()
        # The channel record goes where it always went: after the messages before it.
        self._guard(self._hand_over)
        schema = self._schemas.get(schema_name)
        if schema is None:
            definition = schema_for(schema_name)
            schema = self._writer.register_schema(
                name=definition.name, encoding=SCHEMA_ENCODING, data=definition.data
            )
            self._schemas[schema_name] = schema
        channel = self._writer.register_channel(
            topic=topic, message_encoding=MESSAGE_ENCODING, schema_id=schema, metadata={}
        )
        if self._tap is not None:
            definition = schema_for(schema_name)
            self._tap.channel_added(
                reading_of(
                    channel,
                    topic,
                    definition.name,
                    SCHEMA_ENCODING,
                    definition.data,
                    MESSAGE_ENCODING,
                )
            )
        return channel

    def _write(self, channel: int, log_time_ns: int, data: bytes) -> None:
        # Every message of a simulated session comes here: kept as add_message's
        # arguments (the sequence is a uint32); the flush bound is counted down.
        if self._closed:
            if self._lost:
                return  # already reported (OutputLost); the session is unwinding
            self._check_open()
        count = self._count
        self._count = count + 1
        self._keep((channel, log_time_ns, data, log_time_ns, count & 0xFFFFFFFF))
        room = self._room - 1
        room_bytes = self._room_bytes - len(data)
        if room > 0 and room_bytes > 0:
            self._room = room
            self._room_bytes = room_bytes
            return
        self.flush()

    def _write_watched(self, channel: int, log_time_ns: int, data: bytes) -> None:
        """`_write` with a live view (`tap`) and the time bound of a live session."""
        if self._closed:
            if self._lost:
                return
            self._check_open()
        count = self._count
        self._count = count + 1
        self._keep((channel, log_time_ns, data, log_time_ns, count & 0xFFFFFFFF))
        if self._tap is not None:  # a live viewer sees it now, not at the next flush
            self._tap.message_written(channel, log_time_ns, data)
        since = self._unflushed_since
        if since is None:
            self._unflushed_since = since = log_time_ns
        room = self._room - 1
        room_bytes = self._room_bytes - len(data)
        interval = self.flush_interval_ns
        if room > 0 and room_bytes > 0 and (interval is None or log_time_ns - since < interval):
            self._room = room
            self._room_bytes = room_bytes
            return
        self.flush()

    def _hand_over(self) -> None:
        """The pending messages to the writer (into its chunk in progress), in order."""
        pending = self._pending
        if not pending:
            return
        add = self._add
        for channel, log_time_ns, data, publish_ns, sequence in pending:
            add(channel, log_time_ns, data, publish_ns, sequence)
        self._last_ns = pending[-1][1]
        pending.clear()

    def _flush(self) -> None:
        self._hand_over()
        self._writer.flush()
        self._room = self.flush_messages
        self._room_bytes = self.flush_bytes
        self._unflushed_since = None

    def _finish(self) -> None:
        self._hand_over()
        self._writer.finish()
        self._stream.flush()  # here, where a full disk is caught, not in close()

    def _check_open(self) -> None:
        if self._closed:
            raise RecordingError("the recorder is closed", Mark(str(self.path)))

    def _guard(self, action: Callable[..., None], *args: Any) -> None:
        try:
            action(*args)
        except OSError as exc:
            self._lose(exc)

    def _mark_good(self) -> None:
        try:
            self._good_offset = self._stream.tell()
        except OSError:  # not seekable (a pipe): nothing to cut back to
            return
        self._good_messages = self._count
        self._good_until_ns = self._last_ns

    def _lose(self, exc: OSError) -> NoReturn:
        """A write failed: stop writing, keep what is safely on disk, say what."""
        self._lost = True
        if not self._closed:
            self._closed = True
            atexit.unregister(self.close)
            self._forget_finisher()
            if self._tap is not None:
                self._tap.recording_closed()
        with contextlib.suppress(OSError):  # flushing the buffer fails again: drop it
            self._stream.close()
        kept = self._salvage()
        raise OutputLost(
            RecordingError(f"cannot write: {exc.strerror or exc}; {kept}", Mark(str(self.path)))
        ) from None

    def _salvage(self) -> str:
        """Cut the file back to its last flush (or remove it if that holds no message)."""
        try:
            regular = stat.S_ISREG(os.stat(self.path).st_mode)
        except OSError:
            return "nothing was kept"
        if not regular:  # /dev/full, a pipe: nothing to keep or remove
            return "nothing was kept"
        if self._good_messages == 0:
            with contextlib.suppress(OSError):
                os.unlink(self.path)
            return "no message had been written: the partial file was removed"
        try:
            os.truncate(self.path, self._good_offset)
        except OSError as exc:
            return (
                f"the first {self._good_messages} messages are in the file, followed by "
                f"a partial chunk ({exc.strerror or exc} cutting it off); "
                "`aeroexec recover` reads up to it"
            )
        until = (self._good_until_ns or 0) / _NS
        return (
            f"kept the first {self._good_messages} messages (to {until:.1f} s), readable "
            "without a footer (`aeroexec recover` makes a complete copy)"
        )
