"""Convert one aeroexec recording into Rerun rows, in one streaming pass.

`convert_recording` reads the records once, in file order, and writes each as rows on
the entities of its `Layout` (see layout.py) through a `ColumnWriter`. It keeps only the
current state of each behavior, capability and process, the previous vehicle position,
and the service calls of the call tree under way: memory does not grow with the file.

Times: `sim_time` is the log time relative to the session start (the executive clock:
0 for a simulated session, whose clock starts at 0; the first message's time otherwise),
so two sessions line up. Service-call rows are also on the `seq` timeline.

One value per instant: a plot series never gets two rows at one `sim_time` (Rerun's plot
would draw their average, a level that never happened). When a series changes twice in
one instant (a behavior preempted the tick it starts, a capability released and taken
again by the next behavior), the second row goes 1 ns after the first, so the plot shows
the drop and the rise; the behavior's state lane moves with it.

The vehicle's pose comes from `vehicle/state` (position and yaw), which every recording
has; the pose channels Foxglove reads (`vehicle/transform`, or `vehicle/pose` in older
recordings) carry the same values and are not read.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import rerun as rr

from aeroexec.recording.foxglove import OBJECT_COLOR
from aeroexec.recording.reader import RecordedCall, RecordedTopic, Recording
from aeroexec.vehicles.world import World
from aeroexec.viz import texts
from aeroexec.viz.calltree import CallTree
from aeroexec.viz.columns import ColumnWriter
from aeroexec.viz.intervals import BehaviorIntervals, CapabilityCounts, Transition
from aeroexec.viz.layout import Layout
from aeroexec.viz.scene import log_series_style

#: Report progress every this many records.
PROGRESS_EVERY = 256
#: The executive's tick: a property's violating interval covers its last tick too.
PROPERTY_TICK_NS = 100_000_000

ProgressCallback = Callable[[int], None]


@dataclass(slots=True)
class ConvertStats:
    """What one conversion wrote (counts of source messages, by kind)."""

    records: int = 0
    vehicle_states: int = 0
    poses: int = 0
    behavior_events: int = 0
    activations: int = 0
    rejections: int = 0
    calls: int = 0
    last_ns: int | None = None
    behaviors: list[str] = field(default_factory=list)
    capabilities: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def session_origin_ns(recording: Recording) -> int:
    """The log time that becomes sim_time 0."""
    clock = recording.metadata.get("aeroexec", {}).get("clock")
    if clock == "sim":
        return 0
    return recording.survey().first_log_time_ns or 0


class SessionConverter:
    """Turns records into rows; `feed` each record in file order, then `finish`."""

    def __init__(
        self,
        stream: rr.RecordingStream,
        writer: ColumnWriter,
        layout: Layout,
        *,
        origin_ns: int = 0,
        world: World | None = None,
        color: tuple[int, int, int] = (66, 133, 244),
    ) -> None:
        self._stream = stream
        self._w = writer
        self._layout = layout
        self._origin = origin_ns
        self._world = world
        self._color = color
        self._behaviors = BehaviorIntervals()
        self._capabilities = CapabilityCounts()
        self._calls = CallTree()
        self._previous: tuple[float, float, float] | None = None
        self._fault = ""
        self._styled: set[str] = set()
        #: entity -> (time, value) of its last row
        self._last_values: dict[str, tuple[int, float]] = {}
        #: property -> the end (ns) of its violating interval marked so far
        self._violations: dict[str, int] = {}
        self.stats = ConvertStats()

    # -- dispatch ------------------------------------------------------------------------
    def feed(self, record: RecordedCall | RecordedTopic) -> None:
        self.stats.records += 1
        t = record.log_time_ns - self._origin
        if self.stats.last_ns is None or t > self.stats.last_ns:
            self.stats.last_ns = t
        if isinstance(record, RecordedCall):
            self._call(record, t)
            return
        handler = _TOPIC_HANDLERS.get(record.name)
        if handler is not None:
            handler(self, record.data, t)

    def pass_over(self, log_time_ns: int) -> None:
        """A record that draws nothing (a topic with no handler: MAVLink traffic), counted
        and timed as `feed` would, without decoding it."""
        self.stats.records += 1
        t = log_time_ns - self._origin
        if self.stats.last_ns is None or t > self.stats.last_ns:
            self.stats.last_ns = t

    def finish(self) -> ConvertStats:
        """Place what is still held (unfinished call trees), extend every step series to
        the end of the session, and send the remaining rows."""
        for call, depth in self._calls.drain():
            self._call_row(call, depth)
        end = self.stats.last_ns
        if end is not None:
            for transition in self._behaviors.finish(end):
                self._scalar(
                    self._layout.behavior_active(transition.name),
                    end,
                    1.0 if transition.active else 0.0,
                    extend=True,
                )
            for name, count in self._capabilities.counts.items():
                self._scalar(self._layout.capability(name), end, float(count), extend=True)
        self._w.flush()
        self.stats.behaviors = self._behaviors.names
        self.stats.capabilities = list(self._capabilities.counts)
        return self.stats

    # -- service calls -----------------------------------------------------------------------
    def _call(self, call: RecordedCall, t: int) -> None:
        self.stats.calls += 1
        activation = call.service == "activate_behavior"
        if activation:
            self._activation(call, t)
        if not call.ok and call.parent_seq is None:
            self.stats.rejections += activation
            text, level = texts.rejection_row(call)
            self._w.row(self._layout.errors, rr.TextLog, t, seq=call.seq, text=text, level=level)
        for placed, depth in self._calls.add(call):
            self._call_row(placed, depth)

    def _call_row(self, call: RecordedCall, depth: int) -> None:
        text, level = texts.call_row(call, depth)
        t = call.log_time_ns - self._origin
        self._w.row(self._layout.calls, rr.TextLog, t, seq=call.seq, text=text, level=level)

    def _activation(self, call: RecordedCall, t: int) -> None:
        self.stats.activations += 1
        uid = call.response.get("uid")
        behavior = call.request.get("behavior")
        if not call.ok or not isinstance(uid, int) or not isinstance(behavior, str):
            return
        args = texts.arguments_text(call.request.get("arguments"))
        label = f"#{uid} {args}".rstrip()
        self._transitions(self._behaviors.activated(behavior, uid, t, label))

    # -- topics ------------------------------------------------------------------------------
    def _behavior_event(self, data: Any, t: int) -> None:
        self.stats.behavior_events += 1
        text, level = texts.event_row(data)
        self._w.row(self._layout.events, rr.TextLog, t, text=text, level=level)
        if isinstance(data, dict) and isinstance(data.get("name"), str):
            uid = data.get("uid")
            self._transitions(
                self._behaviors.ended(data["name"], uid if isinstance(uid, int) else None, t)
            )

    def _transitions(self, transitions: list[Transition]) -> None:
        for tr in transitions:
            entity = self._layout.behavior_active(tr.name)
            t = self._scalar(entity, tr.t_ns, 1.0 if tr.active else 0.0)
            state = (tr.label or "active") if tr.active else ""
            self._w.row(self._layout.behavior_state(tr.name), rr.StateChange, t, state=state)

    def _active_capabilities(self, data: Any, t: int) -> None:
        capabilities = data.get("capabilities") if isinstance(data, dict) else None
        for name, count in self._capabilities.update(capabilities):
            self._scalar(self._layout.capability(name), t, float(count))

    def _process_state(self, data: Any, t: int) -> None:
        if not isinstance(data, dict) or not isinstance(data.get("process"), str):
            return
        state = str(data.get("state", ""))
        shown = "" if state in ("stopped", "") else state
        self._w.row(self._layout.process(data["process"]), rr.StateChange, t, state=shown)

    def _vehicle_state(self, data: Any, t: int) -> None:
        if not isinstance(data, dict):
            return
        position = _vector(data.get("position"))
        if position is None:
            return
        self.stats.vehicle_states += 1
        layout = self._layout
        self._w.row(layout.trajectory, rr.Points3D, t, positions=position, colors=self._color)
        segment = [self._previous or position, position]
        self._w.row(layout.trajectory_line, rr.LineStrips3D, t, strips=segment, colors=self._color)
        self._previous = position
        battery = data.get("battery")
        if isinstance(battery, (int, float)):
            self._scalar(layout.telemetry("battery"), t, 100.0 * float(battery))
        self._scalar(layout.telemetry("altitude"), t, position[2])
        velocity = _vector(data.get("velocity"))
        if velocity is not None:
            self._scalar(layout.telemetry("speed"), t, math.hypot(*velocity))
        if self._world is not None and self._world.object is not None:
            where = self._world.object.at(t / 1e9)
            self._w.row(
                layout.object,
                rr.Points3D,
                t,
                positions=where,
                labels="object",
                colors=OBJECT_COLOR,
            )
        fault = str(data.get("fault", "") or "")
        if fault != self._fault:
            text = f"vehicle fault: {fault}" if fault else f"vehicle fault cleared: {self._fault}"
            level = texts.ERROR if fault else texts.INFO
            self._w.row(layout.errors, rr.TextLog, t, text=text, level=level)
            self._fault = fault
        yaw = data.get("yaw")
        yaw = float(yaw) if isinstance(yaw, (int, float)) and math.isfinite(yaw) else 0.0
        quaternion = (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
        self._pose(position, quaternion, t)

    def _pose(
        self, position: tuple[float, float, float], quaternion: tuple[float, ...], t: int
    ) -> None:
        self.stats.poses += 1
        self._w.row(
            self._layout.vehicle,
            rr.Transform3D,
            t,
            translation=position,
            quaternion=quaternion,
        )

    def _mission(self, data: Any, t: int) -> None:
        self._text_row(self._layout.mission, texts.mission_row(data), t)

    def _log(self, data: Any, t: int) -> None:
        self._text_row(self._layout.log, texts.log_row(data), t)

    def _belief(self, data: Any, t: int) -> None:
        self._text_row(self._layout.beliefs, texts.belief_row(data), t)

    def _property(self, data: Any, t: int) -> None:
        """A violated property (the `properties` channel of run/fly --spec): an error at
        the start of its first violating interval, and a lane marking that interval. A
        violation seen during the flight is published again with the final verdicts: one
        mark, with the interval the end knows."""
        if not isinstance(data, dict) or data.get("status") != "violated":
            return
        name, start_s = data.get("property"), data.get("t_s")
        if not isinstance(name, str) or not isinstance(start_s, (int, float)):
            return
        end_s = data.get("end_s", start_s)
        end_s = end_s if isinstance(end_s, (int, float)) else start_s
        start = round(start_s * 1e9) - self._origin
        end = round(end_s * 1e9) - self._origin
        entity = self._layout.property_state(name)
        if name not in self._violations:
            message = str(data.get("message", "") or "")
            self._w.row(self._layout.errors, rr.TextLog, start, text=message, level=texts.ERROR)
            self._w.row(entity, rr.StateChange, start, state="violated")
        if end > self._violations.get(name, start):
            # The interval ends a tick after its last violating sample.
            self._w.row(entity, rr.StateChange, end + PROPERTY_TICK_NS, state="")
        self._violations[name] = max(end, self._violations.get(name, start))

    # -- helpers -----------------------------------------------------------------------------
    def _text_row(self, entity: str, row: tuple[str, str], t: int) -> None:
        text, level = row
        self._w.row(entity, rr.TextLog, t, text=text, level=level)

    def _scalar(self, entity: str, t: int, value: float, *, extend: bool = False) -> int:
        """One row of a step series, at `t` or, when the series already has a row at or
        after `t`, 1 ns after that row (one value per instant); the row's time.
        `extend` adds the closing row only when the series has one and ends earlier."""
        last = self._last_values.get(entity)
        if extend and (last is None or last[0] >= t):
            return t
        if last is not None and t <= last[0]:
            t = last[0] + 1
        if entity not in self._styled:
            self._styled.add(entity)
            log_series_style(self._stream, entity, entity.rsplit("/", 1)[-1])
        self._w.row(entity, rr.Scalars, t, scalars=value)
        self._last_values[entity] = (t, value)
        return t


def _vector(value: Any) -> tuple[float, float, float] | None:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        return None
    try:
        x, y, z = (float(v) for v in value)
    except (TypeError, ValueError):
        return None
    return (x, y, z)


_TOPIC_HANDLERS: dict[str, Callable[[SessionConverter, Any, int], None]] = {
    "behavior_event": SessionConverter._behavior_event,
    "list_of_active_capabilities": SessionConverter._active_capabilities,
    "process_state": SessionConverter._process_state,
    "vehicle/state": SessionConverter._vehicle_state,
    "mission/command": SessionConverter._mission,
    "log": SessionConverter._log,
    "beliefs": SessionConverter._belief,
    "properties": SessionConverter._property,
}


def draws(name: str) -> bool:
    """Whether a topic's records (by name inside the namespace) become rows."""
    return name in _TOPIC_HANDLERS


__all__ = [
    "PROGRESS_EVERY",
    "ConvertStats",
    "ProgressCallback",
    "SessionConverter",
    "draws",
    "session_origin_ns",
]
