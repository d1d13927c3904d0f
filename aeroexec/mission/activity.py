"""What the mission did, one row per activation: the run printout and its summary table.

A bus observer, so it sees exactly what the recorder sees: the mission's
`activate_behavior` calls (accepted or refused), the `behavior_event`s that end them,
and the vehicle faults `vehicle/state` reports.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from aeroexec.display import shown_arguments
from aeroexec.executive.clock import NS_PER_S
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord


@dataclass(frozen=True, slots=True)
class Activation:
    behavior: str
    arguments: dict[str, Any]
    accepted: bool
    start_ns: int
    uid: int = 0
    error: str = ""
    end_code: str = ""
    end_ns: int | None = None
    detail: str = ""

    @property
    def start_s(self) -> float:
        return self.start_ns / NS_PER_S

    @property
    def end_s(self) -> float | None:
        return None if self.end_ns is None else self.end_ns / NS_PER_S

    @property
    def result(self) -> str:
        if not self.accepted:
            return "REJECTED"
        return self.end_code or "RUNNING"


format_arguments = shown_arguments


class ActivityLog:
    """Collects `Activation` rows; `on_change(row)` is told as each starts and ends."""

    def __init__(
        self,
        on_change: Callable[[Activation], None] | None = None,
        on_fault: Callable[[int, str], None] | None = None,
    ) -> None:
        self.rows: list[Activation] = []
        #: (clock ns, fault) each time the vehicle's reported fault changed.
        self.faults: list[tuple[int, str]] = []
        self._fault = ""
        self._on_fault = on_fault
        self._by_uid: dict[int, int] = {}
        # A behavior whose on_start fails ends inside its own activate_behavior call,
        # so its event arrives before the (completed) call does.
        self._early: dict[int, TopicRecord] = {}
        self._on_change = on_change

    def on_service_call(self, record: ServiceCallRecord) -> None:
        if record.service != "activate_behavior" or record.parent_seq is not None:
            return
        response = record.response
        row = Activation(
            behavior=str(record.request.get("behavior", "")),
            arguments=dict(record.request.get("arguments", {})),
            accepted=bool(response.get("ok")),
            start_ns=record.log_time_ns,
            uid=int(response.get("uid", 0)),
            error=str(response.get("error", "")),
        )
        if row.accepted:
            self._by_uid[row.uid] = len(self.rows)
        self.rows.append(row)
        self._changed(row)
        early = self._early.pop(row.uid, None)
        if row.accepted and early is not None:
            self.on_topic(early)

    def on_topic(self, record: TopicRecord) -> None:
        if record.topic == "vehicle/state":
            fault = str(record.data.get("fault") or "")
            if fault != self._fault:
                self._fault = fault
                self.faults.append((record.log_time_ns, fault))
                if self._on_fault is not None:
                    self._on_fault(record.log_time_ns, fault)
            return
        if record.topic != "behavior_event":
            return
        uid = int(record.data.get("uid", -1))
        index = self._by_uid.pop(uid, None)
        if index is None:
            self._early[uid] = record
            return
        start = self.rows[index].start_ns
        row = replace(
            self.rows[index],
            end_code=str(record.data.get("code", "")),
            # A behavior that failed in its own activation call ended in it: on the wall
            # clock its event can be stamped a few microseconds before the call's record.
            end_ns=max(record.log_time_ns, start),
            detail=str(record.data.get("detail", "")),
        )
        self.rows[index] = row
        self._changed(row)

    def _changed(self, row: Activation) -> None:
        if self._on_change is not None:
            self._on_change(row)
