"""`DroneProcess`: the state machine every Aerostack process follows.

CREATED --set_up--> READY --start--> RUNNING --stop--> READY. Anything else is refused
with an error result (never an exception), as the thesis' processes answered services.
"""

from __future__ import annotations

from enum import Enum

from aeroexec.executive.messages import OK, ServiceResult, failure


class ProcessState(str, Enum):
    CREATED = "CREATED"
    READY = "READY"
    RUNNING = "RUNNING"


class DroneProcess:
    __slots__ = ("name", "state")

    def __init__(self, name: str) -> None:
        self.name = name
        self.state = ProcessState.CREATED

    def set_up(self) -> ServiceResult:
        if self.state is not ProcessState.CREATED:
            return failure(f"{self.name}: set_up in state {self.state.value}")
        self.state = ProcessState.READY
        return OK

    def start(self) -> ServiceResult:
        if self.state is not ProcessState.READY:
            return failure(f"{self.name}: start in state {self.state.value}")
        self.state = ProcessState.RUNNING
        return OK

    def stop(self) -> ServiceResult:
        if self.state is not ProcessState.RUNNING:
            return failure(f"{self.name}: stop in state {self.state.value}")
        self.state = ProcessState.READY
        return OK

    @property
    def running(self) -> bool:
        return self.state is ProcessState.RUNNING
