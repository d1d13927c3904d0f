"""ROS 2 bags without embedded definitions (rosbag2 before Iron; here: a bag whose
`message_definitions` rows are removed): the import takes the definitions aeroexec ships
(as2_msgs, Jazzy's types) and those of `--types DIR`, writes them as the raw channels'
schemas, and decodes the mapped topics with them."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest
from as2_support import EXPECTED, write_flight
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from ros2_support import bag_streams, raw_streams
from rosbags.rosbag2 import StoragePlugin, Writer
from typer.testing import CliRunner

from aeroexec.bags import import_bag
from aeroexec.bags.ros2types import Ros2Types
from aeroexec.cli import app

CHARGE = "# a team's own battery message\nfloat32 percentage\nstring cell\n"
START = 1_764_000_000_000_000_000


def _strip_definitions(bag: Path) -> Path:
    for db3 in bag.glob("*.db3"):
        with sqlite3.connect(db3) as db:
            db.execute("DELETE FROM message_definitions")
    return bag


def _types_dir(root: Path) -> Path:
    folder = root / "types" / "my_msgs" / "msg"
    folder.mkdir(parents=True)
    (folder / "Charge.msg").write_text(CHARGE)
    return root / "types"


def _charge_bag(root: Path, types: Path) -> Path:
    """A pose and the team's own battery message, in sqlite3, definitions removed."""
    store = Ros2Types(types).store
    T = store.types
    bag = root / "charge"
    with Writer(bag, version=8, storage_plugin=StoragePlugin.SQLITE3) as writer:
        battery = writer.add_connection(
            "/drone0/sensor_measurements/battery", "my_msgs/msg/Charge", typestore=store
        )
        pose_c = writer.add_connection(
            "/drone0/self_localization/pose", "geometry_msgs/msg/PoseStamped", typestore=store
        )
        for i in range(5):
            t = START + i * 200_000_000
            charge = T["my_msgs/msg/Charge"](percentage=0.9 - 0.1 * i, cell="A")
            writer.write(battery, t, bytes(store.serialize_cdr(charge, "my_msgs/msg/Charge")))
            pose = T["geometry_msgs/msg/PoseStamped"](
                header=T["std_msgs/msg/Header"](
                    stamp=T["builtin_interfaces/msg/Time"](sec=t // 10**9, nanosec=t % 10**9),
                    frame_id="earth",
                ),
                pose=T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=float(i), y=0.0, z=1.0),
                    orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                ),
            )
            writer.write(
                pose_c, t + 1, bytes(store.serialize_cdr(pose, "geometry_msgs/msg/PoseStamped"))
            )
    return _strip_definitions(bag)


def _summary(path: Path):
    with open(path, "rb") as stream:
        return make_reader(stream).get_summary()


def test_a_flight_without_definitions_imports_with_the_shipped_ones(tmp_path: Path) -> None:
    bag = _strip_definitions(write_flight(tmp_path / "flight", "sqlite3", services=False))
    target = tmp_path / "flight.mcap"
    import_bag(bag, target)
    assert raw_streams(target) == bag_streams(bag)
    summary = _summary(target)
    factory = DecoderFactory()
    for channel in summary.channels.values():
        if channel.message_encoding == "cdr":
            assert channel.metadata["definition_from"] == "aeroexec"
            assert summary.schemas[channel.schema_id].encoding == "ros2msg"
    with open(target, "rb") as stream:
        events = []
        for schema, channel, message in make_reader(stream).iter_messages():
            if channel.message_encoding == "cdr":
                factory.decoder_for("cdr", schema)(message.data)
            elif channel.topic == "/drone0/behavior_event":
                events.append(json.loads(message.data)["code"])
    assert events == [code for *_, code in EXPECTED]


def test_an_unknown_type_stays_raw_without_a_schema_and_says_so(tmp_path: Path) -> None:
    bag = _charge_bag(tmp_path, _types_dir(tmp_path))
    target = tmp_path / "charge.mcap"
    report = import_bag(bag, target)
    assert raw_streams(target) == bag_streams(bag)  # nothing lost, even undecodable
    assert any(
        "/drone0/sensor_measurements/battery" in note and "--types" in note for note in report.notes
    )
    battery = next(c for c in _summary(target).channels.values() if c.topic.endswith("/battery"))
    assert battery.schema_id == 0
    assert "battery" not in report.mapped


def test_types_dir_gives_the_definition_and_the_battery(tmp_path: Path) -> None:
    types = _types_dir(tmp_path)
    bag = _charge_bag(tmp_path, types)
    target = tmp_path / "charge.mcap"
    result = CliRunner().invoke(
        app, ["import", str(bag), "-o", str(target), "--types", str(types), "-f", "json"]
    )
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["mapped"]["battery"] == "/drone0/sensor_measurements/battery"
    summary = _summary(target)
    battery = next(c for c in summary.channels.values() if c.topic.endswith("/battery"))
    assert battery.metadata["definition_from"] == str(types)
    assert summary.schemas[battery.schema_id].data.decode().startswith("float32 percentage\n")
    with open(target, "rb") as stream:
        states = [
            json.loads(m.data)
            for _, _, m in make_reader(stream).iter_messages(topics=["/drone0/vehicle/state"])
        ]
    # each state takes the latest battery message before its pose
    assert [round(s["battery"], 3) for s in states] == [0.9, 0.8, 0.7, 0.6, 0.5]


@pytest.mark.parametrize(
    ("case", "says"),
    [
        ("missing", "--types wants a folder of .msg/.srv/.action files"),
        ("empty", "no <package>/msg, srv or action folders with definitions in it"),
        ("broken", "cannot read the definition"),
    ],
)
def test_bad_types_dir_is_one_line_and_exit_2(tmp_path: Path, case: str, says: str) -> None:
    bag = write_flight(tmp_path / "flight", "sqlite3", services=False)
    types = tmp_path / "types"
    where = types
    if case == "empty":
        types.mkdir()
    elif case == "broken":
        (types / "my_msgs" / "msg").mkdir(parents=True)
        where = types / "my_msgs" / "msg" / "Bad.msg"
        where.write_text("float32[ x\n")
    target = tmp_path / "out.mcap"
    result = CliRunner().invoke(app, ["import", str(bag), "-o", str(target), "--types", str(types)])
    assert result.exit_code == 2
    assert result.stderr.startswith(f"{where}: error: {says}"), result.stderr
    assert result.stderr.count("\n") == 1
    assert not target.exists()
