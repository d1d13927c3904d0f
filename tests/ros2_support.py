"""Helpers shared by the ROS 2 bag tests: the fixture bags, their directory forms, and
what rosbags and the mcap library read of a bag and of its import."""

from __future__ import annotations

import shutil
from collections import defaultdict
from pathlib import Path

from mcap.reader import make_reader
from rosbags.rosbag2 import Reader

REPO = Path(__file__).resolve().parent.parent
ROS2 = REPO / "tests" / "fixtures" / "ros2"
TALKER = ROS2 / "mcap_ros2_talker_zstd.mcap"
MSGTYPES = ROS2 / "mcap_ros2_94_msgtypes_rosbags_rs.mcap"
SERVICES_MCAP = ROS2 / "ros2_rosbag2_service_events.mcap"
SERVICES_DB3 = ROS2 / "ros2_rosbag2_service_events.db3"
ADD_TWO_INTS = ROS2 / "ros2_rosbag2_add_two_ints_service_events.mcap"
REAL_FILES = (TALKER, MSGTYPES, SERVICES_MCAP, SERVICES_DB3, ADD_TWO_INTS)
#: The name rosbag2 gave the service-event bags (their metadata.yaml lists it).
DIRECTORY_BAG_NAME = "bag_with_topics_and_service_events"


def as_directory(bag: Path, folder: Path) -> Path:
    """The rosbag2 directory form of a fixture that has a `.metadata.yaml`."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(bag, folder / f"{DIRECTORY_BAG_NAME}{bag.suffix}")
    shutil.copyfile(bag.with_name(bag.name + ".metadata.yaml"), folder / "metadata.yaml")
    return folder


def bag_streams(path: Path) -> dict[str, list[tuple[int, bytes]]]:
    """Topic -> sorted (log time, bytes) of every message, as rosbags reads the bag."""
    streams: dict[str, list[tuple[int, bytes]]] = defaultdict(list)
    with Reader(path) as reader:
        for connection in reader.connections:
            streams.setdefault(connection.topic, [])
        for connection, time_ns, data in reader.messages():
            streams[connection.topic].append((time_ns, bytes(data)))
    return {topic: sorted(items) for topic, items in streams.items()}


def raw_streams(path: Path) -> dict[str, list[tuple[int, bytes]]]:
    """Original topic -> sorted (log time, bytes) of the raw cdr channels of an import,
    as the mcap library reads it (channels without messages included)."""
    streams: dict[str, list[tuple[int, bytes]]] = {}
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        for channel in summary.channels.values():
            if channel.message_encoding == "cdr":
                streams[channel.metadata["topic"]] = []
        for _, channel, message in reader.iter_messages(log_time_order=False):
            if channel.message_encoding == "cdr":
                streams[channel.metadata["topic"]].append((message.log_time, message.data))
    return {topic: sorted(items) for topic, items in streams.items()}
