"""Record-level reading of an MCAP file that survives damage.

`RecordScanner` walks the file front to back, one record at a time, with the record
parsers of the `mcap` library, and expands chunks into the records they hold. Unlike the
`mcap` readers it never needs the footer or the summary: on a file cut short (a process
killed mid-write) or damaged part-way, it yields every record before the damage and then
stops, saying where and why (`ScanEnd`). Memory stays flat in the file size: one record
(or one chunk) at a time.

Files that cannot be read at all (missing, a directory, empty, not MCAP, no header)
raise `RecordingError` at construction, with a one-line reason.
"""

from __future__ import annotations

import io
import os
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Channel,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    McapRecord,
    Message,
    MessageIndex,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.stream_reader import breakup_chunk

from aeroexec.errors import Mark, RecordingError
from aeroexec.inputs import regular_file
from aeroexec.interrupts import check as check_interrupts
from aeroexec.recording.damage import (
    Damage,
    attachment_crc_ok,
    is_damage_opcode,
    kind_of_region,
    next_record,
)

MAGIC = bytes([137, 77, 67, 65, 80, 48, 13, 10])
_PREFIX = struct.Struct("<BQ")

_PARSERS: dict[int, Callable[[ReadDataStream, int], McapRecord]] = {
    Opcode.HEADER: lambda s, n: Header.read(s),
    Opcode.FOOTER: lambda s, n: Footer.read(s),
    Opcode.SCHEMA: lambda s, n: Schema.read(s),
    Opcode.CHANNEL: lambda s, n: Channel.read(s),
    Opcode.MESSAGE: Message.read,
    Opcode.CHUNK: lambda s, n: Chunk.read(s),
    Opcode.MESSAGE_INDEX: lambda s, n: MessageIndex.read(s),
    Opcode.CHUNK_INDEX: lambda s, n: ChunkIndex.read(s),
    Opcode.ATTACHMENT: lambda s, n: Attachment.read(s),
    Opcode.ATTACHMENT_INDEX: lambda s, n: AttachmentIndex.read(s),
    Opcode.STATISTICS: lambda s, n: Statistics.read(s),
    Opcode.METADATA: lambda s, n: Metadata.read(s),
    Opcode.METADATA_INDEX: lambda s, n: MetadataIndex.read(s),
    Opcode.SUMMARY_OFFSET: lambda s, n: SummaryOffset.read(s),
    Opcode.DATA_END: lambda s, n: DataEnd.read(s),
}


def _opcode_name(opcode: int) -> str:
    try:
        return Opcode(opcode).name.lower()
    except ValueError:
        return f"opcode 0x{opcode:02x}"


@dataclass(frozen=True, slots=True)
class ScanEnd:
    """How a scan ended. `complete`: the footer (and closing magic) were read, nothing
    on the way was damaged, and every message the file's own statistics count was read;
    otherwise `problem` says what is wrong. `offset` is where reading stopped."""

    complete: bool
    offset: int
    problem: str | None = None
    #: Every damaged region stepped over (zero-filled, garbage, CRC mismatch), in order.
    damages: tuple[Damage, ...] = ()
    #: The footer was reached: the writer closed the file (damage or not).
    footer: bool = False
    #: How many messages the file's Statistics record promises (None: no summary).
    expected_messages: int | None = None
    messages_read: int = 0
    #: Why reading stopped before the footer (None when it was reached).
    cut: str | None = None

    @property
    def missing_messages(self) -> int | None:
        if self.expected_messages is None:
            return None
        return max(self.expected_messages - self.messages_read, 0)

    #: With damage: the log time of the last message read before the first damaged
    #: region (comparisons stop there, so a lost message is not taken for a changed one).
    intact_until_ns: int | None = None


def check_readable(path: str | os.PathLike[str]) -> Path:
    """The path if it names a non-empty regular file, else a `RecordingError`."""
    if regular_file(path, "a recording", RecordingError) == 0:
        raise RecordingError("empty file, not an MCAP recording", Mark(str(path)))
    return Path(path)


