"""The in-process bus: every service call and topic message of the core passes here.

The thesis' components talked over ROS services and topics; here they call each other
directly, but through `Bus.call`/`Bus.publish`, so observers (the MCAP recorder, the CLI
printer, tests) see the same traffic a ROS graph would have carried. Requests and
payloads may be given as zero-argument callables: with nobody observing, they are never
built, which keeps the unrecorded path fast. An observer that reads only some topics and
services says which (`reads`): it is not called for the others.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from aeroexec.executive.clock import Clock
from aeroexec.executive.messages import ServiceCallRecord, ServiceResult, TopicRecord

Payload = dict[str, Any] | Callable[[], dict[str, Any]]


class BusObserver(Protocol):
    def on_service_call(self, record: ServiceCallRecord) -> None: ...

    def on_topic(self, record: TopicRecord) -> None: ...


def reads(observer: BusObserver, name: str) -> bool:
    """Whether `observer` reads the topic or service `name`: an optional attribute
    `reads`, the names it reads (a property monitor reads 7 of the ~25 of a session);
    without it, all."""
    wanted = getattr(observer, "reads", None)
    return wanted is None or name in wanted


def _build(payload: Payload | None) -> dict[str, Any]:
    if payload is None:
        return {}
    return payload() if callable(payload) else payload


class Bus:
    def __init__(self, clock: Clock) -> None:
        self.clock = clock
        self._observers: list[BusObserver] = []
        #: Per topic or service, the observers that read it (filled on first use).
        self._routes: dict[str, list[BusObserver]] = {}
        #: Whether anyone observes (a plain attribute: the hot path reads it often).
        self.observed = False
        self._seq = 0
        self._stack: list[int] = []

    def attach(self, observer: BusObserver) -> None:
        self._observers.append(observer)
        self._routes.clear()
        self.observed = True

    def detach(self, observer: BusObserver) -> None:
        self._observers.remove(observer)
        self._routes.clear()
        self.observed = bool(self._observers)

    def quiet(self) -> bool:
        """Nobody observes: take the next call's seq number and return True, so the
        caller runs its handler directly, without building closures or payloads (the
        activation hot path). With observers: False, and the caller uses `call`."""
        if self.observed:
            return False
        self._seq += 1
        return True

    def call(
        self,
        service: str,
        caller: str,
        handler: Callable[[], ServiceResult],
        request: Payload | None = None,
    ) -> ServiceResult:
        """Run `handler` as the service `service` called by `caller`; observers see the
        completed call (nested calls complete, and are seen, before their parent)."""
        seq = self._seq
        self._seq = seq + 1
        observers = self._observers
        if not observers:
            return handler()
        # Observed: some ten calls per recorded activation come here, so `_build` is
        # inlined and the stack is a local.
        stack = self._stack
        parent = stack[-1] if stack else None
        stack.append(seq)
        try:
            result = handler()
        finally:
            stack.pop()
        readers = self._routes.get(service)
        if readers is None:
            readers = self._route(service)
        if not readers:
            return result
        if request is None:
            request = {}
        elif type(request) is not dict:
            request = _build(request)
        record = ServiceCallRecord(
            seq, parent, caller, service, request, result.as_dict(), self.clock.now_ns()
        )
        for observer in readers:
            observer.on_service_call(record)
        return result

    def publish(self, topic: str, data: Payload) -> None:
        observers = self._routes.get(topic)
        if observers is None:
            observers = self._route(topic)
        if not observers:
            return
        if type(data) is not dict:
            data = _build(data)
        record = TopicRecord(topic, data, self.clock.now_ns())
        for observer in observers:
            observer.on_topic(record)

    def _route(self, name: str) -> list[BusObserver]:
        readers = self._routes[name] = [o for o in self._observers if reads(o, name)]
        return readers


class MemoryObserver:
    """Keeps everything it sees, in order (for tests and the CLI's summary)."""

    def __init__(self) -> None:
        self.records: list[ServiceCallRecord | TopicRecord] = []

    def on_service_call(self, record: ServiceCallRecord) -> None:
        self.records.append(record)

    def on_topic(self, record: TopicRecord) -> None:
        self.records.append(record)

    def topics(self, topic: str) -> list[dict[str, Any]]:
        return [r.data for r in self.records if isinstance(r, TopicRecord) and r.topic == topic]

    def calls(self, service: str | None = None) -> list[ServiceCallRecord]:
        return [
            r
            for r in self.records
            if isinstance(r, ServiceCallRecord) and (service is None or r.service == service)
        ]
