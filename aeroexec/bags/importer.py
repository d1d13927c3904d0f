"""`import_bag`: a ROS 1 or ROS 2 bag to an aeroexec-profile MCAP file, losing nothing.

Every message of every connection is copied byte for byte to a raw `ros1` or `cdr`
channel (`sink.py`); only messages of mapped topics are decoded, and only those used (a pose
when it gives a vehicle state, the latest velocity/battery/status before it), to derive
the aeroexec channels: `behavior_event`, `list_of_active_behaviors`, reconstructed
`mission/command` and coordinator calls (`reconstruct.py`),
`list_of_active_capabilities` (+ `capability_state`), `beliefs`, `process_state`, `vehicle/state` (+
`vehicle/transform` when the pose changed), the `scene` with the vehicle's body at the
bag's first message when a pose is mapped (a bag has no world; its first transform
comes with its first pose), `call_log` for the reconstructed calls. A ROS 2 bag adds
Aerostack2's behavior status, action status, goals and results (`as2.py`, feeding the
same reconstruction) and its recorded service calls (`ros2calls.py`). Log times are the bag's.
Messages are written in bag time order: reconstruction decides an input only when the 2
x grace after it has been read, so the messages from its horizon on wait (about a second
of bag time) until it has: the bag's own in a queue (they come in time order), the
derived ones in a small heap; within one instant the reconstructed commands come first,
as the executive would have published them.

The output is written next to the target and renamed into place at the end, so a bag
that turns out damaged halfway leaves no half-written file behind.
"""

from __future__ import annotations

import heapq
import os
from collections import deque
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from aeroexec import __version__
from aeroexec.bags import extract
from aeroexec.bags.as2 import BehaviorTimeline
from aeroexec.bags.bagfile import BagConnection
from aeroexec.bags.derive import (
    BeliefTracker,
    CapabilityTracker,
    ProcessTracker,
    VehicleStateBuilder,
    pose_transform,
)
from aeroexec.bags.mapping import Kind, Mapping, Rule, check_drone, load_mapping
from aeroexec.bags.reconstruct import ACTIVATE, INHIBIT, Reconstructor, Stats
from aeroexec.bags.ros2calls import Call, ServiceCalls
from aeroexec.bags.sink import COMPRESSIONS, RAW_PREFIXES, ImportSink
from aeroexec.bags.source import Bag, open_bag, ros_version_of
from aeroexec.bags.types import Decoder, TypeResolver
from aeroexec.errors import Mark, RecordingError
from aeroexec.outputs import whole_file_or_none
from aeroexec.progress import Advance, ProgressFactory
from aeroexec.recording.foxglove import (
    CAPABILITY_TOPIC,
    SCENE_TOPIC,
    CapabilityChanges,
    moving_entities,
    scene_update,
    vehicle_frame,
)
from aeroexec.recording.writer import METADATA_NAME

#: The import's metadata: what replay and info read (clock and vehicle kinds).
CLOCK = "wall"
#: By ROS version: the `vehicle` metadata and the name of the bag's own metadata.
VEHICLES = {1: "ros1-bag", 2: "ros2-bag"}
BAG_METADATAS = {1: "ros1_bag", 2: "ros2_bag"}
VEHICLE = VEHICLES[1]
BAG_METADATA = BAG_METADATAS[1]
MAPPING_ATTACHMENT = "bag_mapping.yaml"
_NS = 1_000_000_000
#: Progress is reported every this many bag messages.
PROGRESS_EVERY = 1000
#: Kinds of which only the latest message before a vehicle state matters.
_LATEST_ONLY = frozenset({Kind.VELOCITY, Kind.BATTERY, Kind.FLIGHT_STATUS})
#: ROS 2 kinds, one topic per behavior or service (named by the rule's `*`).
_ROS2_KINDS = frozenset(
    {
        Kind.BEHAVIOR_STATUS,
        Kind.ACTION_STATUS,
        Kind.ACTION_GOAL,
        Kind.ACTION_RESULT,
        Kind.SERVICE_EVENTS,
    }
)
_BEHAVIOR_KINDS = frozenset(
    {
        Kind.BEHAVIOR_EVENT,
        Kind.ACTIVE_BEHAVIORS,
        Kind.ACTIVATE_COMMAND,
        Kind.INHIBIT_COMMAND,
        Kind.BEHAVIOR_STATUS,
        Kind.ACTION_STATUS,
        Kind.ACTION_RESULT,
    }
)


