"""A chunked MCAP writer for bulk imports, with a fast path for messages.

mcap's `Writer` builds a record object per message and writes it field by field, about
15 us a message; an import copies every message of a bag, so that alone would cost
more than rosbags reading the bag. This writer packs each message record with one
`struct` call into the chunk buffer and keeps the message index as plain lists; every
other record (header, schemas, channels, chunks, indexes, statistics, summary, footer)
is written with mcap's own record classes, in the layout mcap's `Writer` uses (schemas
and channels inside the chunk that first needs them, message indexes after each chunk,
the summary repeating schemas and channels, statistics, chunk/attachment/metadata
indexes and summary offsets; CRCs of chunks and of the summary). Output readable by
every MCAP reader; nothing in it depends on the clock.
"""

from __future__ import annotations

import struct
import zlib
from typing import IO

import lz4.frame
import zstandard
from mcap.data_stream import RecordBuilder
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
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)

MAGIC = struct.pack("<8B", 137, 77, 67, 65, 80, 48, 13, 10)
_MESSAGE = struct.Struct("<BQHIQQ")  # opcode, length, channel, sequence, log, publish
_MESSAGE_FIXED = 2 + 4 + 8 + 8
_INDEX_HEAD = struct.Struct("<BQHI")  # opcode, length, channel, records length
_FOOTER_CRC = struct.Struct("<BQQQ")
COMPRESSIONS = ("lz4", "zstd", "none")


