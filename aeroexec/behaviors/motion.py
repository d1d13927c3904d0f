"""GO_TO_POINT, START_MOVING and FOLLOW_OBJECT_IMAGE."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

from aeroexec.behaviors._support import (
    MotionBehavior,
    ProgressWatch,
    fmt,
    must_be_flying,
)
from aeroexec.executive.behavior import ALLOWED, Finished, FlightState, Situation
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.messages import EventCode
from aeroexec.vehicles.base import Vec3


def _vector(value: Any, name: str) -> Vec3:
    x, y, z = (float(c) for c in value)
    if not all(math.isfinite(c) for c in (x, y, z)):
        raise ValueError(f"{name} must be finite numbers")
    return (x, y, z)


class GoToPoint(MotionBehavior):
    """Fly to COORDINATES (absolute) or RELATIVE_COORDINATES (from where it starts)."""

    name = "GO_TO_POINT"
    argument_names = ("COORDINATES", "RELATIVE_COORDINATES")
    needs = FlightState.FLYING
    #: Arguments that are destinations, absolute or relative to where the behavior
    #: starts: the verifier checks that they can be reached within the timeout at the
    #: vehicle's speed limits.
    destinations: ClassVar[Mapping[str, str]] = {
        "COORDINATES": "absolute",
        "RELATIVE_COORDINATES": "relative",
    }
    #: Reached = within `tolerance` and nearly stopped. 5 cm: close enough that a point
    #: memorized right after arriving is the point asked for; loose enough for a real
    #: autopilot's position hold.
    tolerance = 0.05  # m
    settled_speed = 0.1  # m/s

    def check_situation(self, beliefs: Beliefs) -> Situation:
        return must_be_flying(beliefs)

    def on_start(self, args: Mapping[str, Any]) -> None:
        absolute = args.get("COORDINATES")
        relative = args.get("RELATIVE_COORDINATES")
        if (absolute is None) == (relative is None):
            raise ValueError("give exactly one of COORDINATES and RELATIVE_COORDINATES")
        if absolute is not None:
            self.goal = _vector(absolute, "COORDINATES")
        else:
            dx, dy, dz = _vector(relative, "RELATIVE_COORDINATES")
            x, y, z = self.vehicle.state().position
            self.goal = (x + dx, y + dy, z + dz)
        self.watch = ProgressWatch(min_gain=0.05)
        self.vehicle.go_to(*self.goal)

    def on_run(self) -> Finished | None:
        state = self.vehicle.state()
        remaining = math.dist(state.position, self.goal)
        if remaining <= self.tolerance and state.speed <= self.settled_speed:
            # The vehicle keeps holding the goal itself: no hover, which would hold
            # wherever inside the tolerance it happens to be now.
            return self.achieved(f"reached {fmt(self.goal)}")
        if self.watch.stalled(self.now, remaining):
            return Finished(
                EventCode.WRONG_PROGRESS,
                f"no progress toward {fmt(self.goal)} for {self.watch.window:g} s "
                f"({remaining:.2f} m away)",
            )
        return None


#: START_MOVING directions in the body frame (forward = the heading), z up.
_DIRECTIONS: dict[str, tuple[float, float, float]] = {
    "FORWARD": (1.0, 0.0, 0.0),
    "BACKWARD": (-1.0, 0.0, 0.0),
    "LEFT": (0.0, 1.0, 0.0),
    "RIGHT": (0.0, -1.0, 0.0),
    "UP": (0.0, 0.0, 1.0),
    "DOWN": (0.0, 0.0, -1.0),
}


class StartMoving(MotionBehavior):
    """Hold SPEED (m/s) toward DIRECTION, relative to the heading at start.

    Succeeds once the vehicle moves at that velocity, and leaves it moving: that is
    what "start" means (a later motion behavior takes over). If it ends any other way
    the vehicle is left hovering.
    """

    name = "START_MOVING"
    argument_names = ("SPEED", "DIRECTION")
    needs = FlightState.FLYING
    tolerance = 0.1  # m/s

    def check_situation(self, beliefs: Beliefs) -> Situation:
        return must_be_flying(beliefs)

    def on_start(self, args: Mapping[str, Any]) -> None:
        if "SPEED" not in args or "DIRECTION" not in args:
            raise ValueError("START_MOVING needs SPEED and DIRECTION")
        speed = float(args["SPEED"])
        bx, by, bz = _DIRECTIONS[str(args["DIRECTION"]).upper()]
        yaw = self.vehicle.state().yaw
        cos, sin = math.cos(yaw), math.sin(yaw)
        self.target = (
            speed * (bx * cos - by * sin),
            speed * (bx * sin + by * cos),
            speed * bz,
        )
        self.watch = ProgressWatch(min_gain=0.05)
        self.vehicle.set_velocity(*self.target)

    def on_run(self) -> Finished | None:
        state = self.vehicle.state()
        error = math.dist(state.velocity, self.target)
        if error <= self.tolerance:
            return self.achieved(f"moving at {state.speed:.2f} m/s")
        if self.watch.stalled(self.now, error):
            return Finished(
                EventCode.WRONG_PROGRESS,
                f"speed not reached: {state.speed:.2f} m/s, {error:.2f} m/s off the target",
            )
        return None


class FollowObjectImage(MotionBehavior):
    """Fly toward the object the camera tracks, at the current altitude, until within
    `reach` metres of it (horizontally); fails if the object stays out of sight."""

    name = "FOLLOW_OBJECT_IMAGE"
    argument_names = ()
    needs = FlightState.FLYING
    reach = 1.0  # m
    lost_after = 2.0  # s out of sight

    def check_situation(self, beliefs: Beliefs) -> Situation:
        flying = must_be_flying(beliefs)
        if not flying.ok:
            return flying
        if self.vehicle.visible_object() is None:
            return Situation(False, "no object in view")
        return ALLOWED

    def on_start(self, args: Mapping[str, Any]) -> None:
        self.altitude = self.vehicle.state().altitude
        self.last_seen = self.now
        self.watch = ProgressWatch(min_gain=0.05, window=10.0)
        if self.vehicle.visible_object() is None:
            raise ValueError("no object in view")
        self._chase()

    def _chase(self) -> float | None:
        """Re-aim at the object; its horizontal distance, or None when out of sight."""
        seen = self.vehicle.visible_object()
        if seen is None:
            return None
        self.last_seen = self.now
        x, y, _ = self.vehicle.state().position
        self.vehicle.go_to(seen[0], seen[1], self.altitude)
        return math.hypot(seen[0] - x, seen[1] - y)

    def on_run(self) -> Finished | None:
        distance = self._chase()
        if distance is None:
            if self.now - self.last_seen >= self.lost_after:
                return Finished(EventCode.WRONG_PROGRESS, "lost sight of the object")
            return None
        if distance <= self.reach:
            return Finished(EventCode.GOAL_ACHIEVED, f"object {distance:.2f} m away")
        if self.watch.stalled(self.now, distance):
            return Finished(EventCode.WRONG_PROGRESS, f"not closing in ({distance:.2f} m away)")
        return None
