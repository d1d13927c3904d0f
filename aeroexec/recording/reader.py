"""Read an aeroexec recording (or any MCAP file) as typed records, streaming.

    rec = open_recording("flight.mcap")
    rec.complete                  # False when the footer is missing (crash, kill)
    rec.metadata["aeroexec"]      # {"seed": "0", "clock": "sim", ...}
    rec.attachment("catalog.yaml").text
    for item in rec.records():    # RecordedCall | RecordedTopic, in file order
        ...

`records()` decodes JSON messages only: a foreign file (a ROS 2 `cdr` bag, say) is still
readable for its channels and counts (`messages()`, `survey()`), and the messages that
could not be decoded are reported in `notes` instead of failing. Every pass streams the
file (one chunk in memory at a time); nothing keeps the messages. A damaged or truncated
file is read up to the damage: `complete` is False and `problem` says where reading
stopped.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from mcap.records import Attachment, Channel, DataEnd, Message, Metadata, Schema

from aeroexec.recording.scan import RecordScanner, ScanEnd
from aeroexec.recording.schemas import MESSAGE_ENCODING, PROFILE, SERVICE_CALL


@dataclass(frozen=True, slots=True)
class ChannelInfo:
    id: int
    topic: str
    message_encoding: str
    schema_name: str
    schema_encoding: str
    schema_data: bytes = field(repr=False)
    metadata: tuple[tuple[str, str], ...] = ()


def attachment_place(recording: str | os.PathLike[str], name: str) -> str:
    """The file of a `Mark` inside attachment `name` of `recording`: `REC#NAME` (then
    `:LINE:COL`), as a URL names a fragment of a page. A tampered attachment is the
    recording's fault: its errors must name the recording, not the file it was copied
    from."""
    return f"{os.fspath(recording)}#{name}"


@dataclass(frozen=True, slots=True)
class RecordedAttachment:
    name: str
    media_type: str
    log_time_ns: int
    create_time_ns: int
    data: bytes = field(repr=False)

    @property
    def text(self) -> str:
        return self.data.decode("utf-8", errors="replace")


@dataclass(frozen=True, slots=True)
class RawMessage:
    """One message as stored: channel, times, MCAP sequence number, undecoded bytes."""

    channel: ChannelInfo
    log_time_ns: int
    publish_time_ns: int
    sequence: int
    data: bytes = field(repr=False)


@dataclass(frozen=True, slots=True)
class RecordedCall:
    """A completed service call (a message on a `aeroexec.ServiceCall` channel)."""

    topic: str
    log_time_ns: int
    seq: int
    parent_seq: int | None
    caller: str
    service: str
    request: dict[str, Any]
    response: dict[str, Any]

    @property
    def ok(self) -> bool:
        return bool(self.response.get("ok"))

    @property
    def error(self) -> str:
        return str(self.response.get("error", ""))


@dataclass(frozen=True, slots=True)
class RecordedTopic:
    """A topic message: `topic` is the channel topic (`/drone1/behavior_event`), `name`
    the topic inside the drone's namespace (`behavior_event`)."""

    topic: str
    name: str
    log_time_ns: int
    data: Any


Record = RecordedCall | RecordedTopic


@dataclass(frozen=True, slots=True)
class Survey:
    """What one pass over the whole file found (no message kept)."""

    channels: dict[int, ChannelInfo]
    counts: dict[int, int]
    metadata: dict[str, dict[str, str]]
    attachments: tuple[RecordedAttachment, ...]
    first_log_time_ns: int | None
    last_log_time_ns: int | None
    end: ScanEnd

    @property
    def message_count(self) -> int:
        return sum(self.counts.values())

    def topic_counts(self) -> dict[str, int]:
        """Topic -> message count, in channel order (channels sharing a topic add up)."""
        out: dict[str, int] = {}
        for cid, channel in self.channels.items():
            out[channel.topic] = out.get(channel.topic, 0) + self.counts.get(cid, 0)
        return out


