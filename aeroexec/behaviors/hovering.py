"""KEEP_HOVERING, START_HOVERING and FLIP: holding still, and the one acrobatic move."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from aeroexec.behaviors._support import (
    LINK_FAULTS,
    MOTOR_FAULTS,
    POSITION_FAULTS,
    POWER_FAULTS,
    PROGRESS_WINDOW,
    STOPPED_SPEED,
    MotionBehavior,
    altitude,
    is_flying,
    low_battery_reason,
    must_be_flying,
)
from aeroexec.executive.behavior import ALLOWED, Finished, FlightState, Situation
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.messages import EventCode


class KeepHovering(MotionBehavior):
    """Hover for DURATION seconds (default 5). With ARUCO, the hover is kept in sight of
    that visual marker: it must be in view at the start and is a failure to lose."""

    name = "KEEP_HOVERING"
    argument_names = ("DURATION", "ARUCO")
    needs = FlightState.FLYING
    default_duration = 5.0
    fails_on_faults = LINK_FAULTS + POWER_FAULTS + MOTOR_FAULTS + POSITION_FAULTS

    def check_situation(self, beliefs: Beliefs) -> Situation:
        return must_be_flying(beliefs)

    def on_start(self, args: Mapping[str, Any]) -> None:
        self.duration = float(args.get("DURATION", self.default_duration))
        aruco = args.get("ARUCO")
        self.marker = None if aruco is None else int(aruco)
        if self.marker is not None and self.marker not in self.vehicle.visible_markers():
            raise ValueError(f"marker {self.marker} is not in view")
        self.vehicle.hover()

    def on_run(self) -> Finished | None:
        if self.marker is not None and self.marker not in self.vehicle.visible_markers():
            return Finished(EventCode.WRONG_PROGRESS, f"lost sight of marker {self.marker}")
        if self.elapsed >= self.duration:
            return Finished(EventCode.GOAL_ACHIEVED, f"hovered {self.duration:g} s")
        return None


class StartHovering(MotionBehavior):
    """Brake and hold position; succeeds once the vehicle has (nearly) stopped."""

    name = "START_HOVERING"
    argument_names = ()
    fails_on_faults = LINK_FAULTS + POWER_FAULTS + MOTOR_FAULTS + POSITION_FAULTS
    needs = FlightState.FLYING

    def check_situation(self, beliefs: Beliefs) -> Situation:
        return must_be_flying(beliefs)

    def on_start(self, args: Mapping[str, Any]) -> None:
        self.vehicle.hover()

    def on_run(self) -> Finished | None:
        speed = self.vehicle.state().speed
        if speed < STOPPED_SPEED:
            return self.achieved("hovering")
        if self.elapsed >= PROGRESS_WINDOW:
            return Finished(EventCode.WRONG_PROGRESS, f"still moving at {speed:.2f} m/s")
        return None


class Flip(MotionBehavior):
    """Flip toward DIRECTION (BACK, FRONT, LEFT, RIGHT). Needs 1 m of height and a
    battery that is not low (a flip draws a burst of power)."""

    name = "FLIP"
    argument_names = ("DIRECTION",)
    needs = FlightState.FLYING
    min_altitude = 1.0  # m
    max_duration = 3.0  # s: a flip the vehicle has not finished by then went wrong

    def check_situation(self, beliefs: Beliefs) -> Situation:
        if not is_flying(beliefs):
            return Situation(False, "not flying")
        height = altitude(beliefs)
        if height is not None and height < self.min_altitude:
            return Situation(
                False, f"too low to flip ({height:.2f} m, needs {self.min_altitude:g} m)"
            )
        low = low_battery_reason(beliefs)
        return Situation(False, low) if low else ALLOWED

    def on_start(self, args: Mapping[str, Any]) -> None:
        if "DIRECTION" not in args:
            raise ValueError("FLIP needs DIRECTION")
        self.start = self.vehicle.state().position
        self.vehicle.flip(str(args["DIRECTION"]).upper())

    def on_run(self) -> Finished | None:
        state = self.vehicle.state()
        if state.maneuver == "flip":
            if self.elapsed >= self.max_duration:
                return Finished(EventCode.WRONG_PROGRESS, "the flip did not end")
            return None
        drift = math.dist(state.position, self.start)
        return Finished(EventCode.GOAL_ACHIEVED, f"flipped ({drift:.2f} m from the start)")
