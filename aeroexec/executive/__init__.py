"""The deterministic executive core: clock, bus, processes, behaviors, the thesis'
coordinator / specialist / resource manager, beliefs, and the `Executive` facade."""

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
