"""Stand-in behaviors and a vehicle for running a mission abstractly in the real executive.

The verifier's sequence checks run a mission's calls through `aeroexec.executive.Executive`
itself — its coordinator, specialist and resource manager decide what is accepted,
preempted and rejected — with stand-ins in place of the behavior implementations:

* a stand-in is allowed to start exactly when its implementation's *declared*
  situation (`Behavior.needs`: flying, landed or either) holds, judged on the beliefs
  the executive feeds from the vehicle, as the real behaviors judge theirs;
* it never ends by itself (an activated behavior may still be running at any later
  call: the case that matters for conflicts), unless the mission executes it: then it
  achieves its goal at the next tick and leaves the flight state its implementation
  declares (`Behavior.leaves`: TAKE_OFF leaves the vehicle flying);
* `FlightStateVehicle` is a `NullVehicle` whose only state is that flight state.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from aeroexec.behaviors._support import is_flying
from aeroexec.executive.behavior import ALLOWED, Behavior, Finished, FlightState, Situation
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.messages import EventCode
from aeroexec.vehicles.base import Vec3, VehicleState
from aeroexec.vehicles.null import NullVehicle

#: The reasons a stand-in gives, so the runner can tell a situation rejection apart.
NOT_FLYING = "needs the vehicle flying"
NOT_LANDED = "needs the vehicle landed"


class FlightStateVehicle(NullVehicle):
    """A vehicle that stays put, flying or landed as the stand-ins leave it."""

    kind = "abstract"

    def __init__(self, start: Vec3 = (0.0, 0.0, 0.0)) -> None:
        super().__init__()
        self.flying = False
        self.start = start

    def state(self) -> VehicleState:
        return VehicleState(self.start, (0.0, 0.0, 0.0), 0.0, 1.0, self.flying, self.flying)


class StandIn(Behavior):
    """Subclassed per catalog behavior by `stand_ins` (with `name`, `needs`, `leaves`)."""

    def check_situation(self, beliefs: Beliefs) -> Situation:
        flying = is_flying(beliefs)
        if self.needs is FlightState.FLYING and not flying:
            return Situation(False, NOT_FLYING)
        if self.needs is FlightState.LANDED and flying:
            return Situation(False, NOT_LANDED)
        return ALLOWED

    def on_start(self, args: Mapping[str, Any]) -> None:
        self.finishing = False

    def on_run(self) -> Finished | None:
        if not self.finishing:
            return None
        vehicle = self.vehicle
        if self.leaves is not None and isinstance(vehicle, FlightStateVehicle):
            vehicle.flying = self.leaves is FlightState.FLYING
        return Finished(EventCode.GOAL_ACHIEVED, "stand-in")


def stand_ins(
    names: list[str] | tuple[str, ...], library: Mapping[str, type[Behavior]]
) -> dict[str, type[Behavior]]:
    """A stand-in class per catalog behavior, with the situation its implementation in
    `library` declares (none declared: allowed in any situation)."""
    classes: dict[str, type[Behavior]] = {}
    for name in names:
        implementation = library.get(name)
        attributes = {
            "name": name,
            "needs": getattr(implementation, "needs", None),
            "leaves": getattr(implementation, "leaves", None),
        }
        classes[name] = type(f"StandIn_{name}", (StandIn,), attributes)
    return classes
