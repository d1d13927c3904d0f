"""ROTATE: turn to an absolute heading."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from aeroexec.behaviors._support import (
    MotionBehavior,
    ProgressWatch,
    angle_error_degrees,
    must_be_flying,
)
from aeroexec.executive.behavior import Finished, FlightState, Situation
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.messages import EventCode


class Rotate(MotionBehavior):
    """Turn to ANGLE: an absolute heading in degrees, counter-clockwise from the world +x
    axis (0 faces +x, 90 faces +y, -90 faces -y), as Aerostack's ROTATE took an absolute
    yaw in degrees. 270 and -90 are the same heading; the vehicle turns the short way."""

    name = "ROTATE"
    argument_names = ("ANGLE",)
    needs = FlightState.FLYING
    tolerance = 1.0  # degrees

    def check_situation(self, beliefs: Beliefs) -> Situation:
        return must_be_flying(beliefs)

    def on_start(self, args: Mapping[str, Any]) -> None:
        if "ANGLE" not in args:
            raise ValueError("ROTATE needs ANGLE (degrees)")
        self.angle = float(args["ANGLE"])
        self.target = math.radians(self.angle)
        self.watch = ProgressWatch(min_gain=1.0)
        self.vehicle.set_yaw(self.target)

    def on_run(self) -> Finished | None:
        error = angle_error_degrees(self.target, self.vehicle.state().yaw)
        if error <= self.tolerance:
            return self.achieved(f"heading {self.angle:g} degrees")
        if self.watch.stalled(self.now, error):
            return Finished(
                EventCode.WRONG_PROGRESS, f"not turning: {error:.0f} degrees from {self.angle:g}"
            )
        return None
