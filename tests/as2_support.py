"""Aerostack2 flights written as rosbag2 bags with rosbags' writer, from the as2_msgs
definitions aeroexec ships (no public Aerostack2 flight bag exists).

What is written follows what Aerostack2 publishes (reference/aerostack2/NOTES.md):

* every behavior server (`TakeoffBehavior`, `GoToBehavior`, `FollowPathBehavior`,
  `LandBehavior` in namespace `/drone0`) publishes `_behavior/behavior_status`
  (as2_msgs/BehaviorStatus) from its own 100 ms wall timer, IDLE included: each timer
  has its own phase; a goal accepted at t shows RUNNING from the next tick, an end shows
  IDLE from the next tick after it;
* its action server publishes `_action/status` (action_msgs/GoalStatusArray) at every
  goal state change (ACCEPTED 1, EXECUTING 2, SUCCEEDED 4, CANCELED 5, ABORTED 6) with
  every goal it still keeps: terminal goals stay in later arrays; a stop (`_behavior/stop`,
  a Trigger service) ends the run with no terminal status at all;
* `platform/info` (as2_msgs/PlatformInfo) at 10 Hz (DISARMED, LANDED, TAKING_OFF, FLYING,
  LANDING) and `self_localization/pose` (geometry_msgs/PoseStamped, frame `earth`) at
  30 Hz;
* with `services=True`, the action's `send_goal` and `get_result` service events
  (REQUEST_RECEIVED and RESPONSE_SENT, server side) as rosbag2 (Iron+) records them; in
  an MCAP bag their schema is the `.action` text (the raw-text form of
  ros2/rosbag2#2365), in sqlite3 the full definition; and the `_behavior/stop` call.

`FLIGHT` is the mission: takeoff (succeeds), go to (succeeds), follow path (aborted),
go to (stopped by the operator), land (paused and resumed, succeeds). `EXPECTED` is
the behavior timeline an import must find.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys.store import Typestore

from aeroexec.bags.ros2types import Ros2Types

NS = 1_000_000_000
MS = 1_000_000
START_NS = 1_764_000_000 * NS  # 2025-11-24
DRONE = "drone0"
STATUS_PERIOD_NS = 100 * MS
#: Each behavior server's status timer phase (their timers are not aligned).
PHASE_NS = {
    "TakeoffBehavior": 13 * MS,
    "GoToBehavior": 41 * MS,
    "FollowPathBehavior": 67 * MS,
    "LandBehavior": 89 * MS,
}
ACTIONS = {
    "TakeoffBehavior": "Takeoff",
    "GoToBehavior": "GoToWaypoint",
    "FollowPathBehavior": "FollowPath",
    "LandBehavior": "Land",
}
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6
IDLE, RUNNING, PAUSED = 0, 1, 2
ACTION_DIR = Path(__file__).resolve().parent.parent / "aeroexec/data/msg_ros2/as2_msgs/action"


@dataclass(frozen=True)
class Run:
    """One goal: accepted at `start_s`, ended at `end_s` with a terminal status (None:
    stopped through `_behavior/stop`), paused over `paused` (start, end) when given."""

    behavior: str
    start_s: float
    end_s: float
    terminal: int | None
    success: bool = True
    paused: tuple[float, float] | None = None


FLIGHT = (
    Run("TakeoffBehavior", 2.0, 6.0, SUCCEEDED),
    Run("GoToBehavior", 7.0, 12.0, SUCCEEDED),
    Run("FollowPathBehavior", 13.0, 16.0, ABORTED, success=False),
    Run("GoToBehavior", 17.0, 19.0, None),
    Run("LandBehavior", 20.0, 25.0, SUCCEEDED, paused=(21.0, 22.0)),
)
END_S = 27.0
#: (behavior, start s, end s, code) an import must find (times: when the goal started
#: and ended; the import sees them through the 10 Hz status, within one period).
EXPECTED = (
    ("TakeoffBehavior", 2.0, 6.0, "GOAL_ACHIEVED"),
    ("GoToBehavior", 7.0, 12.0, "GOAL_ACHIEVED"),
    ("FollowPathBehavior", 13.0, 16.0, "WRONG_PROGRESS"),
    ("GoToBehavior", 17.0, 19.0, "INTERRUPTED"),
    ("LandBehavior", 20.0, 25.0, "GOAL_ACHIEVED"),
)


def t_ns(seconds: float) -> int:
    return START_NS + round(seconds * NS)


def _stamp(store: Typestore, time_ns: int) -> object:
    return store.types["builtin_interfaces/msg/Time"](sec=time_ns // NS, nanosec=time_ns % NS)


def _header(store: Typestore, time_ns: int, frame: str) -> object:
    return store.types["std_msgs/msg/Header"](stamp=_stamp(store, time_ns), frame_id=frame)


def _uuid(store: Typestore, n: int) -> object:
    return store.types["unique_identifier_msgs/msg/UUID"](uuid=np.array([n] * 16, dtype=np.uint8))


def _status_at(run: Run, time_s: float) -> int:
    """The behavior status a tick at `time_s` shows for `run` (None outside it)."""
    if run.paused and run.paused[0] < time_s <= run.paused[1]:
        return PAUSED
    return RUNNING


def _platform_state(time_s: float) -> tuple[int, bool]:
    """(PlatformStatus state, armed) over the mission."""
    if time_s < 1.0:
        return 0, False  # DISARMED
    if time_s < 2.0:
        return 1, True  # LANDED
    if time_s < 6.0:
        return 2, True  # TAKING_OFF
    if time_s < 20.0:
        return 3, True  # FLYING
    if time_s < 25.0:
        return 4, True  # LANDING
    if time_s < 26.0:
        return 1, True  # LANDED
    return 0, False


def _position(time_s: float) -> tuple[float, float, float]:
    def lerp(a: float, b: float, t0: float, t1: float) -> float:
        f = min(max((time_s - t0) / (t1 - t0), 0.0), 1.0)
        return a + (b - a) * f

    z = lerp(0.0, 1.5, 2.0, 6.0) if time_s < 20.0 else lerp(1.5, 0.0, 22.0, 25.0)
    x = lerp(0.0, 4.0, 7.0, 12.0) + lerp(0.0, -2.0, 13.0, 16.0) + lerp(0.0, 1.0, 17.0, 19.0)
    y = lerp(0.0, 3.0, 7.0, 12.0)
    return x, y, z


class _Bag:
    """Messages gathered, then written in time order."""

    def __init__(self, store: Typestore) -> None:
        self.store = store
        self.messages: list[tuple[int, str, object, str]] = []  # time, topic, msg, type

    def add(self, time_ns: int, topic: str, message: object, decode_type: str) -> None:
        self.messages.append((time_ns, topic, message, decode_type))


def write_flight(path: Path, storage: str = "mcap", services: bool = True) -> Path:
    """Write `FLIGHT` as a rosbag2 directory at `path` (`storage`: mcap or sqlite3)."""
    types = Ros2Types()
    store = types.store
    bag = _Bag(store)
    T = store.types
    ns = f"/{DRONE}"
    # behavior status ticks
    for behavior, phase in PHASE_NS.items():
        runs = [r for r in FLIGHT if r.behavior == behavior]
        tick = START_NS + phase
        while tick <= t_ns(END_S):
            time_s = (tick - START_NS) / NS
            value = IDLE
            for run in runs:
                if run.start_s < time_s <= run.end_s:
                    value = _status_at(run, time_s)
            bag.add(
                tick,
                f"{ns}/{behavior}/_behavior/behavior_status",
                T["as2_msgs/msg/BehaviorStatus"](status=value),
                "as2_msgs/msg/BehaviorStatus",
            )
            tick += STATUS_PERIOD_NS
    # goal status arrays and action services
    kept: dict[str, list[object]] = {b: [] for b in ACTIONS}
    for number, run in enumerate(FLIGHT, start=1):
        action = ACTIONS[run.behavior]
        uuid = _uuid(store, number)
        base = f"{ns}/{run.behavior}/_action"

        start = t_ns(run.start_s)
        _publish_status(bag, kept[run.behavior], base, run, uuid, 1, start + 1 * MS)  # ACCEPTED
        _publish_status(bag, kept[run.behavior], base, run, uuid, 2, start + 2 * MS)  # EXECUTING
        end = t_ns(run.end_s)
        if run.terminal is not None:
            _publish_status(bag, kept[run.behavior], base, run, uuid, run.terminal, end)
        if services:
            _goal_events(bag, base, action, run, uuid, start)
            if run.terminal is not None:
                _result_events(bag, base, action, run, uuid, start, end)
            else:
                _stop_events(bag, f"{ns}/{run.behavior}/_behavior/stop", end, number)
    # platform and pose
    tick = START_NS + 5 * MS
    while tick <= t_ns(END_S):
        state, armed = _platform_state((tick - START_NS) / NS)
        info = T["as2_msgs/msg/PlatformInfo"](
            header=_header(store, tick, f"{DRONE}/base_link"),
            connected=True,
            armed=armed,
            offboard=armed,
            status=T["as2_msgs/msg/PlatformStatus"](state=state),
            current_control_mode=T["as2_msgs/msg/ControlMode"](
                header=_header(store, tick, ""), yaw_mode=1, control_mode=2 if armed else 0
            ),
        )
        bag.add(tick, f"{ns}/platform/info", info, "as2_msgs/msg/PlatformInfo")
        tick += STATUS_PERIOD_NS
    tick = START_NS
    while tick <= t_ns(END_S):
        x, y, z = _position((tick - START_NS) / NS)
        pose = T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=x, y=y, z=z),
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
        )
        bag.add(
            tick,
            f"{ns}/self_localization/pose",
            T["geometry_msgs/msg/PoseStamped"](header=_header(store, tick, "earth"), pose=pose),
            "geometry_msgs/msg/PoseStamped",
        )
        tick += NS // 30
    return _write(path, bag, storage, types)


def _publish_status(
    bag: _Bag, kept: list[object], base: str, run: Run, uuid: object, state: int, when: int
) -> None:
    """A GoalStatusArray with this goal's new state and every goal the server keeps."""
    T = bag.store.types
    info = T["action_msgs/msg/GoalInfo"](goal_id=uuid, stamp=_stamp(bag.store, t_ns(run.start_s)))
    kept[:] = [g for g in kept if g.goal_info.goal_id is not uuid]  # type: ignore[attr-defined]
    kept.append(T["action_msgs/msg/GoalStatus"](goal_info=info, status=state))
    array = T["action_msgs/msg/GoalStatusArray"](status_list=list(kept))
    bag.add(when, f"{base}/status", array, "action_msgs/msg/GoalStatusArray")


