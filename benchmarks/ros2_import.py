"""Benchmark: `aeroexec import` of ROS 2 bags (MCAP and sqlite3 storage) vs rosbags
reading them, and the import's memory against the bag's length.

Targets: docs/design.md#performance-targets (issue 29: import <= 1.5x rosbags' read +
deserialize on the same bag, for both storages; memory flat in bag size).

Bags: a synthetic Aerostack2 flight written here with rosbags' rosbag2 writer from the
as2_msgs definitions aeroexec ships, --minutes long: `self_localization/pose` at 30 Hz,
four behavior servers' `behavior_status` at 10 Hz each, `platform/info` at 10 Hz, and
an activation every 5 s (each goal ACCEPTED, EXECUTING, SUCCEEDED on `_action/status`,
RUNNING for 4 s): every mapped topic, so the import decodes what it uses, derives the
timeline, and reconstructs every activation.

* time: `import_bag` against rosbags reading every message and deserializing it with the
  bag's own definitions, types built first (warm; the import keeps its type stores for
  the process too, and a warm-up import built them). Median CPU time of --repeat
  interleaved runs (shared machine). The floor line beside it: what any importer built
  on rosbags' reader and mcap's Python `Writer` pays at least, each part measured alone
  and printed under it: rosbags reading every message's bytes (no deserializing), rosbags
  deserializing the very messages the import decoded (the poses that give a vehicle
  state, the platform info before each, the behavior and goal statuses that changed:
  recorded during the warm-up import), and the `mcap` library alone writing the very
  records the import wrote, already encoded, with the import's chunk size and
  compression. The import's distance to the floor is its own work (deciding what to
  decode, the timeline, reconstruction, ordering, JSON).
* memory: the peak Python allocation (tracemalloc) of one import of a 2-minute and of a
  --minutes flight: their ratio should stay near 1 (the import streams: messages wait
  about a second of bag time for the reconstruction, never the whole bag).

    .venv/bin/python benchmarks/ros2_import.py [--repeat 5] [--minutes 10]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import tracemalloc
from pathlib import Path

import numpy as np
from bag_import import mcap_alone, written_records
from figures import Figure, interleaved, timed
from rosbags.rosbag2 import Reader, StoragePlugin, Writer

from aeroexec.bags import import_bag
from aeroexec.bags.ros2types import Ros2Types
from aeroexec.bags.types import Decoder, TypeResolver

TARGET = 1.5
MEMORY_TARGET = 1.2
NS = 1_000_000_000
BEHAVIORS = ("TakeoffBehavior", "GoToBehavior", "FollowPathBehavior", "LandBehavior")


def synthetic_flight(path: Path, minutes: float, storage: str) -> Path:
    store = Ros2Types().store
    T = store.types
    start = 1_764_000_000 * NS
    end = start + int(minutes * 60 * NS)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3

    def stamp(t: int) -> object:
        return T["builtin_interfaces/msg/Time"](sec=t // NS, nanosec=t % NS)

    def header(t: int, frame: str) -> object:
        return T["std_msgs/msg/Header"](stamp=stamp(t), frame_id=frame)

    def active(behavior: int, t: int) -> bool:
        k, offset = divmod(t - start, 5 * NS)
        return k % len(BEHAVIORS) == behavior and offset < 4 * NS

    with Writer(path, version=8, storage_plugin=plugin) as writer:
        pose_t, status_t = "geometry_msgs/msg/PoseStamped", "as2_msgs/msg/BehaviorStatus"
        info_t, goals_t = "as2_msgs/msg/PlatformInfo", "action_msgs/msg/GoalStatusArray"
        pose_c = writer.add_connection("/drone0/self_localization/pose", pose_t, typestore=store)
        info_c = writer.add_connection("/drone0/platform/info", info_t, typestore=store)
        status_c = [
            writer.add_connection(
                f"/drone0/{b}/_behavior/behavior_status", status_t, typestore=store
            )
            for b in BEHAVIORS
        ]
        goals_c = [
            writer.add_connection(f"/drone0/{b}/_action/status", goals_t, typestore=store)
            for b in BEHAVIORS
        ]
        tick = start
        step = NS // 30
        n = 0
        while tick < end:
            pose = T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](x=n * 0.01, y=0.0, z=1.5),
                orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            )
            message = T[pose_t](header=header(tick, "earth"), pose=pose)
            writer.write(pose_c, tick, store.serialize_cdr(message, pose_t))
            if n % 3 == 0:  # 10 Hz
                for b, connection in enumerate(status_c):
                    status = T[status_t](status=1 if active(b, tick) else 0)
                    writer.write(connection, tick + 1, store.serialize_cdr(status, status_t))
                info = T[info_t](
                    header=header(tick, "drone0/base_link"),
                    connected=True,
                    armed=True,
                    offboard=True,
                    status=T["as2_msgs/msg/PlatformStatus"](state=3),
                    current_control_mode=T["as2_msgs/msg/ControlMode"](
                        header=header(tick, ""), yaw_mode=1, control_mode=2
                    ),
                )
                writer.write(info_c, tick + 2, store.serialize_cdr(info, info_t))
            offset = (tick - start) % (5 * NS)
            if offset < step or 4 * NS <= offset < 4 * NS + step:
                k = (tick - start) // (5 * NS)
                uuid = T["unique_identifier_msgs/msg/UUID"](uuid=np.full(16, k % 256, np.uint8))
                goal = T["action_msgs/msg/GoalInfo"](goal_id=uuid, stamp=stamp(tick))
                state = 2 if offset < step else 4
                array = T[goals_t](
                    status_list=[T["action_msgs/msg/GoalStatus"](goal_info=goal, status=state)]
                )
                writer.write(
                    goals_c[k % len(BEHAVIORS)], tick + 3, store.serialize_cdr(array, goals_t)
                )
            tick += step
            n += 1
    return path


def decoders(path: Path) -> dict[int, Decoder]:
    resolver = TypeResolver()
    with Reader(path) as reader:
        return {
            c.id: resolver.decoder(c.msgtype, c.msgdef.data, "", "ros2msg")
            for c in reader.connections
        }


def rosbags_read(path: Path) -> int:
    """rosbags reading every message's bytes, deserializing none."""
    count = 0
    with Reader(path) as reader:
        for _ in reader.messages():
            count += 1
    return count