@dataclass(frozen=True, slots=True)
class ImportReport:
    source: str
    target: str
    drone: str
    #: Bag messages carried over (= the bag's message count) and connections.
    messages: int
    connections: int
    topics: int
    compression: str
    start_ns: int | None
    end_ns: int | None
    #: Kind -> the bag topic it was taken from.
    mapped: dict[str, str]
    #: aeroexec topic -> messages derived.
    derived: dict[str, int]
    reconstructed_activations: int
    reconstructed_inhibitions: int
    notes: tuple[str, ...] = field(default=())
    ros_version: int = 1

    def as_dict(self) -> dict[str, Any]:
        return {
            "source": self.source,
            "target": self.target,
            "drone": self.drone,
            "messages": self.messages,
            "connections": self.connections,
            "topics": self.topics,
            "compression": self.compression,
            "start_ns": self.start_ns,
            "end_ns": self.end_ns,
            "mapped": dict(self.mapped),
            "derived": dict(self.derived),
            "reconstructed": {
                "activations": self.reconstructed_activations,
                "inhibitions": self.reconstructed_inhibitions,
            },
            "notes": list(self.notes),
            "ros_version": self.ros_version,
        }

    def summary(self) -> str:
        lines = [
            f"{self.source} -> {self.target}: {self.messages} messages on "
            f"{self.topics} topics ({self.connections} connections, {self.compression}) "
            f"carried over as raw {'ros1' if self.ros_version == 1 else 'cdr'} channels "
            f"under {RAW_PREFIXES[self.ros_version]}/",
        ]
        for kind, topic in self.mapped.items():
            lines.append(f"  {kind:<20} <- {topic}")
        if self.derived:
            derived = ", ".join(f"{t} {n}" for t, n in self.derived.items())
            lines.append(f"  derived /{self.drone}/: {derived}")
        if self.reconstructed_activations or self.reconstructed_inhibitions:
            lines.append(
                f"  reconstructed commands: {self.reconstructed_activations} activations, "
                f"{self.reconstructed_inhibitions} inhibitions"
            )
        lines.extend(f"note: {note}" for note in self.notes)
        return "\n".join(lines)


#: How one mapped connection is handled: its kind, its decoder, and the name the rule's
#: `*` matched (a behavior, a service; "" for exact topics).
_Entry = tuple[Kind, Decoder, str]
#: A mapped message kept undecoded until it is needed: (entry, connection, log time,
#: bytes).
_Pending = tuple[_Entry, BagConnection, int, bytes]


class _Ordered:
    """Writes messages in (time, rank, arrival) order. A message is held until bag time
    has moved past its instant and past the reconstruction horizon, so that the
    reconstructed commands and calls (rank 0) of an instant come before the other
    messages of that instant (rank 1): the order in which the executive publishes them
    (the capability and process changes of an activation follow its command).

    Raw messages come in bag time order, so they wait in a queue (already in order);
    only derived messages go through the heap, and `release` merges the two."""

    RECONSTRUCTED = 0
    OTHER = 1

    def __init__(self, sink: ImportSink) -> None:
        self._sink = sink
        #: (time, rank, arrival, topic, payload, call)
        self.heap: list[tuple[int, int, int, str, Any, bool]] = []
        #: (time, arrival, connection, raw bytes), in time order
        self.queue: deque[tuple[int, int, BagConnection, bytes]] = deque()
        self._order = 0

    def raw(self, time_ns: int, connection: BagConnection, data: bytes) -> None:
        self._order += 1
        self.queue.append((time_ns, self._order, connection, data))

    def derived(
        self, time_ns: int, rank: int, topic: str, data: dict[str, Any], call: bool = False
    ) -> None:
        self._order += 1
        heapq.heappush(self.heap, (time_ns, rank, self._order, topic, data, call))

    def release(self, limit: int | None) -> None:
        """Write every message before `limit` (everything when None)."""
        heap, queue = self.heap, self.queue
        write_raw, write_derived = self._sink.raw, self._sink.derived_message
        end = float("inf") if limit is None else limit
        other = self.OTHER
        while queue or heap:
            stop = heap[0][0] if heap and heap[0][0] < end else end
            # the raw messages before the next derived one are in order already
            while queue and queue[0][0] < stop:
                time_ns, _, connection, data = queue.popleft()
                write_raw(connection, time_ns, data)
            if not heap or heap[0][0] >= end:
                return
            top = heap[0]
            # the same instant: reconstructed first, then in arrival order
            if queue and queue[0][0] == top[0] and (other, queue[0][1]) < top[1:3]:
                time_ns, _, connection, data = queue.popleft()
                write_raw(connection, time_ns, data)
                continue
            time_ns, _, _, topic, payload, call = heapq.heappop(heap)
            write_derived(topic, time_ns, payload, call)