def _strip_namespace(topic: str) -> str:
    parts = topic.split("/", 2)
    if len(parts) == 3 and parts[0] == "":
        return parts[2]
    return topic.lstrip("/")


class Recording:
    """An MCAP file opened for reading. Construction reads only the header; each pass
    (`messages`, `records`, `survey`) streams the file again."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self._scanner = RecordScanner(path)
        self.path = self._scanner.path
        self.name = self._scanner.name
        self.profile: str = self._scanner.header.profile
        self.library: str = self._scanner.header.library
        self.notes: list[str] = []
        self._survey: Survey | None = None
        self._end: ScanEnd | None = None
        self._summary: tuple[dict[int, Schema], dict[int, Channel]] | None = None

    @property
    def is_aeroexec(self) -> bool:
        return self.profile == PROFILE

    # -- whole-file facts (one survey pass, cached) ---------------------------------------
    def survey(self) -> Survey:
        if self._survey is None:
            self._survey = self._run_survey()
        return self._survey

    @property
    def end(self) -> ScanEnd:
        """How the last full pass ended (runs the survey if no pass has finished)."""
        return self._ended()

    @property
    def complete(self) -> bool:
        """True when the footer was read (the writer closed the file)."""
        return self._ended().complete

    @property
    def problem(self) -> str | None:
        """Why reading stopped before the footer (None for a complete file)."""
        return self._ended().problem

    @property
    def metadata(self) -> dict[str, dict[str, str]]:
        return self.survey().metadata

    @property
    def attachments(self) -> tuple[RecordedAttachment, ...]:
        return self.survey().attachments

    @property
    def channels(self) -> dict[int, ChannelInfo]:
        return self.survey().channels

    def attachment(self, name: str) -> RecordedAttachment | None:
        for item in self.attachments:
            if item.name == name:
                return item
        return None

    # -- passes -----------------------------------------------------------------------------
    def items(self) -> Iterator[ChannelInfo | RawMessage | RecordedAttachment | Metadata]:
        """Everything in file order: each channel when it first appears, messages,
        attachments, metadata records. Records of the summary section (repeated
        channels and schemas, indexes, statistics) are not repeated here."""
        schemas: dict[int, Schema] = {}
        channels: dict[int, ChannelInfo] = {}
        in_summary = False
        for _, record in self._scanner.records():
            if isinstance(record, Message):
                channel = channels.get(record.channel_id)
                if channel is None:
                    channel = self._unknown_channel(record.channel_id)
                    channels[record.channel_id] = channel
                    yield channel
                yield RawMessage(
                    channel, record.log_time, record.publish_time, record.sequence, record.data
                )
            elif isinstance(record, Schema):
                schemas.setdefault(record.id, record)
            elif isinstance(record, Channel):
                if record.id not in channels:
                    info = _channel_info(record, schemas.get(record.schema_id))
                    channels[record.id] = info
                    if not in_summary:
                        yield info
            elif isinstance(record, Attachment):
                yield RecordedAttachment(
                    record.name,
                    record.media_type,
                    record.log_time,
                    record.create_time,
                    record.data,
                )
            elif isinstance(record, Metadata):
                yield record
            elif isinstance(record, DataEnd):
                in_summary = True
        self._end = self._scanner.end

    def messages(self) -> Iterator[RawMessage]:
        """Every readable message, undecoded, in file order."""
        for item in self.items():
            if isinstance(item, RawMessage):
                yield item

    def records(self) -> Iterator[Record]:
        """Typed, decoded records (JSON channels only), in file order. Messages that are
        not JSON (or not valid JSON) are skipped and counted in `notes`."""
        skipped: dict[str, int] = {}
        invalid = 0
        for message in self.messages():
            channel = message.channel
            if channel.message_encoding != MESSAGE_ENCODING:
                key = channel.message_encoding or "unencoded"
                skipped[key] = skipped.get(key, 0) + 1
                continue
            try:
                data = json.loads(message.data)
            except ValueError:
                invalid += 1
                continue
            record = _typed(channel, message.log_time_ns, data)
            if record is None:
                invalid += 1
                continue
            yield record
        for encoding, count in sorted(skipped.items()):
            self.notes.append(
                f"{count} {encoding} message(s) not decoded (typed records need JSON)"
            )
        if invalid:
            self.notes.append(f"{invalid} JSON message(s) could not be decoded")

    # -- internals ---------------------------------------------------------------------------
    def _ended(self) -> ScanEnd:
        if self._end is None:
            self.survey()
        assert self._end is not None
        return self._end

    def _run_survey(self) -> Survey:
        channels: dict[int, ChannelInfo] = {}
        counts: dict[int, int] = {}
        metadata: dict[str, dict[str, str]] = {}
        attachments: list[RecordedAttachment] = []
        first: int | None = None
        last: int | None = None
        for item in self.items():
            if isinstance(item, RawMessage):
                cid = item.channel.id
                counts[cid] = counts.get(cid, 0) + 1
                t = item.log_time_ns
                if first is None or t < first:
                    first = t
                if last is None or t > last:
                    last = t
            elif isinstance(item, ChannelInfo):
                channels[item.id] = item
                counts.setdefault(item.id, 0)
            elif isinstance(item, RecordedAttachment):
                attachments.append(item)
            else:
                metadata[item.name] = dict(item.metadata)
        assert self._end is not None
        return Survey(channels, counts, metadata, tuple(attachments), first, last, self._end)

    def _unknown_channel(self, channel_id: int) -> ChannelInfo:
        if self._summary is None:
            self._summary = self._scanner.summary_definitions()
        schemas, channels = self._summary
        channel = channels.get(channel_id)
        if channel is not None:  # its definition was lost with a damaged chunk
            return _channel_info(channel, schemas.get(channel.schema_id))
        self.notes.append(f"messages on channel {channel_id}, which the file never defines")
        return ChannelInfo(channel_id, f"<channel {channel_id}>", "", "", "", b"")


def _channel_info(channel: Channel, schema: Schema | None) -> ChannelInfo:
    return ChannelInfo(
        id=channel.id,
        topic=channel.topic,
        message_encoding=channel.message_encoding,
        schema_name=schema.name if schema else "",
        schema_encoding=schema.encoding if schema else "",
        schema_data=schema.data if schema else b"",
        metadata=tuple(channel.metadata.items()),
    )


def decode_record(channel: ChannelInfo, log_time_ns: int, data: bytes) -> Record | None:
    """One message's typed record, as `Recording.records` gives it (None when its
    channel is not JSON or it does not decode): the live view reads what is written
    through this, as `view` reads the file."""
    if channel.message_encoding != MESSAGE_ENCODING:
        return None
    try:
        value = json.loads(data)
    except ValueError:
        return None
    return _typed(channel, log_time_ns, value)


def _typed(channel: ChannelInfo, log_time_ns: int, data: Any) -> Record | None:
    if channel.schema_name == SERVICE_CALL:
        if not isinstance(data, dict):
            return None
        try:
            return RecordedCall(
                topic=channel.topic,
                log_time_ns=log_time_ns,
                seq=int(data["seq"]),
                # Absent at the top (null in older recordings).
                parent_seq=_parent_seq(data.get("parent_seq")),
                caller=str(data["caller"]),
                service=str(data["service"]),
                request=dict(data["request"]),
                response=dict(data["response"]),
            )
        except (KeyError, TypeError, ValueError):
            return None
    return RecordedTopic(channel.topic, _strip_namespace(channel.topic), log_time_ns, data)


def _parent_seq(value: Any) -> int | None:
    return value if isinstance(value, int) and not isinstance(value, bool) else None


def open_recording(path: str | os.PathLike[str]) -> Recording:
    """Open `path` for reading; `RecordingError` (one line) if it is not readable MCAP."""
    return Recording(path)
