"""The aeroexec channels that follow a bag topic message by message (no reconstruction):
`vehicle/state` (+ `vehicle/transform`), `list_of_active_capabilities`, `beliefs`,
`process_state`.

Each tracker takes the plain values of `extract` and returns the payloads to write (the
aeroexec profile's, see aeroexec/recording/schemas.py); like the executive, the list and
process channels are written on change only.
"""

from __future__ import annotations

from typing import Any

from aeroexec.bags.extract import Pose
from aeroexec.recording.foxglove import transform

#: Without a flight-status topic, the vehicle counts as flying above this height (m).
FLYING_ABOVE_M = 0.1


class VehicleStateBuilder:
    """`vehicle/state` at each pose, with the latest velocity, battery and flight status
    seen before it. Fields the bag has not given (yet) are filled (velocity 0, battery
    1.0, flying = higher than FLYING_ABOVE_M) and named in the message's `defaulted`;
    `armed` is the flight status's own where it has one (Aerostack2's PlatformInfo),
    else flying."""

    def __init__(self) -> None:
        self._velocity: tuple[float, float, float] | None = None
        self._battery: float | None = None
        self._flying: bool | None = None
        self._armed: bool | None = None

    def velocity(self, value: tuple[float, float, float]) -> None:
        self._velocity = value

    def battery(self, value: float) -> None:
        self._battery = value

    def flying(self, value: bool) -> None:
        self._flying = value

    def armed(self, value: bool) -> None:
        self._armed = value

    def state(self, pose: Pose) -> dict[str, Any]:
        missing = []
        velocity = self._velocity
        if velocity is None:
            velocity = (0.0, 0.0, 0.0)
            missing.append("velocity")
        battery = self._battery
        if battery is None:
            battery = 1.0
            missing.append("battery")
        flying = self._flying
        if flying is None:
            flying = pose.position[2] > FLYING_ABOVE_M
            missing.append("flying")
        data: dict[str, Any] = {
            "position": list(pose.position),
            "velocity": list(velocity),
            "yaw": pose.yaw,
            "battery": battery,
            "flying": flying,
            "armed": flying if self._armed is None else self._armed,
            "fault": "",
        }
        if missing:
            data["defaulted"] = missing
        return data


def pose_transform(pose: Pose, time_ns: int, child_frame: str) -> dict[str, Any] | None:
    """The `vehicle/transform` (foxglove.FrameTransform) the Recorder derives from a
    `vehicle/state` with this position and yaw; None when a value is not finite."""
    x, y, z = pose.position
    return transform(x, y, z, pose.yaw, time_ns, child_frame)


class CapabilityTracker:
    def __init__(self) -> None:
        self._last: tuple[str, ...] | None = None

    def update(self, names: tuple[str, ...]) -> dict[str, Any] | None:
        """The `list_of_active_capabilities` payload when the list changed. Aerostack's
        list has no reference counts: each capability counts 1 (`counts_known: false`)."""
        if names == self._last or (self._last is None and not names):
            self._last = names
            return None
        self._last = names
        return {
            "capabilities": [{"name": n, "references": 1} for n in names],
            "counts_known": False,
        }


class BeliefTracker:
    """`beliefs` changes (add/remove, like the executive's) between belief snapshots."""

    def __init__(self) -> None:
        self._last: tuple[str, ...] = ()

    def update(self, snapshot: tuple[str, ...]) -> list[dict[str, Any]]:
        before = set(self._last)
        after = set(snapshot)
        changes = [{"op": "remove", "belief": b} for b in self._last if b not in after]
        changes += [{"op": "add", "belief": b} for b in snapshot if b not in before]
        self._last = snapshot
        return changes


class ProcessTracker:
    """`process_state` (started/stopped) when a process's heartbeat state changes."""

    def __init__(self) -> None:
        self._running: dict[str, bool] = {}

    def update(self, process: str, running: bool) -> dict[str, Any] | None:
        if self._running.get(process) == running:
            return None
        self._running[process] = running
        return {"process": process, "state": "started" if running else "stopped"}
