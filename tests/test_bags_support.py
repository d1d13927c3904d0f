"""Helpers shared by tests/test_bags*.py: the fixture bags, and Aerostack-style bags
written with rosbags' writer from the real message definitions.

`AerostackBag` collects a timeline (active-behavior lists, behavior events, capability
lists, poses, flight status, battery) and writes it as a ROS 1 bag the way a 2017-2018
Aerostack drone would have recorded it: droneMsgsROS/BehaviorEvent and ListOfBehaviors
(2018) or behaviorEvent and listOfBehaviors (June 2017, with the literal quotes of its
string constants), from aeroexec's shipped definitions; droneMsgsROS/dronePose,
droneStatus and battery with the definitions of the real 2017 Aerostack bag's
connection headers. Holds no tests itself beyond checking its own output.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rosbags.rosbag1 import Reader, Writer
from rosbags.typesys.store import Typestore

from aeroexec.bags.types import aerostack_typestore, parse_msgdef

REPO = Path(__file__).resolve().parent.parent
BAGS = REPO / "tests" / "fixtures" / "bags"
AEROSTACK_BAG = BAGS / "aerostack_2017_first_view_ros1.bag"
ROTORS_BAG = BAGS / "ros1_rotors_waypoint_example_uncompressed.bag"
TURTLE_BZ2 = BAGS / "ros1_turtlesim_example_bz2.bag"
TURTLE_LZ4 = BAGS / "ros1_turtlesim_example_lz4.bag"
REAL_BAGS = (AEROSTACK_BAG, ROTORS_BAG, TURTLE_BZ2, TURTLE_LZ4)
THESIS_CATALOG = REPO / "catalog" / "aerostack-2017.yaml"
NS = 1_000_000_000
#: Bag time of the synthetic missions' start (the real bag's day, 2017-06-28).
START_NS = 1_498_638_127_000_000_000

#: Types the synthetic bags take from the real bag's connection headers.
_REAL_TYPES = (
    "droneMsgsROS/msg/dronePose",
    "droneMsgsROS/msg/droneStatus",
    "droneMsgsROS/msg/battery",
)


def topic_times(path: Path, topic: str) -> list[int]:
    """Log times of `topic`'s messages, as rosbags reads them."""
    with Reader(path) as reader:
        connections = [c for c in reader.connections if c.topic == topic]
        return [t for _, t, _ in reader.messages(connections)]


