"""Benchmark: `aeroexec import` of ROS 1 bags vs rosbags reading them.

Targets: docs/design.md#performance-targets.

For each bag: the time of `aeroexec.bags.import_bag` (read every message, copy it raw to
the MCAP output, decode only the mapped topics, derive and write the aeroexec channels)
against rosbags reading and deserializing every message of the same bag. Two baselines:

* warm: rosbags with the type stores built beforehand (rosbags' code generation for the
  ~40 types of the Aerostack bag costs more than reading it): the stricter figure, and
  the target's. The import line is warm too: aeroexec keeps the stores it built for the
  process (keyed by definition text), and the warm-up import built them;
* cold: both from scratch: rosbags opening the bag, building a store per distinct
  definition, reading and deserializing every message (what a script using rosbags does),
  against an import after aeroexec's kept stores are dropped.

Bags: the four real test fixtures (tests/fixtures/bags/), and a synthetic Aerostack
mission written here (--minutes of flight: PoseStamped at 30 Hz, an activation every 2 s
with its end event and active lists), where the commands are reconstructed and every
derived message goes through the reorder heap.

The floor line: the warm baseline plus the `mcap` library alone writing the very records
the import wrote (schemas, channels, messages with their log times and sequence numbers,
bytes already encoded; the importer's chunk size and compression: `writer_options`). An
importer built on mcap's Python `Writer` reads the bag, decodes what it derives from and
hands every record to `add_message`: the distance from the import line down to the floor
is the importer's own work (reordering, deriving, JSON encoding). The floor decodes every
message, the importer only the mapped ones it uses (on the mission bag 6,901 of 18,900),
so a bag with few mapped messages (the fixtures) imports below the line; on the mission
bag it bounds what any importer writing through mcap's Writer can reach.

Definitions are parsed with aeroexec's lenient `.msg` parser (rosbags' own refuses the
CamelCase constants of Aerostack's ProcessState), so the baseline decodes everything.
Target (issue 17): import <= 1.5x rosbags (the warm baseline) on the Aerostack-style
mission bag; the other bags are printed for scale. Whole-process variant for the mission
bag: `python -m aeroexec import BAG -o OUT` against a fresh `python` that reads and
deserializes the bag with rosbags (its types built there: the cold baseline), CPU time
of each child. Every figure is the median of --repeat interleaved runs, CPU time (shared
machine: figures move by 10-20 %). One line per figure (figure, baseline, ratio,
target); exits 1 when the target is missed.

    .venv/bin/python benchmarks/bag_import.py [--repeat 5] [BAG ...]
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from figures import Figure, child_cpu, interleaved, timed
from mcap.reader import make_reader
from mcap.writer import Writer as McapWriter
from rosbags.rosbag1 import Reader, Writer

from aeroexec.bags import import_bag, types
from aeroexec.bags.sink import writer_options
from aeroexec.bags.types import Decoder, TypeResolver, aerostack_typestore

TARGET = 1.5
ROOT = Path(__file__).resolve().parent.parent
FIXTURES = Path(__file__).resolve().parent.parent / "tests" / "fixtures" / "bags"
DEFAULT_BAGS = (
    "aerostack_2017_first_view_ros1.bag",
    "ros1_rotors_waypoint_example_uncompressed.bag",
    "ros1_turtlesim_example_bz2.bag",
    "ros1_turtlesim_example_lz4.bag",
)


def synthetic_mission(path: Path, minutes: float) -> Path:
    """An Aerostack-style bag: PoseStamped at 30 Hz; every 2 s a behavior appears in the
    active list, and ends GOAL_ACHIEVED 1.5 s later (event, then the list without it)."""
    store = aerostack_typestore()
    pose_t = "geometry_msgs/msg/PoseStamped"
    event_t = "droneMsgsROS/msg/BehaviorEvent"
    list_t = "droneMsgsROS/msg/ListOfBehaviors"
    types = store.types
    start = 1_500_000_000 * 10**9
    messages: list[tuple[int, str, object]] = []
    steps = int(minutes * 60 * 30)
    for i in range(steps):
        t = start + i * 10**9 // 30
        stamp = types["builtin_interfaces/msg/Time"](sec=t // 10**9, nanosec=t % 10**9)
        header = types["std_msgs/msg/Header"](seq=i, stamp=stamp, frame_id="world")
        point = types["geometry_msgs/msg/Point"](x=i * 0.01, y=0.0, z=1.0)
        quat = types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
        pose = types["geometry_msgs/msg/Pose"](position=point, orientation=quat)
        messages.append((t, pose_t, types[pose_t](header=header, pose=pose)))
    header0 = types["std_msgs/msg/Header"](
        seq=0, stamp=types["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id=""
    )
    for k in range(int(minutes * 30)):
        t = start + k * 2 * 10**9
        name = ("GO_TO_POINT", "ROTATE", "WAIT")[k % 3]
        command = types["droneMsgsROS/msg/BehaviorCommand"](name=name, arguments="")
        listed = types[list_t](behaviors=[name], behavior_commands=[command])
        messages.append((t, list_t, listed))
        event = types[event_t](
            header=header0,
            name=name,
            uid=float(k),
            failed_belief="",
            belief_conflict="",
            behavior_event_code="GOAL_ACHIEVED",
        )
        messages.append((t + 1_500_000_000, event_t, event))
        messages.append(
            (t + 1_510_000_000, list_t, types[list_t](behaviors=[], behavior_commands=[]))
        )
    topics = {
        pose_t: "/drone1/self_localization/pose",
        event_t: "/drone1/behavior_event",
        list_t: "/drone1/list_of_active_behaviors",
    }
    with Writer(path) as writer:
        connections = {
            msgtype: writer.add_connection(topic, msgtype, typestore=store)
            for msgtype, topic in topics.items()
        }
        for t, msgtype, message in sorted(messages, key=lambda m: m[0]):
            writer.write(connections[msgtype], t, store.serialize_ros1(message, msgtype))
    return path


def _decoders(reader: Reader) -> dict[int, Decoder]:
    resolver = TypeResolver()
    found: dict[int, Decoder] = {}
    for c in reader.connections:
        with contextlib.suppress(ValueError):  # an undecodable type: counted below
            found[c.id] = resolver.decoder(c.msgtype, c.msgdef.data, c.digest)
    return found


def forget_types() -> None:
    """Drop the type stores aeroexec keeps for the process (a fresh process's state)."""
    types._store_from_text.cache_clear()


def rosbags_cold(path: Path) -> int:
    """Read and deserialize every message, building the types first. Messages decoded."""
    forget_types()
    decoded = 0
    with Reader(path) as reader:
        decoders = _decoders(reader)
        for connection, _, data in reader.messages():
            decoder = decoders.get(connection.id)
            if decoder is not None:
                decoder.decode(data)
                decoded += 1
    return decoded


def rosbags_warm(path: Path, decoders: dict[int, Decoder]) -> None:
    with Reader(path) as reader:
        for connection, _, data in reader.messages():
            decoder = decoders.get(connection.id)
            if decoder is not None:
                decoder.decode(data)


#: One message as the import wrote it: (schema name, schema encoding, schema data, topic,
#: message encoding, channel metadata, log time, publish time, sequence, data).
Record = tuple[str, str, bytes, str, str, dict[str, str], int, int, int, bytes]


def written_records(path: Path) -> list[Record]:
    """The messages of an MCAP file in file order, bytes as they are in it."""
    records: list[Record] = []
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            assert schema is not None
            records.append(
                (
                    schema.name,
                    schema.encoding,
                    schema.data,
                    channel.topic,
                    channel.message_encoding,
                    dict(channel.metadata),
                    message.log_time,
                    message.publish_time,
                    message.sequence,
                    message.data,
                )
            )
    return records


def mcap_alone(path: Path, records: list[Record]) -> None:
    """The floor's writing half: mcap's Writer alone writing `records` (already encoded),
    with the importer's options (chunk size, compression)."""
    with open(path, "wb") as stream:
        writer = McapWriter(stream, **writer_options("lz4"))
        writer.start(profile="aeroexec", library="benchmark")
        schemas: dict[tuple[str, str, bytes], int] = {}
        channels: dict[str, int] = {}
        add = writer.add_message
        for name, encoding, schema_data, topic, message_encoding, metadata, *message in records:
            channel = channels.get(topic)
            if channel is None:
                key = (name, encoding, schema_data)
                schema = schemas.get(key)
                if schema is None:
                    schema = schemas[key] = writer.register_schema(name, encoding, schema_data)
                channel = writer.register_channel(topic, message_encoding, schema, metadata)
                channels[topic] = channel
            log_time, publish_time, sequence, data = message
            add(channel, log_time, data, publish_time, sequence)
        writer.finish()


@dataclass(frozen=True)
class Measured:
    """Medians of one bag: the import, rosbags cold and warm, mcap alone."""

    imported: float
    imported_cold: float
    cold: float
    warm: float
    mcap: float
    messages: int
    decoded: int
    written: int


def measure(path: Path, workdir: Path, repeat: int) -> Measured:
    target = workdir / (path.stem + ".mcap")
    alone = workdir / (path.stem + "-alone.mcap")
    report = import_bag(path, target)  # warm-up: imports, caches
    records = written_records(target)
    decoded = rosbags_cold(path)
    with Reader(path) as reader:
        decoders = _decoders(reader)
    medians = interleaved(
        {
            "import": timed(lambda: import_bag(path, target)),
            "import cold": timed(lambda: (forget_types(), import_bag(path, target))),
            "cold": timed(lambda: rosbags_cold(path)),
            "warm": timed(lambda: rosbags_warm(path, decoders)),
            "mcap": timed(lambda: mcap_alone(alone, records)),
        },
        repeat,
    )
    return Measured(
        medians["import"],
        medians["import cold"],
        medians["cold"],
        medians["warm"],
        medians["mcap"],
        report.messages,
        decoded,
        len(records),
    )


#: A fresh process reading and deserializing BAG with rosbags (the whole-process floor).
ROSBAGS_SCRIPT = """
import sys
sys.path.insert(0, {benchmarks!r})
from bag_import import rosbags_cold
rosbags_cold(__import__("pathlib").Path({bag!r}))
"""


def whole_process(path: Path, workdir: Path, repeat: int, root: Path) -> Figure:
    script = ROSBAGS_SCRIPT.format(benchmarks=str(Path(__file__).parent), bag=str(path))
    out = workdir / "whole.mcap"
    command = [sys.executable, "-m", "aeroexec", "import", str(path), "-o", str(out)]
    medians = interleaved(
        {
            "import": lambda: child_cpu(command, str(root)),
            "rosbags": lambda: child_cpu([sys.executable, "-c", script], str(root)),
        },
        repeat,
    )
    return Figure(
        f"  whole process: aeroexec import {path.name}",
        medians["import"],
        medians["rosbags"],
        "python reading it with rosbags",
        TARGET,
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("bags", nargs="*", type=Path, help="bags (default: the test fixtures)")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--minutes", type=float, default=10.0, help="synthetic mission length")
    parser.add_argument(
        "--root", type=Path, default=ROOT, help="the checkout whole processes run (`python -m`)"
    )
    args = parser.parse_args(argv)
    print(
        "ROS 1 bag import vs rosbags read + deserialize, CPU time, median of "
        f"{args.repeat} interleaved runs (shared machine)"
    )
    failed = False
    with tempfile.TemporaryDirectory() as folder:
        bags = list(args.bags)
        mission = None
        if not bags:
            bags = [FIXTURES / name for name in DEFAULT_BAGS]
            mission = synthetic_mission(Path(folder) / "synthetic_mission.bag", args.minutes)
            bags.append(mission)
        for bag in bags:
            m = measure(bag, Path(folder), args.repeat)
            named = bag == mission or mission is None
            label = f"{bag.name} ({m.messages:,} messages, {bag.stat().st_size / 1e6:.1f} MB)"
            if m.decoded != m.messages:
                label += f", {m.decoded:,} decodable"
            warm = "rosbags, types built first"
            figure = Figure(
                f"import {label}" + ("" if named else " (for scale)"),
                m.imported,
                m.warm,
                warm,
                TARGET,
            )
            failed |= named and not figure.ok
            print(figure.line())
            floor = f"  floor: rosbags + mcap alone writing the same {m.written:,} encoded records"
            print(Figure(floor, m.warm + m.mcap, m.warm, warm, TARGET).line())
            print(
                Figure(
                    "  both from scratch (types built)", m.imported_cold, m.cold, "cold", TARGET
                ).line()
            )
        if mission is not None:
            print(whole_process(mission, Path(folder), args.repeat, args.root).line())
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
