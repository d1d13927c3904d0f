"""The `Executive` facade: catalog + behavior library + vehicle + clock + bus, wired.

    ex = Executive(load_catalog("catalog/default.yaml"), library=STANDARD_LIBRARY)
    ex.activate_behavior("TAKE_OFF")
    ex.run_until(lambda: not ex.active_behaviors, timeout_s=30)

One thread, one clock: `step()` advances the clock one tick, moves the vehicle,
refreshes the beliefs it feeds, runs every active behavior once (in catalog order) and
publishes the vehicle state. With a `SimClock` the whole run is a pure function of the
catalog, the code, the world, the seed and the commands.

The executive is given its behavior library (the session composes it: the standard
library, a developer's behaviors); it imports none itself. A catalog behavior the library
does not implement is an error, unless a `stand_in` class is given explicitly (the
verifier's witnesses and the generated-catalog tests run catalogs that way).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import Any

from aeroexec.catalog.model import Catalog
from aeroexec.errors import BehaviorError
from aeroexec.executive.behavior import Behavior
from aeroexec.executive.beliefs import Beliefs
from aeroexec.executive.beliefs_feed import update_beliefs
from aeroexec.executive.bus import Bus, BusObserver
from aeroexec.executive.clock import NS_PER_S, Clock, SimClock
from aeroexec.executive.coordinator import BehaviorCoordinator
from aeroexec.executive.messages import BehaviorEvent, ServiceResult
from aeroexec.executive.resources import ResourceManager
from aeroexec.executive.specialist import SPECIALIST, BehaviorSpecialist
from aeroexec.interrupts import check as check_interrupts
from aeroexec.vehicles.base import Vehicle

Library = Mapping[str, type[Behavior]]


class TimeLimitReached(BaseException):
    """The clock reached `Executive.time_limit_ns`: the session must end.

    A `BaseException`, like `KeyboardInterrupt`, so that a mission's `except Exception:`
    cannot swallow it and loop on forever.
    """

    def __init__(self, limit_ns: int) -> None:
        self.limit_ns = limit_ns
        super().__init__(f"the simulated time limit of {_seconds_text(limit_ns)} was reached")


class StopRequested(BaseException):
    """An observer asked the session to end (`Executive.request_stop`): a property
    monitor whose property was violated (`by` "property"), an operator's abort (`by`
    "abort": a live viewer's), with the action that ends the flight.

    A `BaseException` for the reason `TimeLimitReached` is one."""

    def __init__(self, reason: str, action: str, by: str = "property") -> None:
        self.reason = reason
        self.action = action
        self.by = by
        super().__init__(reason)


def _seconds_text(ns: int) -> str:
    seconds = ns / NS_PER_S
    if seconds >= 3600 and seconds % 3600 == 0:
        return f"{seconds / 3600:g} h"
    return f"{seconds:g} s"


def _default_vehicle() -> Vehicle:
    from aeroexec.vehicles.sim import SimVehicle

    return SimVehicle()


class Executive:
    def __init__(
        self,
        catalog: Catalog,
        vehicle: Vehicle | None = None,
        clock: Clock | None = None,
        *,
        library: Library,
        observers: Iterable[BusObserver] = (),
        drone: str = "drone1",
        stand_in: type[Behavior] | None = None,
    ) -> None:
        missing = [name for name in catalog.behaviors if name not in library]
        if missing and stand_in is None:
            raise BehaviorError(
                f"no implementation for {', '.join(missing)} in the executive's library "
                "(give stand_in=GenericBehavior to run stand-ins)"
            )
        self.catalog = catalog
        self.drone = drone
        self.clock: Clock = clock or SimClock()
        self.bus = Bus(self.clock)
        for observer in observers:
            self.bus.attach(observer)
        self.vehicle: Vehicle = vehicle if vehicle is not None else _default_vehicle()
        self.beliefs = Beliefs(self._belief_changed, on_replace=self._belief_replaced)
        # Bound once: the feed runs every tick.
        self._update_beliefs = update_beliefs
        #: (vehicle state, belief store version) after the last feed: fed again with the
        #: same state and untouched beliefs, the feed would change nothing.
        self._fed: tuple[Any, int] | None = None
        self.events: list[BehaviorEvent] = []
        self._event_listeners: list[Callable[[BehaviorEvent], None]] = []
        self.specialist = BehaviorSpecialist(catalog, self.bus)
        self.resources = ResourceManager(catalog, self.bus, self.specialist)
        self.behaviors: dict[str, Behavior] = {}
        for name, descriptor in catalog.behaviors.items():
            cls = library.get(name, stand_in)
            assert cls is not None  # checked above
            behavior = cls()
            behavior.bind(self, descriptor)
            self.behaviors[name] = behavior
        self.coordinator = BehaviorCoordinator(self)
        #: The clock time at which `step()` refuses to go on (`TimeLimitReached`): a
        #: mission that never ends must not run forever. None: no limit.
        self.time_limit_ns: int | None = None
        #: (reason, action, by) once an observer asked the session to end; the next tick
        #: boundary raises `StopRequested` (never inside a publish or a record).
        self.stop_request: tuple[str, str, str] | None = None
        self._feed_beliefs()
        self.initiation = self.bus.call(
            "initiate_behaviors",
            "executive",
            lambda: self.resources.initiate_resources(SPECIALIST),
        )

    # -- the services a mission (or an operator) uses ------------------------------------
    def activate_behavior(
        self, name: str, arguments: Mapping[str, Any] | None = None, caller: str = "mission"
    ) -> ServiceResult:
        return self.coordinator.activate_behavior(name, arguments, caller)

    def inhibit_behavior(self, name: str, caller: str = "mission") -> ServiceResult:
        return self.coordinator.inhibit_behavior(name, caller)

    def request_stop(self, reason: str, action: str, by: str = "property") -> None:
        """End the session at the next tick boundary (the first request wins). `by`:
        who asked, as the recording says why the session ended ("property", "abort")."""
        if self.stop_request is None:
            self.stop_request = (reason, action, by)

    # -- state ---------------------------------------------------------------------------
    @property
    def active_behaviors(self) -> tuple[str, ...]:
        return self.coordinator.active_names

    @property
    def capability_references(self) -> dict[str, int]:
        return dict(self.resources.references)

    @property
    def running_processes(self) -> tuple[str, ...]:
        return self.resources.running_processes

    @property
    def now_s(self) -> float:
        return self.clock.now_ns() / NS_PER_S

    # -- time ----------------------------------------------------------------------------
    def step(self) -> None:
        # A tick boundary is a safe point: nothing is half-published or half-recorded.
        check_interrupts()
        if self.time_limit_ns is not None and self.clock.now_ns() >= self.time_limit_ns:
            raise TimeLimitReached(self.time_limit_ns)
        if self.stop_request is not None:
            raise StopRequested(*self.stop_request)
        clock = self.clock
        clock.advance()
        self.vehicle.step(clock.tick_ns / NS_PER_S)
        self._feed_beliefs()
        active = self.coordinator.active
        if len(active) == 1:  # the common case: no catalog order to sort by
            (behavior,) = active.values()
            behavior.tick()
        elif active:
            for behavior in [active[n] for n in self.active_behaviors]:
                behavior.tick()
        if self.bus.observed:
            self.bus.publish("vehicle/state", self._vehicle_state)

    def publish_vehicle_state(self) -> None:
        """Publish the vehicle's state now, outside a step: a live session records the
        state it starts from (its first step comes a tick later)."""
        self.bus.publish("vehicle/state", self._vehicle_state)

    def run_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Step until `predicate()` holds (True) or `timeout_s` of clock time pass (False)."""
        deadline = self.clock.now_ns() + round(timeout_s * NS_PER_S)
        while not predicate():
            if self.clock.now_ns() >= deadline:
                return False
            self.step()
        return True

    def run_for(self, seconds: float) -> None:
        deadline = self.clock.now_ns() + round(seconds * NS_PER_S)
        while self.clock.now_ns() < deadline:
            self.step()

    # -- plumbing ------------------------------------------------------------------------
    def add_event_listener(self, listener: Callable[[BehaviorEvent], None]) -> None:
        self._event_listeners.append(listener)

    def on_behavior_event(self, event: BehaviorEvent) -> None:
        self.events.append(event)
        self.bus.publish("behavior_event", event.as_dict)
        self.coordinator.on_behavior_event(event)
        for listener in self._event_listeners:
            listener(event)

    def log(self, message: str, level: str = "INFO", name: str = "executive") -> None:
        self.bus.publish("log", lambda: {"level": level, "name": name, "message": message})

    def _belief_changed(self, op: str, belief: str) -> None:
        self.bus.publish("beliefs", lambda: {"op": op, "belief": belief})

    def _belief_replaced(self, old: str, new: str) -> None:
        # One message, not a remove and an add: most belief changes are the vehicle
        # feed's new position (or yaw, or charge) replacing the old one.
        self.bus.publish("beliefs", lambda: {"op": "replace", "belief": new, "replaced": old})

    def _feed_beliefs(self) -> None:
        state = self.vehicle.state()
        fed = self._fed
        beliefs = self.beliefs
        if fed is not None and fed[1] == beliefs.version and (fed[0] is state or fed[0] == state):
            return
        self._update_beliefs(beliefs, state)
        self._fed = (state, beliefs.version)

    def _vehicle_state(self) -> dict[str, Any]:
        state = self.vehicle.state()
        return {
            "position": list(state.position),
            "velocity": list(state.velocity),
            "yaw": state.yaw,
            "battery": state.battery,
            "flying": state.flying,
            "armed": state.armed,
            "fault": state.fault,
        }
