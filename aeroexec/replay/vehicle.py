"""`ReplayVehicle`: the recorded vehicle, played back (open-loop replay).

It implements the `Vehicle` protocol; `state()` is the latest recorded `vehicle/state`
at or before the executive's current time, read lazily from a streaming iterator, so
memory does not grow with the recording. Commands are accepted and ignored: in open
loop the aircraft did what the recording says it did.
"""

from __future__ import annotations

import json
from collections.abc import Iterator

from aeroexec.executive.clock import Clock
from aeroexec.replay.source import SourceMessage
from aeroexec.vehicles.base import Vec3, VehicleState
from aeroexec.vehicles.null import NullVehicle

GROUNDED = VehicleState((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 1.0, False, False)


def _vec3(value: object) -> Vec3 | None:
    if not isinstance(value, list) or len(value) != 3:
        return None
    try:
        x, y, z = (float(v) for v in value)
    except (TypeError, ValueError):
        return None
    return (x, y, z)


def decode_state(data: bytes) -> VehicleState | None:
    """A `vehicle/state` message as a `VehicleState` (None if it is not one)."""
    try:
        message = json.loads(data)
    except ValueError:
        return None
    if not isinstance(message, dict):
        return None
    position = _vec3(message.get("position"))
    if position is None:
        return None
    velocity = _vec3(message.get("velocity")) or (0.0, 0.0, 0.0)
    try:
        yaw = float(message.get("yaw") or 0.0)
        battery = float(message.get("battery") if message.get("battery") is not None else 1.0)
    except (TypeError, ValueError):
        return None
    return VehicleState(
        position,
        velocity,
        yaw,
        battery,
        bool(message.get("flying")),
        bool(message.get("armed", message.get("flying"))),
        str(message.get("fault") or ""),
    )


class ReplayVehicle(NullVehicle):
    """Shows the recorded vehicle state at the clock's time; commands change nothing
    (the recorded flight already happened)."""

    kind = "replay"

    def __init__(self, states: Iterator[SourceMessage], clock: Clock, offset_ns: int = 0) -> None:
        """`states`: the recording's `vehicle/state` messages in order; `offset_ns`: the
        recorded time of the clock's zero."""
        self._states = states
        self._clock = clock
        self._offset = offset_ns
        self._next: tuple[int, VehicleState] | None = None
        self._current = GROUNDED
        self._pull()
        if self._next is not None:  # before the first record: the first recorded state
            self._current = self._next[1]

    def _pull(self) -> None:
        self._next = None
        for message in self._states:
            state = decode_state(message.data)
            if state is not None:
                self._next = (message.log_time_ns, state)
                return

    def state(self) -> VehicleState:
        now = self._clock.now_ns() + self._offset
        while self._next is not None and self._next[0] <= now:
            self._current = self._next[1]
            self._pull()
        return self._current
