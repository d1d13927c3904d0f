"""Real ROS 2 bags made by others (tests/fixtures/ros2/README.md): every message lands
byte for byte on its raw /ros2 channel (checked against rosbags' own reading), the raw
channels decode with Foxglove's own ROS 2 parser (mcap_ros2), the service events
rosbag2 records (whose schema no reader decodes, ros2/rosbag2#2365) become aeroexec
service calls, and the aeroexec channels pass the viewers' schema parsers.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from ros2_support import (
    ADD_TWO_INTS,
    MSGTYPES,
    REAL_FILES,
    REPO,
    SERVICES_DB3,
    SERVICES_MCAP,
    TALKER,
    as_directory,
    bag_streams,
    raw_streams,
)
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from typer.testing import CliRunner

from aeroexec.bags import import_bag
from aeroexec.cli import app
from aeroexec.recording import open_recording
from aeroexec.recording.reader import RecordedCall

#: messages, topics, chunk compression of each file (SOURCES.md, sections 2 and 5).
EXPECTED = {
    TALKER.name: (20, 3, "zstd"),
    MSGTYPES.name: (188, 94, "none"),
    SERVICES_MCAP.name: (10, 5, "none"),
    SERVICES_DB3.name: (10, 5, "none (sqlite3)"),
    ADD_TWO_INTS.name: (13, 5, "none"),
}
TOOL = Path(
    os.environ.get("AEROEXEC_FOXGLOVE_CHECK", REPO.parent / "shared/tools/foxglove-schema-check")
)


def _sources(root: Path) -> dict[str, Path]:
    """Every fixture, plus the directory forms of the two that have a metadata.yaml."""
    found = {bag.name: bag for bag in REAL_FILES}
    for bag in (SERVICES_MCAP, SERVICES_DB3):
        found[f"dir-{bag.suffix[1:]}"] = as_directory(bag, root / f"dir-{bag.suffix[1:]}")
    return found


@pytest.fixture(scope="module")
def imported(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, Path, object]]:
    """name -> (bag, imported file, report)."""
    root = tmp_path_factory.mktemp("ros2_real")
    out = {}
    for name, bag in _sources(root).items():
        target = root / f"{name}.out.mcap"
        out[name] = (bag, target, import_bag(bag, target))
    return out


NAMES = [bag.name for bag in REAL_FILES] + ["dir-mcap", "dir-db3"]


@pytest.mark.parametrize("name", NAMES)
def test_every_message_lands_byte_for_byte(name: str, imported: dict) -> None:
    bag, target, report = imported[name]
    expected = bag_streams(bag)
    got = raw_streams(target)
    base = name if name in EXPECTED else (SERVICES_MCAP if "mcap" in name else SERVICES_DB3).name
    messages, topics, compression = EXPECTED[base]
    assert sum(len(v) for v in expected.values()) == messages
    assert report.messages == messages
    assert report.ros_version == 2
    assert report.compression == compression
    assert len(got) == topics  # every topic has its channel, even one without messages
    assert got == expected


@pytest.mark.parametrize("name", NAMES)
def test_raw_channels_decode_with_foxglove_parser(name: str, imported: dict) -> None:
    """Each raw channel names its type (`pkg/msg/Name`), says `cdr`, and carries the
    full `ros2msg` definition: mcap_ros2 (Foxglove's parser and CDR decoder, as the
    Foxglove app uses it) decodes every message with it. Service events, whose type
    names (`AddTwoInts_Event`) break the rosidl naming rule mcap_ros2 enforces, are
    decoded with rosbags' strict parser from the channel's definition instead."""
    _, target, _ = imported[name]
    factory = DecoderFactory()
    decoded = 0
    with open(target, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages():
            if channel.message_encoding != "cdr":
                continue
            assert channel.topic == "/ros2" + channel.metadata["topic"]
            assert schema is not None and schema.encoding == "ros2msg"
            if schema.name.endswith("_Event"):
                store = get_typestore(Stores.EMPTY)
                main = "pkg/msg/Event"
                store.register(get_types_from_msg(schema.data.decode(), main))
                event = store.deserialize_cdr(message.data, main)
                assert event.info.event_type in (0, 1, 2, 3)
                assert len(event.request) + len(event.response) >= 1
            else:
                decoder = factory.decoder_for("cdr", schema)
                assert decoder is not None
                decoder(message.data)
            decoded += 1
    assert decoded == imported[name][2].messages


@pytest.mark.parametrize("name", [SERVICES_MCAP.name, SERVICES_DB3.name, "dir-db3"])
def test_service_event_channels_carry_the_real_event_definition(name: str, imported: dict) -> None:
    """rosbag2 stored the bare `.srv` text (MCAP) or nothing (sqlite3); the channel gets
    the Event type around the Request and Response, and keeps the bag's text."""
    _, target, _ = imported[name]
    with open(target, "rb") as stream:
        summary = make_reader(stream).get_summary()
    events = [c for c in summary.channels.values() if c.topic.endswith("/_service_event")]
    assert len(events) == 2
    for channel in events:
        schema = summary.schemas[channel.schema_id]
        text = schema.data.decode()
        assert schema.name == "test_msgs/srv/BasicTypes_Event"
        assert text.startswith(
            "service_msgs/ServiceEventInfo info\n"
            "test_msgs/BasicTypes_Request[<=1] request\n"
            "test_msgs/BasicTypes_Response[<=1] response\n"
        )
        assert "MSG: test_msgs/BasicTypes_Request\n" in text
        assert "MSG: builtin_interfaces/Time\n" in text
        assert "---" not in text
        assert "---" in channel.metadata["bag_definition"]


