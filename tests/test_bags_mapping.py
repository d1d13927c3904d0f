"""The topic mapping: the shipped Aerostack default, fallbacks in order, type rules,
{drone}, and a --mapping file that overrides the default."""

from __future__ import annotations

import math
from pathlib import Path

from test_bags_support import (
    AEROSTACK_BAG,
    NS,
    TURTLE_LZ4,
    short_mission,
    state_times,
    topic_times,
)
from typer.testing import CliRunner

from aeroexec.bags import Kind, import_bag, load_mapping
from aeroexec.cli import app
from aeroexec.recording import open_recording


def test_the_default_mapping_has_aerostacks_names() -> None:
    mapping = load_mapping()
    assert mapping.drone == "drone1"
    assert mapping.grace_ns == 500_000_000
    by_kind: dict[Kind, list[str]] = {}
    for rule in mapping.rules:
        by_kind.setdefault(rule.kind, []).append(rule.topic or f"type {rule.type}")
    assert by_kind[Kind.BEHAVIOR_EVENT] == ["/{drone}/behavior_event"]
    assert by_kind[Kind.ACTIVE_BEHAVIORS] == ["/{drone}/list_of_active_behaviors"]
    assert by_kind[Kind.ACTIVE_CAPABILITIES] == ["/{drone}/list_of_active_capabilities"]
    assert by_kind[Kind.POSE][0] == "/{drone}/EstimatedPose_droneGMR_wrt_GFF"
    assert by_kind[Kind.POSE][-1] == "type geometry_msgs/PoseStamped"
    assert Kind.ACTIVATE_COMMAND not in by_kind  # 2017 commands were service calls


def test_the_first_listed_pose_wins_and_a_mapping_file_can_prefer_another(
    tmp_path: Path,
) -> None:
    """The real bag has both EstimatedPose_droneGMR_wrt_GFF and SOEstimatedPose: the
    default takes the first; a mapping listing SOEstimatedPose takes that."""
    default = import_bag(AEROSTACK_BAG, tmp_path / "a.mcap")
    assert default.mapped["pose"] == "/drone1/EstimatedPose_droneGMR_wrt_GFF"
    first = topic_times(AEROSTACK_BAG, "/drone1/EstimatedPose_droneGMR_wrt_GFF")
    so = topic_times(AEROSTACK_BAG, "/drone1/SOEstimatedPose")
    assert default.derived["vehicle/state"] == len(state_times(first))
    custom = tmp_path / "so.yaml"
    custom.write_text('topics:\n  - {topic: "/{drone}/SOEstimatedPose", kind: pose}\n')
    other = import_bag(AEROSTACK_BAG, tmp_path / "b.mcap", mapping=custom)
    assert other.mapped == {"pose": "/drone1/SOEstimatedPose"}
    assert other.derived["vehicle/state"] == len(state_times(so))
    assert len(state_times(so)) != len(state_times(first))
    assert "process_state" not in other.derived  # the custom file replaces the default


def test_a_type_rule_takes_the_first_topic_of_that_type(tmp_path: Path) -> None:
    custom = tmp_path / "turtle.yaml"
    custom.write_text(
        "drone: turtle\nstate_period_s: 0\ntopics:\n  - {type: turtlesim/Pose, kind: pose}\n"
    )
    report = import_bag(TURTLE_LZ4, tmp_path / "t.mcap", mapping=custom)
    assert report.mapped == {"pose": "/turtle1/pose"}
    states = [
        r.data
        for r in open_recording(tmp_path / "t.mcap").records()
        if r.topic == "/turtle/vehicle/state"
    ]
    assert len(states) == 1344
    first = states[0]
    assert first["position"][2] == 0.0  # turtlesim has x, y, theta
    assert -math.pi <= first["yaw"] <= math.pi
    assert first["defaulted"] == ["velocity", "battery", "flying"]
    assert first["flying"] is False


def test_drone_namespace_selects_topics_and_names_channels(tmp_path: Path) -> None:
    path = short_mission(drone="drone2").write(tmp_path / "d2.bag")
    report = import_bag(path, tmp_path / "default.mcap")
    assert "behavior_event" not in report.mapped  # /drone1/... names only
    report = import_bag(path, tmp_path / "d2.mcap", drone="drone2")
    assert report.mapped["behavior_event"] == "/drone2/behavior_event"
    topics = set(open_recording(tmp_path / "d2.mcap").survey().topic_counts())
    assert "/drone2/mission/command" in topics
    assert "/ros1/drone2/behavior_event" in topics
    assert not any(t.startswith("/drone1/") for t in topics)


def test_cli_mapping_and_drone_options(tmp_path: Path) -> None:
    custom = tmp_path / "turtle.yaml"
    custom.write_text('state_period_s: 0.5\ntopics:\n  - {topic: "/turtle2/pose", kind: pose}\n')
    result = CliRunner().invoke(
        app,
        [
            "import",
            str(TURTLE_LZ4),
            "-o",
            str(tmp_path / "t.mcap"),
            "--mapping",
            str(custom),
            "--drone",
            "t2",
        ],
    )
    assert result.exit_code == 0, result.stderr
    assert "pose                 <- /turtle2/pose" in result.stdout
    states = len(state_times(topic_times(TURTLE_LZ4, "/turtle2/pose"), NS // 2))
    assert states == 43  # 1344 poses over ~21 s: one state per 0.5 s, and the last pose
    # A transform only for a state whose pose changed (as the Recorder writes them).
    recording = open_recording(tmp_path / "t.mcap")
    poses = [
        (tuple(r.data["position"]), r.data["yaw"])
        for r in recording.records()
        if r.topic == "/t2/vehicle/state"
    ]
    moved = [p for i, p in enumerate(poses) if i == 0 or p != poses[i - 1]]
    transforms = [
        ((r.data["translation"]["x"], r.data["translation"]["y"]), r.log_time_ns)
        for r in recording.records()
        if r.topic == "/t2/vehicle/transform"
    ]
    assert len(poses) == states and 0 < len(moved) < states  # the turtle stops once
    assert [t[0] for t in transforms] == [p[0][:2] for p in moved]
    assert (
        f"derived /t2/: scene 1, vehicle/state {states}, vehicle/transform {len(moved)}"
        in result.stdout
    )
