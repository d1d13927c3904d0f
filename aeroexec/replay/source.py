"""Selective, streaming reading of a recording: only the channels replay needs.

Replay reads a few sparse channels (mission commands, behavior events, a handful of
service calls, process and capability changes) out of a stream dominated by
`vehicle/state`, `vehicle/pose` and `beliefs`. Decoding every chunk would cost more than
re-running the mission, so this reader walks the file record by record and uses the
message-index records the writer puts after each chunk to skip, without decompressing,
every chunk that holds none of the wanted channels (or of the channels not defined yet).
Chunks without message indexes (other writers) are always decoded.

Memory is flat in the file size: one chunk at a time, plus, for "last" channels (the
final `vehicle/state`), the compressed bytes of the latest chunk holding one. Damage
stops the walk at the first bad record, like `aeroexec.recording.scan`; `end` says why.
"""

from __future__ import annotations

import io
import os
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Attachment, Channel, Chunk, Message, Metadata
from mcap.stream_reader import breakup_chunk

from aeroexec.errors import Mark, RecordingError
from aeroexec.interrupts import check as check_interrupts
from aeroexec.recording.reader import Recording
from aeroexec.recording.schemas import MESSAGE_ENCODING

_PREFIX = struct.Struct("<BQ")
_CHUNK_TIMES = struct.Struct("<QQ")
_CHANNEL_ID = struct.Struct("<H")
_MAGIC_LENGTH = 8
_BUFFER = 1 << 18


def topic_name(topic: str) -> str:
    """`/drone1/mission/command` -> `mission/command` (the name inside the namespace)."""
    parts = topic.split("/", 2)
    if len(parts) == 3 and parts[0] == "":
        return parts[2]
    return topic.lstrip("/")


@dataclass(frozen=True, slots=True)
class SourceMessage:
    name: str
    log_time_ns: int
    data: bytes = field(repr=False)


@dataclass(frozen=True, slots=True)
class ScanSummary:
    """What a selective pass learned besides the messages it yielded."""

    metadata: dict[str, dict[str, str]]
    attachments: dict[str, bytes]
    first_ns: int | None
    last_ns: int | None
    complete: bool
    problem: str | None
    #: The last message of each "last" channel (name -> message).
    tail: dict[str, SourceMessage]
    notes: tuple[str, ...] = ()


class _Pending:
    __slots__ = ("body", "channels", "offset", "start_ns")

    def __init__(self, offset: int, body: bytes) -> None:
        self.offset = offset
        self.body = body
        self.start_ns: int = _CHUNK_TIMES.unpack_from(body)[0]
        self.channels: set[int] = set()


