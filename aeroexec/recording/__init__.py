"""MCAP recording of executive sessions: the aeroexec profile (see docs/recording.md).

- `Recorder` (writer.py): the bus observer that writes a session, deterministic and
  crash-safe (flush bound: 100 messages or 4 MiB; live flights also 0.5 s of wall clock);
- `open_recording` (reader.py): typed, streaming reading of a recording, complete or not;
- `recover` (recover.py): salvage an unfinished or damaged file into a complete one;
- `recording_info` (info.py): what `aeroexec info` prints;
- `schemas` (schemas.py): the JSON Schemas of the profile's channels.
"""

from __future__ import annotations

from aeroexec.recording.info import BehaviorRun, InfoReport, recording_info
from aeroexec.recording.reader import (
    ChannelInfo,
    RawMessage,
    RecordedAttachment,
    RecordedCall,
    RecordedTopic,
    Recording,
    open_recording,
)
from aeroexec.recording.recover import RecoverReport, recover
from aeroexec.recording.schemas import PROFILE
from aeroexec.recording.writer import FLUSH_BYTES, FLUSH_INTERVAL_NS, FLUSH_MESSAGES, Recorder

__all__ = [
    "FLUSH_BYTES",
    "FLUSH_INTERVAL_NS",
    "FLUSH_MESSAGES",
    "PROFILE",
    "BehaviorRun",
    "ChannelInfo",
    "InfoReport",
    "RawMessage",
    "RecordedAttachment",
    "RecordedCall",
    "RecordedTopic",
    "Recorder",
    "Recording",
    "RecoverReport",
    "open_recording",
    "recording_info",
    "recover",
]