def decoded_by_import(path: Path, target: Path) -> list[tuple[Decoder, bytes]]:
    """The messages one import decodes, with their decoders (in order)."""
    seen: list[tuple[Decoder, bytes]] = []
    decode = Decoder.decode

    def recording(self: Decoder, data: bytes | memoryview) -> object:
        seen.append((self, bytes(data)))
        return decode(self, data)

    Decoder.decode = recording  # type: ignore[method-assign]
    try:
        import_bag(path, target)
    finally:
        Decoder.decode = decode  # type: ignore[method-assign]
    return seen


def decode_alone(messages: list[tuple[Decoder, bytes]]) -> None:
    for decoder, data in messages:
        decoder.decode(data)


def rosbags_warm(path: Path, found: dict[int, Decoder]) -> int:
    count = 0
    with Reader(path) as reader:
        for connection, _, data in reader.messages():
            found[connection.id].decode(data)
            count += 1
    return count


def peak_memory(path: Path, target: Path) -> float:
    tracemalloc.start()
    import_bag(path, target)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 1e6


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--minutes", type=float, default=10.0)
    args = parser.parse_args(argv)
    print(
        "ROS 2 bag import vs rosbags read + deserialize, CPU time, median of "
        f"{args.repeat} interleaved runs (shared machine)"
    )
    failed = False
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        for storage in ("mcap", "sqlite3"):
            bag = synthetic_flight(work / f"flight_{storage}", args.minutes, storage)
            short = synthetic_flight(work / f"short_{storage}", 2.0, storage)
            target = work / f"{storage}.mcap"
            report = import_bag(bag, target)  # warm-up: type stores kept for the process
            found = decoders(bag)
            records = written_records(target)
            needed = decoded_by_import(bag, target)
            alone = work / f"{storage}-alone.mcap"
            medians = interleaved(
                {
                    "import": timed(lambda bag=bag, target=target: import_bag(bag, target)),
                    "rosbags": timed(lambda bag=bag, found=found: rosbags_warm(bag, found)),
                    "read": timed(lambda bag=bag: rosbags_read(bag)),
                    "decode": timed(lambda needed=needed: decode_alone(needed)),
                    "mcap": timed(lambda alone=alone, records=records: mcap_alone(alone, records)),
                },
                args.repeat,
            )
            size = sum(f.stat().st_size for f in bag.iterdir()) / 1e6
            figure = Figure(
                f"import {storage} flight ({args.minutes:g} min, {report.messages:,} messages, "
                f"{size:.1f} MB)",
                medians["import"],
                medians["rosbags"],
                "rosbags, types built first",
                TARGET,
            )
            failed |= not figure.ok
            print(figure.line())
            rosbags = medians["rosbags"]
            floor = medians["read"] + medians["decode"] + medians["mcap"]
            floor_line = Figure("  floor: the three parts below", floor, rosbags, "rosbags", TARGET)
            print(floor_line.line())
            for name, part in (
                ("rosbags reading the bytes, decoding none", "read"),
                (f"rosbags decoding the {len(needed):,} messages the import decodes", "decode"),
                (f"mcap alone writing the same {len(records):,} records", "mcap"),
            ):
                part_line = Figure(f"    {name}", medians[part], rosbags, "rosbags", TARGET)
                print(part_line.line().rsplit(" | target", 1)[0])
            long_peak = peak_memory(bag, target)
            short_peak = peak_memory(short, work / f"short_{storage}.mcap")
            memory = Figure(
                f"  peak memory, {args.minutes:g}-min flight",
                long_peak,
                short_peak,
                "the 2-min flight's",
                MEMORY_TARGET,
                unit="MB",
            )
            failed |= not memory.ok
            print(memory.line())
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
