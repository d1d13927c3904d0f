"""The deterministic executive core: clock, bus, processes, behaviors, the thesis'
coordinator / specialist / resource manager, beliefs, and the `Executive` facade.

The names are loaded when first used (PEP 562): a command that needs only `Behavior`
(`verify`, discovering a project's behaviors) does not import the executive, its
vehicles and the simulator with it."""

from __future__ import annotations

from typing import TYPE_CHECKING

from aeroexec.lazy import lazy_exports

if TYPE_CHECKING:
    from aeroexec.executive.behavior import ALLOWED, Behavior, Finished, GenericBehavior, Situation
    from aeroexec.executive.beliefs import Beliefs, BeliefSyntaxError
    from aeroexec.executive.bus import Bus, BusObserver, MemoryObserver
    from aeroexec.executive.clock import DEFAULT_TICK_NS, NS_PER_S, Clock, SimClock, WallClock
    from aeroexec.executive.executive import Executive, Library
    from aeroexec.executive.messages import (
        BehaviorEvent,
        EventCode,
        ServiceCallRecord,
        ServiceResult,
        TopicRecord,
    )
    from aeroexec.executive.process import DroneProcess, ProcessState

__all__ = [
    "ALLOWED",
    "DEFAULT_TICK_NS",
    "NS_PER_S",
    "Behavior",
    "BehaviorEvent",
    "BeliefSyntaxError",
    "Beliefs",
    "Bus",
    "BusObserver",
    "Clock",
    "DroneProcess",
    "EventCode",
    "Executive",
    "Finished",
    "GenericBehavior",
    "Library",
    "MemoryObserver",
    "ProcessState",
    "ServiceCallRecord",
    "ServiceResult",
    "SimClock",
    "Situation",
    "TopicRecord",
    "WallClock",
]

#: Each public name -> the module defining it, imported when the name is first used.
_WHERE = {
    "ALLOWED": "behavior",
    "Behavior": "behavior",
    "BehaviorEvent": "messages",
    "BeliefSyntaxError": "beliefs",
    "Beliefs": "beliefs",
    "Bus": "bus",
    "BusObserver": "bus",
    "Clock": "clock",
    "DEFAULT_TICK_NS": "clock",
    "DroneProcess": "process",
    "EventCode": "messages",
    "Executive": "executive",
    "Finished": "behavior",
    "GenericBehavior": "behavior",
    "Library": "executive",
    "MemoryObserver": "bus",
    "NS_PER_S": "clock",
    "ProcessState": "process",
    "ServiceCallRecord": "messages",
    "ServiceResult": "messages",
    "SimClock": "clock",
    "Situation": "behavior",
    "TopicRecord": "messages",
    "WallClock": "clock",
}


__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
