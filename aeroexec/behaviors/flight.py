"""TAKE_OFF and LAND."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from aeroexec.behaviors._support import (
    LINK_FAULTS,
    STOPPED_SPEED,
    MotionBehavior,
    ProgressWatch,
    is_flying,
    low_battery_reason,
    must_be_flying,
)
from aeroexec.executive.behavior import ALLOWED, Behavior, Finished, FlightState, Situation
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.messages import EventCode


class TakeOff(MotionBehavior):
    """Arm and climb to `altitude` (1 m, Aerostack's usual take-off height), then hold."""

    name = "TAKE_OFF"
    argument_names = ()
    needs = FlightState.LANDED
    leaves = FlightState.FLYING
    altitude = 1.0
    tolerance = 0.05  # m

    def check_situation(self, beliefs: Beliefs) -> Situation:
        if is_flying(beliefs):
            return Situation(False, "already flying")
        low = low_battery_reason(beliefs)
        return Situation(False, low) if low else ALLOWED

    def on_start(self, args: Mapping[str, Any]) -> None:
        self.watch = ProgressWatch(min_gain=0.05)
        self.vehicle.take_off(self.altitude)

    def on_run(self) -> Finished | None:
        state = self.vehicle.state()
        remaining = abs(self.altitude - state.altitude)
        if state.flying and remaining <= self.tolerance and state.speed <= STOPPED_SPEED:
            return self.achieved(f"at {state.altitude:.2f} m")
        if self.watch.stalled(self.now, remaining):
            return Finished(
                EventCode.WRONG_PROGRESS,
                f"not climbing: at {state.altitude:.2f} m of {self.altitude:g} m",
            )
        return None


class Land(Behavior):
    """Descend and disarm. Not a `MotionBehavior`: when it stops, the vehicle keeps
    landing, since hovering is not a safe default for a vehicle that was told to land."""

    name = "LAND"
    argument_names = ()
    needs = FlightState.FLYING
    leaves = FlightState.LANDED
    fails_on_faults = LINK_FAULTS

    def check_situation(self, beliefs: Beliefs) -> Situation:
        return must_be_flying(beliefs)

    def on_start(self, args: Mapping[str, Any]) -> None:
        self.watch = ProgressWatch(min_gain=0.05)
        self.vehicle.land()

    def on_run(self) -> Finished | None:
        state = self.vehicle.state()
        if not state.flying and not state.armed:
            return Finished(EventCode.GOAL_ACHIEVED, "landed")
        if self.watch.stalled(self.now, state.altitude):
            return Finished(
                EventCode.WRONG_PROGRESS, f"not descending: still at {state.altitude:.2f} m"
            )
        return None
