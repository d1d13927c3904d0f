"""Damage inside an MCAP file: what is missing where, and where reading can go on.

A recording can lie in the middle: a chunk zero-filled by a filesystem, a flipped bit
that breaks a chunk's or an attachment's CRC, a run of garbage. Readers must neither
skip such a region silently nor give up on everything after it. The two walkers
(`recording.scan` for every record, `replay.source` for the channels replay needs) share
this module: `Damage` describes one damaged region, `next_record` finds where records
start again after it, and `attachment_crc_ok` checks an attachment's own CRC.
"""

from __future__ import annotations

import io
import re
import struct
import zlib
from dataclasses import dataclass
from typing import IO

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Chunk
from mcap.stream_reader import get_chunk_data_stream

PREFIX = struct.Struct("<BQ")
MAGIC = bytes([137, 77, 67, 65, 80, 48, 13, 10])
_NS = 1_000_000_000
#: How far past a damage `next_record` looks for records (bytes): several of the largest
#: chunks aeroexec writes (4 MiB), so one damaged chunk is always stepped over.
RESYNC_WINDOW = 64 * 1024 * 1024
_BLOCK = 1 << 20
#: Top-level records a resynchronized walk may start at.
_RESUMABLE = frozenset(
    int(op)
    for op in (
        Opcode.SCHEMA,
        Opcode.CHANNEL,
        Opcode.MESSAGE,
        Opcode.CHUNK,
        Opcode.MESSAGE_INDEX,
        Opcode.CHUNK_INDEX,
        Opcode.ATTACHMENT,
        Opcode.ATTACHMENT_INDEX,
        Opcode.STATISTICS,
        Opcode.METADATA,
        Opcode.METADATA_INDEX,
        Opcode.SUMMARY_OFFSET,
        Opcode.DATA_END,
        Opcode.FOOTER,
    )
)


_OPCODE_BYTE = re.compile(
    b"[" + b"".join(re.escape(bytes([op])) for op in sorted(_RESUMABLE)) + b"]"
)


def is_damage_opcode(opcode: int) -> bool:
    """An opcode no writer uses: 0x00 (reserved; what a zero-filled region reads as) and
    0x10-0x7F (reserved for future records). User opcodes (0x80-0xFF) are skipped, as
    the specification asks."""
    return opcode == 0 or 0x10 <= opcode <= 0x7F


@dataclass(frozen=True, slots=True)
class Damage:
    """A damaged region: bytes `offset` up to `end` (where reading went on), why, and
    what was lost there when the file says (message count, log time span)."""

    offset: int
    end: int
    #: "zero-filled", "unreadable" (garbage), "CRC mismatch"
    kind: str
    #: What the region held, when known: "chunk", "attachment 'mission.py'", ...
    what: str = ""
    messages: int | None = None
    start_ns: int | None = None
    end_ns: int | None = None

    def describe(self) -> str:
        """One line: 'bytes 12920..13879 zero-filled (20 messages lost, log time ...)'."""
        if self.what:
            text = f"{self.what} at byte {self.offset}: {self.kind}"
        else:
            text = f"bytes {self.offset}..{self.end} {self.kind}"
        lost = self.lost_text()
        return f"{text} ({lost})" if lost else text

    def lost_text(self) -> str:
        if self.what.startswith("attachment"):
            return "not read"
        parts = []
        if self.messages is not None:
            parts.append(f"{self.messages} message{'s' if self.messages != 1 else ''} lost")
        else:
            parts.append("messages lost")
        if self.start_ns is not None and self.end_ns is not None:
            parts.append(f"log time {self.start_ns / _NS:.3f} .. {self.end_ns / _NS:.3f} s")
        return ", ".join(parts)

    def as_dict(self) -> dict[str, object]:
        return {
            "offset": self.offset,
            "end": self.end,
            "kind": self.kind,
            "what": self.what,
            "messages": self.messages,
            "start_ns": self.start_ns,
            "end_ns": self.end_ns,
            "text": self.describe(),
        }


def kind_of_region(stream: IO[bytes], start: int, end: int) -> str:
    """'zero-filled' if every byte in [start, end) is zero, else 'unreadable'."""
    stream.seek(start)
    left = end - start
    while left > 0:
        block = stream.read(min(left, _BLOCK))
        if not block:
            break
        if block.count(0) != len(block):
            return "unreadable"
        left -= len(block)
    return "zero-filled"


def attachment_crc_ok(body: bytes) -> bool:
    """Does an attachment record's body match its own CRC (0: the writer gave none)?"""
    if len(body) < 4:
        return False
    (stored,) = struct.unpack_from("<I", body, len(body) - 4)
    return stored == 0 or zlib.crc32(body[:-4]) == stored


def chunk_crc_problem(chunk: Chunk) -> str | None:
    """What is wrong with a chunk's data (decompression, CRC), or None."""
    try:
        get_chunk_data_stream(chunk, validate_crc=True)
    except Exception as exc:  # CRCValidationError, lz4/zstd errors, ...
        return " ".join(str(exc).split()) or type(exc).__name__
    return None


def _plausible(stream: IO[bytes], at: int, size: int) -> bool:
    """Does a record start at `at`, followed by another (or by the end of the file)?"""
    stream.seek(at)
    prefix = stream.read(PREFIX.size)
    if len(prefix) < PREFIX.size:
        return False
    opcode, length = PREFIX.unpack(prefix)
    if opcode not in _RESUMABLE or length > size - at - PREFIX.size:
        return False
    after = at + PREFIX.size + length
    if opcode == Opcode.FOOTER:
        stream.seek(after)
        return stream.read(len(MAGIC)) == MAGIC
    if opcode == Opcode.CHUNK:
        try:
            chunk = Chunk.read(ReadDataStream(io.BytesIO(stream.read(length))))
        except Exception:
            return False
        if chunk_crc_problem(chunk) is not None:
            return False
    if after == size:
        return False  # a data record is never the last thing in a file
    stream.seek(after)
    following = stream.read(PREFIX.size)
    if len(following) < PREFIX.size:
        return False
    next_opcode, next_length = PREFIX.unpack(following)
    return next_opcode in _RESUMABLE and next_length <= size - after - PREFIX.size


def next_record(stream: IO[bytes], start: int, size: int) -> int | None:
    """The offset of the first record at or after `start` that starts a plausible run
    of records (two in a row, a chunk's CRC holding), within `RESYNC_WINDOW`; None if
    there is none (the file is cut short, or damaged beyond reach)."""
    limit = min(size, start + RESYNC_WINDOW)
    position = start
    while position < limit:
        stream.seek(position)
        block = stream.read(min(_BLOCK, limit - position))
        if not block:
            return None
        for candidate in _OPCODE_BYTE.finditer(block):
            at = position + candidate.start()
            if _plausible(stream, at, size):
                return at
        position += len(block)
    return None