class _Import:
    """One import run (state shared by the per-message handlers)."""

    def __init__(self, bag: Bag, mapping: Mapping, drone: str, sink: ImportSink) -> None:
        self.bag = bag
        self.drone = drone
        self.sink = sink
        self.notes: list[str] = []
        self.out = _Ordered(sink)
        self.recon = Reconstructor(mapping.grace_ns)
        self.vehicle = VehicleStateBuilder()
        self.period = mapping.state_period_ns
        self._last_state_ns: int | None = None
        #: The pose of the last transform written: a state with the same pose writes none.
        self._last_pose: tuple[tuple[float, float, float], float] | None = None
        self._skipped: _Pending | None = None
        self._latest: dict[Kind, _Pending] = {}
        self.capabilities = CapabilityTracker()
        self.capability_changes = CapabilityChanges()
        self.beliefs = BeliefTracker()
        self.processes = ProcessTracker()
        self.undecodable: dict[str, int] = {}
        self.unreadable: dict[str, int] = {}
        self.timeline = BehaviorTimeline()
        self.calls = ServiceCalls(drone)
        #: The last behavior status bytes of each connection: an unchanged one is skipped.
        self._last_status: dict[int, bytes] = {}
        self.selected = mapping.select(((c.topic, c.type) for c in bag.connections), drone)
        self.handlers: dict[int, list[_Entry]] = {}
        self._resolve(self.selected)
        #: The vehicle topics (velocity, battery, flight status) the bag has messages on
        #: that have not spoken yet: poses give no state until they have (or for at most
        #: grace), so that a flight's first state is not a default where the bag has the
        #: value a moment later (a signal with a default anywhere is missing for `check`).
        counts = {c.id: c.count for c in bag.connections}
        self._awaited = {
            entry[0]
            for cid, entries in self.handlers.items()
            for entry in entries
            if entry[0] in _LATEST_ONLY and counts.get(cid, 0) > 0
        }
        self._first_pose_ns: int | None = None
        self._await_ns = mapping.grace_ns
        #: Behavior topics mapped: reconstruction may insert messages, so order matters.
        self.reconstructing = any(kind in _BEHAVIOR_KINDS for kind in self._kinds())

    # -- set-up ------------------------------------------------------------------------------
    def _kinds(self) -> set[Kind]:
        return {entry[0] for entries in self.handlers.values() for entry in entries}

    def _resolve(self, selected: dict[Kind, Rule]) -> None:
        resolver = TypeResolver()
        for kind, rule in selected.items():
            for connection in self.bag.connections:
                if not rule.matches(connection.topic, connection.type, self.drone):
                    continue
                if rule.topic is None and connection.topic != self._first_topic(rule):
                    continue  # a type-only rule takes one topic, the first of that type
                try:
                    decoder = resolver.decoder(
                        connection.msgtype,
                        connection.msgdef,
                        connection.md5sum,
                        connection.schema_encoding,
                    )
                except ValueError as exc:
                    self.notes.append(f"{connection.topic} not mapped as {kind.value}: {exc}")
                    continue
                if decoder.warning:
                    self.notes.append(decoder.warning)
                label = rule.label(connection.topic, self.drone) or ""
                self.handlers.setdefault(connection.id, []).append((kind, decoder, label))

    def _first_topic(self, rule: Rule) -> str:
        for connection in self.bag.connections:
            if rule.matches(connection.topic, connection.type, self.drone):
                return connection.topic
        return ""

    @property
    def mapped(self) -> dict[str, str]:
        topics: dict[str, str] = {}
        for connection in self.bag.connections:
            for entry in self.handlers.get(connection.id, ()):
                topics.setdefault(entry[0].value, connection.topic)
        return topics

    # -- the pass ----------------------------------------------------------------------------
    def run(self, advance: Advance | None = None) -> None:
        for connection in self.bag.connections:  # every connection, even without messages
            self.sink.raw_channel(connection)
        recon = self.recon
        sink = self.sink
        handlers = self.handlers
        out = self.out
        reconstructing = self.reconstructing
        decide_after = 2 * recon.grace  # an input is decided once this much later is read
        direct = True  # nothing held: a message may be written as it comes
        poses = Kind.POSE in self._kinds()  # a vehicle to draw
        write, hold = sink.raw, out.raw
        heap, queue = out.heap, out.queue
        count = 0
        for connection, time_ns, data in self.bag.messages():
            count += 1
            if count == 1 and poses:  # the 3D panel's scene from the start (nothing held)
                scene = scene_update(moving_entities(time_ns, self.drone, None))
                sink.derived_message(SCENE_TOPIC, time_ns, scene)
            if advance is not None and count % PROGRESS_EVERY == 0:
                advance(PROGRESS_EVERY)
            if reconstructing:
                horizon = recon.horizon
                if horizon is not None and horizon < time_ns - decide_after:
                    recon.advance(time_ns)
                    self._take_reconstruction()
                    horizon = recon.horizon
                limit = time_ns if horizon is None or time_ns < horizon else horizon
                # (most messages arrive with nothing held before the limit: no call)
                if (queue and queue[0][0] < limit) or (heap and heap[0][0] < limit):
                    out.release(limit)
                # Raw messages need no rank: with nothing older held, write at once.
                direct = horizon is None
            if direct:
                write(connection, time_ns, data)
            else:
                hold(time_ns, connection, data)
            entries = handlers.get(connection.id)
            if entries is not None:
                for entry in entries:
                    self._handle(entry, connection, time_ns, data)
        if self._skipped is not None:  # the last pose always gives the final state
            self._flush_latest()
            self._decode(*self._skipped)
        last = self.bag.end_ns or 0
        for call in self.calls.unanswered():  # at the end: their answer never came
            self._call(call, last)
        recon.finish()
        self._take_reconstruction()
        self.out.release(None)
        if advance is not None:
            advance(count % PROGRESS_EVERY)

    def _take_reconstruction(self) -> None:
        for output in self.recon.take():
            self.out.derived(
                output.time_ns, _Ordered.RECONSTRUCTED, output.topic, output.data, output.call
            )

    def _state(self, pose: extract.Pose, time_ns: int) -> None:
        self._last_state_ns = time_ns
        self._derive("vehicle/state", time_ns, self.vehicle.state(pose))
        # As the Recorder does: Foxglove holds the latest transform, so a vehicle that
        # did not move (hovering, landed) needs none.
        moved = (pose.position, pose.yaw)
        if moved != self._last_pose:
            self._last_pose = moved
            frame = pose_transform(pose, time_ns, vehicle_frame(self.drone))
            if frame is not None:
                self._derive("vehicle/transform", time_ns, frame)

    def _derive(self, topic: str, time_ns: int, data: dict[str, Any]) -> None:
        if not self.reconstructing:
            self.sink.derived_message(topic, time_ns, data)
            return
        self.out.derived(time_ns, _Ordered.OTHER, topic, data)

    def _call(self, call: Call, time_ns: int) -> None:
        if not self.reconstructing:
            self.sink.derived_message(call.topic, time_ns, call.data, call=True)
            return
        self.out.derived(time_ns, _Ordered.OTHER, call.topic, call.data, True)

    def _handle(self, entry: _Entry, connection: BagConnection, time_ns: int, data: bytes) -> None:
        """Decode what is used, when it is used: a pose only when it gives a state (or
        is the last one; none before the mapped vehicle topics have spoken, for at most
        grace), velocity/battery/status only the latest before such a pose, a behavior
        status only when its bytes changed (it repeats every 100 ms)."""
        kind = entry[0]
        if kind is Kind.BEHAVIOR_STATUS:
            if self._last_status.get(connection.id) == data:
                return
            self._last_status[connection.id] = data
        elif kind is Kind.POSE:
            if self._awaited:
                if self._first_pose_ns is None:
                    self._first_pose_ns = time_ns
                if time_ns - self._first_pose_ns < self._await_ns:
                    self._skipped = (entry, connection, time_ns, data)
                    return
                self._awaited.clear()
            last = self._last_state_ns
            if last is not None and time_ns - last < self.period:
                self._skipped = (entry, connection, time_ns, data)
                return
            self._skipped = None
            self._flush_latest()
        elif kind in _LATEST_ONLY:
            self._latest[kind] = (entry, connection, time_ns, data)
            self._awaited.discard(kind)
            return
        self._decode(entry, connection, time_ns, data)

    def _flush_latest(self) -> None:
        for latest in self._latest.values():
            self._decode(*latest)
        self._latest.clear()

    def _decode(self, entry: _Entry, connection: BagConnection, time_ns: int, data: bytes) -> None:
        kind, decoder, label = entry
        try:
            message = decoder.decode(data)
        except Exception:  # SerdeError and friends: the raw copy is kept anyway
            self.undecodable[connection.topic] = self.undecodable.get(connection.topic, 0) + 1
            return
        if kind in _ROS2_KINDS:
            handled = self._dispatch_ros2(kind, label, message, time_ns)
        else:
            handled = self._dispatch(kind, message, time_ns)
        if not handled:
            self.unreadable[connection.topic] = self.unreadable.get(connection.topic, 0) + 1

    def _dispatch(self, kind: Kind, message: object, time_ns: int) -> bool:
        """Feed one decoded message; False when it lacks the fields its kind needs."""
        if kind is Kind.POSE:
            pose = extract.pose(message)
            if pose is None:
                return False
            self._state(pose, time_ns)
        elif kind is Kind.VELOCITY:
            velocity = extract.velocity(message)
            if velocity is None:
                return False
            self.vehicle.velocity(velocity)
        elif kind is Kind.BATTERY:
            charge = extract.battery(message)
            if charge is None:
                return False
            self.vehicle.battery(charge)
        elif kind is Kind.FLIGHT_STATUS:
            flying = extract.flying(message)
            if flying is None:
                return False
            self.vehicle.flying(flying)
            armed = extract.armed(message)
            if armed is not None:
                self.vehicle.armed(armed)
        elif kind is Kind.BEHAVIOR_EVENT:
            event = extract.event(message)
            if event is None:
                return False
            self.recon.event(time_ns, event)
        elif kind is Kind.ACTIVE_BEHAVIORS:
            active = extract.active_list(message)
            if active is None:
                return False
            self.recon.active_list(time_ns, active)
        elif kind in (Kind.ACTIVATE_COMMAND, Kind.INHIBIT_COMMAND):
            command = extract.command(message)
            if command is None:
                return False
            self.recon.command(
                time_ns, ACTIVATE if kind is Kind.ACTIVATE_COMMAND else INHIBIT, command
            )
        else:
            return self._dispatch_lists(kind, message, time_ns)
        return True

    def _dispatch_ros2(self, kind: Kind, label: str, message: object, time_ns: int) -> bool:
        """Aerostack2's behavior topics (`as2.py`) and service events (`ros2calls.py`)."""
        if kind is Kind.BEHAVIOR_STATUS:
            if not hasattr(message, "status"):
                return False
            active = self.timeline.status(label, message)
            if active is not None:
                self.recon.active_list(time_ns, active)
        elif kind is Kind.ACTION_STATUS:
            if not hasattr(message, "status_list"):
                return False
            for event in self.timeline.goal_status(label, message):
                self.recon.event(time_ns, event)
        elif kind is Kind.SERVICE_EVENTS:
            if not hasattr(message, "info"):
                return False
            call = self.calls.event("/" + label, message, time_ns)
            if call is not None:
                self._call(call, time_ns)
        else:  # ACTION_GOAL, ACTION_RESULT: service events of the action's services
            if not hasattr(message, "info"):
                return False
            request = next(iter(getattr(message, "request", None) or ()), None)
            response = next(iter(getattr(message, "response", None) or ()), None)
            if kind is Kind.ACTION_GOAL:
                if request is not None:
                    self.timeline.goal(label, request)
            elif response is not None:
                event = self.timeline.result(label, request, response)
                if event is not None:
                    self.recon.event(time_ns, event)
        return True

    def _dispatch_lists(self, kind: Kind, message: object, time_ns: int) -> bool:
        if kind is Kind.ACTIVE_CAPABILITIES:
            names = extract.capabilities(message)
            if names is None:
                return False
            payload = self.capabilities.update(names)
            if payload is not None:
                self._derive("list_of_active_capabilities", time_ns, payload)
                for change in self.capability_changes.update(payload):
                    self._derive(CAPABILITY_TOPIC, time_ns, change)
        elif kind is Kind.BELIEFS:
            snapshot = extract.beliefs(message)
            if snapshot is None:
                return False
            for change in self.beliefs.update(snapshot):
                self._derive("beliefs", time_ns, change)
        else:  # PROCESS_STATE
            found = extract.process(message, self.drone)
            if found is None:
                return False
            payload = self.processes.update(*found)
            if payload is not None:
                self._derive("process_state", time_ns, payload)
        return True

    # -- report ------------------------------------------------------------------------------
    def final_notes(self) -> list[str]:
        notes = list(self.notes)
        for topic, n in sorted(self.undecodable.items()):
            notes.append(f"{n} message(s) of {topic} could not be decoded (kept raw only)")
        for topic, n in sorted(self.unreadable.items()):
            notes.append(f"{n} message(s) of {topic} lack the fields of their kind (kept raw only)")
        stats: Stats = self.recon.stats
        for code, n in sorted(stats.unknown_codes.items()):
            notes.append(
                f"{n} behavior event(s) with code {code!r}, which has no aeroexec equivalent "
                "(kept raw only; the activation counts as ended)"
            )
        if stats.late_events:
            notes.append(
                f"{stats.late_events} end event(s) came long after their behavior left the "
                "active list (it was reconstructed as inhibited; kept raw only)"
            )
        if stats.bad_arguments:
            notes.append(
                f"{stats.bad_arguments} behavior argument text(s) were not a YAML mapping "
                "(replaced by no arguments)"
            )
        selected = self._kinds()  # mapped and decodable
        if Kind.BEHAVIOR_STATUS in selected and not selected & {
            Kind.ACTION_STATUS,
            Kind.ACTION_RESULT,
        }:
            notes.append(
                "the bag has behavior status but no action status or results: every "
                "behavior going back to IDLE is reconstructed as inhibited (outcomes unknown)"
            )
        if Kind.BEHAVIOR_STATUS not in selected and selected & {
            Kind.ACTION_STATUS,
            Kind.ACTION_RESULT,
        }:
            notes.append(
                "the bag has action status or results but no behavior status (recorded "
                "with --include-hidden-topics): each activation is reconstructed at its end "
                "(durations unknown)"
            )
        if Kind.ACTIVE_BEHAVIORS in selected and Kind.BEHAVIOR_EVENT not in selected:
            notes.append(
                "the bag has active-behavior lists but no behavior events: every behavior "
                "leaving the list is reconstructed as inhibited"
            )
        if Kind.BEHAVIOR_EVENT in selected and Kind.ACTIVE_BEHAVIORS not in selected:
            notes.append(
                "the bag has behavior events but no active-behavior list: each activation "
                "is reconstructed at its end event (durations unknown)"
            )
        return notes


