"""The Recorder writes the aeroexec MCAP profile: checked with the `mcap` library's own
reader and `jsonschema`, not only with aeroexec's reader."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import jsonschema
import pytest
from mcap.decoder import DecoderFactory
from mcap.reader import make_reader
from mcap.records import Schema

from aeroexec.errors import RecordingError
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.recording import FLUSH_BYTES, FLUSH_INTERVAL_NS, FLUSH_MESSAGES, Recorder
from aeroexec.recording.scan import RecordScanner
from aeroexec.recording.schemas import SCHEMAS, schema_document
from aeroexec.recording.writer import LIBRARY
from aeroexec.vehicles.world import DEFAULT_WORLD, parse_world

ROOT = Path(__file__).resolve().parent.parent


class JsonDecoders(DecoderFactory):
    def decoder_for(
        self, message_encoding: str, schema: Schema | None
    ) -> Callable[[bytes], Any] | None:
        return json.loads if message_encoding == "json" else None


def _record_session(path: Path) -> None:
    simulate(SessionConfig(mission=APPENDIX_C, record=path))


@pytest.fixture(scope="module")
def session_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("rec") / "appendix_c.mcap"
    _record_session(path)
    return path


def _decoded(path: Path) -> list[Any]:
    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[JsonDecoders()])
        return list(reader.iter_decoded_messages(log_time_order=False))


def _readable_messages(path: Path) -> int:
    """Messages an independent record-level pass reads from a file still being written."""
    scanner = RecordScanner(path)
    return sum(type(r).__name__ == "Message" for _, r in scanner.records())


def _call(
    seq: int, service: str = "activate_behavior", t: int = 0, parent: int | None = None
) -> ServiceCallRecord:
    return ServiceCallRecord(
        seq, parent, "mission", service, {"behavior": "TAKE_OFF"}, {"ok": True, "error": ""}, t
    )


def _nested(seq: int) -> ServiceCallRecord:
    """A call made inside call 0: one message (a top-level call also writes a call_log line)."""
    return _call(seq, "check_consistency", parent=0)


# -- the profile, as the mcap library reads it ----------------------------------------------
def test_header_profile_and_library_are_stable(session_file: Path) -> None:
    with open(session_file, "rb") as stream:
        header = make_reader(stream).get_header()
    assert header.profile == "aeroexec"
    assert header.library == LIBRARY
    assert "mcap-python" in header.library and os.uname().nodename not in header.library


def test_every_channel_has_a_json_schema_and_every_message_validates(session_file: Path) -> None:
    messages = _decoded(session_file)
    assert len(messages) > 500
    validators: dict[int, jsonschema.protocols.Validator] = {}
    for schema, channel, message, decoded in messages:
        assert channel.message_encoding == "json"
        assert schema is not None and schema.encoding == "jsonschema", channel.topic
        if schema.id not in validators:
            document = json.loads(schema.data)
            cls = jsonschema.validators.validator_for(document)
            cls.check_schema(document)
            validators[schema.id] = cls(document)
        validators[schema.id].validate(decoded)
        assert message.publish_time == message.log_time
    # All the profile's schemas that a mission uses are present.
    names = {schema.name for schema, *_ in messages}
    assert {
        "aeroexec.ServiceCall",
        "aeroexec.BehaviorEvent",
        "aeroexec.ActiveBehaviors",
        "aeroexec.ActiveCapabilities",
        "aeroexec.ProcessState",
        "aeroexec.BeliefChange",
        "aeroexec.MissionCommand",
        "aeroexec.VehicleState",
        "foxglove.FrameTransform",
        "foxglove.SceneUpdate",
        "foxglove.Log",
    } <= names


def test_channels_are_namespaced_one_per_service(session_file: Path) -> None:
    messages = _decoded(session_file)
    topics = {channel.topic for _, channel, _, _ in messages}
    for name in (
        "behavior_event",
        "list_of_active_behaviors",
        "list_of_active_capabilities",
        "process_state",
        "beliefs",
        "mission/command",
        "vehicle/state",
        "vehicle/transform",
        "scene",
        "log",
        "call_log",
        "activate_behavior",
        "inhibit_behavior",
        "check_behavior_format",
        "behavior_take_off/start",
    ):
        assert f"/drone1/{name}" in topics
    for schema, channel, _, decoded in messages:
        if schema.name == "aeroexec.ServiceCall":
            assert channel.topic == "/drone1/" + decoded["service"]
            # A call made at the top has no parent_seq: the key is left out, never null.
            keys = {"seq", "caller", "service", "request", "response"}
            assert set(decoded) in (keys, keys | {"parent_seq"})
            assert isinstance(decoded.get("parent_seq", 0), int)


def test_channel_ids_follow_first_use(session_file: Path) -> None:
    first_seen: list[int] = []
    for _, channel, _, _ in _decoded(session_file):
        if channel.id not in first_seen:
            first_seen.append(channel.id)
    assert first_seen == sorted(first_seen) == list(range(1, len(first_seen) + 1))


def test_call_tree_can_be_rebuilt(session_file: Path) -> None:
    calls = [d for s, _, _, d in _decoded(session_file) if s.name == "aeroexec.ServiceCall"]
    position = {c["seq"]: i for i, c in enumerate(calls)}
    assert len(position) == len(calls)  # seq is unique
    nested = [c for c in calls if "parent_seq" in c]
    assert nested and len(nested) < len(calls)
    for call in nested:
        # a nested call completes, and is recorded, before the call it happened inside
        assert position[call["seq"]] < position[call["parent_seq"]]
        assert call["seq"] > call["parent_seq"]


def test_log_time_is_the_clock(session_file: Path) -> None:
    states = [(m, d) for s, c, m, d in _decoded(session_file) if c.topic == "/drone1/vehicle/state"]
    times = [m.log_time for m, _ in states]
    assert times == sorted(times)
    assert all(t % 100_000_000 == 0 for t in times)  # 10 Hz simulated ticks
    assert times[-1] == round(18.6e9)


def test_metadata_and_attachments(session_file: Path) -> None:
    with open(session_file, "rb") as stream:
        reader = make_reader(stream)
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        attachments = {a.name: a for a in reader.iter_attachments()}
    assert metadata["aeroexec"]["seed"] == "0"
    assert metadata["aeroexec"]["clock"] == "sim"
    assert metadata["aeroexec"]["mission"] == "appendix_c.py"
    assert all(isinstance(v, str) for v in metadata["aeroexec"].values())
    assert attachments["mission.py"].data == Path(APPENDIX_C).read_bytes()
    assert b"behavior_descriptors" in attachments["catalog.yaml"].data
    for attachment in attachments.values():
        assert attachment.log_time == 0 and attachment.create_time == 0


def test_behavior_events_and_capabilities_are_recorded(session_file: Path) -> None:
    messages = _decoded(session_file)
    events = [d for _, c, _, d in messages if c.topic == "/drone1/behavior_event"]
    assert [e["name"] for e in events][:2] == ["TAKE_OFF", "GO_TO_POINT"]
    assert events[-1] == {**events[-1], "name": "LAND", "code": "GOAL_ACHIEVED"}
    caps = [d for _, c, _, d in messages if c.topic == "/drone1/list_of_active_capabilities"]
    assert any(
        entry["references"] >= 1 and entry["name"] for d in caps for entry in d["capabilities"]
    )


# -- derived Foxglove messages ----------------------------------------------------------------
def _by_topic(path: Path) -> dict[str, list[Any]]:
    decoded: dict[str, list[Any]] = {}
    for _, channel, _, data in _decoded(path):
        decoded.setdefault(channel.topic, []).append(data)
    return decoded


def test_frame_transform_from_position_and_yaw_and_log_levels(tmp_path: Path) -> None:
    path = tmp_path / "derived.mcap"
    with Recorder(path) as recorder:
        state = {
            "position": [1.0, 2.0, 3.0],
            "velocity": [0.0, 0.0, 0.0],
            "yaw": math.pi / 2,
            "battery": 0.9,
            "flying": True,
            "armed": True,
            "fault": "",
        }
        recorder.on_topic(TopicRecord("vehicle/state", state, 1_500_000_000))
        recorder.on_topic(TopicRecord("log", {"level": "WARNING", "message": "m", "name": "x"}, 7))
        recorder.on_topic(TopicRecord("log", {"level": "ERROR", "message": "e", "name": "x"}, 8))
    decoded = _by_topic(path)
    (transform,) = decoded["/drone1/vehicle/transform"]
    assert transform["timestamp"] == {"sec": 1, "nsec": 500_000_000}
    assert transform["parent_frame_id"] == "world"
    assert transform["child_frame_id"] == "drone1/base_link"
    assert transform["translation"] == {"x": 1.0, "y": 2.0, "z": 3.0}
    q = transform["rotation"]
    assert q["z"] == pytest.approx(math.sqrt(0.5)) and q["w"] == pytest.approx(math.sqrt(0.5))
    assert q["x"] == 0.0 and q["y"] == 0.0
    jsonschema.validate(transform, schema_document("foxglove.FrameTransform"))
    logs = decoded["/drone1/log"]
    assert [entry["level"] for entry in logs] == [3, 4]
    assert logs[0] == {
        "timestamp": {"sec": 0, "nsec": 7},
        "level": 3,
        "message": "m",
        "name": "x",
        "file": "",
        "line": 0,
    }
    jsonschema.validate(logs[0], SCHEMAS["foxglove.Log"])


def test_scene_holds_the_vehicle_markers_and_the_moving_object(session_file: Path) -> None:
    decoded = _decoded(session_file)
    statics = [(m.log_time, d) for _, c, m, d in decoded if c.topic == "/drone1/scene/static"]
    scenes = [(m.log_time, d) for _, c, m, d in decoded if c.topic == "/drone1/scene"]
    world = parse_world(DEFAULT_WORLD.read_text(), "default.yaml")
    # The markers stand still: one message, at the start.
    ((t_static, static),) = statics
    assert t_static == 0
    assert [e["id"] for e in static["entities"]] == [f"marker/{m.id}" for m in world.markers]
    for marker in world.markers:
        (entity,) = [e for e in static["entities"] if e["id"] == f"marker/{marker.id}"]
        assert entity["frame_id"] == "world"
        (cube,) = entity["cubes"]
        p = cube["pose"]["position"]
        assert (p["x"], p["y"], p["z"]) == marker.position
        assert entity["texts"][0]["text"] == f"marker {marker.id}"
    # The vehicle and the walker, whole in every message: at the start, then each time
    # the walker (0.05 m/s) has moved 0.2 m (4 s), where it is then.
    assert world.object is not None
    assert [t for t, _ in scenes] == [0, 4 * 10**9, 8 * 10**9, 12 * 10**9, 16 * 10**9]
    for t, update in scenes:
        vehicle, obj = update["entities"]
        assert vehicle["id"] == "vehicle" and obj["id"] == "object"
        assert vehicle["frame_id"] == "drone1/base_link" and vehicle["frame_locked"] is True
        assert vehicle["cubes"] and vehicle["arrows"]  # the body, and its heading
        x = obj["spheres"][0]["pose"]["position"]["x"]
        assert x == pytest.approx(world.object.at(t / 1e9)[0])
    for _, update in statics + scenes:
        jsonschema.validate(update, schema_document("foxglove.SceneUpdate"))


def test_the_3d_panel_has_its_frame_and_scene_at_the_first_log_time(session_file: Path) -> None:
    # Lichtblick opens a recording at its start + 99 ms: the vehicle's frame and the
    # scene must be there already, not with the first state (a tick later).
    decoded = _decoded(session_file)
    first = min(m.log_time for _, _, m, _ in decoded)
    states = [m.log_time for _, c, m, _ in decoded if c.topic == "/drone1/vehicle/state"]
    assert states[0] > first  # what made the panel blank: the first state comes later
    heads = [c.topic for _, c, _, _ in decoded[:3]]
    assert heads == ["/drone1/scene/static", "/drone1/scene", "/drone1/vehicle/transform"]
    assert all(m.log_time == first for _, _, m, _ in decoded[:3])
    transform = decoded[2][3]
    world = parse_world(DEFAULT_WORLD.read_text(), "default.yaml")
    t = transform["translation"]
    assert (t["x"], t["y"], t["z"]) == world.start
    assert transform["child_frame_id"] == "drone1/base_link"


def test_start_pose_comes_before_the_first_message_and_is_not_repeated(tmp_path: Path) -> None:
    path = tmp_path / "start.mcap"
    with Recorder(path, start_pose=(1.0, 2.0, 0.0, 0.5)) as recorder:
        recorder.on_topic(TopicRecord("beliefs", {"op": "add", "belief": "x"}, 7))
        state = {"position": [1.0, 2.0, 0.0], "velocity": [0, 0, 0], "yaw": 0.5}
        recorder.on_topic(TopicRecord("vehicle/state", {**state, "battery": 1.0}, 10))
        moved = {**state, "position": [1.0, 2.0, 0.5]}
        recorder.on_topic(TopicRecord("vehicle/state", {**moved, "battery": 1.0}, 20))
    topics = [(c.topic, m.log_time) for _, c, m, _ in _decoded(path)]
    assert topics == [
        ("/drone1/scene", 7),  # no world: the vehicle only, and no static scene
        ("/drone1/vehicle/transform", 7),
        ("/drone1/beliefs", 7),
        ("/drone1/vehicle/state", 10),  # the start pose: no second transform
        ("/drone1/vehicle/state", 20),
        ("/drone1/vehicle/transform", 20),
    ]


def test_call_log_has_one_line_per_top_level_call(session_file: Path) -> None:
    messages = _decoded(session_file)
    roots = [
        (m.log_time, d)
        for s, _, m, d in messages
        if s.name == "aeroexec.ServiceCall" and "parent_seq" not in d
    ]
    lines = [(m.log_time, d) for _, c, m, d in messages if c.topic == "/drone1/call_log"]
    assert len(lines) == len(roots) == 15
    for (t_call, call), (t_line, line) in zip(roots, lines, strict=True):
        assert t_line == t_call
        assert line["name"] == call["caller"]
        assert line["message"].startswith(call["service"])
    by_text = [line["message"] for _, line in lines]
    assert "activate_behavior GO_TO_POINT coordinates=[3, 5.5, 1.3] -> ok uid=4" in by_text
    assert "inhibit_behavior PAY_ATTENTION_TO_VISUAL_MARKERS -> ok" in by_text


def test_a_refused_call_is_a_warning_in_the_call_log(tmp_path: Path) -> None:
    path = tmp_path / "refused.mcap"
    refused = ServiceCallRecord(
        3,
        None,
        "mission",
        "activate_behavior",
        {"behavior": "FLIP"},
        {"ok": False, "error": "no"},
        5,
    )
    with Recorder(path) as recorder:
        recorder.on_service_call(refused)
        recorder.on_service_call(_nested(4))
    decoded = _by_topic(path)
    (line,) = decoded["/drone1/call_log"]
    assert line["level"] == 3 and line["message"] == "activate_behavior FLIP -> refused: no"
    assert "parent_seq" not in decoded["/drone1/activate_behavior"][0]
    assert decoded["/drone1/check_consistency"][0]["parent_seq"] == 0


def test_absent_mission_command_fields_are_left_out(tmp_path: Path) -> None:
    path = tmp_path / "command.mcap"
    with Recorder(path) as recorder:
        command = {"command": "inhibit_behavior", "behavior": "LAND", "arguments": None}
        recorder.on_topic(TopicRecord("mission/command", command, 0))
    (data,) = _by_topic(path)["/drone1/mission/command"]
    assert data == {"command": "inhibit_behavior", "behavior": "LAND"}
    jsonschema.validate(data, SCHEMAS["aeroexec.MissionCommand"])


def test_non_finite_floats_become_null_so_json_stays_valid(tmp_path: Path) -> None:
    path = tmp_path / "nan.mcap"
    with Recorder(path) as recorder:
        recorder.on_topic(TopicRecord("custom", {"x": float("nan"), "y": (1, 2)}, 0))
    ((schema, channel, _, data),) = _decoded(path)
    assert data == {"x": None, "y": [1, 2]}
    assert schema.name == "aeroexec.Topic" and channel.topic == "/drone1/custom"


# -- determinism --------------------------------------------------------------------------------
def test_two_runs_are_byte_identical(tmp_path: Path, session_file: Path) -> None:
    again = tmp_path / "again.mcap"
    _record_session(again)
    assert again.read_bytes() == session_file.read_bytes()


def test_separate_processes_with_different_hash_seeds_are_byte_identical(tmp_path: Path) -> None:
    outputs = []
    for hash_seed in ("1", "2"):
        out = tmp_path / f"run{hash_seed}.mcap"
        env = {**os.environ, "PYTHONHASHSEED": hash_seed}
        subprocess.run(
            [sys.executable, "-m", "aeroexec", "run", str(APPENDIX_C), "-q", "--output", str(out)],
            check=True,
            capture_output=True,
            env=env,
            cwd=tmp_path,
        )
        outputs.append(out.read_bytes())
    assert outputs[0] == outputs[1]


# -- flush bound --------------------------------------------------------------------------------
def test_flush_after_100_messages(tmp_path: Path) -> None:
    path = tmp_path / "count.mcap"
    recorder = Recorder(path)
    for i in range(99):
        recorder.on_service_call(_nested(i))
    assert _readable_messages(path) == 0 and recorder.messages_flushed == 0
    recorder.on_service_call(_nested(99))
    assert _readable_messages(path) == 100 and recorder.messages_flushed == 100
    for i in range(100, 250):
        recorder.on_service_call(_nested(i))
    assert _readable_messages(path) == 200
    recorder.close()
    assert _readable_messages(path) == 250


def test_live_flush_after_half_a_second_of_clock_time(tmp_path: Path) -> None:
    # A live session's log time is the wall clock: its recorder keeps the time bound.
    path = tmp_path / "time.mcap"
    recorder = Recorder(path, flush_interval_ns=FLUSH_INTERVAL_NS)
    state = {"velocity": [0, 0, 0], "yaw": 0.0, "battery": 1.0}
    # 0.0 .. 0.4 s: span 0.4 s, 11 messages (state + transform, and the scene at 0.0)
    for tick in range(5):
        moving = {**state, "position": [tick, 0, 0], "flying": False}
        recorder.on_topic(TopicRecord("vehicle/state", moving, tick * 10**8))
    assert _readable_messages(path) == 0
    moved = {**state, "position": [5, 0, 0], "flying": True}
    recorder.on_topic(TopicRecord("vehicle/state", moved, 5 * 10**8))
    assert _readable_messages(path) == 12  # the state at 0.5 s is flushed; its transform follows
    recorder.close()
    assert _readable_messages(path) == 13


def test_simulated_flush_by_count_and_size_only(tmp_path: Path) -> None:
    # Without the live time bound: an hour of clock time in 99 messages stays in one
    # chunk; the 100th message, or 4 MiB of data, closes it.
    path = tmp_path / "sim.mcap"
    recorder = Recorder(path)
    for i in range(99):
        recorder.on_topic(TopicRecord("log", {"message": str(i)}, i * 36 * 10**9))
    assert _readable_messages(path) == 0 and recorder.messages_flushed == 0
    recorder.on_topic(TopicRecord("log", {"message": "100th"}, 3600 * 10**9))
    assert _readable_messages(path) == 100 and recorder.messages_flushed == 100
    recorder.on_topic(TopicRecord("log", {"message": "x" * (FLUSH_BYTES // 2)}, 3601 * 10**9))
    assert _readable_messages(path) == 100
    recorder.on_topic(TopicRecord("log", {"message": "y" * (FLUSH_BYTES // 2)}, 3602 * 10**9))
    assert _readable_messages(path) == 102 and recorder.messages_flushed == 102
    recorder.close()


def test_a_new_channel_keeps_the_chunk_and_its_count(tmp_path: Path) -> None:
    # Pending messages are handed to mcap before a new channel's record (the file's
    # order is the stream's), but the chunk stays open and the count goes on.
    path = tmp_path / "channels.mcap"
    recorder = Recorder(path)
    for i in range(60):
        recorder.on_topic(TopicRecord("log", {"message": str(i)}, i))
    for i in range(39):
        recorder.on_topic(TopicRecord(f"extra/{i}", {"i": i}, 60 + i))
    assert _readable_messages(path) == 0
    recorder.on_topic(TopicRecord("log", {"message": "100th"}, 99))
    assert _readable_messages(path) == 100
    recorder.close()
    with open(path, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    assert [(c.message_start_time, c.message_end_time) for c in summary.chunk_indexes] == [(0, 99)]


def _record_poses(path: Path, poses: list) -> dict:
    """Record a vehicle state per (position, yaw), one a tick; the file decoded by topic."""
    with Recorder(path) as recorder:
        for tick, (position, yaw) in enumerate(poses):
            state = {"position": position, "velocity": [0, 0, 0], "yaw": yaw, "battery": 1.0}
            recorder.on_topic(TopicRecord("vehicle/state", state, tick * 10**8))
    return _by_topic(path)


def test_transform_only_when_the_pose_changed(tmp_path: Path) -> None:
    # Foxglove holds the latest transform: a vehicle that did not move needs no new one.
    path = tmp_path / "still.mcap"
    poses = [([0, 0, 1], 0.0), ([0, 0, 1], 0.0), ([0, 0, 1], 0.5), ([0, 0, 1], 0.5)]
    poses += [([1, 0, 1], 0.5), ([1, 0, 1], 0.5)]
    decoded = _record_poses(path, poses)
    assert len(decoded["/drone1/vehicle/state"]) == 6
    transforms = decoded["/drone1/vehicle/transform"]
    assert [t["timestamp"]["nsec"] for t in transforms] == [0, 2 * 10**8, 4 * 10**8]
    assert [t["translation"]["x"] for t in transforms] == [0, 0, 1]


def test_no_transform_for_a_pose_that_is_not_finite(tmp_path: Path) -> None:
    # JSON has no inf or NaN, and a FrameTransform of nulls is refused by the viewers: a
    # state whose position or yaw is not finite is recorded, without a transform; huge
    # but finite values still give one.
    path = tmp_path / "odd.mcap"
    inf, nan = float("inf"), float("nan")
    poses = [([0, 0, 1], 0.0), ([inf, 0, 1], 0.0), ([0, -inf, 1], 0.0), ([0, 0, nan], 0.0)]
    poses += [([0, 0, 1], inf), ([1e308, -1e308, 1e308], 3.0), ([0, 0, 2], 0.0)]
    decoded = _record_poses(path, poses)
    assert len(decoded["/drone1/vehicle/state"]) == 7
    transforms = decoded["/drone1/vehicle/transform"]
    assert [t["timestamp"]["nsec"] for t in transforms] == [0, 5 * 10**8, 6 * 10**8]
    assert [t["translation"]["x"] for t in transforms] == [0, 1e308, 0]


def test_header_metadata_and_attachments_are_on_disk_before_any_message(tmp_path: Path) -> None:
    path = tmp_path / "early.mcap"
    recorder = Recorder(path, metadata={"seed": 3}, attachments={"mission.py": "x = 1\n"})
    records = [type(r).__name__ for _, r in RecordScanner(path).records()]
    assert records == ["Metadata", "Attachment"]
    recorder.close()


def test_unclosed_recorder_is_completed_at_normal_exit(tmp_path: Path) -> None:
    path = tmp_path / "atexit.mcap"
    code = (
        "from aeroexec.recording import Recorder\n"
        "from aeroexec.executive.messages import TopicRecord\n"
        f"r = Recorder({str(path)!r})\n"
        "for i in range(7):\n"
        "    r.on_topic(TopicRecord('log', {'message': str(i)}, i))\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
    with open(path, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == 7


def test_chunks_respect_the_flush_bound(session_file: Path) -> None:
    with open(session_file, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and summary.statistics is not None
    chunks = summary.chunk_indexes
    assert chunks and all(c.compression == "lz4" for c in chunks)
    # A simulated session: a chunk per 100 messages, whatever clock time they span.
    assert len(chunks) == -(-summary.statistics.message_count // FLUSH_MESSAGES)
    assert max(c.message_end_time - c.message_start_time for c in chunks) > FLUSH_INTERVAL_NS


def test_service_call_with_nan_is_still_valid_json(tmp_path: Path) -> None:
    path = tmp_path / "nan-call.mcap"
    record = ServiceCallRecord(
        0, None, "mission", "activate_behavior", {"x": float("inf")}, {"ok": True, "error": ""}, 0
    )
    with Recorder(path) as recorder:
        recorder.on_service_call(record)
    (data,) = _by_topic(path)["/drone1/activate_behavior"]
    assert data["request"] == {"x": None}


# -- lifecycle and errors ---------------------------------------------------------------------
def test_close_is_idempotent_and_writing_after_close_fails(tmp_path: Path) -> None:
    path = tmp_path / "closed.mcap"
    recorder = Recorder(path)
    recorder.on_service_call(_call(0))
    recorder.close()
    size = path.stat().st_size
    recorder.close()
    assert path.stat().st_size == size
    with pytest.raises(RecordingError, match="closed"):
        recorder.on_service_call(_call(1))


def test_unwritable_path_is_a_recording_error(tmp_path: Path) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory")
    with pytest.raises(RecordingError) as info:
        Recorder(blocker / "x.mcap")
    assert str(info.value).startswith(str(blocker / "x.mcap") + ": error: ")
    with pytest.raises(RecordingError, match="error: cannot write"):
        Recorder(tmp_path)


def test_capability_state_has_each_change_and_the_release(tmp_path: Path) -> None:
    # One series per capability for a State Transitions panel: a release must be a
    # message of its own (0), not an absence from the list.
    path = tmp_path / "capabilities.mcap"
    lists = [
        [("A", 1)],
        [("A", 1), ("B", 1)],
        [("A", 2), ("B", 1)],
        [("A", 2), ("B", 1)],  # no change: no message
        [("B", 1)],
        [],
    ]
    with Recorder(path) as recorder:
        for tick, names in enumerate(lists):
            data = {"capabilities": [{"name": n, "references": r} for n, r in names]}
            recorder.on_topic(TopicRecord("list_of_active_capabilities", data, tick))
    changes = [
        (m.log_time, d["name"], d["references"])
        for _, c, m, d in _decoded(path)
        if c.topic == "/drone1/capability_state"
    ]
    assert changes == [(0, "A", 1), (1, "B", 1), (2, "A", 2), (4, "A", 0), (5, "B", 0)]
