"""World files: the shipped worlds, and clear errors with file:line:col for bad ones."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from aeroexec.errors import WorldError
from aeroexec.vehicles import World, default_world, load_world, parse_world
from aeroexec.vehicles.world import (
    FAULTS_WORLD,
    BatteryModel,
    Limits,
    Marker,
    MovingObject,
    RandomFailure,
    ScheduledFailure,
)


def test_default_world_has_the_mission_markers_and_an_object() -> None:
    world = default_world()
    assert world.name == "default"
    assert [m.id for m in world.markers] == [1, 2, 3, 4, 9]
    assert world.object == MovingObject((-3.0, 1.0, 0.0), (0.05, 0.0, 0.0))
    assert world.camera_range == 4.0
    assert world.limits == Limits(2.0, 1.0, 2.0, 90.0)
    assert world.battery == BatteryModel(1.0, 1200.0, 7200.0)
    assert world.failures == () and world.random_failure is None
    assert default_world() is world  # loaded once, shared (it is immutable)


def test_faults_world_seizes_a_motor_at_eight_seconds() -> None:
    world = load_world(FAULTS_WORLD)
    assert world.failures == (
        ScheduledFailure("stuck_motor", 8.0),
        ScheduledFailure("low_battery", 60.0, 0.15),
    )


def test_worlds_are_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        default_world().camera_range = 10.0  # type: ignore[misc]


def test_a_full_world_file_is_read_into_typed_values() -> None:
    world = parse_world(
        """
name: yard
seed: 42
camera: {range: 6}
vehicle:
  start: [1, 2, 0]
  start_yaw: 90
  max_horizontal_speed: 3
  max_vertical_speed: 0.5
  max_acceleration: 4
  max_yaw_rate: 45
battery: {initial: 50, flight_endurance: 600, idle_endurance: 3600}
markers:
  - {id: 7, position: [1, 1, 1]}
  - {id: 3, position: [2.5, 0, 0.2]}
object: {position: [5, 5, 0]}
failures:
  - {kind: stuck_motor, at: 20}
  - {kind: low_battery, at: 10, level: 5}
random_failure: {kind: low_battery, rate: 0.02}
"""
    )
    assert world == World(
        name="yard",
        # Sorted by id so what the camera reports never depends on the file's order.
        markers=(Marker(3, (2.5, 0.0, 0.2)), Marker(7, (1.0, 1.0, 1.0))),
        object=MovingObject((5.0, 5.0, 0.0)),
        camera_range=6.0,
        start=(1.0, 2.0, 0.0),
        start_yaw=90.0,
        limits=Limits(3.0, 0.5, 4.0, 45.0),
        battery=BatteryModel(0.5, 600.0, 3600.0),
        failures=(
            ScheduledFailure("low_battery", 10.0, 0.05),
            ScheduledFailure("stuck_motor", 20.0),
        ),
        random_failure=RandomFailure("low_battery", 0.02, None),
        seed=42,
    )


def test_an_empty_file_is_an_empty_world() -> None:
    assert parse_world("") == World()
    assert parse_world("# nothing here\n") == World()


@pytest.mark.parametrize(
    ("text", "where", "message"),
    [
        ("markers:\n  - {id: 1, position: [0, 0]}\n", "2:23", "list of 3 numbers"),
        (
            "markers:\n  - {id: 1, position: [0, 0, 0]}\n  - {id: 1, position: [1, 1, 1]}\n",
            "3:10",
            "marker id 1 is used twice (first at line 2)",
        ),
        ("markers:\n  - {id: 1024, position: [0, 0, 0]}\n", "2:10", "[0, 1023]"),
        ("markers:\n  - {position: [0, 0, 0]}\n", "2:5", "marker needs 'id'"),
        ("camera:\n  range: -1\n", "2:10", "camera.range must be positive"),
        ("camera:\n  rnage: 3\n", "2:3", "unknown key 'rnage'"),
        ("seed: 1\nmarkers: {}\nwind: 3\n", "3:1", "unknown key 'wind'"),
        ("failures:\n  - {kind: engine_fire, at: 3}\n", "2:12", "unknown failure kind"),
        ("failures:\n  - {kind: stuck_motor}\n", "2:5", "failure needs 'at'"),
        (
            "failures:\n  - {kind: stuck_motor, at: 3, level: 5}\n",
            "2:39",
            "'level' applies to low_battery only",
        ),
        ("failures:\n  - {kind: low_battery, at: -1}\n", "2:29", "at least 0"),
        ("random_failure: {kind: stuck_motor, rate: fast}\n", "1:43", "must be a number"),
        ("vehicle:\n  start: [0, 0, 2]\n", "2:10", "on the ground"),
        ("battery: {initial: 150}\n", "1:20", "at most 100"),
        ("object: {velocity: [1, 0, 0]}\n", "1:9", "object needs a position"),
        ("seed: 1\nseed: 2\n", "2:1", "'seed' is given twice"),
        ("- a list\n", "1:1", "world must be a mapping"),
        ("markers: [\n", "2:1", "invalid YAML"),
        ("name: !!python/object:os.system x\n", "1:7", "YAML tag"),
    ],
)
def test_errors_name_the_place(text: str, where: str, message: str) -> None:
    with pytest.raises(WorldError) as caught:
        parse_world(text, "yard.yaml")
    assert str(caught.value).startswith(f"yard.yaml:{where}: error: ")
    assert message in str(caught.value)


def test_missing_or_unreadable_files_are_world_errors(tmp_path: Path) -> None:
    with pytest.raises(WorldError, match="no such file"):
        load_world(tmp_path / "nowhere.yaml")
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"name: \xff\xfe\n")
    with pytest.raises(WorldError, match="not UTF-8"):
        load_world(binary)


def test_a_world_file_on_disk_reports_its_path(tmp_path: Path) -> None:
    path = tmp_path / "w.yaml"
    path.write_text("camera:\n  range: 0\n")
    with pytest.raises(WorldError) as caught:
        load_world(path)
    assert caught.value.mark is not None
    assert (caught.value.mark.file, caught.value.mark.line) == (str(path), 2)