def _event(
    store: Typestore, kind: int, when: int, sequence: int, request: list, response: list, name: str
) -> object:
    info = store.types["service_msgs/msg/ServiceEventInfo"](
        event_type=kind,
        stamp=_stamp(store, when),
        client_gid=np.array([7] * 16, dtype=np.uint8),
        sequence_number=sequence,
    )
    return store.types[name](info=info, request=request, response=response)


def _goal_events(bag: _Bag, base: str, action: str, run: Run, uuid: object, start: int) -> None:
    T = bag.store.types
    goal = _goal(bag.store, action, run)
    request = T[f"as2_msgs/msg/{action}_SendGoal_Request"](goal_id=uuid, goal=goal)
    response = T[f"as2_msgs/msg/{action}_SendGoal_Response"](
        accepted=True, stamp=_stamp(bag.store, start)
    )
    name = f"as2_msgs/msg/{action}_SendGoal_Event"
    seq = int(run.start_s * 10)
    topic = f"{base}/send_goal/_service_event"
    bag.add(
        start - 1 * MS, topic, _event(bag.store, 1, start - 1 * MS, seq, [request], [], name), name
    )
    bag.add(start, topic, _event(bag.store, 2, start, seq, [request], [response], name), name)


def _result_events(
    bag: _Bag, base: str, action: str, run: Run, uuid: object, start: int, end: int
) -> None:
    T = bag.store.types
    request = T[f"as2_msgs/msg/{action}_GetResult_Request"](goal_id=uuid)
    flag = {
        "Takeoff": "takeoff_success",
        "GoToWaypoint": "go_to_success",
        "FollowPath": "follow_path_success",
        "Land": "land_success",
    }[action]
    result = T[f"as2_msgs/msg/{action}_Result"](**{flag: run.success})
    response = T[f"as2_msgs/msg/{action}_GetResult_Response"](status=run.terminal, result=result)
    name = f"as2_msgs/msg/{action}_GetResult_Event"
    seq = int(run.start_s * 10) + 1
    topic = f"{base}/get_result/_service_event"
    bag.add(
        start + 3 * MS, topic, _event(bag.store, 1, start + 3 * MS, seq, [request], [], name), name
    )
    bag.add(
        end + 1 * MS,
        topic,
        _event(bag.store, 2, end + 1 * MS, seq, [request], [response], name),
        name,
    )