class BulkMcapWriter:
    def __init__(
        self, stream: IO[bytes], *, compression: str = "lz4", chunk_size: int = 1024 * 1024
    ) -> None:
        if compression not in COMPRESSIONS:
            raise ValueError(f"compression must be one of {COMPRESSIONS}")
        self._stream = stream
        self._compression = "" if compression == "none" else compression
        self._chunk_size = chunk_size
        self._schemas: dict[int, Schema] = {}
        self._channels: dict[int, Channel] = {}
        self._chunk = bytearray()
        self._index: dict[int, list[int]] = {}  # channel -> [log, offset, log, offset...]
        self._chunk_start = self._chunk_end = 0
        self._chunk_messages = 0
        self._chunk_indexes: list[ChunkIndex] = []
        self._attachment_indexes: list[AttachmentIndex] = []
        self._metadata_indexes: list[MetadataIndex] = []
        self._counts: dict[int, int] = {}
        self._messages = 0
        self._start = self._end = 0
        self._chunks = 0

    # -- records outside chunks --------------------------------------------------------------
    def start(self, profile: str, library: str) -> None:
        self._stream.write(MAGIC)
        self._write_record(Header(profile, library))

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        offset = self._stream.tell()
        length = self._write_record(Metadata(name=name, metadata=data))
        self._metadata_indexes.append(MetadataIndex(offset=offset, length=length, name=name))

    def add_attachment(self, name: str, media_type: str, data: bytes) -> None:
        """An attachment with log and create time 0 (no clock in the file)."""
        offset = self._stream.tell()
        record = Attachment(create_time=0, log_time=0, name=name, media_type=media_type, data=data)
        length = self._write_record(record)
        self._attachment_indexes.append(
            AttachmentIndex(
                offset=offset,
                length=length,
                create_time=0,
                log_time=0,
                data_size=len(data),
                name=name,
                media_type=media_type,
            )
        )

    def _write_record(self, record: object) -> int:
        builder = RecordBuilder()
        record.write(builder)  # type: ignore[attr-defined]
        data = builder.end()
        self._stream.write(data)
        return len(data)

    # -- schemas and channels (into the current chunk) -----------------------------------------
    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        schema = Schema(id=len(self._schemas) + 1, name=name, encoding=encoding, data=data)
        self._schemas[schema.id] = schema
        self._chunk_record(schema)
        return schema.id

    def register_channel(
        self, topic: str, message_encoding: str, schema_id: int, metadata: dict[str, str]
    ) -> int:
        channel = Channel(
            id=len(self._channels) + 1,
            topic=topic,
            message_encoding=message_encoding,
            schema_id=schema_id,
            metadata=metadata,
        )
        self._channels[channel.id] = channel
        self._counts[channel.id] = 0
        self._chunk_record(channel)
        return channel.id

    def _chunk_record(self, record: object) -> None:
        builder = RecordBuilder()
        record.write(builder)  # type: ignore[attr-defined]
        self._chunk += builder.end()

    # -- messages ----------------------------------------------------------------------------
    def add_message(
        self, channel_id: int, log_time: int, data: bytes, publish_time: int, sequence: int
    ) -> None:
        chunk = self._chunk
        index = self._index.get(channel_id)
        if index is None:
            index = self._index[channel_id] = []
        index.append(log_time)
        index.append(len(chunk))
        chunk += _MESSAGE.pack(
            Opcode.MESSAGE,
            _MESSAGE_FIXED + len(data),
            channel_id,
            sequence,
            log_time,
            publish_time,
        )
        chunk += data
        self._counts[channel_id] += 1
        if self._chunk_messages == 0:
            self._chunk_start = self._chunk_end = log_time
        elif log_time < self._chunk_start:
            self._chunk_start = log_time
        elif log_time > self._chunk_end:
            self._chunk_end = log_time
        self._chunk_messages += 1
        if len(chunk) > self._chunk_size:
            self._finish_chunk()

    def _finish_chunk(self) -> None:
        if self._chunk_messages == 0:
            return
        raw = bytes(self._chunk)
        if self._compression == "lz4":
            data = lz4.frame.compress(raw)
        elif self._compression == "zstd":
            data = zstandard.compress(raw)
        else:
            data = raw
        chunk = Chunk(
            compression=self._compression,
            data=data,
            message_start_time=self._chunk_start,
            message_end_time=self._chunk_end,
            uncompressed_crc=zlib.crc32(raw),
            uncompressed_size=len(raw),
        )
        chunk_offset = self._stream.tell()
        chunk_length = self._write_record(chunk)
        index_start = self._stream.tell()
        offsets: dict[int, int] = {}
        parts = []
        position = index_start
        for channel_id, entries in self._index.items():
            offsets[channel_id] = position
            body = struct.pack(f"<{len(entries)}Q", *entries)
            head = _INDEX_HEAD.pack(Opcode.MESSAGE_INDEX, 2 + 4 + len(body), channel_id, len(body))
            parts.append(head)
            parts.append(body)
            position += len(head) + len(body)
        self._stream.write(b"".join(parts))
        if self._messages == 0:
            self._start, self._end = self._chunk_start, self._chunk_end
        else:
            self._start = min(self._start, self._chunk_start)
            self._end = max(self._end, self._chunk_end)
        self._messages += self._chunk_messages
        self._chunks += 1
        self._chunk_indexes.append(
            ChunkIndex(
                message_start_time=self._chunk_start,
                message_end_time=self._chunk_end,
                chunk_start_offset=chunk_offset,
                chunk_length=chunk_length,
                message_index_offsets=offsets,
                message_index_length=position - index_start,
                compression=self._compression,
                compressed_size=len(data),
                uncompressed_size=len(raw),
            )
        )
        self._chunk = bytearray()
        self._index = {}
        self._chunk_messages = 0

    # -- the end -----------------------------------------------------------------------------
    def finish(self) -> None:
        """Last chunk, data end, summary, footer and closing magic (the stream stays open)."""
        if self._chunk_messages == 0 and self._chunk:
            # schemas/channels registered after the last message: a chunk of their own
            self._stream.write(self._record_bytes_of_chunk_without_messages())
        self._finish_chunk()
        self._write_record(DataEnd(0))
        summary_start = self._stream.tell()
        builder = RecordBuilder()
        offsets: list[SummaryOffset] = []

        def group(opcode: Opcode, records: list[object]) -> None:
            start = builder.count
            for record in records:
                record.write(builder)  # type: ignore[attr-defined]
            offsets.append(SummaryOffset(opcode, summary_start + start, builder.count - start))

        group(Opcode.SCHEMA, list(self._schemas.values()))
        group(Opcode.CHANNEL, list(self._channels.values()))
        statistics = Statistics(
            attachment_count=len(self._attachment_indexes),
            channel_count=len(self._channels),
            channel_message_counts={k: v for k, v in self._counts.items() if v},
            chunk_count=self._chunks,
            message_count=self._messages,
            message_end_time=self._end,
            message_start_time=self._start,
            metadata_count=len(self._metadata_indexes),
            schema_count=len(self._schemas),
        )
        group(Opcode.STATISTICS, [statistics])
        group(Opcode.CHUNK_INDEX, list(self._chunk_indexes))
        group(Opcode.ATTACHMENT_INDEX, list(self._attachment_indexes))
        group(Opcode.METADATA_INDEX, list(self._metadata_indexes))
        offset_start = summary_start + builder.count
        for offset in offsets:
            offset.write(builder)
        summary = builder.end()
        crc = zlib.crc32(summary)
        crc = zlib.crc32(_FOOTER_CRC.pack(Opcode.FOOTER, 20, summary_start, offset_start), crc)
        self._stream.write(summary)
        self._write_record(Footer(summary_start, offset_start, crc))
        self._stream.write(MAGIC)

    def _record_bytes_of_chunk_without_messages(self) -> bytes:
        """Schema/channel records left in a chunk that got no message: written as plain
        data-section records (allowed by the format)."""
        data = bytes(self._chunk)
        self._chunk = bytearray()
        return data
