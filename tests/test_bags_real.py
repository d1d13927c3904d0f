"""Real ROS 1 bags made by others (tests/fixtures/bags/README.md): nothing is lost on
import, byte for byte, checked against rosbags' own reading of the bag and the mcap
library's reading of the output; `aeroexec info` on bags.
"""

from __future__ import annotations

import hashlib
import json
from collections import defaultdict
from pathlib import Path

import jsonschema
import pytest
from mcap.reader import make_reader
from rosbags.rosbag1 import Reader
from test_bags_support import (
    AEROSTACK_BAG,
    REAL_BAGS,
    ROTORS_BAG,
    TURTLE_BZ2,
    TURTLE_LZ4,
    state_times,
    topic_times,
)
from typer.testing import CliRunner

from aeroexec.bags import import_bag
from aeroexec.bags.types import Decoder, TypeResolver, ros1_name
from aeroexec.cli import app
from aeroexec.recording import open_recording

#: What each real bag holds (tests/fixtures/bags/README.md and the sources' own notes).
EXPECTED = {
    AEROSTACK_BAG.name: (10046, 111, 151, "none"),
    ROTORS_BAG.name: (20278, 5, 5, "none"),
    TURTLE_BZ2.name: (8647, 9, 9, "bz2"),
    TURTLE_LZ4.name: (8647, 9, 9, "lz4"),
}


def bag_streams(path: Path) -> dict[str, list[tuple[int, bytes]]]:
    """Topic -> sorted (log time, bytes) of every message, as rosbags reads the bag."""
    streams: dict[str, list[tuple[int, bytes]]] = defaultdict(list)
    with Reader(path) as reader:
        for connection, time_ns, data in reader.messages():
            streams[connection.topic].append((time_ns, bytes(data)))
    return {topic: sorted(items) for topic, items in streams.items()}