def _calls(target: Path) -> list[tuple[str, int, dict]]:
    """The service calls of an import, as aeroexec's recording reader reads them."""
    return [
        (c.topic, c.log_time_ns, {"request": c.request, "response": c.response, "seq": c.seq})
        for c in open_recording(target).records()
        if isinstance(c, RecordedCall)
    ]


def test_add_two_ints_events_become_three_answered_calls(imported: dict) -> None:
    """Six events (REQUEST_SENT, RESPONSE_RECEIVED per call) -> three calls, each with
    its request and its own answer (a + b = sum proves the pairing)."""
    _, target, report = imported[ADD_TWO_INTS.name]
    calls = _calls(target)
    assert report.derived["services/add_two_ints"] == 3
    assert [t for t, _, _ in calls] == ["/drone0/services/add_two_ints"] * 3
    assert [c["request"] for _, _, c in calls] == [{"a": a, "b": 3} for a in (1, 2, 3)]
    for _, _, call in calls:
        assert call["response"]["ok"] is True
        assert call["response"]["sum"] == call["request"]["a"] + call["request"]["b"]
    # each call is written at its response's time: the server's RESPONSE_SENT events
    response_times = []
    for time_ns, data in bag_streams(ADD_TWO_INTS)["/add_two_ints/_service_event"]:
        if data[4] in (2, 3):  # CDR header (4 bytes), then info.event_type
            response_times.append(time_ns)
    assert len(response_times) == 3
    assert [t for _, t, _ in calls] == response_times


@pytest.mark.parametrize("name", [SERVICES_MCAP.name, SERVICES_DB3.name])
def test_basic_types_events_become_calls_on_both_services(name: str, imported: dict) -> None:
    _, target, _ = imported[name]
    calls = _calls(target)
    assert sorted(t for t, _, _ in calls) == [
        "/drone0/services/test_service1",
        "/drone0/services/test_service1",
        "/drone0/services/test_service2",
        "/drone0/services/test_service2",
    ]
    assert [c["seq"] for _, _, c in calls] == [0, 1, 2, 3]
    for _, _, call in calls:
        assert set(call["request"]) >= {"bool_value", "string_value", "int64_value"}
        assert call["response"]["ok"] is True and "string_value" in call["response"]