def _metadata(
    bag: Bag, mapping: Mapping, drone: str, mapped: dict[str, str]
) -> dict[str, dict[str, str]]:
    return {
        METADATA_NAME: {
            "aeroexec_version": __version__,
            "drone": drone,
            "clock": CLOCK,
            "vehicle": VEHICLES[bag.ros_version],
            "source": Path(bag.name).name,
            "mapping": mapping.source,
            "grace_s": f"{mapping.grace_ns / _NS:g}",
            "state_period_s": f"{mapping.state_period_ns / _NS:g}",
            # which kinds the bag had: a reader can tell "no capability changes" from
            # "no capability list in the bag"
            "mapped_kinds": ",".join(sorted(mapped)),
        },
        BAG_METADATAS[bag.ros_version]: {
            "file": Path(bag.name).name,
            "format": bag.format,
            "bytes": str(bag.size),
            "compression": bag.compression_text,
            "chunks": str(bag.chunk_count),
            "connections": str(len(bag.connections)),
            "messages": str(bag.message_count),
            "start_ns": "" if bag.start_ns is None else str(bag.start_ns),
            "end_ns": "" if bag.end_ns is None else str(bag.end_ns),
        },
    }


def import_bag(
    bag_path: str | os.PathLike[str],
    output: str | os.PathLike[str],
    mapping: Mapping | str | os.PathLike[str] | None = None,
    drone: str | None = None,
    compression: str = "lz4",
    progress: ProgressFactory | None = None,
    types_dir: str | os.PathLike[str] | None = None,
) -> ImportReport:
    """Import `bag_path` into the MCAP file `output` (see the module docstring).
    `mapping`: a `Mapping`, a mapping file, or None for the shipped one (Aerostack's for
    a ROS 1 bag, Aerostack2's for a ROS 2 one); `types_dir`: `.msg`/`.srv`/`.action`
    folders for a ROS 2 bag without definitions;
    `drone`: the namespace (default: the mapping's); `progress(name, messages)`: told the
    bag messages as they are imported (a progress bar). `RecordingError` (one line) when
    the bag, the mapping or the output cannot be used; then no output file is left."""
    if compression not in COMPRESSIONS:
        raise ValueError(f"compression must be one of {COMPRESSIONS}")
    version = ros_version_of(bag_path)
    if not isinstance(mapping, Mapping):
        mapping = load_mapping(mapping, version)
    drone = check_drone(drone if drone is not None else mapping.drone, Mark("--drone"))
    if f"/{drone}" in RAW_PREFIXES.values():
        raise RecordingError(f"drone {drone!r} is reserved for the raw channels", Mark("--drone"))
    if types_dir is not None and version != 2:
        raise RecordingError(
            "--types is for ROS 2 bags (a ROS 1 bag carries its definitions)", Mark(str(types_dir))
        )
    target = Path(output)
    with open_bag(bag_path, types_dir) as bag:
        if target.exists() and target.resolve() == bag.path.resolve():
            raise RecordingError("the output would overwrite the bag", Mark(str(output)))
        # Written beside the target, renamed into place only when complete (and created
        # like any other file: 0666 less the umask, not mkstemp's 0600).
        with whole_file_or_none(target) as temp, open(temp, "wb") as stream:
            sink = ImportSink(stream, drone, compression, bag.ros_version)
            run = _Import(bag, mapping, drone, sink)
            sink.start(
                _metadata(bag, mapping, drone, run.mapped),
                {MAPPING_ATTACHMENT: mapping.text.encode("utf-8")},
            )
            bar = progress(Path(bag.name).name, bag.message_count) if progress else None
            with bar if bar is not None else nullcontext(None) as advance:
                run.run(advance)
            sink.finish()
            stream.flush()  # a full disk is an error here, inside the block
        stats = run.recon.stats
        return ImportReport(
            source=bag.name,
            target=str(output),
            drone=drone,
            messages=sink.raw_messages,
            connections=len(bag.connections),
            topics=len({c.topic for c in bag.connections}),
            compression=bag.compression_text,
            start_ns=bag.start_ns,
            end_ns=bag.end_ns,
            mapped=run.mapped,
            derived=dict(sink.derived),
            reconstructed_activations=stats.activations,
            reconstructed_inhibitions=stats.inhibitions,
            notes=tuple(getattr(bag, "notes", ())) + tuple(run.final_notes()),
            ros_version=bag.ros_version,
        )