class RecordScanner:
    """Iterate an MCAP file's records (chunks expanded) up to the first damage.

    `header` is read at construction. After `records()` is exhausted, `end` tells
    whether the file was complete or where and why reading stopped.
    """

    def __init__(self, path: str | os.PathLike[str], validate_crcs: bool = True) -> None:
        self.path = check_readable(path)
        self.name = str(path)
        self.size = self.path.stat().st_size
        self.validate_crcs = validate_crcs
        self.end: ScanEnd | None = None
        try:
            with open(self.path, "rb") as stream:
                self.header = self._read_header(stream)
        except OSError as exc:
            raise RecordingError(f"cannot read: {exc.strerror or exc}", Mark(self.name)) from None
        self._data_start = len(MAGIC) + _PREFIX.size + self._header_length

    def _read_header(self, stream: io.BufferedReader) -> Header:
        magic = stream.read(len(MAGIC))
        if magic != MAGIC:
            if MAGIC.startswith(magic):
                raise RecordingError(
                    f"file ends inside the MCAP magic ({len(magic)} bytes)", Mark(self.name)
                )
            raise RecordingError("not an MCAP file (bad magic bytes)", Mark(self.name))
        prefix = stream.read(_PREFIX.size)
        if len(prefix) < _PREFIX.size:
            raise RecordingError("file ends before the MCAP header record", Mark(self.name))
        opcode, length = _PREFIX.unpack(prefix)
        if opcode != Opcode.HEADER:
            raise RecordingError(
                f"first record is {_opcode_name(opcode)}, not a header (byte 8)", Mark(self.name)
            )
        if length > self.size - len(MAGIC) - _PREFIX.size:
            raise RecordingError(
                f"file ends inside the MCAP header record ({length} bytes declared, "
                f"{self.size - len(MAGIC) - _PREFIX.size} left)",
                Mark(self.name),
            )
        body = stream.read(length)
        if len(body) < length:
            raise RecordingError("file ends inside the MCAP header record", Mark(self.name))
        try:
            header = Header.read(ReadDataStream(io.BytesIO(body)))
        except Exception as exc:
            raise RecordingError(f"malformed MCAP header record: {exc}", Mark(self.name)) from None
        self._header_length = length
        return header

    def summary_definitions(self) -> tuple[dict[int, Schema], dict[int, Channel]]:
        """The schemas and channels the summary section repeats (found from the footer),
        or nothing if the file has no readable summary. A damaged data section may have
        lost a channel's first definition; the summary still names it."""
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        footer_length = _PREFIX.size + 20 + len(MAGIC)
        if self.size < self._data_start + footer_length:
            return schemas, channels
        try:
            with open(self.path, "rb") as stream:
                stream.seek(self.size - footer_length)
                tail = stream.read(footer_length)
                opcode, length = _PREFIX.unpack_from(tail)
                if opcode != Opcode.FOOTER or length != 20 or tail[-len(MAGIC) :] != MAGIC:
                    return schemas, channels
                footer = Footer.read(ReadDataStream(io.BytesIO(tail[_PREFIX.size : -len(MAGIC)])))
                start = footer.summary_start
                end = footer.summary_offset_start or self.size - footer_length
                if not self._data_start <= start < end <= self.size:
                    return schemas, channels
                stream.seek(start)
                section = stream.read(end - start)
            position = 0
            while position + _PREFIX.size <= len(section):
                opcode, length = _PREFIX.unpack_from(section, position)
                body = section[position + _PREFIX.size : position + _PREFIX.size + length]
                position += _PREFIX.size + length
                if opcode == Opcode.SCHEMA:
                    schema = Schema.read(ReadDataStream(io.BytesIO(body)))
                    schemas[schema.id] = schema
                elif opcode == Opcode.CHANNEL:
                    channel = Channel.read(ReadDataStream(io.BytesIO(body)))
                    channels[channel.id] = channel
        except Exception:  # a damaged summary: the data section is all there is
            return {}, {}
        return schemas, channels

    def records(self) -> Iterator[tuple[int, McapRecord]]:
        """(offset, record) in file order; records inside a chunk carry the chunk's
        offset. Steps over damaged regions (noting each), stops quietly where the file
        ends early, and sets `end`."""
        with open(self.path, "rb") as stream:
            stream.seek(self._data_start)
            walk = _Walk(stream, self._data_start, self.size, self.validate_crcs)
            yield from walk.run()
            self.end = walk.end()


