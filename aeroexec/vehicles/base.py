"""The `Vehicle` protocol: what behaviors may ask of an aircraft, simulated or live.

Behaviors talk only to this protocol, so the same behavior library flies the built-in
simulator (`vehicles.sim`) and a MAVLink autopilot (`vehicles.mavlink`). Frames are
local ENU in metres (x east, y north, z up); yaw is in radians, counter-clockwise from +x.
A command the vehicle refuses raises `VehicleCommandError`; the behavior base class turns
that into a `PROCESS_FAILURE` event.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

Vec3 = tuple[float, float, float]

#: The flip directions a vehicle accepts (the catalog's FLIP DIRECTION values).
FLIP_DIRECTIONS = ("BACK", "FRONT", "LEFT", "RIGHT")


class VehicleCommandError(RuntimeError):
    """The vehicle refused or could not carry out a command."""


@dataclass(frozen=True, slots=True)
class VehicleState:
    position: Vec3
    velocity: Vec3
    yaw: float
    battery: float  # remaining charge, 0.0 .. 1.0
    flying: bool
    armed: bool
    #: A fault the vehicle reports ("stuck_motor", "link_lost", ...), or "" when healthy.
    fault: str = ""
    #: A scripted maneuver in progress ("flip"), or "" when the vehicle follows setpoints.
    maneuver: str = ""

    @property
    def speed(self) -> float:
        vx, vy, vz = self.velocity
        return (vx * vx + vy * vy + vz * vz) ** 0.5

    @property
    def altitude(self) -> float:
        return self.position[2]

    @property
    def yaw_degrees(self) -> float:
        return math.degrees(self.yaw)


@runtime_checkable
class Vehicle(Protocol):
    """An aircraft the executive drives. Commands set a goal and return at once."""

    #: "sim", "mavlink", ... (recorded in the session metadata).
    kind: str

    def step(self, dt: float) -> None:
        """Advance `dt` seconds (the simulator integrates; a live link polls telemetry)."""

    def state(self) -> VehicleState:
        """The latest state estimate."""

    def take_off(self, altitude: float) -> None:
        """Arm if needed and climb to `altitude` metres above the ground, then hold."""

    def land(self) -> None:
        """Descend and disarm on the ground."""

    def go_to(self, x: float, y: float, z: float) -> None:
        """Fly to a position setpoint and hold it."""

    def set_velocity(self, vx: float, vy: float, vz: float) -> None:
        """Hold a velocity (until another command). Refused beyond the vehicle's limits."""

    def set_yaw(self, yaw: float) -> None:
        """Turn to an absolute heading (radians) and hold it."""

    def hover(self) -> None:
        """Brake, then hold the position and heading where the vehicle stopped."""

    def flip(self, direction: str) -> None:
        """Flip in place toward `direction` (one of FLIP_DIRECTIONS); while it lasts
        `state().maneuver == "flip"`, then the vehicle holds where it started."""

    def visible_markers(self) -> tuple[int, ...]:
        """IDs of the visual markers the camera sees now, ascending."""

    def visible_object(self) -> Vec3 | None:
        """World position of the tracked object if the camera sees it now, else None."""
