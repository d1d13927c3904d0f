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
from dataclasses import dataclass
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
    """How a scan ended: `complete` when the footer (and closing magic) were read;
    otherwise `problem` says why reading stopped at byte `offset`."""

    complete: bool
    offset: int
    problem: str | None = None


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
        body = stream.read(length)
        if len(body) < length:
            raise RecordingError("file ends inside the MCAP header record", Mark(self.name))
        try:
            header = Header.read(ReadDataStream(io.BytesIO(body)))
        except Exception as exc:
            raise RecordingError(f"malformed MCAP header record: {exc}", Mark(self.name)) from None
        self._header_length = length
        return header

    def records(self) -> Iterator[tuple[int, McapRecord]]:
        """(offset, record) in file order; records inside a chunk carry the chunk's
        offset. Stops quietly at the first damage and sets `end`."""
        with open(self.path, "rb") as stream:
            stream.seek(self._data_start)
            yield from self._walk(stream)

    def _stop(self, offset: int, problem: str | None, complete: bool = False) -> None:
        self.end = ScanEnd(complete, offset, problem)

    def _walk(self, stream: io.BufferedReader) -> Iterator[tuple[int, McapRecord]]:
        offset = self._data_start
        size = self.size
        while True:
            check_interrupts()  # between records: a safe point for every reader
            prefix = stream.read(_PREFIX.size)
            if not prefix:
                self._stop(offset, f"no footer: the file ends at byte {offset} (incomplete)")
                return
            if len(prefix) < _PREFIX.size:
                self._stop(offset, f"record cut short at byte {offset} (incomplete)")
                return
            opcode, length = _PREFIX.unpack(prefix)
            body_start = offset + _PREFIX.size
            if length > size - body_start:
                self._stop(
                    offset,
                    f"{_opcode_name(opcode)} record at byte {offset} is cut short: "
                    f"{length} bytes declared, {size - body_start} left (incomplete)",
                )
                return
            parser = _PARSERS.get(opcode)
            if parser is None:  # unknown or user opcode: skip, as the spec says
                stream.seek(length, io.SEEK_CUR)
                offset = body_start + length
                continue
            body = stream.read(length)
            try:
                record = parser(ReadDataStream(io.BytesIO(body)), length)
            except Exception as exc:
                self._stop(
                    offset, f"malformed {_opcode_name(opcode)} record at byte {offset}: {exc}"
                )
                return
            if isinstance(record, Chunk):
                try:
                    inner = breakup_chunk(record, validate_crc=self.validate_crcs)
                except Exception as exc:
                    self._stop(offset, f"corrupt chunk at byte {offset}: {exc}")
                    return
                for item in inner:
                    yield offset, item
            else:
                yield offset, record
            offset = body_start + length
            if isinstance(record, Footer):
                tail = stream.read(len(MAGIC))
                if tail != MAGIC:
                    self._stop(offset, f"footer at byte {offset} is not followed by the MCAP magic")
                    return
                self._stop(offset + len(MAGIC), None, complete=True)
                return


def scan_all(path: str | os.PathLike[str]) -> tuple[list[Any], ScanEnd]:
    """Every record of a (small) file and how the scan ended: for tests and debugging."""
    scanner = RecordScanner(path)
    records = [record for _, record in scanner.records()]
    assert scanner.end is not None
    return records, scanner.end
