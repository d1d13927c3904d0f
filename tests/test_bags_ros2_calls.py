"""ROS 2 service events as calls, beyond the real bags: a call whose response the bag
never got, a call seen by both client and server (one call, not two), and the topic
patterns (`*`, `**`) that name behaviors and services."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.rosbag2 import StoragePlugin, Writer

from aeroexec.bags import import_bag, load_mapping
from aeroexec.bags.mapping import Kind, _match_segments
from aeroexec.bags.ros2types import Ros2Types

START = 1_764_000_000_000_000_000
MS = 1_000_000


def _trigger_bag(path: Path) -> Path:
    """`/drone0/TakeoffBehavior/_behavior/pause` (std_srvs/Trigger) recorded by client and
    server: call 1 answered (all four events), call 2 asked and never answered."""
    store = Ros2Types().store
    T = store.types
    name = "std_srvs/msg/Trigger_Event"

    def event(kind: int, t: int, seq: int, answered: bool) -> bytes:
        info = T["service_msgs/msg/ServiceEventInfo"](
            event_type=kind,
            stamp=T["builtin_interfaces/msg/Time"](sec=t // 10**9, nanosec=t % 10**9),
            client_gid=np.arange(16, dtype=np.uint8),
            sequence_number=seq,
        )
        request = [T["std_srvs/msg/Trigger_Request"]()]
        response = (
            [T["std_srvs/msg/Trigger_Response"](success=True, message="paused")] if answered else []
        )
        message = T[name](info=info, request=request, response=response)
        return bytes(store.serialize_cdr(message, name))

    with Writer(path, version=8, storage_plugin=StoragePlugin.MCAP) as writer:
        topic = "/drone0/TakeoffBehavior/_behavior/pause/_service_event"
        definition = store.generate_msgdef(name, ros_version=2)[0]
        c = writer.add_connection(
            topic, "std_srvs/srv/Trigger_Event", msgdef=definition, rihs01="RIHS01_" + "0" * 64
        )
        for kind, offset in ((0, 0), (1, 1), (2, 2), (3, 3)):
            writer.write(c, START + offset * MS, event(kind, START, 1, kind >= 2))
        writer.write(c, START + 500 * MS, event(0, START + 500 * MS, 2, False))
        writer.write(c, START + 501 * MS, event(1, START + 501 * MS, 2, False))
    return path


def test_one_call_per_sequence_number_and_the_unanswered_one_at_the_end(tmp_path: Path) -> None:
    bag = _trigger_bag(tmp_path / "pause")
    target = tmp_path / "pause.mcap"
    report = import_bag(bag, target)
    assert report.derived["services/TakeoffBehavior/_behavior/pause"] == 2
    with open(target, "rb") as stream:
        calls = [
            (m.log_time - START, json.loads(m.data))
            for _, _, m in make_reader(stream).iter_messages(
                topics=["/drone0/services/TakeoffBehavior/_behavior/pause"]
            )
        ]
    (t1, answered), (t2, unanswered) = calls
    assert t1 == 2 * MS  # the first response event (the server's RESPONSE_SENT)
    assert answered["response"] == {"success": True, "message": "paused", "ok": True, "error": ""}
    assert answered["service"] == "/drone0/TakeoffBehavior/_behavior/pause"
    assert answered["caller"] == "client 0001020304050607"
    assert t2 == 501 * MS  # written at the bag's end, its last message
    assert unanswered["response"] == {"ok": False, "error": "no response recorded"}
    assert [answered["seq"], unanswered["seq"]] == [0, 1]


@pytest.mark.parametrize(
    ("pattern", "topic", "label"),
    [
        (
            "/d/*/_behavior/behavior_status",
            "/d/TakeoffBehavior/_behavior/behavior_status",
            "TakeoffBehavior",
        ),
        ("/d/*/_behavior/behavior_status", "/d/a/b/_behavior/behavior_status", None),
        ("/d/*/_behavior/behavior_status", "/e/X/_behavior/behavior_status", None),
        ("/**/_service_event", "/add_two_ints/_service_event", "add_two_ints"),
        ("/**/_service_event", "/d/X/_action/send_goal/_service_event", "d/X/_action/send_goal"),
        ("/**/_service_event", "/_service_event", None),
        ("/**/_service_event", "/add_two_ints/_service_event/x", None),
    ],
)
def test_topic_patterns(pattern: str, topic: str, label: str | None) -> None:
    assert _match_segments(pattern, topic) == label


def test_the_ros2_default_mapping_is_aerostack2s() -> None:
    mapping = load_mapping(None, ros_version=2)
    assert mapping.source == "aerostack2.yaml" and mapping.drone == "drone0"
    kinds = {rule.kind for rule in mapping.rules}
    assert {Kind.BEHAVIOR_STATUS, Kind.ACTION_STATUS, Kind.SERVICE_EVENTS, Kind.POSE} <= kinds
    status = next(r for r in mapping.rules if r.kind is Kind.BEHAVIOR_STATUS)
    assert (
        status.label("/drone0/LandBehavior/_behavior/behavior_status", "drone0") == "LandBehavior"
    )
    assert status.label("/drone1/LandBehavior/_behavior/behavior_status", "drone0") is None