def mcap_raw_streams(path: Path) -> dict[str, list[tuple[int, bytes]]]:
    """Original topic -> sorted (log time, bytes) of the raw ros1 channels, as the mcap
    library reads the import."""
    streams: dict[str, list[tuple[int, bytes]]] = defaultdict(list)
    with open(path, "rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            if channel.message_encoding == "ros1":
                streams[channel.metadata["topic"]].append((message.log_time, message.data))
    return {topic: sorted(items) for topic, items in streams.items()}


@pytest.fixture(scope="module")
def imported(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("real_bags")
    return {bag.name: _import(bag, folder / (bag.stem + ".mcap")) for bag in REAL_BAGS}


def _import(bag: Path, target: Path) -> Path:
    import_bag(bag, target)
    return target


@pytest.mark.parametrize("bag", REAL_BAGS, ids=lambda p: p.stem)
def test_every_message_is_carried_over_byte_for_byte(bag: Path, imported: dict[str, Path]) -> None:
    expected = bag_streams(bag)
    got = mcap_raw_streams(imported[bag.name])
    messages, topics, _, _ = EXPECTED[bag.name]
    assert sum(len(v) for v in expected.values()) == messages
    assert len(expected) == topics
    assert got.keys() == expected.keys()
    for topic, items in expected.items():
        assert len(got[topic]) == len(items), topic
        assert got[topic] == items, topic  # same times, same bytes, per topic


def test_the_same_bag_gives_the_same_bytes(tmp_path: Path, imported: dict[str, Path]) -> None:
    """Determinism: a second import of the 2017 bag (several chunks, every derived
    channel, another output name) is byte-identical to the first."""
    again = _import(AEROSTACK_BAG, tmp_path / "again.mcap")
    first = imported[AEROSTACK_BAG.name].read_bytes()
    with open(again, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and len(summary.chunk_indexes) > 1
    assert again.read_bytes() == first


@pytest.mark.parametrize("bag", REAL_BAGS, ids=lambda p: p.stem)
def test_raw_channels_keep_each_connection_and_its_definition(
    bag: Path, imported: dict[str, Path]
) -> None:
    with Reader(bag) as reader:
        connections = {
            (c.topic, c.ext.callerid): (ros1_name(c.msgtype), c.msgdef.data, c.digest)
            for c in reader.connections
        }
    with open(imported[bag.name], "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    raw = {}
    for channel in summary.channels.values():
        if channel.message_encoding != "ros1":
            continue
        schema = summary.schemas[channel.schema_id]
        assert schema.encoding == "ros1msg"
        assert channel.topic == "/ros1" + channel.metadata["topic"]
        key = (channel.metadata["topic"], channel.metadata.get("callerid"))
        raw[key] = (schema.name, schema.data.decode(), channel.metadata["md5sum"])
    assert raw == connections
    assert len(raw) == EXPECTED[bag.name][2]


def test_bz2_and_lz4_copies_of_one_recording_import_to_the_same_messages(
    imported: dict[str, Path],
) -> None:
    bz2 = mcap_raw_streams(imported[TURTLE_BZ2.name])
    lz4 = mcap_raw_streams(imported[TURTLE_LZ4.name])
    assert bz2 == lz4
    assert len(bz2["/tf"]) == 2688


def test_the_import_is_an_aeroexec_recording_with_bag_metadata(imported: dict[str, Path]) -> None:
    recording = open_recording(imported[AEROSTACK_BAG.name])
    assert recording.is_aeroexec and recording.complete
    meta = recording.metadata["aeroexec"]
    assert meta["clock"] == "wall"
    assert meta["vehicle"] == "ros1-bag"
    assert meta["source"] == AEROSTACK_BAG.name
    assert meta["drone"] == "drone1"
    assert meta["mapped_kinds"] == "battery,flight_status,pose,process_state,velocity"
    bag = recording.metadata["ros1_bag"]
    assert bag["compression"] == "none"
    assert bag["chunks"] == "4"
    assert bag["connections"] == "151"
    assert bag["messages"] == "10046"
    mapping = recording.attachment("bag_mapping.yaml")
    assert mapping is not None and "behavior_event" in mapping.text


def test_derived_channels_of_the_real_aerostack_bag(imported: dict[str, Path]) -> None:
    """The 2017 bag has no behavior topics but poses, battery, status and the
    heartbeats of ~35 processes: vehicle/state at most every 0.1 s of its 432 poses (and
    the last one), one process_state each."""
    recording = open_recording(imported[AEROSTACK_BAG.name])
    states, processes = [], []
    for record in recording.records():
        if record.topic == "/drone1/vehicle/state":
            states.append(record)
        elif record.topic == "/drone1/process_state":
            processes.append(record.data)
    poses = topic_times(AEROSTACK_BAG, "/drone1/EstimatedPose_droneGMR_wrt_GFF")
    assert len(poses) == 432
    assert [s.log_time_ns for s in states] == state_times(poses)
    assert len(states) == 123
    assert len(processes) == 35
    names = {p["process"] for p in processes}
    assert {"droneCommand", "behavior_specialist_process", "resource_manager_process"} <= names
    assert all(not p["process"].startswith("/") for p in processes)
    # the first pose, decoded independently with the bag's own definition
    with Reader(AEROSTACK_BAG) as reader:
        pose_conn = [c for c in reader.connections if c.topic.endswith("GMR_wrt_GFF")]
        pose_conn = [c for c in pose_conn if "Pose" in c.topic]
        _, time_ns, data = next(reader.messages(pose_conn))
        decoder = TypeResolver().decoder(
            pose_conn[0].msgtype, pose_conn[0].msgdef.data, pose_conn[0].digest
        )
        pose = decoder.decode(data)
    first = states[0]
    assert first.log_time_ns == time_ns
    assert first.data["position"] == pytest.approx([pose.x, pose.y, pose.z])  # type: ignore[attr-defined]
    assert first.data["yaw"] == pytest.approx(pose.yaw)  # type: ignore[attr-defined]
    assert 0.0 <= first.data["battery"] <= 1.0
    assert "battery" not in first.data.get("defaulted", [])  # the battery topic came first


def test_derived_json_messages_follow_the_profile_schemas(imported: dict[str, Path]) -> None:
    checked = 0
    for name in (AEROSTACK_BAG.name, ROTORS_BAG.name):
        with open(imported[name], "rb") as stream:
            reader = make_reader(stream)
            for schema, channel, message in reader.iter_messages(log_time_order=False):
                if channel.message_encoding != "json":
                    continue
                assert schema is not None and schema.encoding == "jsonschema"
                jsonschema.validate(json.loads(message.data), json.loads(schema.data))
                checked += 1
    # vehicle/state + vehicle/transform of both bags, one scene each, and the real bag's
    # 35 process changes
    assert checked == 2 * (123 + 659) + 2 + 35


def test_a_posestamped_bag_gets_vehicle_state_from_its_first_posestamped_topic(
    imported: dict[str, Path],
) -> None:
    recording = open_recording(imported[ROTORS_BAG.name])
    counts = recording.survey().topic_counts()
    poses = topic_times(ROTORS_BAG, "/ground_truth/pose")
    assert len(poses) == 6577
    assert counts["/drone1/vehicle/state"] == len(state_times(poses)) == 659
    assert "/drone1/behavior_event" not in counts  # nothing invented


def test_only_mapped_topics_are_deserialized(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[int] = []
    original = Decoder.decode

    def counting(self: Decoder, data: bytes | memoryview) -> object:
        calls.append(1)
        return original(self, data)

    monkeypatch.setattr(Decoder, "decode", counting)
    import_bag(AEROSTACK_BAG, tmp_path / "a.mcap")
    # Every process heartbeat (3395); a pose only when it gives a vehicle/state; speed,
    # battery and status only the latest one before such a pose.
    pose = "/drone1/EstimatedPose_droneGMR_wrt_GFF"
    latest_only = {
        "/drone1/EstimatedSpeed_droneGMR_wrt_GFF",
        "/drone1/battery",
        "/drone1/status",
    }
    emitted = set(state_times(topic_times(AEROSTACK_BAG, pose)))
    expected, pending = 3395, set()
    with Reader(AEROSTACK_BAG) as reader:
        for connection, time_ns, _ in reader.messages():
            if connection.topic in latest_only:
                pending.add(connection.topic)
            elif connection.topic == pose and time_ns in emitted:
                expected += 1 + len(pending)
                pending.clear()
    assert len(calls) == expected
    assert expected < 432 + 469 + 177 + 177 + 3395  # what decoding every mapped one costs
    calls.clear()
    import_bag(TURTLE_LZ4, tmp_path / "t.mcap")
    assert calls == []  # nothing of turtlesim is mapped: pure byte copy


def test_every_pose_gives_a_state_with_a_zero_period(tmp_path: Path) -> None:
    mapping = tmp_path / "every.yaml"
    mapping.write_text(
        "state_period_s: 0\ntopics:\n  - {type: geometry_msgs/PoseStamped, kind: pose}\n"
    )
    report = import_bag(ROTORS_BAG, tmp_path / "r.mcap", mapping=mapping)
    assert report.derived == {"vehicle/state": 6577, "vehicle/transform": 6577, "scene": 1}
    states = [r for r in open_recording(tmp_path / "r.mcap").records() if r.name == "vehicle/state"]
    assert [s.log_time_ns for s in states] == topic_times(ROTORS_BAG, "/ground_truth/pose")


def test_importing_twice_gives_the_same_bytes(tmp_path: Path) -> None:
    first = import_bag(TURTLE_BZ2, tmp_path / "one.mcap")
    import_bag(TURTLE_BZ2, tmp_path / "two.mcap")
    one = hashlib.sha256((tmp_path / "one.mcap").read_bytes()).hexdigest()
    two = hashlib.sha256((tmp_path / "two.mcap").read_bytes()).hexdigest()
    assert one == two
    assert first.messages == 8647 and first.compression == "bz2"


# -- aeroexec info BAG ----------------------------------------------------------------------
def _invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.stdout, result.stderr


@pytest.mark.parametrize("bag", REAL_BAGS, ids=lambda p: p.stem)
def test_info_on_a_bag_counts_what_rosbags_counts(bag: Path) -> None:
    code, out, err = _invoke("info", str(bag), "--format", "json")
    assert code == 0 and err == ""
    report = json.loads(out)
    streams = bag_streams(bag)
    assert report["channels"] == {t: len(v) for t, v in streams.items()}
    assert report["messages"] == EXPECTED[bag.name][0]
    assert report["metadata"]["ros1_bag"]["compression"] == EXPECTED[bag.name][3]
    assert report["metadata"]["ros1_bag"]["connections"] == str(EXPECTED[bag.name][2])
    with Reader(bag) as reader:
        types = {c.topic: ros1_name(c.msgtype) for c in reader.connections}
        duration = (reader.end_time - 1 - reader.start_time) / 1e9
    assert {c["topic"]: c["schema"] for c in report["channel_details"]} == types
    assert report["duration_s"] == pytest.approx(duration)


def test_info_text_on_a_bag_shows_types_compression_and_duration() -> None:
    code, out, _ = _invoke("info", str(TURTLE_BZ2))
    assert code == 0
    assert "compression=bz2" in out
    assert "duration:    21.700 s" in out
    assert "1344  /turtle1/pose" in out and "turtlesim/Pose" in out


def test_import_cli_reports_and_writes(tmp_path: Path) -> None:
    target = tmp_path / "out.mcap"
    code, out, err = _invoke("import", str(AEROSTACK_BAG), "-o", str(target), "--format", "json")
    assert code == 0 and err == ""
    report = json.loads(out)
    assert report["messages"] == 10046
    assert report["mapped"]["pose"] == "/drone1/EstimatedPose_droneGMR_wrt_GFF"
    assert report["derived"]["vehicle/state"] == 123
    assert target.exists()
    code, out, _ = _invoke("info", str(target), "--format", "json")
    assert code == 0
    info = json.loads(out)
    assert info["profile"] == "aeroexec"
    assert info["messages"] == 10046 + 123 * 2 + 1 + 35
