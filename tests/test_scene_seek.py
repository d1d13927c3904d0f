"""Seeking keeps the 3D scene whole (issue 28).

After a seek, Foxglove and Lichtblick show only the latest message of each topic at or
before the new time. So at any seek position, the latest message of each scene topic
must together hold every entity of the world plus the vehicle, and the vehicle's frame
must have a transform. Checked at 10 seek points in recordings of the bundled mission
and catalog in the bundled worlds (the default one's walker moves), and in a world whose
object stands still.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import orjson
import pytest
from mcap.reader import make_reader

from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.recording.foxglove import OBJECT_STEP_M
from aeroexec.vehicles.world import DEFAULT_WORLD, FAULTS_WORLD, World, parse_world

SEEK_POINTS = 10
SCENE_TOPICS = ("/drone1/scene", "/drone1/scene/static")
TRANSFORM_TOPIC = "/drone1/vehicle/transform"


def _still_world(tmp: Path) -> Path:
    """The default world with its walker standing still."""
    text = DEFAULT_WORLD.read_text().replace("velocity: [0.05, 0.0, 0.0]", "velocity: [0, 0, 0]")
    assert "velocity: [0, 0, 0]" in text
    path = tmp / "still.yaml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> list[tuple[Path, World]]:
    tmp = tmp_path_factory.mktemp("seek")
    out = []
    for name, world_path in [
        ("default", DEFAULT_WORLD),
        ("faults", FAULTS_WORLD),
        ("still", _still_world(tmp)),
    ]:
        record = tmp / f"{name}.mcap"
        simulate(SessionConfig(mission=APPENDIX_C, world=world_path, record=record))
        out.append((record, parse_world(world_path.read_text(), str(world_path))))
    return out


def _messages(path: Path) -> list[tuple[str, int, dict[str, Any]]]:
    with open(path, "rb") as f:
        return [
            (channel.topic, message.log_time, orjson.loads(message.data))
            for _, channel, message in make_reader(f).iter_messages(log_time_order=True)
        ]


def _latest(messages: list[tuple[str, int, dict[str, Any]]], at_ns: int) -> dict[str, Any]:
    """What a viewer shows after seeking to `at_ns`: the latest message of each topic."""
    latest: dict[str, Any] = {}
    for topic, time_ns, data in messages:
        if time_ns > at_ns:
            break
        latest[topic] = data
    return latest


def _seek_points(messages: list[tuple[str, int, dict[str, Any]]]) -> list[int]:
    first, last = messages[0][1], messages[-1][1]
    return [first + (last - first) * i // (SEEK_POINTS - 1) for i in range(SEEK_POINTS)]


def test_the_whole_scene_is_there_at_every_seek_point(
    recordings: list[tuple[Path, World]],
) -> None:
    for path, world in recordings:
        messages = _messages(path)
        expected = {"vehicle"} | {f"marker/{m.id}" for m in world.markers}
        if world.object is not None:
            expected.add("object")
        assert len(expected) > 2
        for at_ns in _seek_points(messages):
            latest = _latest(messages, at_ns)
            entities = {
                e["id"]: e
                for topic in SCENE_TOPICS
                for e in latest.get(topic, {}).get("entities", [])
            }
            assert set(entities) == expected, (path.name, at_ns)
            # The vehicle's body is drawn in its frame: the frame must be placed.
            assert TRANSFORM_TOPIC in latest, (path.name, at_ns)
            if world.object is not None:  # the object is where it is at that time
                sphere = entities["object"]["spheres"][0]["pose"]["position"]
                x, y, _ = world.object.at(at_ns / 1e9)
                assert math.dist((sphere["x"], sphere["y"]), (x, y)) <= OBJECT_STEP_M + 1e-6


def test_moving_and_still_objects_go_on_their_own_topics(
    recordings: list[tuple[Path, World]],
) -> None:
    # The still world's object is sent once, with the markers; the walker with the vehicle.
    by_name = {path.stem: _messages(path) for path, _ in recordings}
    for name, object_topic in [("default", "/drone1/scene"), ("still", "/drone1/scene/static")]:
        messages = by_name[name]
        holding = {
            topic
            for topic, _, data in messages
            if topic in SCENE_TOPICS and any(e["id"] == "object" for e in data["entities"])
        }
        assert holding == {object_topic}, name
    still_scenes = [t for topic, t, _ in by_name["still"] if topic == "/drone1/scene"]
    assert still_scenes == [0]  # nothing moves but the vehicle, which its frame carries
