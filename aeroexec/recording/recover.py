"""Salvage a damaged or unfinished MCAP file into a complete one.

    report = recover("broken.mcap", "fixed.mcap")

Reads the source record by record (`RecordScanner`: no footer or summary needed) and
writes every schema, channel, message, attachment and metadata record it can read, in
the same order, to a new file with a proper summary and footer. Damaged regions of the
source (zero-filled, garbage, CRC mismatches) are stepped over; the copy then carries an
`aeroexec_recover` metadata record saying what is missing where, so it cannot pass for
the whole recording. The output is written
to a temporary name beside the target and renamed into place only when complete, so a
failed or interrupted recovery never leaves a half-written target. Channel and schema ids
are renumbered in order of appearance (identical to the source's for aeroexec files).
Memory stays flat: one chunk at a time.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from mcap.records import Metadata
from mcap.writer import CompressionType, Writer

from aeroexec.errors import Mark, RecordingError
from aeroexec.outputs import whole_file_or_none
from aeroexec.recording.damage import Damage
from aeroexec.recording.info import RECOVER_METADATA_NAME
from aeroexec.recording.reader import (
    ChannelInfo,
    RawMessage,
    RecordedAttachment,
    Recording,
)
from aeroexec.recording.scan import ScanEnd


@dataclass(frozen=True, slots=True)
class RecoverReport:
    source: str
    target: str
    messages: int
    channels: int
    attachments: int
    metadata: int
    #: The source was whole: footer read, nothing damaged (recovery just rewrote it).
    source_complete: bool
    #: Where reading the source stopped, and why (None when it was complete).
    stopped_at: int
    problem: str | None
    #: Damaged regions of the source stepped over: what the copy is missing, and where.
    damages: tuple[Damage, ...] = ()
    #: What the source's statistics promised (None: it had no summary).
    expected_messages: int | None = None
    #: Why reading stopped before the footer (None: the footer was read).
    cut: str | None = None

    def summary(self) -> str:
        if self.source_complete:
            state = "source was complete"
        else:
            parts = []
            if self.damages:
                regions = len(self.damages)
                parts.append(f"source damaged: {regions} region{'s' if regions > 1 else ''} lost")
                if self.expected_messages is not None:
                    parts.append(f"{self.messages} of its {self.expected_messages} messages copied")
            if self.cut is not None:
                parts.append(f"source incomplete, read up to byte {self.stopped_at}")
            state = "; ".join(parts) or f"source incomplete: {self.problem}"
        return (
            f"{self.target}: recovered {self.messages} messages on {self.channels} channels, "
            f"{self.attachments} attachments, {self.metadata} metadata records ({state})"
        )


def recover(source: str | os.PathLike[str], target: str | os.PathLike[str]) -> RecoverReport:
    recording = Recording(source)
    target_path = Path(target)
    if target_path.exists() and target_path.resolve() == recording.path.resolve():
        raise RecordingError("the output must be a different file", Mark(str(target)))
    if target_path.is_dir():
        raise RecordingError("is a directory", Mark(str(target)))
    counts = {"messages": 0, "channels": 0, "attachments": 0, "metadata": 0}
    with whole_file_or_none(target_path) as temp, open(temp, "wb") as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        writer.start(profile=recording.profile, library=recording.library)
        schemas: dict[tuple[str, str, bytes], int] = {}
        channel_ids: dict[int, int] = {}
        for item in recording.items():
            if isinstance(item, RawMessage):
                writer.add_message(
                    channel_id=channel_ids[item.channel.id],
                    log_time=item.log_time_ns,
                    data=item.data,
                    publish_time=item.publish_time_ns,
                    sequence=item.sequence,
                )
                counts["messages"] += 1
            elif isinstance(item, ChannelInfo):
                channel_ids[item.id] = _register(writer, schemas, item)
                counts["channels"] += 1
            elif isinstance(item, RecordedAttachment):
                writer.add_attachment(
                    create_time=item.create_time_ns,
                    log_time=item.log_time_ns,
                    name=item.name,
                    media_type=item.media_type,
                    data=item.data,
                )
                counts["attachments"] += 1
            elif isinstance(item, Metadata):
                writer.add_metadata(item.name, dict(item.metadata))
                counts["metadata"] += 1
        end = recording.end
        if not end.complete:
            # The copy is complete as a file, not as a recording: it says what it lacks.
            writer.add_metadata(RECOVER_METADATA_NAME, _what_is_missing(recording.name, end))
        writer.finish()
        stream.flush()  # a full disk is an error here, inside the block
    return RecoverReport(
        source=recording.name,
        target=str(target),
        messages=counts["messages"],
        channels=counts["channels"],
        attachments=counts["attachments"],
        metadata=counts["metadata"],
        source_complete=end.complete,
        stopped_at=end.offset,
        problem=end.problem,
        damages=end.damages,
        expected_messages=end.expected_messages,
        cut=end.cut,
    )


def _what_is_missing(source: str, end: ScanEnd) -> dict[str, str]:
    """The `aeroexec_recover` metadata: the source, and each part of it not copied."""
    values = {
        "source": Path(source).name,
        "messages_copied": str(end.messages_read),
        "messages_expected": "" if end.expected_messages is None else str(end.expected_messages),
        "damaged_regions": str(len(end.damages)),
    }
    for number, damage in enumerate(end.damages, 1):
        values[f"damage_{number}"] = damage.describe()
    if end.cut is not None:
        values["cut"] = end.cut
    return values


def _register(
    writer: Writer, schemas: dict[tuple[str, str, bytes], int], channel: ChannelInfo
) -> int:
    schema_id = 0
    if channel.schema_name or channel.schema_encoding or channel.schema_data:
        key = (channel.schema_name, channel.schema_encoding, channel.schema_data)
        schema_id = schemas.get(key, 0)
        if not schema_id:
            schema_id = writer.register_schema(
                name=channel.schema_name, encoding=channel.schema_encoding, data=channel.schema_data
            )
            schemas[key] = schema_id
    return writer.register_channel(
        topic=channel.topic,
        message_encoding=channel.message_encoding,
        schema_id=schema_id,
        metadata=dict(channel.metadata),
    )
