"""Which bag a path is, and opening it: ROS 1 (`bagfile.py`) or ROS 2 (`ros2file.py`).

Both readers give the importer, `info` and `replay` the same face: `connections`
(`BagConnection`), `messages()` in time order, counts, times, `compression_text`,
`ros_version`."""

from __future__ import annotations

import os
from pathlib import Path

from aeroexec.bags.bagfile import BagFile, is_ros1_bag, open_ros1_bag
from aeroexec.bags.ros2file import Ros2Bag, is_ros2_bag
from aeroexec.bags.ros2types import Ros2Types
from aeroexec.inputs import is_directory

Bag = BagFile | Ros2Bag


def is_bag(path: str | os.PathLike[str]) -> bool:
    """A ROS 1 bag (`.bag` or its magic) or a ROS 2 one (a rosbag2 directory, a `.db3`,
    an MCAP file of profile `ros2`)."""
    return is_ros1_bag(path) or is_ros2_bag(path)


def ros_version_of(path: str | os.PathLike[str]) -> int:
    """2 for what `open_bag` reads as ROS 2 (a `.mcap`, a `.db3`, a directory not named
    `.bag`), else 1."""
    file = Path(path)
    suffix = file.suffix.lower()
    return 2 if suffix in (".mcap", ".db3") or (is_directory(file) and suffix != ".bag") else 1


def open_bag(path: str | os.PathLike[str], types_dir: str | os.PathLike[str] | None = None) -> Bag:
    """Open a ROS 1 or ROS 2 bag (`RecordingError`, one line, when it cannot be read).
    A `.mcap`, `.db3` or a directory is read as ROS 2; anything else (`.bag`) as ROS 1.
    `types_dir`: `.msg`/`.srv`/`.action` folders for a ROS 2 bag without definitions."""
    if ros_version_of(path) == 2:
        return Ros2Bag(path, Ros2Types(types_dir))
    return open_ros1_bag(path)
