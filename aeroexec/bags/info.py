"""`aeroexec info BAG`: a ROS 1 or ROS 2 bag summarized in the same report as an MCAP
recording.

Topics with their ROS 1 types and message counts, time span, compression, chunk and
connection counts from the bag's index; every chunk is then read (decompressed, with its
checksums, but no message decoded), so a bag `import` would refuse is not called
complete. The report
is `aeroexec.recording.info.InfoReport`, so text and JSON look like those of a recording
(`messages`, `channels` as topic -> count, `channel_details`); a topic with several
connections (one per publisher) is one channel here, and the metadata counts connections.
"""

from __future__ import annotations

import os

from aeroexec.bags.bagfile import BagConnection
from aeroexec.bags.source import Bag, open_bag
from aeroexec.errors import RecordingError
from aeroexec.recording.info import ChannelSummary, InfoReport

PROFILE = "ros1"
LIBRARY = "rosbag v2.0"
METADATA_NAME = "ros1_bag"
#: By ROS version: the profile, the metadata name, the message encoding.
PROFILES = {1: PROFILE, 2: "ros2"}
METADATA_NAMES = {1: METADATA_NAME, 2: "ros2_bag"}


def _types(connections: list[BagConnection]) -> str:
    return ", ".join(dict.fromkeys(c.schema_name or c.type for c in connections))


def _first_damage(bag: Bag) -> str | None:
    """Decompress every chunk (messages are not decoded): the first damage, or None."""
    try:
        for _ in bag.messages():
            pass
    except RecordingError as exc:
        return exc.message
    return None


def bag_info(path: str | os.PathLike[str]) -> InfoReport:
    """The summary of the bag at `path` (`RecordingError`, one line, if it is not a
    readable bag)."""
    with open_bag(path) as bag:
        by_topic: dict[str, list[BagConnection]] = {}
        for connection in bag.connections:
            by_topic.setdefault(connection.topic, []).append(connection)
        channels = tuple(
            ChannelSummary(
                id=group[0].id,
                topic=topic,
                message_encoding=group[0].encoding,
                schema_name=_types(group),
                messages=sum(c.count for c in group),
            )
            for topic, group in sorted(by_topic.items())
        )
        metadata = {
            METADATA_NAMES[bag.ros_version]: {
                "format": bag.format,
                "bytes": str(bag.size),
                "compression": bag.compression_text,
                "chunks": str(bag.chunk_count),
                "connections": str(len(bag.connections)),
                "topics": str(len(by_topic)),
            }
        }
        notes = [
            f"a ROS {bag.ros_version} bag: `aeroexec import` converts it to an aeroexec "
            "recording (`aeroexec replay` takes it directly)"
        ]
        if bag.ros_version == 2:
            notes.extend(bag.notes)  # type: ignore[union-attr]
        # The index alone would call a bag complete whose chunks `import` then refuses
        # (an lz4 checksum, a message where the index says none is): read them all.
        problem = _first_damage(bag)
        multi = sum(1 for group in by_topic.values() if len(group) > 1)
        if multi:
            notes.append(
                f"{multi} topic(s) have several connections (publishers), counted together"
            )
        return InfoReport(
            file=bag.name,
            profile=PROFILES[bag.ros_version],
            library=LIBRARY if bag.ros_version == 1 else f"{bag.format} {bag.distro}".strip(),
            complete=problem is None,
            problem=problem,
            messages=bag.message_count,
            channels=channels,
            start_ns=bag.start_ns,
            end_ns=bag.end_ns,
            metadata=metadata,
            attachments=(),
            behaviors=(),
            notes=tuple(notes),
        )