def _stop_events(bag: _Bag, topic: str, end: int, number: int) -> None:
    T = bag.store.types
    name = "std_srvs/msg/Trigger_Event"
    request = T["std_srvs/msg/Trigger_Request"]()
    response = T["std_srvs/msg/Trigger_Response"](success=True, message="")
    bag.add(
        end - 1 * MS,
        f"{topic}/_service_event",
        _event(bag.store, 1, end - 1 * MS, number, [request], [], name),
        name,
    )
    bag.add(
        end,
        f"{topic}/_service_event",
        _event(bag.store, 2, end, number, [request], [response], name),
        name,
    )


def _goal(store: Typestore, action: str, run: Run) -> object:
    T = store.types
    goal_type = T[f"as2_msgs/msg/{action}_Goal"]
    if action == "Takeoff":
        return goal_type(takeoff_height=1.5, takeoff_speed=0.5)
    if action == "Land":
        return goal_type(land_speed=0.4)
    yaw = T["as2_msgs/msg/YawMode"](mode=0, angle=0.0)
    if action == "GoToWaypoint":
        point = T["geometry_msgs/msg/PointStamped"](
            header=_header(store, t_ns(run.start_s), "earth"),
            point=T["geometry_msgs/msg/Point"](x=4.0, y=3.0, z=1.5),
        )
        return goal_type(yaw=yaw, target_pose=point, max_speed=1.0)
    pose = T["geometry_msgs/msg/Pose"](
        position=T["geometry_msgs/msg/Point"](x=2.0, y=3.0, z=1.5),
        orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
    )
    path = [T["as2_msgs/msg/PoseWithID"](id="wp1", pose=pose)]
    return goal_type(
        header=_header(store, t_ns(run.start_s), "earth"), yaw=yaw, path=path, max_speed=1.0
    )


