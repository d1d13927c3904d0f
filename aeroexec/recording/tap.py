"""`RecordTap`: what sees a recording as it is written (the live view, `--live`).

A tap is told what the recorder writes, when it writes it: the session's metadata and
attachments once, each channel when it is created, then each message with its channel,
log time and the very bytes handed to the MCAP writer; and when the file is finished.
It sees no other encoding of the session: a live viewer gets the recording itself.

Every call comes from inside the recorder (on the session's thread, in a file the
signal watchdog never cuts short): a tap does not block for long and does not raise.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol

from aeroexec.recording.reader import ChannelInfo


class RecordTap(Protocol):
    def recording_started(
        self, metadata: Mapping[str, str], attachments: Mapping[str, bytes]
    ) -> None:
        """The header's metadata (`aeroexec` record) and the attachments, by name."""
        ...

    def channel_added(self, channel: ChannelInfo) -> None:
        """A channel (with its schema), before its first message."""
        ...

    def message_written(self, channel_id: int, log_time_ns: int, data: bytes) -> None:
        """One message, as written: its channel's id, log time and bytes."""
        ...

    def recording_closed(self) -> None:
        """The file is finished (or lost): no more messages."""
        ...


def reading_of(
    channel_id: int,
    topic: str,
    schema_name: str,
    schema_encoding: str,
    schema: bytes,
    encoding: str,
) -> ChannelInfo:
    """The channel as a reader of the finished file will see it."""
    return ChannelInfo(channel_id, topic, encoding, schema_name, schema_encoding, schema)