class RecordingSource:
    """A recording opened for selective passes. Construction reads only the header
    (`RecordingError` when the file is missing, empty or not MCAP)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        recording = Recording(path)
        self.path = recording.path
        self.name = recording.name
        self.profile = recording.profile
        self.library = recording.library
        self.summary: ScanSummary | None = None

    def scan(
        self,
        wanted: Callable[[str], bool],
        last: frozenset[str] = frozenset(),
        attachments: frozenset[str] = frozenset(),
        until_ns: int | None = None,
    ) -> Iterator[SourceMessage]:
        """Messages of the channels `wanted(name)` accepts, in file order (JSON channels
        only). When the generator is exhausted, `summary` holds metadata, the named
        attachments, the time span, the last message of each `last` channel (logged
        before `until_ns`, when given) and how the pass ended."""
        walk = _Walk(self, wanted, last, attachments, until_ns)
        yield from walk.run()
        self.summary = walk.summary()


class _Walk:
    def __init__(
        self,
        source: RecordingSource,
        wanted: Callable[[str], bool],
        last: frozenset[str],
        attachment_names: frozenset[str],
        until_ns: int | None,
    ) -> None:
        self.source = source
        self.until_ns = until_ns
        self.wanted = wanted
        self.last = last
        self.attachment_names = attachment_names
        self.names: dict[int, str] = {}
        self.wanted_ids: set[int] = set()
        self.foreign_ids: set[int] = set()
        self.last_ids: dict[int, str] = {}
        self.tail_chunks: dict[int, _Pending] = {}
        self.tail: dict[str, SourceMessage] = {}
        self.metadata: dict[str, dict[str, str]] = {}
        self.attachments: dict[str, bytes] = {}
        self.first: int | None = None
        self.last_ns: int | None = None
        self.complete = False
        self.problem: str | None = None
        self.foreign = 0
        self.undefined = 0

    def summary(self) -> ScanSummary:
        notes = []
        if self.foreign:
            notes.append(f"{self.foreign} wanted message(s) not JSON-encoded, skipped")
        if self.undefined:
            notes.append(f"{self.undefined} message(s) on channels the file never defines")
        return ScanSummary(
            self.metadata,
            self.attachments,
            self.first,
            self.last_ns,
            self.complete,
            self.problem,
            self.tail,
            tuple(notes),
        )

    # -- the walk --------------------------------------------------------------------------
    def run(self) -> Iterator[SourceMessage]:
        path = self.source.path
        size = path.stat().st_size
        try:
            stream = open(path, "rb", buffering=_BUFFER)  # noqa: SIM115 (closed below)
        except OSError as exc:
            raise RecordingError(f"cannot read: {exc.strerror or exc}", Mark(str(path))) from None
        with stream:
            yield from self._records(stream, size)
        self._finish_tail()

    def _records(self, stream: io.BufferedReader, size: int) -> Iterator[SourceMessage]:
        stream.seek(_MAGIC_LENGTH)
        offset = _MAGIC_LENGTH
        pending: _Pending | None = None
        while True:
            check_interrupts()
            prefix = stream.read(_PREFIX.size)
            if len(prefix) < _PREFIX.size:
                if pending is not None:
                    yield from self._chunk(pending)
                self._stop(
                    f"no footer: the file ends at byte {offset} (incomplete)"
                    if not prefix
                    else f"record cut short at byte {offset} (incomplete)"
                )
                return
            opcode, length = _PREFIX.unpack(prefix)
            body_start = offset + _PREFIX.size
            if length > size - body_start:
                if pending is not None:
                    yield from self._chunk(pending)
                self._stop(
                    f"record at byte {offset} is cut short: {length} bytes declared, "
                    f"{size - body_start} left (incomplete)"
                )
                return
            if opcode == Opcode.MESSAGE_INDEX and pending is not None:
                head = stream.read(_CHANNEL_ID.size)
                pending.channels.add(_CHANNEL_ID.unpack(head)[0])
                stream.seek(length - _CHANNEL_ID.size, io.SEEK_CUR)
                offset = body_start + length
                continue
            if pending is not None:
                yield from self._chunk(pending)
                pending = None
                if self.problem is not None:
                    return
            if opcode == Opcode.CHUNK:
                pending = _Pending(offset, stream.read(length))
                self._span(*_CHUNK_TIMES.unpack_from(pending.body))
            elif opcode == Opcode.MESSAGE:
                message = self._parse(Message.read, stream.read(length), offset, length)
                if message is None:
                    return
                self._span(message.log_time, message.log_time)
                found = self._message(message)
                if found is not None:
                    yield found
            elif opcode == Opcode.CHANNEL:
                channel = self._parse(Channel.read, stream.read(length), offset)
                if channel is None:
                    return
                self._channel(channel)
            elif opcode == Opcode.METADATA:
                metadata = self._parse(Metadata.read, stream.read(length), offset)
                if metadata is None:
                    return
                self.metadata[metadata.name] = dict(metadata.metadata)
            elif opcode == Opcode.ATTACHMENT:
                attachment = self._parse(Attachment.read, stream.read(length), offset)
                if attachment is None:
                    return
                if attachment.name in self.attachment_names:
                    self.attachments.setdefault(attachment.name, attachment.data)
            elif opcode in (Opcode.DATA_END, Opcode.FOOTER):
                # Every message is before the summary section: the data is complete.
                self.complete = True
                return
            else:
                stream.seek(length, io.SEEK_CUR)
            offset = body_start + length

    def _before_horizon(self, log_time_ns: int) -> bool:
        return self.until_ns is None or log_time_ns < self.until_ns

    def _stop(self, problem: str) -> None:
        if self.problem is None:  # the first damage is the one to report
            self.problem = problem

    def _parse(self, reader: Callable[..., object], body: bytes, offset: int, *args: int) -> object:
        try:
            return reader(ReadDataStream(io.BytesIO(body)), *args)
        except Exception as exc:
            self._stop(f"malformed record at byte {offset}: {exc}")
            return None

    def _span(self, start: int, end: int) -> None:
        if self.first is None or start < self.first:
            self.first = start
        if self.last_ns is None or end > self.last_ns:
            self.last_ns = end

    def _channel(self, channel: Channel) -> None:
        if channel.id in self.names:
            return
        name = topic_name(channel.topic)
        self.names[channel.id] = name
        json_channel = channel.message_encoding == MESSAGE_ENCODING
        if self.wanted(name):
            (self.wanted_ids if json_channel else self.foreign_ids).add(channel.id)
        if name in self.last and json_channel:
            self.last_ids[channel.id] = name

    def _message(self, message: Message) -> SourceMessage | None:
        cid = message.channel_id
        if cid in self.wanted_ids:
            return SourceMessage(self.names[cid], message.log_time, message.data)
        name = self.last_ids.get(cid)
        if name is not None:
            if self._before_horizon(message.log_time):
                self.tail[name] = SourceMessage(name, message.log_time, message.data)
        elif cid not in self.names:
            self.undefined += 1
        elif cid in self.foreign_ids:
            self.foreign += 1
        return None

    def _chunk(self, pending: _Pending) -> Iterator[SourceMessage]:
        ids = pending.channels
        needed = not ids or any(c in self.wanted_ids or c not in self.names for c in ids)
        if not needed:
            if self._before_horizon(pending.start_ns):
                for cid in ids:
                    if cid in self.last_ids:
                        self.tail_chunks[cid] = pending
            return
        records = self._decode(pending)
        if isinstance(records, str):
            self._stop(records)
            return
        for record in records:
            if isinstance(record, Message):
                found = self._message(record)
                if found is not None:
                    yield found
            elif isinstance(record, Channel):
                self._channel(record)
        for cid in ids:  # the tail messages of this chunk were seen while decoding
            self.tail_chunks.pop(cid, None)

    @staticmethod
    def _decode(pending: _Pending) -> list[object] | str:
        """The chunk's records, or what is wrong with it."""
        try:
            chunk = Chunk.read(ReadDataStream(io.BytesIO(pending.body)))
            return list(breakup_chunk(chunk, validate_crc=True))
        except Exception as exc:
            return f"corrupt chunk at byte {pending.offset}: {exc}"

    def _finish_tail(self) -> None:
        """Decode the latest skipped chunk of each "last" channel for its last message,
        unless a later decoded chunk already gave one."""
        for cid, pending in self.tail_chunks.items():
            name = self.last_ids[cid]
            records = self._decode(pending)
            if isinstance(records, str):
                continue
            for record in records:
                if (
                    isinstance(record, Message)
                    and record.channel_id == cid
                    and self._before_horizon(record.log_time)
                ):
                    current = self.tail.get(name)
                    if current is None or record.log_time >= current.log_time_ns:
                        self.tail[name] = SourceMessage(name, record.log_time, record.data)
