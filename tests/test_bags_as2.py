"""Aerostack2 flights (written by tests/as2_support.py as Aerostack2 publishes, in both
rosbag2 storage formats) import into the right behavior timeline: names, activation and
end times within one status period (100 ms), outcomes from the action status or result,
reconstructed activations marked so, goals as arguments, vehicle state from the
platform and self-localization; every message byte for byte on its raw channel."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from as2_support import DRONE, END_S, EXPECTED, START_NS, write_flight
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from ros2_support import bag_streams, raw_streams

from aeroexec.bags import import_bag

PERIOD_S = 0.1
VARIANTS = {
    "mcap": ("mcap", True),
    "sqlite3": ("sqlite3", True),
    "mcap-topics-only": ("mcap", False),
    "sqlite3-topics-only": ("sqlite3", False),
}


@pytest.fixture(scope="module")
def flights(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, Path, object]]:
    root = tmp_path_factory.mktemp("as2")
    out = {}
    for name, (storage, services) in VARIANTS.items():
        bag = write_flight(root / name, storage, services)
        target = root / f"{name}.mcap"
        out[name] = (bag, target, import_bag(bag, target))
    return out


def _messages(target: Path, topic: str) -> list[tuple[float, dict]]:
    with open(target, "rb") as stream:
        return [
            ((m.log_time - START_NS) / 1e9, json.loads(m.data))
            for _, _, m in make_reader(stream).iter_messages(topics=[f"/{DRONE}/{topic}"])
        ]


@pytest.mark.parametrize("variant", VARIANTS)
def test_behavior_timeline_names_times_outcomes(variant: str, flights: dict) -> None:
    _, target, report = flights[variant]
    starts = _messages(target, "activate_behavior")
    ends = _messages(target, "behavior_event")
    assert [c["request"]["behavior"] for _, c in starts] == [name for name, *_ in EXPECTED]
    assert [(e["name"], e["code"]) for _, e in ends] == [(n, code) for n, _, _, code in EXPECTED]
    for (start_t, call), (end_t, event), (_, start, end, _) in zip(
        starts, ends, EXPECTED, strict=True
    ):
        assert start <= start_t <= start + PERIOD_S, (call, start_t)
        assert end <= end_t <= end + PERIOD_S, (event, end_t)
        assert call["reconstructed"] is True
        assert event["uid"] == call["response"]["uid"]
    assert report.reconstructed_activations == 5
    assert report.reconstructed_inhibitions == 1  # the GoTo the operator stopped
    stopped = ends[3][1]
    assert stopped["detail"] == "inhibited" and stopped["reconstructed"] is True
    assert ends[2][1]["detail"] == "aborted"


def test_goals_become_the_activation_arguments(flights: dict) -> None:
    _, target, _ = flights["mcap"]
    commands = [
        c for _, c in _messages(target, "mission/command") if c["command"] == "activate_behavior"
    ]
    assert commands[0]["arguments"] == {"takeoff_height": 1.5, "takeoff_speed": 0.5}
    # flattened for a catalog: the point of the stamped target, the path's positions,
    # the yaw mode's fields; no headers
    assert commands[1]["arguments"] == {
        "target_pose": [4.0, 3.0, 1.5],
        "max_speed": 1.0,
        "yaw_mode": 0,
        "yaw_angle": 0.0,
    }
    assert commands[2]["arguments"]["path"] == [[2.0, 3.0, 1.5]]
    assert "header" not in commands[2]["arguments"]
    assert "FIXED_YAW" not in json.dumps(commands[1])  # constants are not values
    # without recorded services, the goals are unknown
    _, bare, _ = flights["mcap-topics-only"]
    bare_commands = [
        c for _, c in _messages(bare, "mission/command") if c["command"] == "activate_behavior"
    ]
    assert [c["arguments"] for c in bare_commands] == [{}] * 5


def test_recorded_action_services_are_calls(flights: dict) -> None:
    _, target, report = flights["sqlite3"]
    assert report.derived["services/GoToBehavior/_action/send_goal"] == 2
    assert report.derived["services/GoToBehavior/_behavior/stop"] == 1
    ((_, result),) = _messages(target, "services/FollowPathBehavior/_action/get_result")
    assert result["response"]["status"] == 6 and result["response"]["ok"] is True
    assert result["response"]["result"] == {"follow_path_success": False}


@pytest.mark.parametrize("variant", ["mcap", "sqlite3"])
def test_vehicle_state_from_platform_info_and_pose(variant: str, flights: dict) -> None:
    _, target, _ = flights[variant]
    states = _messages(target, "vehicle/state")

    def at(time_s: float) -> dict:
        return [s for t, s in states if t <= time_s][-1]

    # flying from the platform's state, armed from its own flag (landed but armed before
    # the takeoff and after the landing)
    assert (at(1.5)["flying"], at(1.5)["armed"]) == (False, True)  # LANDED
    assert (at(10.0)["flying"], at(10.0)["armed"]) == (True, True)  # FLYING
    assert at(24.0)["flying"] is True  # LANDING
    assert (at(25.5)["flying"], at(25.5)["armed"]) == (False, True)  # LANDED
    assert (at(26.5)["flying"], at(26.5)["armed"]) == (False, False)  # DISARMED
    # The first pose (0 s) comes before the first platform info (5 ms): no state is a
    # guess, the first one waits for it.
    assert all("flying" not in s.get("defaulted", ()) for _, s in states)
    assert states[0][0] == pytest.approx(1 / 30, abs=1e-3)
    last_t, last = states[-1]
    assert last_t == pytest.approx(END_S, abs=0.04)
    assert last["position"] == pytest.approx([3.0, 3.0, 0.0], abs=1e-6)
    assert max(s["position"][2] for _, s in states) == pytest.approx(1.5)
    assert len(_messages(target, "vehicle/transform")) > 0


@pytest.mark.parametrize("variant", VARIANTS)
def test_generated_flight_imports_losslessly(variant: str, flights: dict) -> None:
    bag, target, report = flights[variant]
    expected = bag_streams(bag)
    assert raw_streams(target) == expected
    assert report.messages == sum(len(v) for v in expected.values())


def test_action_service_events_with_raw_action_text_decode(flights: dict) -> None:
    """The MCAP flight stores the `.action` text as the schema of the action's service
    events (rosbag2's raw-text form): the import writes the real definition."""
    _, target, _ = flights["mcap"]
    factory = DecoderFactory()
    with open(target, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        for channel in summary.channels.values():
            schema = summary.schemas.get(channel.schema_id)
            if channel.topic.endswith("/get_result/_service_event"):
                assert "bag_definition" in channel.metadata
                assert "as2_msgs/Land_GetResult_Response[<=1] response" in schema.data.decode() or (
                    "LandBehavior" not in channel.topic
                )
        for schema, channel, message in reader.iter_messages():
            if channel.message_encoding == "cdr" and not schema.name.endswith("_Event"):
                factory.decoder_for("cdr", schema)(message.data)


def test_same_flight_gives_the_same_bytes(flights: dict, tmp_path: Path) -> None:
    bag, target, _ = flights["mcap"]
    again = tmp_path / "again.mcap"
    import_bag(bag, again)
    assert again.read_bytes() == target.read_bytes()


def test_without_behavior_status_activations_are_placed_at_their_ends(
    flights: dict, tmp_path: Path
) -> None:
    """A mapping (or a bag recorded without hidden topics' behavior status) with only the
    action status: each goal that ended is an activation of unknown duration at its end;
    the stopped one, which has no terminal status, is not seen at all; a note says so."""
    mapping = tmp_path / "outcomes_only.yaml"
    mapping.write_text(
        "version: 1\ndrone: drone0\ntopics:\n"
        '  - {topic: "/{drone}/*/_action/status", kind: action_status}\n'
    )
    bag, _, _ = flights["sqlite3-topics-only"]
    target = tmp_path / "outcomes.mcap"
    report = import_bag(bag, target, mapping=mapping)
    assert any("no behavior status" in note for note in report.notes)
    ends = _messages(target, "behavior_event")
    assert [(e["name"], e["code"]) for _, e in ends] == [
        (n, code) for n, _, _, code in EXPECTED if code != "INTERRUPTED"
    ]
    starts = _messages(target, "activate_behavior")
    assert [round(t, 3) for t, _ in starts] == [round(t, 3) for t, _ in ends]


TOOL = Path(
    os.environ.get(
        "AEROEXEC_FOXGLOVE_CHECK",
        Path(__file__).resolve().parents[2] / "shared/tools/foxglove-schema-check",
    )
)


def _missing_tool() -> str | None:
    if shutil.which("node") is None:
        return "node is not installed (Debian package nodejs): cannot run the viewers' parsers"
    if not TOOL.is_file():
        return f"{TOOL} not found (set AEROEXEC_FOXGLOVE_CHECK to foxglove-schema-check)"
    return None


@pytest.mark.skipif(_missing_tool() is not None, reason=_missing_tool() or "")
@pytest.mark.parametrize("variant", ["mcap", "sqlite3"])
def test_the_import_channels_pass_the_viewers_schema_parsers(variant: str, flights: dict) -> None:
    """Every channel the Aerostack2 mapping derives (behavior events and list, commands,
    calls and call log, vehicle state and transform, scene) parses in Lichtblick's and
    Foxglove Studio's own schema code."""
    _, target, _ = flights[variant]
    result = subprocess.run(
        [str(TOOL), str(target), sys.executable], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stdout + result.stderr
    with open(target, "rb") as stream:
        summary = make_reader(stream).get_summary()
    json_schemas = {s.name for s in summary.schemas.values() if s.encoding == "jsonschema"}
    assert {"aeroexec.BehaviorEvent", "aeroexec.VehicleState", "aeroexec.ServiceCall"} <= (
        json_schemas
    )
    checked = {line.split(" ", 1)[0] for line in result.stdout.splitlines() if line.strip()}
    assert json_schemas <= checked