def test_same_bag_gives_the_same_bytes(tmp_path: Path) -> None:
    first, second = tmp_path / "a.mcap", tmp_path / "b.mcap"
    import_bag(ADD_TWO_INTS, first)
    import_bag(ADD_TWO_INTS, second)
    assert first.read_bytes() == second.read_bytes()


def test_info_reads_a_ros2_bag() -> None:
    result = CliRunner().invoke(app, ["info", str(TALKER), "--format", "json"])
    assert result.exit_code == 0, result.output
    info = json.loads(result.output)
    assert info["messages"] == 20
    assert info["channels"] == {"/parameter_events": 0, "/rosout": 10, "/topic": 10}
    assert info["profile"] == "ros2"
    assert info["complete"] is True


def _missing_tool() -> str | None:
    if shutil.which("node") is None:
        return "node is not installed (Debian package nodejs): cannot run the viewers' parsers"
    if not TOOL.is_file():
        return f"{TOOL} not found (set AEROEXEC_FOXGLOVE_CHECK to foxglove-schema-check)"
    return None


@pytest.mark.skipif(_missing_tool() is not None, reason=_missing_tool() or "")
@pytest.mark.parametrize("name", NAMES)
def test_channels_pass_the_viewers_schema_parsers(name: str, imported: dict) -> None:
    _, target, _ = imported[name]
    result = subprocess.run(
        [str(TOOL), str(target), sys.executable], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stdout + result.stderr
    with open(target, "rb") as stream:
        summary = make_reader(stream).get_summary()
    json_schemas = {s.name for s in summary.schemas.values() if s.encoding == "jsonschema"}
    checked = {line.split(" ", 1)[0] for line in result.stdout.splitlines() if line.strip()}
    assert json_schemas <= checked


#: A node_modules folder with @foxglove/rosmsg, @foxglove/rosmsg2-serialization and
#: @mcap/core (`npm install` them anywhere): the test then decodes with Foxglove's own
#: TypeScript libraries, the ones the Foxglove app runs.
FOXGLOVE_NODE_MODULES = os.environ.get("AEROEXEC_FOXGLOVE_NODE_MODULES", "")
DECODE_SCRIPT = REPO / "tests" / "tools" / "foxglove_ros2_decode.mjs"


@pytest.mark.skipif(
    not FOXGLOVE_NODE_MODULES or shutil.which("node") is None,
    reason="set AEROEXEC_FOXGLOVE_NODE_MODULES to a node_modules with @foxglove/rosmsg, "
    "@foxglove/rosmsg2-serialization and @mcap/core (and install node) to decode with "
    "Foxglove's own libraries",
)
@pytest.mark.parametrize("bag", [SERVICES_MCAP, ADD_TWO_INTS, MSGTYPES])
def test_foxglove_decodes_every_raw_channel_the_bag_itself_fails_on(
    bag: Path, tmp_path: Path
) -> None:
    def decode(path: Path) -> dict:
        modules = tmp_path / "node_modules"
        if not modules.exists():
            modules.symlink_to(FOXGLOVE_NODE_MODULES)
        shutil.copyfile(DECODE_SCRIPT, tmp_path / DECODE_SCRIPT.name)
        done = subprocess.run(
            ["node", str(tmp_path / DECODE_SCRIPT.name), str(path)],
            capture_output=True,
            text=True,
            check=True,
            cwd=tmp_path,
        )
        return json.loads(done.stdout)

    target = tmp_path / "imported.mcap"
    report = import_bag(bag, target, compression="none")
    imported = decode(target)
    assert imported["bad"] == 0, imported["errors"]
    assert imported["ok"] == report.messages
    if bag is not MSGTYPES:  # the bag's own service events: Foxglove cannot parse '---'
        original = decode(bag)
        assert original["bad"] > 0
        assert all("---" in error for error in original["errors"].values())