class _Walk:
    """One pass over the data and summary sections."""

    def __init__(self, stream: io.BufferedReader, start: int, size: int, crcs: bool) -> None:
        self.stream = stream
        self.offset = start
        self.size = size
        self.crcs = crcs
        self.damages: list[Damage] = []
        self.stopped: tuple[int, str | None, bool] | None = None  # offset, problem, footer
        self.expected: int | None = None
        self.read = 0
        self.last_ns: int | None = None
        #: Log time of the last message read before the first damage.
        self.intact_until: int | None = None
        self.chunk_times: dict[int, tuple[int, int]] = {}
        #: The damaged chunk whose message indexes may follow (they say what it held).
        self.lost: int | None = None

    # -- the walk ------------------------------------------------------------------------
    def run(self) -> Iterator[tuple[int, McapRecord]]:
        stream, size = self.stream, self.size
        while self.stopped is None:
            check_interrupts()  # between records: a safe point for every reader
            offset = self.offset
            prefix = stream.read(_PREFIX.size)
            if not prefix:
                self._stop(f"no footer: the file ends at byte {offset} (incomplete)")
                return
            if len(prefix) < _PREFIX.size:
                self._stop(f"record cut short at byte {offset} (incomplete)")
                return
            opcode, length = _PREFIX.unpack(prefix)
            body_start = offset + _PREFIX.size
            if is_damage_opcode(opcode):
                self._damaged(offset, f"{_opcode_name(opcode)} at byte {offset}")
                continue
            if length > size - body_start:
                if self._resume(offset):
                    continue
                self._stop(
                    f"{_opcode_name(opcode)} record at byte {offset} is cut short: "
                    f"{length} bytes declared, {size - body_start} left (incomplete)"
                )
                return
            parser = _PARSERS.get(opcode)
            if parser is None:  # a user opcode: skip, as the spec says
                stream.seek(length, io.SEEK_CUR)
                self.offset = body_start + length
                continue
            body = stream.read(length)
            try:
                record = parser(ReadDataStream(io.BytesIO(body)), length)
            except Exception as exc:
                self._damaged(
                    offset, f"malformed {_opcode_name(opcode)} record at byte {offset}: {exc}"
                )
                continue
            self.offset = body_start + length
            if not isinstance(record, MessageIndex):
                self.lost = None
            if isinstance(record, Chunk):
                if _chunk_size(record) != length:
                    # A damaged header can declare an empty chunk inside a long record:
                    # reading on would skip its messages without a word.
                    self._damaged(offset, f"malformed chunk record at byte {offset}")
                    continue
                yield from self._chunk(offset, record)
            elif isinstance(record, Attachment) and self.crcs and not attachment_crc_ok(body):
                self._note(
                    Damage(offset, self.offset, "CRC mismatch", f"attachment {record.name!r}")
                )
            else:
                yield from self._other(offset, record)

    def _chunk(self, offset: int, chunk: Chunk) -> Iterator[tuple[int, McapRecord]]:
        try:
            inner = breakup_chunk(chunk, validate_crc=self.crcs)
        except Exception as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            kind = "CRC mismatch" if "crc" in reason.lower() else f"corrupt ({reason})"
            self._note(
                Damage(
                    offset,
                    self.offset,
                    kind,
                    "chunk",
                    start_ns=chunk.message_start_time,
                    end_ns=chunk.message_end_time,
                )
            )
            self.lost = len(self.damages) - 1
            return
        for item in inner:
            if isinstance(item, Message):
                self._message(item)
            yield offset, item

    def _other(self, offset: int, record: McapRecord) -> Iterator[tuple[int, McapRecord]]:
        if isinstance(record, Message):
            self._message(record)
        elif isinstance(record, MessageIndex):
            self._message_index(record)
        elif isinstance(record, ChunkIndex):
            self.chunk_times[record.chunk_start_offset] = (
                record.message_start_time,
                record.message_end_time,
            )
        elif isinstance(record, Statistics):
            self.expected = record.message_count
        yield offset, record
        if isinstance(record, Footer):
            tail = self.stream.read(len(MAGIC))
            if tail != MAGIC:
                self._stop(
                    f"footer at byte {self.offset} is not followed by the MCAP magic",
                    footer=True,
                )
                return
            self.offset += len(MAGIC)
            self._stop(None, footer=True)

    # -- bookkeeping -----------------------------------------------------------------------
    def _message(self, message: Message) -> None:
        self.read += 1
        self.last_ns = message.log_time
        if not self.damages:
            self.intact_until = message.log_time

    def _message_index(self, index: MessageIndex) -> None:
        """Message indexes right after a damaged chunk count what it held."""
        if self.lost is None or not index.records:
            return
        damage = self.damages[self.lost]
        times = [t for t, _ in index.records]
        self.damages[self.lost] = replace(
            damage,
            messages=(damage.messages or 0) + len(index.records),
            start_ns=min(times) if damage.start_ns is None else min(damage.start_ns, *times),
            end_ns=max(times) if damage.end_ns is None else max(damage.end_ns, *times),
        )

    def _note(self, damage: Damage) -> None:
        self.damages.append(damage)

    def _damaged(self, offset: int, problem: str) -> None:
        """Damage at `offset`: step over it, or stop if records never start again."""
        if self._resume(offset):
            return
        if kind_of_region(self.stream, offset, self.size) == "zero-filled":
            problem = f"bytes {offset}..{self.size} are zero-filled to the end of the file"
            self._stop(f"{problem} (incomplete)")
        else:
            self._stop(f"{problem}: nothing readable after it")

    def _resume(self, offset: int) -> bool:
        resume = next_record(self.stream, offset + 1, self.size)
        if resume is None:
            self.stream.seek(offset)
            return False
        self._note(Damage(offset, resume, kind_of_region(self.stream, offset, resume)))
        self.lost = None
        self.offset = resume
        self.stream.seek(resume)
        return True

    def _stop(self, problem: str | None, footer: bool = False) -> None:
        self.stopped = (self.offset, problem, footer)

    def end(self) -> ScanEnd:
        assert self.stopped is not None
        offset, problem, footer = self.stopped
        damages = self._completed_damages()
        missing = None if self.expected is None else self.expected - self.read
        problems = [d.describe() for d in damages]
        if damages and self.expected is not None:
            problems.append(f"{self.read} of the {self.expected} messages read")
        if problem is not None:
            problems.append(problem)
        elif missing and not damages:
            problems.append(
                f"the file's statistics count {self.expected} messages, {self.read} were read"
            )
        text = "; ".join(problems) if problems else None
        if damages:
            count = f"{len(damages)} damaged region{'s' if len(damages) > 1 else ''}"
            text = f"{count}: {text}"
        return ScanEnd(
            complete=footer and text is None,
            offset=offset,
            problem=text,
            damages=damages,
            footer=footer,
            expected_messages=self.expected,
            messages_read=self.read,
            intact_until_ns=self.intact_until if damages else None,
            cut=problem if not footer else None,
        )

    def _completed_damages(self) -> tuple[Damage, ...]:
        """The damages, with what the summary section says they held: the time span of
        chunks indexed inside them and, for a lone region of unknown size, the message
        count the statistics leave unaccounted for."""
        damages = []
        for damage in self.damages:
            spans = [
                times
                for start, times in self.chunk_times.items()
                if damage.offset <= start < damage.end
            ]
            if spans and damage.start_ns is None:
                damage = replace(
                    damage,
                    start_ns=min(t[0] for t in spans),
                    end_ns=max(t[1] for t in spans),
                )
            damages.append(damage)
        unknown = [
            i
            for i, d in enumerate(damages)
            if d.messages is None and not d.what.startswith("attachment")
        ]
        known = sum(d.messages or 0 for d in damages)
        if self.expected is not None and len(unknown) == 1:
            rest = self.expected - self.read - known
            if rest >= 0:
                damages[unknown[0]] = replace(damages[unknown[0]], messages=rest)
        return tuple(damages)


def _chunk_size(chunk: Chunk) -> int:
    """The body length a chunk's fields account for (start, end, size, crc, compression,
    records)."""
    return 8 + 8 + 8 + 4 + 4 + len(chunk.compression.encode()) + 8 + len(chunk.data)


def scan_all(path: str | os.PathLike[str]) -> tuple[list[Any], ScanEnd]:
    """Every record of a (small) file and how the scan ended: for tests and debugging."""
    scanner = RecordScanner(path)
    records = [record for _, record in scanner.records()]
    assert scanner.end is not None
    return records, scanner.end