def _ros_type(decode_type: str, topic: str) -> str:
    """The ROS 2 type name a real bag gives (actions and services under their kind)."""
    pkg, _, name = decode_type.split("/")
    if "/_action/" in topic and decode_type.startswith("as2_msgs/"):
        return f"{pkg}/action/{name}"
    if topic.endswith("/_service_event") and decode_type.startswith("std_srvs/"):
        return f"{pkg}/srv/{name}"
    return decode_type


def _write(path: Path, bag: _Bag, storage: str, types: Ros2Types) -> Path:
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    store = bag.store
    with Writer(path, version=8, storage_plugin=plugin) as writer:
        connections = {}
        for _, topic, _, decode_type in sorted(bag.messages, key=lambda m: m[1]):
            if topic in connections:
                continue
            ros_type = _ros_type(decode_type, topic)
            msgdef = store.generate_msgdef(decode_type, ros_version=2)[0]
            if storage == "mcap" and "/_action/" in topic and topic.endswith("/_service_event"):
                action = ros_type.rsplit("/", 1)[-1].rsplit("_", 2)[0]
                msgdef = (ACTION_DIR / f"{action}.action").read_text()  # rosbag2's raw text
            connections[topic] = writer.add_connection(
                topic, ros_type, msgdef=msgdef, rihs01="RIHS01_" + "0" * 64
            )
        for time_ns, topic, message, decode_type in sorted(
            bag.messages, key=lambda m: (m[0], m[1])
        ):
            writer.write(
                connections[topic], time_ns, bytes(store.serialize_cdr(message, decode_type))
            )
    return path