def state_times(pose_times: list[int], period_ns: int = NS // 10) -> list[int]:
    """When the import writes vehicle/state for poses at `pose_times`: the first pose,
    then the first pose at least `period_ns` after the last written one, and the last
    pose in any case (the final state)."""
    out: list[int] = []
    for t in pose_times:
        if not out or t - out[-1] >= period_ns:
            out.append(t)
    if pose_times and out[-1] != pose_times[-1]:
        out.append(pose_times[-1])
    return out


def real_definitions() -> dict[str, tuple[str, str]]:
    """msgtype -> (message definition, md5sum), as the real Aerostack bag has them."""
    found: dict[str, tuple[str, str]] = {}
    with Reader(AEROSTACK_BAG) as reader:
        for connection in reader.connections:
            if connection.msgtype in _REAL_TYPES:
                found.setdefault(connection.msgtype, (connection.msgdef.data, connection.digest))
    return found


def typestore() -> Typestore:
    """aeroexec's Aerostack store plus the real bag's pose/status/battery types."""
    store = aerostack_typestore()
    for msgtype, (text, _) in real_definitions().items():
        store.register(parse_msgdef(text, msgtype))  # type: ignore[arg-type]
    return store


@dataclass
class AerostackBag:
    """A timeline to write as an Aerostack bag. Times are seconds from the start."""

    drone: str = "drone1"
    #: "2018": BehaviorEvent/ListOfBehaviors; "2017": behaviorEvent/listOfBehaviors.
    version: str = "2018"
    start_ns: int = START_NS
    items: list[tuple[int, str, str, dict[str, Any]]] = field(default_factory=list)

    def _add(self, t: float, topic: str, msgtype: str, fields: dict[str, Any]) -> None:
        self.items.append(
            (self.start_ns + round(t * NS), f"/{self.drone}/{topic}", msgtype, fields)
        )

    def active(self, t: float, *names: str, args: dict[str, str] | None = None) -> None:
        if self.version == "2017":
            self._add(
                t,
                "list_of_active_behaviors",
                "droneMsgsROS/msg/listOfBehaviors",
                {"active_behaviors": list(names)},
            )
        else:
            commands = [(n, (args or {}).get(n, "")) for n in names]
            self._add(
                t,
                "list_of_active_behaviors",
                "droneMsgsROS/msg/ListOfBehaviors",
                {"behaviors": list(names), "behavior_commands": commands},
            )

    def event(self, t: float, name: str, code: str, failed_belief: str = "") -> None:
        if self.version == "2017":
            self._add(
                t,
                "behavior_event",
                "droneMsgsROS/msg/behaviorEvent",
                {"name": name, "behavior_event_code": f'"{code}"', "failed_belief": failed_belief},
            )
        else:
            self._add(
                t,
                "behavior_event",
                "droneMsgsROS/msg/BehaviorEvent",
                {"name": name, "behavior_event_code": code, "failed_belief": failed_belief},
            )

    def capabilities(self, t: float, *names: str) -> None:
        self._add(
            t,
            "list_of_active_capabilities",
            "droneMsgsROS/msg/ListOfCapabilities",
            {"capabilities": list(names)},
        )

    def process(self, t: float, name: str, running: bool) -> None:
        """An AliveSignal heartbeat (Started=7 when running, ReadyToStart=2 when not)."""
        self._add(
            t,
            "process_alive_signal",
            "droneMsgsROS/msg/AliveSignal",
            {
                "process_name": f"/{self.drone}/{name}",
                "hostname": "test",
                "current_state": {"state": 7 if running else 2},
            },
        )

    def pose(self, t: float, x: float, y: float, z: float, yaw: float = 0.0) -> None:
        self._add(
            t,
            "EstimatedPose_droneGMR_wrt_GFF",
            "droneMsgsROS/msg/dronePose",
            {"x": x, "y": y, "z": z, "yaw": yaw},
        )

    def status(self, t: float, status: int) -> None:
        self._add(t, "status", "droneMsgsROS/msg/droneStatus", {"status": status})

    def battery(self, t: float, percent: float) -> None:
        self._add(t, "battery", "droneMsgsROS/msg/battery", {"batteryPercent": percent})

    def write(self, path: Path, compression: str | None = None) -> Path:
        store = typestore()
        real = real_definitions()
        writer = Writer(path)
        if compression is not None:
            writer.set_compression(Writer.CompressionFormat[compression.upper()])
        with writer:
            connections: dict[tuple[str, str], Any] = {}
            for time_ns, topic, msgtype, fields in sorted(self.items, key=lambda i: i[0]):
                key = (topic, msgtype)
                if key not in connections:
                    extra: dict[str, str] = {}
                    if msgtype in real:
                        extra = {"msgdef": real[msgtype][0], "md5sum": real[msgtype][1]}
                    connections[key] = writer.add_connection(
                        topic, msgtype, typestore=store, callerid=f"/{self.drone}/test", **extra
                    )
                data = store.serialize_ros1(_message(store, msgtype, fields, time_ns), msgtype)
                writer.write(connections[key], time_ns, data)
        return path


def _message(store: Typestore, msgtype: str, fields: dict[str, Any], time_ns: int) -> object:
    """A message of `msgtype` with `fields` set and everything else zero/empty."""
    return _build(store, msgtype, fields, time_ns)


def _build(store: Typestore, msgtype: str, fields: dict[str, Any], time_ns: int) -> object:
    cls = store.types[msgtype]
    _, entries = store.fielddefs[msgtype]
    values: dict[str, Any] = {}
    for name, desc in entries:
        if name in fields:
            value = fields[name]
            if isinstance(value, dict):
                value = _build(store, desc[1], value, time_ns)
            elif name == "behavior_commands":
                command_type = "droneMsgsROS/msg/BehaviorCommand"
                value = [
                    _build(store, command_type, {"name": n, "arguments": a}, 0) for n, a in value
                ]
            values[name] = value
        else:
            values[name] = _zero(store, desc, time_ns)
    return cls(**values)


def _zero(store: Typestore, desc: Any, time_ns: int) -> Any:
    kind, detail = desc
    if kind == 1:  # base type
        typ = detail[0]
        if typ == "string":
            return ""
        if typ == "bool":
            return False
        return 0.0 if typ.startswith("float") else 0
    if kind == 2:  # named message
        name = detail
        if name == "builtin_interfaces/msg/Time":
            sec, nsec = divmod(time_ns, NS)
            return store.types[name](sec=sec, nanosec=nsec)
        return _build(store, name, {}, time_ns)
    return []  # sequences and arrays: empty


#: The capabilities of the Appendix A catalog in catalog order, and their processes.
CAPABILITY_PROCESSES = {
    "SETPOINT_BASED_FLIGHT_CONTROL": ("droneTrajectoryController",),
    "PATH_PLANNING": ("droneTrajectoryPlanner", "droneYawPlanner"),
    "SELF_LOCALIZATION_BY_ODOMETRY": ("droneOdometryStateEstimator",),
    "VISUAL_MARKERS_RECOGNITION": ("droneArucoEyeROSModule",),
}


def short_mission(
    version: str = "2018", resources: bool = True, drone: str = "drone1"
) -> AerostackBag:
    """Take off, pay attention, go to (1, 2, 1), hover, inhibit PAY_ATTENTION, land
    (LAND preempts KEEP_HOVERING), as an Aerostack drone flying the thesis' Appendix A
    catalog would record it. With `resources`, also the resource manager's capability
    lists and the processes' heartbeats that catalog implies (processes start in
    capability order and stop in reverse)."""
    bag = AerostackBag(drone=drone, version=version)
    if resources:
        _resources(bag)
    bag.battery(0.0, 90.0)
    bag.status(0.0, 2)  # LANDED
    for i in range(0, 161):
        t = i / 10
        z = _altitude(t)
        progress = min(max((t - 5.0) / 3.5, 0.0), 1.0)
        bag.pose(t + 0.005, 1.0 * progress, 2.0 * progress, z)
    bag.status(1.0, 6)  # TAKING_OFF
    bag.status(3.6, 3)  # FLYING
    bag.status(12.5, 8)  # LANDING
    bag.status(14.6, 2)  # LANDED
    bag.active(1.0, "TAKE_OFF")
    bag.active(2.0, "TAKE_OFF", "PAY_ATTENTION")
    bag.event(3.8, "TAKE_OFF", "GOAL_ACHIEVED")
    bag.active(3.81, "PAY_ATTENTION")
    bag.active(5.0, "GO_TO_POINT", "PAY_ATTENTION", args={"GO_TO_POINT": "coordinates: [1, 2, 1]"})
    bag.event(8.6, "GO_TO_POINT", "GOAL_ACHIEVED")
    bag.active(8.61, "PAY_ATTENTION")
    bag.active(9.0, "PAY_ATTENTION", "KEEP_HOVERING")
    bag.active(10.0, "KEEP_HOVERING")  # PAY_ATTENTION gone without an event: inhibited
    bag.event(12.5, "KEEP_HOVERING", "INTERRUPTED")
    bag.active(12.5, "LAND")  # LAND preempted KEEP_HOVERING
    bag.event(14.6, "LAND", "GOAL_ACHIEVED")
    bag.active(14.61)
    return bag


def _altitude(t: float) -> float:
    """0 m on the ground, climbing from 1 s to 1 m at 3.5 s, down from 12.5 s to 14.5 s."""
    if t < 1.0:
        return 0.0
    if t < 12.5:
        return min(1.0, (t - 1.0) / 2.5)
    return max(0.0, 1.0 - (t - 12.5) / 2.0)


def _resources(bag: AerostackBag) -> None:
    odometry = "SELF_LOCALIZATION_BY_ODOMETRY"
    attention = "VISUAL_MARKERS_RECOGNITION"
    setpoint, planning = "SETPOINT_BASED_FLIGHT_CONTROL", "PATH_PLANNING"
    lists = [
        (0.0, [odometry]),
        (2.0, [odometry, attention]),
        (5.0, [setpoint, planning, odometry, attention]),
        (8.6, [odometry, attention]),
        (9.0, [setpoint, odometry, attention]),
        (10.0, [setpoint, odometry]),
        (12.5, [odometry]),
    ]
    running: list[str] = []
    timeline: list[tuple[float, list[str]]] = []
    for t, names in lists:
        bag.capabilities(t, *names)
        now = [p for n in names for p in CAPABILITY_PROCESSES[n]]
        for process in reversed(_in_start_order(p for p in running if p not in now)):
            bag.process(t, process, False)
        for process in _in_start_order(p for p in now if p not in running):
            bag.process(t, process, True)
        running = now
        timeline.append((t, now))
    for second in range(1, 17):  # heartbeats repeating the current state change nothing
        current = [names for t, names in timeline if t <= second + 0.5][-1]
        for process in current:
            bag.process(second + 0.5, process, True)


def _in_start_order(processes: Iterable[str]) -> list[str]:
    wanted = set(processes)
    return [p for names in CAPABILITY_PROCESSES.values() for p in names if p in wanted]


def test_short_mission_bag_reads_back(tmp_path: Path) -> None:
    path = short_mission().write(tmp_path / "m.bag")
    with Reader(path) as reader:
        topics = {c.topic: c.msgcount for c in reader.connections}
    assert topics["/drone1/behavior_event"] == 4
    assert topics["/drone1/list_of_active_behaviors"] == 9
    assert topics["/drone1/EstimatedPose_droneGMR_wrt_GFF"] == 161
