"""ROS 1 and ROS 2 bags: read them (rosbags, with Aerostack's message definitions
shipped in `aeroexec/data/msg/` and Aerostack2's in `aeroexec/data/msg_ros2/`), import
them into the aeroexec MCAP profile without losing a byte, and let `info`, `view` and
`replay` take them directly. See docs/bags.md.

- `import_bag(bag, out.mcap, mapping=None, drone=None, types_dir=None)` (importer.py) ->
  `ImportReport`;
- `load_mapping(path | None, ros_version)` (mapping.py): the topic mapping (default:
  Aerostack's names for ROS 1, Aerostack2's for ROS 2);
- `open_bag(path)` (source.py): a checked, streaming reader of either (`bagfile.py`,
  `ros2file.py`); `is_bag(path)`;
- `bag_info(path)` (info.py): what `aeroexec info BAG` prints;
- `bag_recording(path)` (replay.py): a bag imported to a temporary recording, for the
  replay engine (its `replay_bag` for `.bag` inputs) and `view`;
- `aerostack_typestore()` (types.py): rosbags' Noetic store plus Aerostack's types;
  `Ros2Types` (ros2types.py): Jazzy's plus Aerostack2's and `--types`.
"""

from __future__ import annotations

from aeroexec.bags.bagfile import BagConnection, BagFile
from aeroexec.bags.importer import ImportReport, import_bag
from aeroexec.bags.mapping import Kind, Mapping, Rule, default_mapping_path, load_mapping
from aeroexec.bags.source import is_bag, open_bag
from aeroexec.bags.types import aerostack_typestore

__all__ = [
    "BagConnection",
    "BagFile",
    "ImportReport",
    "Kind",
    "Mapping",
    "Rule",
    "aerostack_typestore",
    "default_mapping_path",
    "import_bag",
    "is_bag",
    "load_mapping",
    "open_bag",
]
