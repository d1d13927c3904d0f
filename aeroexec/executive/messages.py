"""Values that cross the bus: service results, events, and what observers receive."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any


class EventCode(str, Enum):
    """`droneMsgsROS/BehaviorEvent` codes (2017) plus PROCESS_FAILURE (Aerostack 2019+)."""

    GOAL_ACHIEVED = "GOAL_ACHIEVED"
    TIME_OUT = "TIME_OUT"
    WRONG_PROGRESS = "WRONG_PROGRESS"
    ASSUMPTION_CONFLICT = "ASSUMPTION_CONFLICT"
    INTERRUPTED = "INTERRUPTED"
    PROCESS_FAILURE = "PROCESS_FAILURE"


# Frozen dataclasses set their fields through `object.__setattr__`, which makes them
# three times dearer to build than plain ones; an activation builds several results and
# one event, so those two classes set their fields through the slot descriptors instead
# (same signature, still frozen, equal, hashable and printable as generated).
@dataclass(frozen=True, slots=True, init=False)
class ServiceResult:
    """Every service answers `(ok, error, payload)`: errors are data, not exceptions."""

    ok: bool
    error: str = ""
    payload: dict[str, Any] = field(default_factory=dict)

    def __init__(self, ok: bool, error: str = "", payload: dict[str, Any] | None = None) -> None:
        _SR_OK(self, ok)
        _SR_ERROR(self, error)
        _SR_PAYLOAD(self, {} if payload is None else payload)

    def as_dict(self) -> dict[str, Any]:
        return {"ok": self.ok, "error": self.error, **self.payload}


_SR_OK, _SR_ERROR, _SR_PAYLOAD = (
    ServiceResult.__dict__[n].__set__ for n in ("ok", "error", "payload")
)


OK = ServiceResult(True)


def failure(error: str, **payload: Any) -> ServiceResult:
    return ServiceResult(False, error, payload)


@dataclass(frozen=True, slots=True, init=False)
class BehaviorEvent:
    """A behavior's one end event: which activation (`uid`) ended, how, and when."""

    name: str
    uid: int
    code: EventCode
    time_ns: int
    detail: str = ""

    def __init__(
        self, name: str, uid: int, code: EventCode, time_ns: int, detail: str = ""
    ) -> None:
        _EV_NAME(self, name)
        _EV_UID(self, uid)
        _EV_CODE(self, code)
        _EV_TIME(self, time_ns)
        _EV_DETAIL(self, detail)

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "uid": self.uid,
            "code": self.code.value,
            "detail": self.detail,
        }


_EV_NAME, _EV_UID, _EV_CODE, _EV_TIME, _EV_DETAIL = (
    BehaviorEvent.__dict__[n].__set__ for n in ("name", "uid", "code", "time_ns", "detail")
)


# The bus builds one of these per observed call or message (some 18 per recorded
# activation): same slot-descriptor construction as above.
@dataclass(frozen=True, slots=True, init=False)
class ServiceCallRecord:
    """A completed service call as observers see it (and the recorder writes it)."""

    seq: int
    parent_seq: int | None
    caller: str
    service: str
    request: dict[str, Any]
    response: dict[str, Any]
    log_time_ns: int

    def __init__(
        self,
        seq: int,
        parent_seq: int | None,
        caller: str,
        service: str,
        request: dict[str, Any],
        response: dict[str, Any],
        log_time_ns: int,
    ) -> None:
        _SC_SEQ(self, seq)
        _SC_PARENT(self, parent_seq)
        _SC_CALLER(self, caller)
        _SC_SERVICE(self, service)
        _SC_REQUEST(self, request)
        _SC_RESPONSE(self, response)
        _SC_TIME(self, log_time_ns)

    def as_dict(self) -> dict[str, Any]:
        return {
            "seq": self.seq,
            "parent_seq": self.parent_seq,
            "caller": self.caller,
            "service": self.service,
            "request": self.request,
            "response": self.response,
        }


_SC_SEQ, _SC_PARENT, _SC_CALLER, _SC_SERVICE, _SC_REQUEST, _SC_RESPONSE, _SC_TIME = (
    ServiceCallRecord.__dict__[n].__set__
    for n in ("seq", "parent_seq", "caller", "service", "request", "response", "log_time_ns")
)


@dataclass(frozen=True, slots=True, init=False)
class TopicRecord:
    """A message published on a topic."""

    topic: str
    data: dict[str, Any]
    log_time_ns: int

    def __init__(self, topic: str, data: dict[str, Any], log_time_ns: int) -> None:
        _TR_TOPIC(self, topic)
        _TR_DATA(self, data)
        _TR_TIME(self, log_time_ns)


_TR_TOPIC, _TR_DATA, _TR_TIME = (
    TopicRecord.__dict__[n].__set__ for n in ("topic", "data", "log_time_ns")
)
