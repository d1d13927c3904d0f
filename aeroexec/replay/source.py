"""Selective, streaming reading of a recording: only the channels replay needs.

Replay reads a few sparse channels (mission commands, behavior events, a handful of
service calls, process and capability changes) out of a stream dominated by
`vehicle/state`, `vehicle/pose` and `beliefs`. Decoding every chunk would cost more than
re-running the mission, so this reader walks the file record by record and uses the
message-index records the writer puts after each chunk to skip, without decompressing,
every chunk that holds none of the wanted channels (or of the channels not defined yet).
Chunks without message indexes (other writers) are always decoded.

Memory is flat in the file size: one chunk at a time, plus, for "last" channels (the
final `vehicle/state`), the compressed bytes of the latest chunk holding one. Damaged
regions (zero-filled, garbage, a chunk whose CRC fails, skipped chunks included) are
stepped over and reported, like `aeroexec.recording.scan` does; a damaged attachment
that replay needs is an input error. The summary says what was damaged and until when
the file was intact, so comparisons can stop there.
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
from aeroexec.interrupts import Interrupted
from aeroexec.interrupts import check as check_interrupts
from aeroexec.recording.damage import (
    Damage,
    attachment_crc_ok,
    chunk_crc_problem,
    is_damage_opcode,
    kind_of_region,
    next_record,
)
from aeroexec.recording.reader import Recording
from aeroexec.recording.scan import RecordScanner
from aeroexec.recording.schemas import MESSAGE_ENCODING

_PREFIX = struct.Struct("<BQ")
_CHUNK_TIMES = struct.Struct("<QQ")
_CHANNEL_ID = struct.Struct("<H")
_MAGIC_LENGTH = 8
_BUFFER = 1 << 18
#: Records whose body the walk reads (the others are skipped with a seek).
_READ = frozenset(
    int(op)
    for op in (Opcode.CHUNK, Opcode.MESSAGE, Opcode.CHANNEL, Opcode.METADATA, Opcode.ATTACHMENT)
)


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
    #: Damaged regions stepped over (the walk reads on after each).
    damages: tuple[Damage, ...] = ()
    #: With damage: the log time of the last message before the first damaged region.
    intact_until_ns: int | None = None


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
        self._scanner = RecordScanner(path)
        self._definitions: dict[int, Channel] | None = None

    def summary_channel(self, channel_id: int) -> Channel | None:
        """The channel as the summary section defines it (for a channel whose first
        definition was lost with a damaged chunk), read once when first needed."""
        if self._definitions is None:
            self._definitions = self._scanner.summary_definitions()[1]
        return self._definitions.get(channel_id)

    def scan(
        self,
        wanted: Callable[[str], bool],
        last: frozenset[str] = frozenset(),
        attachments: frozenset[str] = frozenset(),
        until_ns: int | None = None,
        on_read: Callable[[int], None] | None = None,
    ) -> Iterator[SourceMessage]:
        """Messages of the channels `wanted(name)` accepts, in file order (JSON channels
        only). When the generator is exhausted, `summary` holds metadata, the named
        attachments, the time span, the last message of each `last` channel (logged
        before `until_ns`, when given) and how the pass ended. `on_read(offset)` is
        told, record by record, how far into the file the pass is."""
        walk = _Walk(self, wanted, last, attachments, until_ns, on_read)
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
        on_read: Callable[[int], None] | None = None,
    ) -> None:
        self.source = source
        self.on_read = on_read
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
        self.damages: list[Damage] = []
        #: Log time of the last message before the first damage (None: no damage).
        self.intact_until: int | None = None
        self.last_message_ns: int | None = None
        self.foreign = 0
        self.undefined = 0

    def summary(self) -> ScanSummary:
        notes = []
        if self.foreign:
            notes.append(f"{self.foreign} wanted message(s) not JSON-encoded, skipped")
        if self.undefined:
            notes.append(f"{self.undefined} message(s) on channels the file never defines")
        problems = [d.describe() for d in self.damages]
        if self.problem is not None:
            problems.append(self.problem)
        problem = "; ".join(problems) or None
        if self.damages:
            count = len(self.damages)
            problem = f"{count} damaged region{'s' if count > 1 else ''}: {problem}"
        return ScanSummary(
            self.metadata,
            self.attachments,
            self.first,
            self.last_ns,
            self.complete and not self.damages,
            problem,
            self.tail,
            tuple(notes),
            tuple(self.damages),
            self.intact_until,
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
        on_read = self.on_read
        while True:
            check_interrupts()
            if on_read is not None:
                on_read(offset)
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
            if is_damage_opcode(opcode) or length > size - body_start:
                if pending is not None:
                    yield from self._chunk(pending)
                    pending = None
                resume = self._resync(stream, offset, size)
                if resume is None:
                    self._stop(self._cut_reason(stream, offset, opcode, length, size))
                    return
                offset = resume
                continue
            if opcode == Opcode.MESSAGE_INDEX and pending is not None:
                head = stream.read(_CHANNEL_ID.size)
                pending.channels.add(_CHANNEL_ID.unpack(head)[0])
                stream.seek(length - _CHANNEL_ID.size, io.SEEK_CUR)
                offset = body_start + length
                continue
            if pending is not None:
                yield from self._chunk(pending)
                pending = None
            body = stream.read(length) if opcode in _READ else b""
            try:
                if opcode == Opcode.CHUNK:
                    pending = _Pending(offset, body)
                    self._span(*_CHUNK_TIMES.unpack_from(pending.body))
                elif opcode == Opcode.MESSAGE:
                    message = Message.read(ReadDataStream(io.BytesIO(body)), length)
                    self._span(message.log_time, message.log_time)
                    found = self._message(message)
                    if found is not None:
                        yield found
                elif opcode == Opcode.CHANNEL:
                    self._channel(Channel.read(ReadDataStream(io.BytesIO(body))))
                elif opcode == Opcode.METADATA:
                    metadata = Metadata.read(ReadDataStream(io.BytesIO(body)))
                    self.metadata[metadata.name] = dict(metadata.metadata)
                elif opcode == Opcode.ATTACHMENT:
                    self._attachment(body, offset)
                elif opcode in (Opcode.DATA_END, Opcode.FOOTER):
                    # Every message is before the summary section: the data is all read.
                    self.complete = not self.damages
                    return
                else:
                    stream.seek(length, io.SEEK_CUR)
            except (RecordingError, Interrupted):
                raise
            except Exception as exc:  # a malformed record: damage, step over it
                resume = self._resync(stream, offset, size)
                if resume is None:
                    self._stop(f"malformed record at byte {offset}: {exc}")
                    return
                offset = resume
                continue
            offset = body_start + length

    def _attachment(self, body: bytes, offset: int) -> None:
        attachment = Attachment.read(ReadDataStream(io.BytesIO(body)))
        if attachment.name not in self.attachment_names:
            return
        if not attachment_crc_ok(body):
            # What replay would run or load from it (the mission, the catalog, the world)
            # must be what was recorded: a damaged one is unusable input, not a guess.
            raise RecordingError(
                f"attachment {attachment.name!r} at byte {offset} is damaged (CRC mismatch)",
                Mark(str(self.source.path)),
            )
        self.attachments.setdefault(attachment.name, attachment.data)

    def _resync(self, stream: io.BufferedReader, offset: int, size: int) -> int | None:
        """Step over a damaged region at `offset`: where records start again (noted as
        damage), or None (the stream is left at `offset`)."""
        resume = next_record(stream, offset + 1, size)
        if resume is None:
            stream.seek(offset)
            return None
        self._damage(Damage(offset, resume, kind_of_region(stream, offset, resume)))
        stream.seek(resume)
        return resume

    @staticmethod
    def _cut_reason(
        stream: io.BufferedReader, offset: int, opcode: int, length: int, size: int
    ) -> str:
        if is_damage_opcode(opcode):
            if kind_of_region(stream, offset, size) == "zero-filled":
                return f"bytes {offset}..{size} are zero-filled to the end of the file (incomplete)"
            return f"unreadable from byte {offset} on"
        return (
            f"record at byte {offset} is cut short: {length} bytes declared, "
            f"{size - offset - _PREFIX.size} left (incomplete)"
        )

    def _damage(self, damage: Damage, before_ns: int | None = None) -> None:
        """Note `damage`; `before_ns`: the time before which nothing is lost (default:
        the last message time read so far)."""
        if not self.damages:
            self.intact_until = before_ns if before_ns is not None else self.last_message_ns
        self.damages.append(damage)

    def _before_horizon(self, log_time_ns: int) -> bool:
        return self.until_ns is None or log_time_ns < self.until_ns

    def _stop(self, problem: str) -> None:
        if self.problem is None:  # the first damage is the one to report
            self.problem = problem

    def _span(self, start: int, end: int) -> None:
        if self.first is None or start < self.first:
            self.first = start
        if self.last_ns is None or end > self.last_ns:
            self.last_ns = end
        self.last_message_ns = end

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
            channel = self.source.summary_channel(cid)
            if channel is not None:
                self._channel(channel)
                return self._message(message)
            self.undefined += 1
        elif cid in self.foreign_ids:
            self.foreign += 1
        return None

    def _chunk(self, pending: _Pending) -> Iterator[SourceMessage]:
        ids = pending.channels
        needed = not ids or any(c in self.wanted_ids or c not in self.names for c in ids)
        if not needed:
            # Not decoded, but checked: replay reports every damaged chunk, not only the
            # ones holding what it compares (decompressing is cheap; parsing is not).
            problem = self._check(pending)
            if problem is not None:
                self._lost_chunk(pending, problem)
                return
            if self._before_horizon(pending.start_ns):
                for cid in ids:
                    if cid in self.last_ids:
                        self.tail_chunks[cid] = pending
            return
        records = self._decode(pending)
        if isinstance(records, str):
            self._lost_chunk(pending, records)
            return
        before = {name: message.log_time_ns for name, message in self.tail.items()}
        for record in records:
            if isinstance(record, Message):
                found = self._message(record)
                if found is not None:
                    yield found
            elif isinstance(record, Channel):
                self._channel(record)
        for cid in ids:
            # A tail message this chunk gave (logged before the horizon) replaces any
            # skipped chunk's; a chunk wholly past the horizon replaces nothing.
            name = self.last_ids.get(cid)
            tail = self.tail.get(name) if name is not None else None
            if tail is not None and tail.log_time_ns != before.get(name):
                self.tail_chunks.pop(cid, None)

    @staticmethod
    def _decode(pending: _Pending) -> list[object] | str:
        """The chunk's records, or what is wrong with it."""
        try:
            chunk = Chunk.read(ReadDataStream(io.BytesIO(pending.body)))
            return list(breakup_chunk(chunk, validate_crc=True))
        except Exception as exc:
            return " ".join(str(exc).split()) or type(exc).__name__

    @staticmethod
    def _check(pending: _Pending) -> str | None:
        try:
            chunk = Chunk.read(ReadDataStream(io.BytesIO(pending.body)))
        except Exception as exc:
            return " ".join(str(exc).split()) or type(exc).__name__
        return chunk_crc_problem(chunk)

    def _lost_chunk(self, pending: _Pending, problem: str) -> None:
        start, end = _CHUNK_TIMES.unpack_from(pending.body)
        kind = "CRC mismatch" if "crc" in problem.lower() else f"corrupt ({problem})"
        damage = Damage(pending.offset, pending.offset, kind, "chunk", start_ns=start, end_ns=end)
        self._damage(damage, before_ns=start)

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
